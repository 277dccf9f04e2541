// Selective photon tracing invariants (Larsen ch. 9): repair equals rebuild, detection, energy.
#include "cpu/photon_simulation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <tuple>
#include <utility>

#include "cpu/aim.h"
#include "test_scenes.h"

namespace ag::cpu {

namespace {

using Key = std::tuple<uint32_t, uint32_t, uint32_t>;  // light, group, path vertex

std::map<Key, PhotonHit> hits_of(const PhotonMaps& maps, int surface) {
    std::map<Key, PhotonHit> out;
    for (const PhotonHit& h : maps.surface(surface).hits) out[{h.light, h.group, h.vertex}] = h;
    return out;
}

// Compares two simulations' photon hits surface by surface: same hits (by owner), positions
// within the path tolerance, powers within float rounding.
void expect_same_hits(const PhotonSimulation& a, const PhotonSimulation& b, float tolerance,
                      const std::string& what) {
    ASSERT_EQ(a.maps().surface_count(), b.maps().surface_count());
    size_t total = 0;
    for (int s = 0; s < int(a.maps().surface_count()); ++s) {
        const auto ha = hits_of(a.maps(), s), hb = hits_of(b.maps(), s);
        ASSERT_EQ(ha.size(), hb.size()) << what << ": surface " << s;
        for (const auto& [key, hit] : ha) {
            auto it = hb.find(key);
            ASSERT_NE(it, hb.end()) << what << ": surface " << s;
            EXPECT_LE(glm::length(hit.position - it->second.position), tolerance)
                << what << ": surface " << s;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(hit.power[c], it->second.power[c],
                            1e-4f * std::max(1e-20f, std::abs(it->second.power[c])))
                    << what << ": surface " << s;
        }
        total += ha.size();
        const glm::dvec3 fa = a.maps().surface(s).flux, fb = b.maps().surface(s).flux;
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(fa[c], fb[c], 1e-4 * std::max(1e-12, std::abs(fb[c]))) << what;
    }
    EXPECT_GT(total, 0u) << what;
}

// Bit-identical maps, hit order included (determinism across thread counts).
void expect_identical_maps(const PhotonMaps& a, const PhotonMaps& b) {
    ASSERT_EQ(a.surface_count(), b.surface_count());
    for (int s = 0; s < int(a.surface_count()); ++s) {
        const auto& ha = a.surface(s).hits;
        const auto& hb = b.surface(s).hits;
        ASSERT_EQ(ha.size(), hb.size());
        for (size_t i = 0; i < ha.size(); ++i) {
            EXPECT_EQ(ha[i].position, hb[i].position);
            EXPECT_EQ(ha[i].power, hb[i].power);
            EXPECT_EQ(ha[i].group, hb[i].group);
            EXPECT_EQ(ha[i].vertex, hb[i].vertex);
        }
    }
}

// World bounds of the static objects: dynamic objects are only moved to where they stay inside,
// so the scene's diagonal (hence ray epsilon and path tolerance) is the one a fresh trace sees.
Bounds static_bounds(const Scene& scene) {
    Bounds b;
    for (const Object& o : scene.objects)
        if (!o.dynamic)
            for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    return b;
}

// Places object `o` at `t` if it stays inside the static bounds; false (and no edit) otherwise.
bool place_inside(Scene& scene, int o, const Transform& t) {
    const Bounds room = static_bounds(scene);
    for (const glm::vec3& p : scene.objects[size_t(o)].mesh.positions) {
        const glm::vec3 w = t.apply_point(p);
        if (glm::any(glm::lessThan(w, room.min)) || glm::any(glm::greaterThan(w, room.max)))
            return false;
    }
    set_object_transform(scene, o, t);
    return true;
}

// Applies one random edit of the kinds the issue lists: small moves and turns, jumps (teleports
// across the room in one edit), large rotations, light moves, switches and colours, albedos.
void random_edit(Scene& scene, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<int> dynamic;
    for (int i = 0; i < int(scene.objects.size()); ++i)
        if (scene.objects[size_t(i)].dynamic) dynamic.push_back(i);
    std::vector<int> diffuse;
    for (int i = 0; i < int(scene.objects.size()); ++i)
        if (scene.objects[size_t(i)].material.type == MaterialType::diffuse) diffuse.push_back(i);
    const float step = 0.08f * scene.diagonal();
    switch (rng() % 9) {
        case 0:
        case 1:
            if (!dynamic.empty()) {
                const int o = dynamic[rng() % dynamic.size()];
                Transform t = scene.objects[size_t(o)].transform;
                t.translation += glm::vec3(step * u(rng), 0.0f, step * u(rng));
                if (rng() % 2)
                    t.rotation = glm::angleAxis(glm::radians(30.0f * u(rng)), glm::vec3(0, 1, 0)) *
                                 t.rotation;
                place_inside(scene, o, t);
            }
            break;
        case 2: {
            const int l = int(rng() % scene.lights.size());
            set_light_position(scene, l,
                               scene.lights[size_t(l)].center() +
                                   0.3f * step * glm::vec3(u(rng), -std::abs(u(rng)), u(rng)));
            break;
        }
        case 3: {
            const int l = int(rng() % scene.lights.size());
            set_light_enabled(scene, l, !scene.lights[size_t(l)].enabled);
            break;
        }
        case 4: {
            const int l = int(rng() % scene.lights.size());
            const glm::vec3 c = scene.lights[size_t(l)].type == LightType::point
                                    ? scene.lights[size_t(l)].intensity
                                    : scene.lights[size_t(l)].radiance;
            set_light_color(scene, l,
                            c * glm::vec3(0.5f + 0.5f * std::abs(u(rng)), 1.0f,
                                          0.7f + 0.5f * std::abs(u(rng))));
            break;
        }
        case 5: {
            const int o = diffuse[rng() % diffuse.size()];
            set_albedo(
                scene, o,
                glm::vec3(0.2f + 0.6f * std::abs(u(rng)), 0.3f + 0.6f * std::abs(u(rng)), 0.5f));
            break;
        }
        case 6:
        case 7:  // a jump: anywhere in the room at the same height, in one set_position
            if (!dynamic.empty()) {
                const int o = dynamic[rng() % dynamic.size()];
                const Bounds room = static_bounds(scene);
                for (int attempt = 0; attempt < 8; ++attempt) {
                    Transform t = scene.objects[size_t(o)].transform;
                    const glm::vec3 f(0.5f + 0.5f * u(rng), 0.0f, 0.5f + 0.5f * u(rng));
                    t.translation.x = room.min.x + f.x * (room.max.x - room.min.x);
                    t.translation.z = room.min.z + f.z * (room.max.z - room.min.z);
                    if (place_inside(scene, o, t)) break;
                }
            }
            break;
        case 8:  // a large rotation about an arbitrary axis
            if (!dynamic.empty()) {
                const int o = dynamic[rng() % dynamic.size()];
                Transform t = scene.objects[size_t(o)].transform;
                const glm::vec3 axis(u(rng), 1.0f + u(rng), u(rng));
                t.rotation = glm::angleAxis(glm::radians(180.0f * u(rng)), glm::normalize(axis)) *
                             t.rotation;
                place_inside(scene, o, t);
            }
            break;
    }
}

// Stored paths equal within the path tolerance (world and object space), photon by photon.
bool same_paths(const PhotonGroup& a, const PhotonGroup& b, float tolerance) {
    if (a.photon_begin != b.photon_begin) return false;
    for (size_t i = 0; i < a.vertices.size(); ++i) {
        const PathVertex &x = a.vertices[i], &y = b.vertices[i];
        if (x.surface != y.surface || glm::length(x.position - y.position) > tolerance ||
            glm::length(x.local - y.local) > tolerance)
            return false;
    }
    return true;
}

// Bit-identical stored paths and hit positions of every traced group against a fresh trace; hit
// powers within float rounding (a light colour edit rescales hits instead of re-tracing them).
void expect_exact_paths(const PhotonSimulation& a, const PhotonSimulation& b,
                        const std::string& what) {
    const Scene& scene = b.scene();
    ASSERT_EQ(a.layers(), b.layers()) << what;
    for (int l = 0; l < int(scene.lights.size()); ++l)
        for (int g = 0; g < scene.settings.photons.groups; ++g)
            ASSERT_EQ(a.maps().sets(l, g), b.maps().sets(l, g))
                << what << ": light " << l << " group " << g;
    for (int l = 0; l < int(scene.lights.size()); ++l)
        for (int g = 0; g < scene.settings.photons.groups * b.layers(); ++g) {
            const PhotonGroup &x = a.maps().group(l, g), &y = b.maps().group(l, g);
            ASSERT_EQ(x.traced, y.traced) << what << ": light " << l << " group " << g;
            ASSERT_EQ(x.photon_begin, y.photon_begin) << what << ": light " << l << " group " << g;
            for (size_t i = 0; i < x.vertices.size(); ++i) {
                ASSERT_EQ(x.vertices[i].surface, y.vertices[i].surface)
                    << what << ": light " << l << " group " << g;
                ASSERT_EQ(x.vertices[i].position, y.vertices[i].position)
                    << what << ": light " << l << " group " << g;
                ASSERT_EQ(x.vertices[i].local, y.vertices[i].local)
                    << what << ": light " << l << " group " << g;
            }
        }
    for (int s = 0; s < int(a.maps().surface_count()); ++s) {
        const auto ha = hits_of(a.maps(), s), hb = hits_of(b.maps(), s);
        ASSERT_EQ(ha.size(), hb.size()) << what << ": surface " << s;
        for (const auto& [key, hit] : ha) {
            auto it = hb.find(key);
            ASSERT_NE(it, hb.end()) << what << ": surface " << s;
            EXPECT_EQ(hit.position, it->second.position) << what << ": surface " << s;
        }
    }
}

// Runs frames until every photon has been verified since the last edit and no group waits.
int settle(PhotonSimulation& sim) {
    const int per_group = sim.scene().settings.photons.photons_per_group;
    int frames = 0;
    for (int quiet = 0; quiet < per_group || !sim.settled(); ++frames) {
        const PhotonFrameStats st = sim.frame();
        quiet = (st.groups_invalidated == 0 && st.groups_retraced == 0) ? quiet + 1 : 0;
        if (frames > 100000) break;
    }
    return frames;
}

// With `verify` off the round-robin safety net is switched off: the edits' own invalidation (the
// moved-object query, light and albedo edits) must then find every group alone.
void repair_equals_rebuild(const std::string& scene_file, uint32_t seed, int edits,
                           bool verify = true, int layers = 1, bool all_sets = false) {
    Scene scene = load_scene(test::scene_path(scene_file));
    if (!verify) scene.settings.photons.verify_per_frame = 0;
    scene.settings.photons.refine_layers = layers;
    scene.settings.photons.retrace_all_sets = all_sets;
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    settle(sim);
    std::mt19937 rng(seed);
    for (int e = 0; e < edits; ++e) {
        random_edit(scene, rng);
        // A few frames between edits, sometimes none, so edits overlap with repairs in flight.
        const int frames = int(rng() % 4);
        for (int f = 0; f < frames; ++f) sim.frame();
    }
    if (!scene.lights[0].enabled) set_light_enabled(scene, 0, true);  // keep something to compare
    settle(sim);

    PhotonSimulation fresh(scene, pool);
    fresh.trace_all();
    EXPECT_EQ(sim.layers(), layers);
    EXPECT_EQ(fresh.layers(), layers);
    expect_same_hits(sim, fresh, scene.settings.photons.path_tolerance * scene.diagonal(),
                     scene_file + " seed " + std::to_string(seed));
    expect_exact_paths(sim, fresh, scene_file + " seed " + std::to_string(seed));
}

}  // namespace

TEST(SelectiveTracing, RepairEqualsRebuildCornell) {
    for (uint32_t seed = 1; seed <= 12; ++seed) repair_equals_rebuild("cornell.json", seed, 6);
}

TEST(SelectiveTracing, RepairEqualsRebuildTwoRooms) {
    for (uint32_t seed = 100; seed <= 108; ++seed) repair_equals_rebuild("two_rooms.json", seed, 6);
}

TEST(SelectiveTracing, RepairEqualsRebuildWithoutVerification) {
    for (uint32_t seed = 300; seed <= 311; ++seed)
        repair_equals_rebuild("cornell.json", seed, 8, false);
    for (uint32_t seed = 400; seed <= 408; ++seed)
        repair_equals_rebuild("two_rooms.json", seed, 8, false);
}

// Progressive photon refinement: a grown simulation, edited (which drops its extra photon sets)
// and grown again once settled, holds the photons of a fresh simulation grown to as many sets.
TEST(SelectiveTracing, RepairEqualsRebuildWithRefinementLayers) {
    for (uint32_t seed = 500; seed <= 503; ++seed)
        repair_equals_rebuild("cornell.json", seed, 4, true, 3);
    repair_equals_rebuild("two_rooms.json", 510, 4, false, 3);
    // photons.retrace_all_sets: an invalidated group is re-traced with every set it holds.
    for (uint32_t seed = 520; seed <= 522; ++seed)
        repair_equals_rebuild("cornell.json", seed, 4, true, 3, true);
    repair_equals_rebuild("two_rooms.json", 530, 4, false, 3, true);
}

// photons.retrace_all_sets: the groups an edit invalidates are re-traced with all their sets
// (each counting against the budget), so nothing is regrown afterwards and every group keeps 4.
TEST(SelectiveTracing, RetracingAllSetsLeavesNothingToRegrow) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    scene.settings.photons.refine_layers = 4;
    scene.settings.photons.retrace_all_sets = true;
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    for (int f = 0; f < 1000 && !sim.settled(); ++f) sim.frame();
    ASSERT_TRUE(sim.settled());
    const int cube = scene.find_object("cube");
    ASSERT_GE(cube, 0);
    translate_object(scene, cube, {10.0f, 0.0f, 0.0f});
    const PhotonSettings& p = scene.settings.photons;
    int invalidated = 0, retraced = 0, photons = 0, grown = 0, frames = 0;
    for (; frames < 1000 && (frames == 0 || !sim.settled()); ++frames) {
        const PhotonFrameStats st = sim.frame(p.retrace_budget, true);
        invalidated += st.groups_invalidated;
        retraced += st.groups_retraced;
        photons += st.photons_retraced;
        grown += st.photons_grown;
        EXPECT_EQ(st.layers, 4);
    }
    ASSERT_TRUE(sim.settled());
    EXPECT_GT(invalidated, 0);
    EXPECT_EQ(retraced, invalidated);
    EXPECT_EQ(photons, 4 * p.photons_per_group * retraced);
    EXPECT_EQ(grown, 0);
    EXPECT_GT(frames, 1);  // 4 × 40 photons a group: the 4,000-photon budget takes 25 a frame
}

// Growth: one more set for a few groups at a time once settled, the fewest-set groups first,
// each photon's flux Φ / (G·P·sets of its group) in the AIM. An edit re-traces the groups it
// touches with one set and leaves every other group's sets alone: regrowing afterwards costs
// exactly the touched groups' missing sets (dropping every group's sets would cost them all).
TEST(SelectiveTracing, RefinementGrowsWhenSettledAndAnEditKeepsUntouchedSets) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    scene.settings.photons.refine_layers = 4;
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    EXPECT_FALSE(sim.settled());
    const size_t base_hits = [&] {
        Scene s1 = load_scene(test::scene_path("cornell.json"));
        s1.settings.photons.refine_layers = 1;  // one set, whatever the default
        PhotonSimulation one(s1, pool);
        one.trace_all();
        return one.maps().hit_count();
    }();
    int frames = 0, grown = 0;
    while (!sim.settled() && frames < 1000) {
        const PhotonFrameStats st = sim.frame();
        // Growth only with the queue empty: never in a frame that still had repairs queued.
        if (st.photons_grown > 0) {
            EXPECT_EQ(st.groups_queued, 0);
        }
        grown += st.photons_grown;
        ++frames;
    }
    ASSERT_TRUE(sim.settled());
    EXPECT_EQ(sim.layers(), 4);
    const PhotonSettings& p = scene.settings.photons;
    EXPECT_EQ(grown, 3 * p.groups * p.photons_per_group);
    EXPECT_GT(sim.maps().hit_count(), 3 * base_hits);

    const int cube = scene.find_object("cube");
    ASSERT_GE(cube, 0);
    translate_object(scene, cube, {10.0f, 0.0f, 0.0f});
    const PhotonFrameStats st = sim.frame();
    EXPECT_EQ(st.photons_grown, 0);
    EXPECT_FALSE(sim.settled());
    ASSERT_GT(st.groups_invalidated, 0);
    ASSERT_LT(st.groups_invalidated, p.groups);
    ASSERT_EQ(st.groups_queued, 0);  // the budget re-traces them all in the edit's frame
    const std::set<std::pair<int, int>> touched(sim.invalidated_last_frame().begin(),
                                                sim.invalidated_last_frame().end());
    for (int g = 0; g < p.groups; ++g)
        EXPECT_EQ(sim.maps().sets(0, g), touched.count({0, g}) ? 1 : 4) << "group " << g;
    EXPECT_EQ(st.layers, 1);

    int retraced = st.groups_retraced, regrown = 0;
    for (frames = 0; !sim.settled() && frames < 1000; ++frames) {
        const PhotonFrameStats f = sim.frame();
        retraced += f.groups_retraced;
        regrown += f.photons_grown;
    }
    ASSERT_TRUE(sim.settled());
    EXPECT_EQ(sim.layers(), 4);
    EXPECT_EQ(regrown, 3 * retraced * p.photons_per_group);
    EXPECT_LT(retraced, p.groups);
}

TEST(SelectiveTracing, RepairEqualsRebuildBumpyFloor) {
    for (uint32_t seed = 200; seed <= 202; ++seed) repair_equals_rebuild("bumpy_13k.json", seed, 5);
}

// The same edits and frames on 1 and 3 worker threads give bit-identical maps, hit order included.
TEST(SelectiveTracing, RepairIsIndependentOfThreadCount) {
    Scene a = load_scene(test::scene_path("cornell.json")),
          b = load_scene(test::scene_path("cornell.json"));
    ThreadPool one(1), three(3);
    PhotonSimulation sa(a, one), sb(b, three);
    std::mt19937 ra(5), rb(5);
    const auto frames = [&] {
        for (int f = 0; f < 3; ++f) {
            const PhotonFrameStats x = sa.frame(), y = sb.frame();
            EXPECT_EQ(x.groups_invalidated, y.groups_invalidated);
            EXPECT_EQ(x.groups_invalidated_by_query, y.groups_invalidated_by_query);
            EXPECT_EQ(x.query_segments_tested, y.query_segments_tested);
            EXPECT_EQ(sa.invalidated_last_frame(), sb.invalidated_last_frame());
            EXPECT_EQ(x.photons_retraced, y.photons_retraced);
        }
    };
    for (int e = 0; e < 10; ++e) {
        random_edit(a, ra);
        random_edit(b, rb);
        frames();
    }
    // A jump across the room in one edit.
    const int cube = a.find_object("cube");
    ASSERT_GE(cube, 0);
    for (Scene* s : {&a, &b}) {
        Transform t = s->objects[size_t(cube)].transform;
        t.translation = {400.0f, t.translation.y, 130.0f};
        set_object_transform(*s, cube, t);
    }
    frames();
    expect_identical_maps(sa.maps(), sb.maps());
}

TEST(SelectiveTracing, FreshTraceIsIndependentOfThreadCount) {
    const Scene scene = load_scene(test::scene_path("cornell.json"));
    ThreadPool one(1), three(3);
    PhotonSimulation a(scene, one), b(scene, three);
    a.trace_all();
    b.trace_all();
    expect_identical_maps(a.maps(), b.maps());
}

TEST(SelectiveTracing, GrownTraceIsIndependentOfThreadCount) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    scene.settings.photons.refine_layers = 3;
    ThreadPool one(1), three(3);
    PhotonSimulation a(scene, one), b(scene, three);
    a.trace_all();
    b.trace_all();
    EXPECT_EQ(a.layers(), 3);
    expect_identical_maps(a.maps(), b.maps());
}

TEST(SelectiveTracing, MovingTheCubeInvalidatesGroupsWithinGFrames) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    settle(sim);
    const int cube = scene.find_object("cube");
    ASSERT_GE(cube, 0);
    translate_object(scene, cube, {60.0f, 0.0f, -40.0f});
    int invalidated = 0;
    for (int f = 0; f < scene.settings.photons.groups && invalidated == 0; ++f)
        invalidated += sim.frame().groups_invalidated;
    EXPECT_GT(invalidated, 0);
}

struct EditOutcome {
    std::set<std::pair<int, int>> changed;      // groups whose stored paths a fresh trace changes
    std::set<std::pair<int, int>> invalidated;  // groups invalidated in the frame of the edit
    PhotonFrameStats stats;                     // of that frame
};

// Applies `edit` to a settled simulation of `scene_file`, runs one frame, and finds the ground
// truth by brute force: every group's photons re-traced in the edited scene.
EditOutcome step_edit(const std::string& scene_file, const std::function<void(Scene&)>& edit,
                      bool query) {
    Scene scene = load_scene(test::scene_path(scene_file));
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    sim.set_query_invalidation(query);
    settle(sim);
    const int groups = scene.settings.photons.groups;
    std::vector<PhotonGroup> before;
    for (int l = 0; l < int(scene.lights.size()); ++l)
        for (int g = 0; g < groups; ++g) before.push_back(sim.maps().group(l, g));
    edit(scene);
    EditOutcome out;
    out.stats = sim.frame();
    out.invalidated.insert(sim.invalidated_last_frame().begin(),
                           sim.invalidated_last_frame().end());
    PhotonSimulation fresh(scene, pool);
    fresh.trace_all();
    const float tolerance = scene.settings.photons.path_tolerance * scene.diagonal();
    for (int l = 0; l < int(scene.lights.size()); ++l)
        for (int g = 0; g < groups; ++g)
            if (!same_paths(before[size_t(l * groups + g)], fresh.maps().group(l, g), tolerance))
                out.changed.emplace(l, g);
    return out;
}

size_t missed(const EditOutcome& o) {
    size_t n = 0;
    for (const auto& c : o.changed) n += o.invalidated.count(c) ? 0 : 1;
    return n;
}

// The cube jumps 261 mm in one set_position (to where cornell_move_cube.lua slides it).
void jump_cube(Scene& scene) {
    const int cube = scene.find_object("cube");
    ASSERT_GE(cube, 0);
    Transform t = scene.objects[size_t(cube)].transform;
    t.translation += glm::vec3(254.5f, 0.0f, -59.0f);
    set_object_transform(scene, cube, t);
}

// A moved object invalidates in the frame of the edit every group whose stored path crossed its
// old or new placement; round-robin verification alone finds only some of them in that frame.
TEST(SelectiveTracing, CubeJumpInvalidatesEveryChangedGroupInTheEditFrame) {
    const EditOutcome on = step_edit("cornell.json", jump_cube, true);
    ASSERT_FALSE(on.changed.empty());
    EXPECT_EQ(missed(on), 0u) << "of " << on.changed.size() << " changed groups";
    EXPECT_GT(on.stats.groups_invalidated_by_query, 0);
    EXPECT_GT(on.stats.query_segments_tested, 0u);
    std::printf(
        "cube jump: %zu groups changed, %zu invalidated in the edit frame (%d by the query, %llu "
        "segments tested)\n",
        on.changed.size(), on.invalidated.size(), on.stats.groups_invalidated_by_query,
        static_cast<unsigned long long>(on.stats.query_segments_tested));

    const EditOutcome off = step_edit("cornell.json", jump_cube, false);
    EXPECT_EQ(off.changed, on.changed);
    EXPECT_GT(missed(off), 0u);  // without the query the check above fails
    EXPECT_EQ(off.stats.groups_invalidated_by_query, 0);
    std::printf("cube jump without the query: %zu of %zu changed groups missed in the edit frame\n",
                missed(off), off.changed.size());
}

// The same for the door of two_rooms opened by 90 degrees in one edit (a rotation about its hinge).
TEST(SelectiveTracing, DoorStepInvalidatesEveryChangedGroupInTheEditFrame) {
    const EditOutcome on = step_edit(
        "two_rooms.json",
        [](Scene& scene) {
            rotate_object(scene, scene.find_object("door"), {0, 1, 0}, 90.0f);
        },
        true);
    ASSERT_FALSE(on.changed.empty());
    EXPECT_EQ(missed(on), 0u) << "of " << on.changed.size() << " changed groups";
    std::printf(
        "door step: %zu groups changed, %zu invalidated in the edit frame (%d by the query, %llu "
        "segments tested)\n",
        on.changed.size(), on.invalidated.size(), on.stats.groups_invalidated_by_query,
        static_cast<unsigned long long>(on.stats.query_segments_tested));
}

TEST(SelectiveTracing, ClosedDoorIsolatesTheRooms) {
    Scene scene = load_scene(test::scene_path("two_rooms.json"));
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    settle(sim);
    const int block = scene.find_object("block");
    ASSERT_GE(block, 0);
    const float wall_x = 555.0f;  // the partition between room A (x < 555) and room B
    ASSERT_LT(scene.objects[size_t(block)].transform.translation.x, wall_x);
    std::vector<uint64_t> before;
    for (int l = 0; l < int(scene.lights.size()); ++l) before.push_back(sim.invalidations(l));
    for (int step = 0; step < 8; ++step) {
        translate_object(scene, block, {15.0f, 0.0f, -10.0f});
        rotate_object(scene, block, {0, 1, 0}, 10.0f);
        for (int f = 0; f < 10; ++f) sim.frame();
    }
    settle(sim);
    uint64_t room_a = 0;
    for (int l = 0; l < int(scene.lights.size()); ++l) {
        const uint64_t n = sim.invalidations(l) - before[size_t(l)];
        if (scene.lights[size_t(l)].position.x > wall_x)
            EXPECT_EQ(n, 0u) << scene.lights[size_t(l)].name;
        else
            room_a += n;
    }
    EXPECT_GT(room_a, 0u);  // the edit was seen where it happened
}

TEST(SelectiveTracing, ClosedBoxStoresPhiOverOneMinusRho) {
    for (float rho : {0.5f, 0.8f}) {
        const float intensity = 10.0f;
        const Scene scene = test::closed_box(rho, intensity, 250, 64);
        ThreadPool pool(2);
        PhotonSimulation sim(scene, pool);
        sim.trace_all();
        glm::dvec3 total(0.0);
        for (int s = 0; s < int(sim.maps().surface_count()); ++s)
            total += sim.maps().surface(s).flux;
        const double phi = 4.0 * std::numbers::pi * intensity;
        EXPECT_NEAR(total.x / (phi / (1.0 - rho)), 1.0, 0.01) << "rho " << rho;
        std::printf("closed box rho %.1f: stored flux / (phi / (1 - rho)) = %.5f\n", double(rho),
                    total.x / (phi / (1.0 - rho)));
        EXPECT_NEAR(total.y, total.x, 1e-9 * total.x);
    }
}

TEST(SelectiveTracing, DeltaBookkeepingIsExact) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    settle(sim);
    Aim aim(scene, pool);
    aim.rebuild_all(sim.maps());  // resets every Δ
    std::vector<glm::dvec3> flux0;
    for (int s = 0; s < int(sim.maps().surface_count()); ++s) {
        flux0.push_back(sim.maps().surface(s).flux);
        EXPECT_EQ(sim.maps().surface(s).delta_f, 0.0);
    }
    std::mt19937 rng(7);
    for (int e = 0; e < 8; ++e) {
        random_edit(scene, rng);
        sim.frame();
    }
    settle(sim);
    bool any = false;
    for (int s = 0; s < int(sim.maps().surface_count()); ++s) {
        const SurfaceHits& h = sim.maps().surface(s);
        const glm::dvec3 change = h.flux - flux0[size_t(s)];
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(h.signed_delta[c], change[c],
                        1e-9 * std::max(1.0, std::abs(flux0[size_t(s)][c])));
        // Δf sums |energy| of every add and remove, so it bounds the net change.
        EXPECT_GE(h.delta_f + 1e-9, std::abs(energy(change)));
        glm::dvec3 sum(0.0);
        // Each hit counts at its group's weight (1 / its photon sets with photons.refine_layers),
        // applied as PhotonMaps::add_energy applies it.
        for (const PhotonHit& hit : h.hits) {
            const double w = sim.maps().hit_weight(hit);
            sum += glm::dvec3(w == 1.0 ? hit.power : hit.power * float(w));
        }
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(sum[c], h.flux[c], 1e-9 * std::max(1.0, std::abs(sum[c])));
        any = any || h.delta_f > 0.0;
    }
    EXPECT_TRUE(any);
}

TEST(SelectiveTracing, SwitchingALightOffRemovesItsHitsAndOnRestoresThem) {
    Scene scene = load_scene(test::scene_path("two_rooms.json"));
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    settle(sim);
    set_light_enabled(scene, 0, false);
    sim.frame();
    for (int s = 0; s < int(sim.maps().surface_count()); ++s)
        for (const PhotonHit& h : sim.maps().surface(s).hits) EXPECT_NE(h.light, 0u);
    EXPECT_EQ(sim.light_state(0).valid, 0);
    set_light_enabled(scene, 0, true);
    settle(sim);
    PhotonSimulation fresh(scene, pool);
    fresh.trace_all();
    expect_same_hits(sim, fresh, 1e-3f, "light back on");
}

TEST(SelectiveTracing, LightColourRescalesWithoutRetracing) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    settle(sim);
    set_light_color(scene, 0, scene.lights[0].intensity * glm::vec3(0.5f, 1.0f, 2.0f));
    const PhotonFrameStats st = sim.frame();
    EXPECT_EQ(st.groups_invalidated, 0);
    EXPECT_EQ(st.photons_retraced, 0);
    PhotonSimulation fresh(scene, pool);
    fresh.trace_all();
    expect_same_hits(sim, fresh, 1e-3f, "recoloured");
}

}  // namespace ag::cpu
