// F/P/N classification of (patch, light) pairs (Barczak 2006 §4.3.1, §4.5.1): each cell of
// Table 4-1 as its own test (the action taken, and the result equal to classifying afresh), and
// every F and N label on the Cornell box confirmed by 64 Embree rays.
#include "cpu/vpl_visibility.h"

#include <gtest/gtest.h>

#include <cmath>

#include "cpu/photon_simulation.h"
#include "cpu/sampling.h"
#include "cpu/vpl_shading.h"
#include "cpu/vpl_source.h"
#include "test_scenes.h"

namespace ag::cpu {
namespace {

// A 4×4 floor, a VPL 3 above it facing down, and a small single-triangle blocker whose placement
// makes it fully (just under the light), partly (half-way, centred) or not (far aside) occlude
// each floor triangle.
glm::vec3 blocker_place(Occlusion o) {
    switch (o) {
        case Occlusion::full:
            return {0.0f, 2.95f, 0.0f};
        case Occlusion::partial:
            return {0.0f, 1.5f, 0.0f};
        default:
            return {20.0f, 1.5f, 0.0f};
    }
}

Scene floor_and_blocker(Occlusion at) {
    Scene s;
    s.path = "floor_and_blocker";
    Object floor;
    floor.name = "floor";
    floor.mesh = make_quad(4.0f, 4.0f);
    s.objects.push_back(floor);
    Object blocker;
    blocker.name = "blocker";
    blocker.dynamic = true;
    blocker.mesh.positions = {{-0.3f, 0.0f, -0.3f}, {0.5f, 0.0f, -0.3f}, {-0.3f, 0.0f, 0.5f}};
    blocker.mesh.triangles = {{0, 2, 1}};
    blocker.transform.translation = blocker_place(at);
    s.objects.push_back(blocker);
    Light l;
    l.position = glm::vec3(0.0f, 5.0f, 0.0f);
    l.intensity = glm::vec3(1.0f);
    s.lights.push_back(l);
    init_versions(s);
    return s;
}

const std::vector<Vpl> kLight = {Vpl{{0.0f, 3.0f, 0.0f}, {0.0f, -1.0f, 0.0f}, glm::vec3(1.0f)}};

struct Cell {
    Occlusion old_state, new_state;
    const char* action;  // Table 4-1
};

class Table41 : public ::testing::TestWithParam<Cell> {};

std::string cell_name(const ::testing::TestParamInfo<Cell>& info) {
    static const std::array<const char*, 4> kNames = {"None", "Partial", "Full", "Behind"};
    return std::string(kNames[size_t(info.param.old_state)]) + "To" +
           kNames[size_t(info.param.new_state)];
}

TEST_P(Table41, UpdateRule) {
    const Cell cell = GetParam();
    Scene scene = floor_and_blocker(cell.old_state);
    VisibilityDatabase db(scene, kLight, 2);
    const int roots[2] = {0, db.nodes()[0].first_child < 0 ? 1 : 21};  // two floor triangles
    for (int r : roots) ASSERT_EQ(db.state(r, 0), cell.old_state) << "root " << r;
    const VisibilityCounters before = db.counters();

    translate_object(scene, 1, blocker_place(cell.new_state) - blocker_place(cell.old_state));
    db.object_moved(1);
    const VisibilityCounters after = db.counters();
    const uint64_t unchanged = after.unchanged - before.unchanged;
    const uint64_t recursive = after.recursive - before.recursive;
    const uint64_t propagated = after.propagated - before.propagated;
    const std::string action = cell.action;
    if (action == "no change") {
        EXPECT_EQ(unchanged, 2u);
        EXPECT_EQ(recursive + propagated, 0u);
    } else if (action == "recursive update") {
        EXPECT_GE(recursive, 2u);  // the roots, then children where the mover stays partial
        EXPECT_EQ(propagated + recursive + unchanged > 2u, true);
    } else {
        EXPECT_EQ(propagated, 2u);  // once per root, no tests below it
        EXPECT_EQ(recursive + unchanged, 0u);
    }
    for (int r : roots) EXPECT_EQ(db.state(r, 0), cell.new_state) << "root " << r;
    // Whatever the rule did, the database equals one classified afresh in the new scene.
    const VisibilityDatabase fresh(scene, kLight, 2);
    ASSERT_EQ(fresh.nodes().size(), db.nodes().size());
    for (size_t n = 0; n < db.nodes().size(); ++n)
        EXPECT_EQ(db.state(int(n), 0), fresh.state(int(n), 0)) << "node " << n;
}

INSTANTIATE_TEST_SUITE_P(
    Cells, Table41,
    ::testing::Values(Cell{Occlusion::full, Occlusion::full, "no change"},
                      Cell{Occlusion::full, Occlusion::partial, "recursive update"},
                      Cell{Occlusion::full, Occlusion::none, "propagate"},
                      Cell{Occlusion::partial, Occlusion::full, "propagate"},
                      Cell{Occlusion::partial, Occlusion::partial, "recursive update"},
                      Cell{Occlusion::partial, Occlusion::none, "propagate"},
                      Cell{Occlusion::none, Occlusion::full, "propagate"},
                      Cell{Occlusion::none, Occlusion::partial, "recursive update"},
                      Cell{Occlusion::none, Occlusion::none, "no change"}),
    cell_name);

// Checks every F and N leaf label with 64 shadow rays from points spread over the patch: F, all
// blocked; N, none. Returns how many pairs were checked, {N, F}.
std::array<int, 2> check_labels(const VisibilityDatabase& db, const std::vector<Vpl>& vpls,
                                const RayTracer& rays) {
    std::array<int, 2> checked = {0, 0};
    for (size_t n = 0; n < db.nodes().size(); ++n) {
        if (!db.leaf(int(n))) continue;
        const auto& v = db.nodes()[n].v;
        const glm::vec3 normal = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
        for (int l = 0; l < db.light_count(); ++l) {
            const Occlusion o = db.state(int(n), l);
            if (o != Occlusion::full && o != Occlusion::none) continue;
            const glm::vec3 facing =
                glm::dot(vpls[size_t(l)].position - v[0], normal) > 0.0f ? normal : -normal;
            int blocked = 0;
            for (int i = 0; i < 8; ++i)
                for (int j = 0; j < 8; ++j) {
                    // Stratified, strictly inside the triangle.
                    const float a = std::sqrt((float(i) + 0.5f) / 8.0f),
                                b = (float(j) + 0.5f) / 8.0f;
                    const glm::vec3 x = (1.0f - a) * v[0] + a * (1.0f - b) * v[1] + a * b * v[2];
                    blocked += vpl_visible(rays, vpls[size_t(l)], x, facing) ? 0 : 1;
                }
            EXPECT_EQ(blocked, o == Occlusion::full ? 64 : 0) << "node " << n << " light " << l;
            ++checked[o == Occlusion::full ? 1 : 0];
        }
    }
    return checked;
}

// The Cornell box with 8 photon VPLs, patches subdivided twice: every N label holds (F labels do
// not occur: no single polygon there covers a whole pyramid).
TEST(VplVisibility, FullAndNoneLabelsAgreeWithEmbreeRaysOnCornell) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    ThreadPool pool(2);
    PhotonSimulation sim(scene, pool);
    sim.trace_all();
    std::vector<Vpl> vpls;
    for (int g = 0; g < scene.settings.photons.groups && vpls.size() < 8; g += 9)
        group_vpls(scene, sim.maps(), 0, g, 1, vpls);
    ASSERT_GE(vpls.size(), 6u);
    const VisibilityDatabase db(scene, vpls, 2);
    const std::array<int, 2> checked = check_labels(db, vpls, sim.rays());
    const VisibilityCounters c = db.counters();
    std::printf("cornell leaf pairs: N %llu, P %llu, F %llu, behind %llu (%llu pyramid tests)\n",
                (unsigned long long)c.none, (unsigned long long)c.partial,
                (unsigned long long)c.full, (unsigned long long)c.behind,
                (unsigned long long)c.blocker_tests);
    EXPECT_GT(checked[0], 100);
    EXPECT_GT(c.partial, 0u);
}

// F labels, and N and F after moves, on the floor under a blocker.
TEST(VplVisibility, FullLabelsAgreeWithEmbreeRaysUnderABlocker) {
    Scene scene = floor_and_blocker(Occlusion::full);
    VisibilityDatabase db(scene, kLight, 2);
    std::array<int, 2> checked = check_labels(db, kLight, RayTracer(scene));
    EXPECT_GT(checked[1], 30);
    translate_object(scene, 1, blocker_place(Occlusion::partial) - blocker_place(Occlusion::full));
    db.object_moved(1);
    checked = check_labels(db, kLight, RayTracer(scene));
    EXPECT_GT(checked[0], 0);  // leaves beside the blocker's shadow
    EXPECT_GT(db.counters().partial, 0u);
}

// leaf_at() descends to the leaf whose triangle holds the point.
TEST(VplVisibility, LeafAtFindsTheLeafHoldingAPoint) {
    const Scene scene = floor_and_blocker(Occlusion::none);
    const VisibilityDatabase db(scene, kLight, 3);
    const Mesh& m = scene.objects[0].mesh;
    for (int t = 0; t < int(m.triangles.size()); ++t)
        for (int i = 0; i < 40; ++i) {
            const float u = hashed_uniform(uint64_t(t), uint64_t(2 * i)),
                        v = hashed_uniform(uint64_t(t), uint64_t(2 * i + 1));
            const glm::vec2 uv = u + v > 1.0f ? glm::vec2(1.0f - u, 1.0f - v) : glm::vec2(u, v);
            const glm::uvec3 tri = m.triangles[size_t(t)];
            const glm::vec3 p = (1.0f - uv.x - uv.y) * m.positions[tri.x] +
                                uv.x * m.positions[tri.y] + uv.y * m.positions[tri.z];
            const int leaf = db.leaf_at(0, t, uv);
            ASSERT_GE(leaf, 0);
            EXPECT_TRUE(db.leaf(leaf));
            // p inside the leaf: its barycentrics there are all ≥ 0 (within rounding).
            const auto& v3 = db.nodes()[size_t(leaf)].v;
            const glm::vec3 e1 = v3[1] - v3[0], e2 = v3[2] - v3[0], d = p - v3[0];
            const float d11 = glm::dot(e1, e1), d12 = glm::dot(e1, e2), d22 = glm::dot(e2, e2);
            const float den = d11 * d22 - d12 * d12;
            const float b1 = (d22 * glm::dot(d, e1) - d12 * glm::dot(d, e2)) / den;
            const float b2 = (d11 * glm::dot(d, e2) - d12 * glm::dot(d, e1)) / den;
            EXPECT_GE(b1, -1e-4f);
            EXPECT_GE(b2, -1e-4f);
            EXPECT_LE(b1 + b2, 1.0f + 1e-4f);
        }
    EXPECT_EQ(db.leaf_at(1, 0, {0.2f, 0.2f}) >= 0, true);  // the blocker is diffuse too
}

}  // namespace
}  // namespace ag::cpu
