// Stencil shadow volumes (Larsen ch. 13) built on the CPU: open meshes' prisms welded across
// meshes, so that side faces two prisms share are left out and the rest still closes.
#include "gpu/shadow_volumes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <set>
#include <vector>

#include "../cpu/test_scenes.h"

namespace ag::gpu {

namespace {

struct Casters {
    std::vector<ShadowCaster> casters;
    std::vector<glm::mat4> models;
};

Casters casters_of(const Scene& scene, size_t count) {
    Casters c;
    for (size_t o = 0; o < count; ++o) {
        c.casters.push_back(make_shadow_caster(scene.objects[o].mesh));
        c.models.push_back(scene.objects[o].transform.matrix());
    }
    return c;
}

// Directed edges of `triangles` (homogeneous) that no triangle runs the other way, corners
// matched within `tolerance`: 0 for a closed, consistently wound volume.
int unmatched_edges(const std::vector<glm::vec4>& triangles, float tolerance) {
    const auto same = [&](const glm::vec4& a, const glm::vec4& b) {
        const glm::vec4 d = glm::abs(a - b);
        return std::max({d.x, d.y, d.z, d.w}) <= tolerance;
    };
    const auto edge = [&](size_t t, int k) {
        return std::pair(triangles[3 * t + size_t(k)], triangles[3 * t + size_t((k + 1) % 3)]);
    };
    const size_t n = triangles.size() / 3;
    int unmatched = 0;
    std::vector<bool> used(3 * n, false);
    for (size_t t = 0; t < n; ++t)
        for (int k = 0; k < 3; ++k) {
            const auto [a, b] = edge(t, k);
            bool found = false;
            for (size_t u = 0; u < n && !found; ++u)
                for (int j = 0; j < 3 && !found; ++j) {
                    const auto [c, d] = edge(u, j);
                    if (!used[3 * u + size_t(j)] && same(a, d) && same(b, c)) {
                        used[3 * u + size_t(j)] = true;
                        found = true;
                    }
                }
            unmatched += found ? 0 : 1;
        }
    return unmatched;
}

}  // namespace

// The room's five walls (quads, each turned into place) meet at 8 corners, which the weld finds
// though the walls' copies differ in their last bits.
TEST(ShadowVolumes, TheRoomsWallsWeldAtTheirEightCorners) {
    const Scene scene = test::room_with_lamp_in_box();
    const Casters c = casters_of(scene, 5);
    const SoupWeld weld = weld_soup_corners(c.casters, c.models);
    std::set<uint32_t> ids;
    int differing = 0;  // corners the walls' own transforms put apart
    std::vector<std::pair<glm::vec3, uint32_t>> seen;
    for (size_t o = 0; o < 5; ++o) {
        ASSERT_TRUE(c.casters[o].soup);
        for (size_t i = 0; i < c.casters[o].positions.size(); ++i) {
            const glm::vec3 p = glm::vec3(c.models[o] * glm::vec4(c.casters[o].positions[i], 1));
            const uint32_t id = weld.ids[o][i];
            ids.insert(id);
            for (const auto& [q, qid] : seen)
                if (qid == id && q != p) ++differing;
            seen.emplace_back(p, id);
        }
    }
    EXPECT_EQ(ids.size(), 8u);
    EXPECT_GT(differing, 0) << "the walls' corners agree to the bit: the test poses no question";
}

// With the lamp inside the room every wall's prism shares its side faces with its neighbours'
// and its diagonal with its own other triangle: only the four edges of the open front keep
// theirs. The union still closes (each edge met once each way, corners matched within the weld).
// Drawing every side (240 vertices, as before) left cracks along the seams.
TEST(ShadowVolumes, SidesTheWallsShareAreLeftOutAndTheRoomsVolumeStillCloses) {
    const Scene scene = test::room_with_lamp_in_box();
    const Casters c = casters_of(scene, 5);
    std::vector<glm::vec4> triangles;
    append_shadow_volumes(c.casters, c.models, weld_soup_corners(c.casters, c.models),
                          glm::vec4(scene.lights[0].position, 1.0f), triangles);
    // Caps: 10 triangles × (near + far); sides: 4 quads.
    EXPECT_EQ(triangles.size(), 10u * 2u * 3u + 4u * 6u);
    EXPECT_EQ(unmatched_edges(triangles, 1e-5f), 0);
    // Each wall alone: its two triangles share the diagonal; the four outer edges keep theirs.
    for (size_t o = 0; o < 5; ++o) {
        std::vector<glm::vec4> one;
        append_shadow_volume(c.casters[o], c.models[o], scene.lights[0].position, one);
        EXPECT_EQ(one.size(), 2u * 2u * 3u + 4u * 6u) << scene.objects[o].name;
        EXPECT_EQ(unmatched_edges(one, 0.0f), 0) << scene.objects[o].name;
    }
}

// World bounds of the scene's objects (the receivers append_shadow_volumes tests planar soups
// against).
std::vector<Bounds> world_bounds(const Scene& scene) {
    std::vector<Bounds> out;
    for (const Object& o : scene.objects) {
        Bounds b;
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
        out.push_back(b);
    }
    return out;
}

// With the lamp inside the room every wall's volume lies behind the wall, where nothing is: given
// the receivers, the walls (planar soups) cast nothing and only the box's volume is drawn, closed.
// A receiver below the floor brings the floor's volume back, whole (its seams' pairs, the walls'
// sides, are gone with the walls), and the union still closes.
TEST(ShadowVolumes, PlanarSoupsWithEveryReceiverInFrontCastNothing) {
    const Scene scene = test::room_with_lamp_in_box(0.8f);
    const Casters c = casters_of(scene, scene.objects.size());
    const SoupWeld weld = weld_soup_corners(c.casters, c.models);
    for (size_t o = 0; o < 5; ++o) EXPECT_GT(weld.planes[o].tolerance, 0.0) << o << ": planar";
    EXPECT_EQ(weld.planes[5].tolerance, 0.0) << "the box is closed, not a soup";
    const glm::vec4 lamp(scene.lights[0].position, 1.0f);
    std::vector<glm::vec4> all, culled, box;
    append_shadow_volumes(c.casters, c.models, weld, lamp, all);
    std::vector<Bounds> receivers = world_bounds(scene);
    append_shadow_volumes(c.casters, c.models, weld, lamp, culled, &receivers);
    append_shadow_volume(c.casters[5], c.models[5], scene.lights[0].position, box);
    EXPECT_GT(all.size(), box.size());
    EXPECT_EQ(culled.size(), box.size());
    EXPECT_EQ(unmatched_edges(culled, 1e-5f), 0);

    Bounds below;  // something under the floor: the floor's volume can hold it
    below.add({0.2f, -0.5f, 0.2f});
    below.add({0.4f, -0.3f, 0.4f});
    receivers.push_back(below);
    std::vector<glm::vec4> with_floor, floor;
    append_shadow_volumes(c.casters, c.models, weld, lamp, with_floor, &receivers);
    append_shadow_volume(c.casters[0], c.models[0], scene.lights[0].position, floor);
    EXPECT_EQ(with_floor.size(), box.size() + floor.size());
    EXPECT_EQ(unmatched_edges(with_floor, 1e-5f), 0);

    // A box resting on the floor (its bottom in the floor's plane) is in front of it.
    receivers.back() = Bounds{};
    receivers.back().add({0.2f, 0.0f, 0.2f});
    receivers.back().add({0.4f, 0.3f, 0.4f});
    std::vector<glm::vec4> resting;
    append_shadow_volumes(c.casters, c.models, weld, lamp, resting, &receivers);
    EXPECT_EQ(resting.size(), box.size());
}

// Corners 10⁻⁴ apart are not welded: two quads side by side with that gap each keep all their
// outer sides, and each closes on its own.
TEST(ShadowVolumes, CornersApartAreNotWelded) {
    Scene scene = test::room_with_lamp_in_box();
    Casters c = casters_of(scene, 1);  // the floor
    c.casters.push_back(c.casters[0]);
    c.models.push_back(glm::translate(c.models[0], glm::vec3(1.0001f, 0.0f, 0.0f)));
    const SoupWeld weld = weld_soup_corners(c.casters, c.models);
    std::set<uint32_t> ids;
    for (const auto& per : weld.ids) ids.insert(per.begin(), per.end());
    EXPECT_EQ(ids.size(), 8u);
    std::vector<glm::vec4> triangles;
    append_shadow_volumes(c.casters, c.models, weld, glm::vec4(0.5f, 1.0f, 0.5f, 1.0f), triangles);
    EXPECT_EQ(triangles.size(), 2u * (2u * 2u * 3u + 4u * 6u));
    EXPECT_EQ(unmatched_edges(triangles, 0.0f), 0);
}

// The lamp-in-box room with its box's top 1 cm under the ceiling and both cut into tiles there
// (lightmap.refine_tile: texels of 0.1, a quarter of that near the contact).
Scene tiled_room_with_lamp_in_box() {
    Scene scene = test::room_with_lamp_in_box(0.99f);
    const LightmapSettings before = scene.settings.lightmap;
    scene.settings.lightmap.texel_size = 0.1f;
    scene.objects[5].dynamic = true;  // the box: a partner whose contacts get finer texels
    scene.settings.lightmap.refine_factor = 4;
    scene.settings.lightmap.refine_budget = 10.0f;
    scene.settings.lightmap.refine_tile = 1;
    scene.settings.lightmap.refine_reach = 1.0f;
    settings_changed(scene, before);
    return scene;
}

// Cutting charts into tiles splits a closed mesh's triangles; the split mesh stays closed (its
// T-junctions are closed within the mesh), so it still casts its silhouette's volume.
TEST(ShadowVolumes, ATiledClosedBoxStillCastsAClosedVolume) {
    const Scene scene = tiled_room_with_lamp_in_box();
    const Object& box = scene.objects[5];
    ASSERT_GT(box.mesh.triangles.size(), 12u) << "the box's charts are not cut";
    const ShadowCaster caster = make_shadow_caster(box.mesh);
    EXPECT_TRUE(caster.closed);
    std::vector<glm::vec4> triangles;
    append_shadow_volume(caster, box.transform.matrix(), scene.lights[0].position, triangles);
    EXPECT_EQ(unmatched_edges(triangles, 0.0f), 0);
}

// The cut puts corners on the ceiling's outline, in the middle of the edge each wall beside it has
// whole (a T-junction between two meshes). Those corners split the wall's edge, so that its pieces
// meet the ceiling's and every side face along the seams is left out, as untiled: only the open
// front keeps its sides. Drawn, the seams' sides left a line of light along the ceiling's edges
// with the lamp inside the box (the sweep's light_in_box_below_ceiling with tiles).
TEST(ShadowVolumes, TJunctionsBetweenTiledWallsStillCancelAlongTheSeams) {
    const Scene scene = tiled_room_with_lamp_in_box();
    ASSERT_GT(scene.objects[1].mesh.triangles.size(), 2u) << "the ceiling is not cut";
    const Casters c = casters_of(scene, 5);
    const SoupWeld weld = weld_soup_corners(c.casters, c.models);
    std::vector<glm::vec4> triangles;
    append_shadow_volumes(c.casters, c.models, weld, glm::vec4(scene.lights[0].position, 1.0f),
                          triangles);
    int sides = 0, off_front = 0;
    for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
        const float w = triangles[t].w + triangles[t + 1].w + triangles[t + 2].w;
        if (w != 2.0f) continue;  // a cap, or a side's second half (one near corner)
        ++sides;
        for (int k = 0; k < 3; ++k)
            if (triangles[t + size_t(k)].w == 1.0f && std::abs(triangles[t + size_t(k)].z) > 1e-4f)
                ++off_front;
    }
    EXPECT_GT(sides, 4) << "the front's edges are drawn, the cut ones in pieces";
    EXPECT_EQ(off_front, 0) << "of " << sides << " side faces";
}

}  // namespace ag::gpu
