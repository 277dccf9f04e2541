// Surfaces by crease angle (Larsen ch. 8), charts and the packed lightmap atlas: known answers for
// simple shapes first, then invariants every atlas must keep (coverage, no overlap, distortion,
// texel records on the chart, area conservation, determinism).
#include "shared/charts.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>

#include "shared/input_error.h"
#include "shared/shapes.h"
#include "shared/texel_density.h"

namespace ag {
namespace {

// A box whose faces do not share vertices (as exported with per-face normals): surfaces must
// still be found across its edges by welding equal positions.
Mesh make_face_split_box(const glm::vec3& size) {
    const Mesh shared = make_box(size);
    Mesh mesh;
    for (const glm::uvec3& t : shared.triangles) {
        const unsigned base = unsigned(mesh.positions.size());
        for (int k = 0; k < 3; ++k) mesh.positions.push_back(shared.positions[t[k]]);
        mesh.triangles.push_back({base, base + 1, base + 2});
    }
    return mesh;
}

// Two unit quads sharing the edge x = 0 (along Z): one in the XZ plane facing +Y, one rotated
// up about that edge by `fold_deg` (0 = flat, 90 = a right-angle corner).
Mesh make_folded_quads(float fold_deg) {
    const float a = fold_deg * std::numbers::pi_v<float> / 180.0f;
    Mesh mesh;
    mesh.positions = {{0, 0, 0},
                      {0, 0, 1},
                      {1, 0, 1},
                      {1, 0, 0},
                      {-std::cos(a), std::sin(a), 0},
                      {-std::cos(a), std::sin(a), 1}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 1}, {4, 1, 0}};
    return mesh;
}

// A spiral ramp: gently sloped (normals within a few degrees of +Y) but winding `turns` times
// about the Y axis, so its flat projection along Y folds over itself.
Mesh make_spiral_ramp(float turns, int segments_per_turn, float rise_per_turn) {
    Mesh mesh;
    const int segments = int(turns * float(segments_per_turn));
    for (int i = 0; i <= segments; ++i) {
        const float a = 2.0f * std::numbers::pi_v<float> * float(i) / float(segments_per_turn);
        const float y = rise_per_turn * float(i) / float(segments_per_turn);
        mesh.positions.push_back({1.0f * std::cos(a), y, 1.0f * std::sin(a)});
        mesh.positions.push_back({2.0f * std::cos(a), y, 2.0f * std::sin(a)});
    }
    for (int i = 0; i < segments; ++i) {
        const unsigned in0 = unsigned(2 * i), out0 = in0 + 1, in1 = in0 + 2, out1 = in0 + 3;
        // Angle grows from +X towards +Z: (in0, in1, out1) turns about +Y.
        mesh.triangles.push_back({in0, in1, out1});
        mesh.triangles.push_back({in0, out1, out0});
    }
    return mesh;
}

// A static floor (object 0) with a dynamic box standing on it and a static wall standing apart;
// adaptive density subdivides `refine_factor` times the charts that touch the box.
Scene make_contact_scene(int refine_factor, float budget, int refine_tile = 0,
                         float refine_reach = 0.0f) {
    Scene scene;
    const auto add = [&](const char* name, Mesh mesh, glm::vec3 at, bool dynamic) {
        Object object;
        object.name = name;
        object.mesh = std::move(mesh);
        object.transform.translation = at;
        object.dynamic = dynamic;
        scene.objects.push_back(std::move(object));
    };
    add("floor", make_quad(8.0f, 8.0f), {0, 0, 0}, false);
    add("box", make_box({2.0f, 2.0f, 2.0f}), {0, 1, 0}, true);
    add("wall", make_quad(4.0f, 4.0f), {20, 0, 0}, false);
    scene.settings.lightmap.texel_size = 0.5f;
    scene.settings.lightmap.refine_factor = refine_factor;
    scene.settings.lightmap.refine_budget = budget;
    scene.settings.lightmap.refine_tile = refine_tile;
    scene.settings.lightmap.refine_reach = refine_reach;
    make_surfaces_and_atlas(scene);
    return scene;
}

// One static mesh in an L: an 8 × 8 floor (y = 0) and an 8 × 8 wall standing on its far edge
// (z = 4), sharing that edge's two vertices; a dynamic 2 × 2 × 2 box on the floor 1 from the
// wall. With refine_tile the floor's chart is cut; the wall is another chart of the same mesh
// (a crease), beyond the contact distance, so it is not cut.
Scene make_l_room_scene(int refine_tile) {
    Scene scene;
    Object room;
    room.name = "room";
    room.mesh.positions = {{-4, 0, -4}, {4, 0, -4}, {4, 0, 4}, {-4, 0, 4}, {-4, 8, 4}, {4, 8, 4}};
    room.mesh.triangles = {{0, 2, 1}, {0, 3, 2}, {3, 4, 5}, {3, 5, 2}};
    scene.objects.push_back(std::move(room));
    Object box;
    box.name = "box";
    box.mesh = make_box({2.0f, 2.0f, 2.0f});
    box.transform.translation = {0, 1, 2};
    box.dynamic = true;
    scene.objects.push_back(std::move(box));
    scene.settings.lightmap.texel_size = 0.5f;
    scene.settings.lightmap.refine_factor = 4;
    scene.settings.lightmap.refine_budget = 20.0f;
    scene.settings.lightmap.refine_tile = refine_tile;
    make_surfaces_and_atlas(scene);
    return scene;
}

// The total length of the edges that only one triangle uses: the outline of an open mesh, plus
// twice the length of every T-junction's long edge (a crack).
double open_edge_length(const Mesh& mesh) {
    std::map<std::pair<unsigned, unsigned>, int> uses;
    for (const glm::uvec3& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            const unsigned a = t[k], b = t[(k + 1) % 3];
            ++uses[{std::min(a, b), std::max(a, b)}];
        }
    double length = 0.0;
    for (const auto& [edge, count] : uses)
        if (count == 1)
            length += glm::length(mesh.positions[edge.first] - mesh.positions[edge.second]);
    return length;
}

Scene make_scene(std::vector<Mesh> meshes, float texel_size) {
    Scene scene;
    for (size_t i = 0; i < meshes.size(); ++i) {
        Object object;
        object.name = "object" + std::to_string(i);
        object.mesh = std::move(meshes[i]);
        // Rigid motion must not matter: texel size is in world units, records in object space.
        object.transform.translation = glm::vec3(3.0f * float(i), 0.5f, -1.0f);
        object.transform.rotation = glm::angleAxis(0.3f * float(i), glm::vec3(0, 1, 0));
        scene.objects.push_back(std::move(object));
    }
    scene.settings.lightmap.texel_size = texel_size;
    make_surfaces_and_atlas(scene);
    return scene;
}

// The scenes every invariant is checked on.
std::vector<std::pair<std::string, Scene>> invariant_scenes() {
    std::vector<std::pair<std::string, Scene>> scenes;
    scenes.emplace_back("box", make_scene({make_box({1.0f, 2.0f, 0.5f})}, 0.1f));
    scenes.emplace_back("sphere", make_scene({make_sphere(1.0f, 3)}, 0.05f));
    scenes.emplace_back("bumpy", make_scene({make_bumpy_plane(4.0f, 4.0f, 40, 0.4f, 7)}, 0.05f));
    scenes.emplace_back("spiral", make_scene({make_spiral_ramp(2.5f, 40, 0.3f)}, 0.1f));
    scenes.emplace_back(
        "mixed", make_scene({make_face_split_box({2.0f, 1.0f, 1.0f}), make_sphere(0.7f, 2),
                             make_folded_quads(90.0f), make_bumpy_plane(3.0f, 2.0f, 20, 0.2f, 3)},
                            0.0f));
    scenes.emplace_back("adaptive", make_contact_scene(2, 4.0f));
    scenes.emplace_back("tiled", make_contact_scene(4, 4.0f, 2));
    scenes.emplace_back("tiled_reach", make_contact_scene(4, 20.0f, 2, 1.0f));
    scenes.emplace_back("tiled_l_room", make_l_room_scene(1));
    return scenes;
}

double cross2(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

std::array<glm::dvec2, 3> corner_uvs(const Scene& scene, int object, int triangle) {
    const auto& uvs = scene.atlas.corner_uvs[size_t(object)];
    return {glm::dvec2(uvs[3 * size_t(triangle)]), glm::dvec2(uvs[3 * size_t(triangle) + 1]),
            glm::dvec2(uvs[3 * size_t(triangle) + 2])};
}

// Strict overlap of two triangles in the plane (separating axes with a small tolerance).
bool overlap_2d(const std::array<glm::dvec2, 3>& a, const std::array<glm::dvec2, 3>& b) {
    for (const auto* t : {&a, &b})
        for (int k = 0; k < 3; ++k) {
            const glm::dvec2 e = (*t)[size_t((k + 1) % 3)] - (*t)[size_t(k)];
            const glm::dvec2 n(-e.y, e.x);
            double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300;
            for (int i = 0; i < 3; ++i) {
                a0 = std::min(a0, glm::dot(a[size_t(i)], n)),
                a1 = std::max(a1, glm::dot(a[size_t(i)], n));
                b0 = std::min(b0, glm::dot(b[size_t(i)], n)),
                b1 = std::max(b1, glm::dot(b[size_t(i)], n));
            }
            const double tolerance = 1e-4 * glm::length(n);
            if (a1 - b0 <= tolerance || b1 - a0 <= tolerance) return false;
        }
    return true;
}

TEST(Surfaces, CubeHasSixAt30Degrees) {
    for (const Mesh& box :
         {make_box({1.0f, 1.0f, 1.0f}), make_face_split_box({1.0f, 2.0f, 3.0f})}) {
        int count = 0;
        const std::vector<int> ids = segment_surfaces(box, 30.0f, &count);
        EXPECT_EQ(count, 6);
        ASSERT_EQ(ids.size(), 12u);
        std::map<int, int> sizes;
        for (int id : ids) ++sizes[id];
        for (const auto& [id, n] : sizes) EXPECT_EQ(n, 2) << "surface " << id;
    }
}

TEST(Surfaces, IdsAreOrderedByLowestTriangle) {
    int count = 0;
    const std::vector<int> ids = segment_surfaces(make_face_split_box({1, 1, 1}), 30.0f, &count);
    int next = 0;
    for (int id : ids) {
        EXPECT_LE(id, next);
        if (id == next) ++next;
    }
    EXPECT_EQ(next, count);
}

TEST(Surfaces, FineSphereIsOneAt30Degrees) {
    const Mesh sphere = make_sphere(1.0f, 3);
    ASSERT_GE(sphere.triangles.size(), 1280u);
    int count = 0;
    segment_surfaces(sphere, 30.0f, &count);
    EXPECT_EQ(count, 1);
    // Neighbouring faces of this sphere differ by several degrees: a 1° crease splits them all.
    segment_surfaces(sphere, 1.0f, &count);
    EXPECT_EQ(count, int(sphere.triangles.size()));
}

TEST(Surfaces, RightAngleSplitsAt30AndJoinsAt100) {
    const Mesh corner = make_folded_quads(90.0f);
    int count = 0;
    EXPECT_EQ(segment_surfaces(corner, 30.0f, &count), (std::vector<int>{0, 0, 1, 1}));
    EXPECT_EQ(count, 2);
    EXPECT_EQ(segment_surfaces(corner, 100.0f, &count), (std::vector<int>{0, 0, 0, 0}));
    EXPECT_EQ(count, 1);
    segment_surfaces(make_folded_quads(20.0f), 30.0f, &count);
    EXPECT_EQ(count, 1);
}

TEST(Surfaces, NonManifoldInputDoesNotCrash) {
    // A fin (three faces on one edge), a duplicated face, a face wound the other way, an
    // isolated face and a zero-area face: OpenMesh refuses several of them.
    Mesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0.5f, 0, 1}, {0.5f, 0, -1}, {0.5f, 1, 0},
                      {2, 0, 0}, {5, 0, 0}, {6, 0, 0},    {5, 0, 1},     {0.5f, 0, 0}};
    mesh.triangles = {
        {0, 2, 1},  // 0: faces +Y
        {0, 1, 3},  // 1: faces +Y, across edge 0-1
        {0, 4, 1},  // 2: the fin, vertical, on edge 0-1
        {0, 2, 1},  // 3: duplicate of 0
        {2, 1, 5},  // 4: faces -Y, across edge 1-2, wound against 0
        {6, 8, 7},  // 5: isolated, +Y
        {0, 9, 1},  // 6: zero area on edge 0-1
    };
    int count = 0;
    const std::vector<int> ids = segment_surfaces(mesh, 30.0f, &count);
    ASSERT_EQ(ids.size(), mesh.triangles.size());
    EXPECT_EQ(ids[0], ids[1]);
    EXPECT_EQ(ids[0], ids[3]);
    EXPECT_NE(ids[0], ids[2]);
    EXPECT_NE(ids[0], ids[4]);
    EXPECT_NE(ids[0], ids[5]);
    EXPECT_EQ(count, 4);  // {0,1,3,6}, {2}, {4}, {5}

    Scene scene = make_scene({mesh}, 0.1f);
    EXPECT_EQ(scene.surfaces.size(), 4u);
    EXPECT_FALSE(scene.atlas.texels.empty());
}

TEST(Surfaces, FillsAreaNormalAndGlobalIds) {
    const Scene scene = make_scene({make_box({1.0f, 2.0f, 3.0f}), make_folded_quads(90.0f)}, 0.25f);
    ASSERT_EQ(scene.surfaces.size(), 8u);
    ASSERT_EQ(scene.triangle_surface.size(), 2u);
    EXPECT_EQ(scene.triangle_surface[1], (std::vector<int>{6, 6, 7, 7}));
    float box_area = 0.0f;
    for (int s = 0; s < 6; ++s) {
        const Surface& surface = scene.surfaces[size_t(s)];
        EXPECT_EQ(surface.object, 0);
        box_area += surface.area;
        const glm::vec3 n = surface.normal;
        EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
        EXPECT_NEAR(std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)}), 1.0f, 1e-5f);
    }
    EXPECT_NEAR(box_area, 2.0f * (2.0f + 3.0f + 6.0f), 1e-4f);
    EXPECT_NEAR(scene.surfaces[6].area, 1.0f, 1e-5f);
    EXPECT_NEAR(scene.surfaces[6].normal.y, 1.0f, 1e-5f);
}

TEST(Charts, CoverEveryTriangleExactlyOnce) {
    for (const auto& [name, scene] : invariant_scenes()) {
        SCOPED_TRACE(name);
        std::vector<std::vector<int>> seen(scene.objects.size());
        for (size_t o = 0; o < scene.objects.size(); ++o)
            seen[o].assign(scene.objects[o].mesh.triangles.size(), 0);
        for (int c = 0; c < int(scene.atlas.charts.size()); ++c) {
            const Chart& chart = scene.atlas.charts[size_t(c)];
            const Surface& surface = scene.surfaces[size_t(chart.surface)];
            EXPECT_EQ(chart.object, surface.object);
            EXPECT_NE(std::find(surface.charts.begin(), surface.charts.end(), c),
                      surface.charts.end());
            for (int t : chart.triangles) {
                ++seen[size_t(chart.object)][size_t(t)];
                EXPECT_EQ(scene.triangle_surface[size_t(chart.object)][size_t(t)], chart.surface);
            }
        }
        for (const auto& per_object : seen)
            for (int n : per_object) EXPECT_EQ(n, 1);
        size_t listed = 0;
        for (const Surface& surface : scene.surfaces) listed += surface.charts.size();
        EXPECT_EQ(listed, scene.atlas.charts.size());
    }
}

TEST(Charts, NormalsStayWithinTheCone) {
    for (const auto& [name, scene] : invariant_scenes()) {
        SCOPED_TRACE(name);
        const float cos_cone =
            std::cos(scene.settings.lightmap.chart_cone * std::numbers::pi_v<float> / 180.0f);
        for (const Chart& chart : scene.atlas.charts) {
            EXPECT_NEAR(glm::length(chart.axis), 1.0f, 1e-5f);
            EXPECT_NEAR(glm::dot(glm::cross(chart.u_axis, chart.v_axis), chart.axis), 1.0f, 1e-5f);
            for (int t : chart.triangles)
                EXPECT_GE(glm::dot(triangle_normal(scene.objects[size_t(chart.object)].mesh, t),
                                   chart.axis),
                          cos_cone - 1e-5f);
        }
    }
}

TEST(Charts, TexelWorldSizeWithin25Percent) {
    for (const auto& [name, scene] : invariant_scenes()) {
        SCOPED_TRACE(name);
        ASSERT_GT(scene.atlas.texel_size, 0.0f);
        double worst = 0.0;
        for (const Chart& chart : scene.atlas.charts)
            for (int t : chart.triangles) {
                const auto q = corner_uvs(scene, chart.object, t);
                const double texel_area = 0.5 * cross2(q[1] - q[0], q[2] - q[0]);
                ASSERT_GT(texel_area, 0.0) << "chart triangles keep their winding";
                const double world = triangle_area(scene.objects[size_t(chart.object)].mesh, t);
                const double size = std::sqrt(world / texel_area) / chart.texel_size;
                worst = std::max(worst, std::abs(size - 1.0));
            }
        EXPECT_LE(worst, 0.25);
        // The 30° cone bounds the stretch at sqrt(1 / cos 30°) = 1.075.
        EXPECT_LE(worst, 0.0746);
    }
}

TEST(Charts, SpiralRampIsCutWhereItFolds) {
    const Scene scene = make_scene({make_spiral_ramp(2.5f, 40, 0.3f)}, 0.1f);
    ASSERT_EQ(scene.surfaces.size(), 1u);
    EXPECT_GE(scene.atlas.charts.size(), 3u);
    for (const Chart& chart : scene.atlas.charts)
        for (size_t i = 0; i < chart.triangles.size(); ++i)
            for (size_t j = i + 1; j < chart.triangles.size(); ++j)
                ASSERT_FALSE(overlap_2d(corner_uvs(scene, 0, chart.triangles[i]),
                                        corner_uvs(scene, 0, chart.triangles[j])))
                    << "triangles " << chart.triangles[i] << " and " << chart.triangles[j];
}

TEST(Atlas, ChartsAndTexelsDoNotOverlap) {
    for (const auto& [name, scene] : invariant_scenes()) {
        SCOPED_TRACE(name);
        const LightmapAtlas& atlas = scene.atlas;
        const int g = atlas.gutter;
        EXPECT_EQ(g, scene.settings.lightmap.gutter);
        ASSERT_EQ(atlas.texel_index.size(), size_t(atlas.width) * size_t(atlas.height));
        EXPECT_EQ(atlas.width & (atlas.width - 1), 0) << "width is a power of two";
        // Padded rectangles stay inside the atlas and apart.
        for (size_t a = 0; a < atlas.charts.size(); ++a) {
            const Chart& ca = atlas.charts[a];
            EXPECT_GE(ca.x - g, 0);
            EXPECT_GE(ca.y - g, 0);
            EXPECT_LE(ca.x + ca.width + g, atlas.width);
            EXPECT_LE(ca.y + ca.height + g, atlas.height);
            for (size_t b = a + 1; b < atlas.charts.size(); ++b) {
                const Chart& cb = atlas.charts[b];
                const bool apart =
                    ca.x + ca.width + g <= cb.x - g || cb.x + cb.width + g <= ca.x - g ||
                    ca.y + ca.height + g <= cb.y - g || cb.y + cb.height + g <= ca.y - g;
                EXPECT_TRUE(apart) << "charts " << a << " and " << b;
            }
            // Every corner lies strictly inside its chart's rectangle.
            for (int t : ca.triangles)
                for (const glm::dvec2& uv : corner_uvs(scene, ca.object, t)) {
                    EXPECT_GT(uv.x, ca.x);
                    EXPECT_LT(uv.x, ca.x + ca.width);
                    EXPECT_GT(uv.y, ca.y);
                    EXPECT_LT(uv.y, ca.y + ca.height);
                }
        }
        // One record per used texel, each inside its chart's rectangle.
        std::set<std::pair<int, int>> used;
        for (int i = 0; i < int(atlas.texels.size()); ++i) {
            const TexelRecord& r = atlas.texels[size_t(i)];
            EXPECT_TRUE(used.insert({r.x, r.y}).second) << r.x << "," << r.y;
            ASSERT_GE(r.chart, 0);
            const Chart& chart = atlas.charts[size_t(r.chart)];
            EXPECT_GE(r.x, chart.x);
            EXPECT_LT(r.x, chart.x + chart.width);
            EXPECT_GE(r.y, chart.y);
            EXPECT_LT(r.y, chart.y + chart.height);
            EXPECT_EQ(atlas.texel_at(r.x, r.y), i);
        }
        const auto unused = std::count(atlas.texel_index.begin(), atlas.texel_index.end(), -1);
        EXPECT_EQ(size_t(unused) + atlas.texels.size(), atlas.texel_index.size());
    }
}

// Barycentric weights of the point of the triangle's plane nearest p, and p's distance to it.
glm::dvec3 barycentric_3d(const Mesh& mesh, int t, const glm::dvec3& p, double* off_plane) {
    const glm::uvec3 tri = mesh.triangles[size_t(t)];
    const glm::dvec3 a(mesh.positions[tri.x]), b(mesh.positions[tri.y]), c(mesh.positions[tri.z]);
    const glm::dvec3 n = glm::cross(b - a, c - a);
    const double nn = glm::dot(n, n);
    *off_plane = std::abs(glm::dot(p - a, n)) / std::sqrt(nn);
    const double w1 = glm::dot(glm::cross(p - a, c - a), n) / nn;
    const double w2 = glm::dot(glm::cross(b - a, p - a), n) / nn;
    return {1.0 - w1 - w2, w1, w2};
}

TEST(Atlas, TexelPositionsLieOnTheirChartTriangle) {
    int snapped = 0;
    for (const auto& [name, scene] : invariant_scenes()) {
        SCOPED_TRACE(name);
        for (const TexelRecord& r : scene.atlas.texels) {
            const Chart& chart = scene.atlas.charts[size_t(r.chart)];
            const double ts = chart.texel_size;
            const Mesh& mesh = scene.objects[size_t(r.object)].mesh;
            EXPECT_EQ(r.object, chart.object);
            EXPECT_EQ(r.surface, chart.surface);
            ASSERT_TRUE(
                std::binary_search(chart.triangles.begin(), chart.triangles.end(), r.triangle));
            double off_plane = 0.0;
            const glm::dvec3 w =
                barycentric_3d(mesh, r.triangle, glm::dvec3(r.position), &off_plane);
            EXPECT_LE(off_plane, 1e-4 * ts);
            EXPECT_GE(std::min({w.x, w.y, w.z}), -1e-5);
            const glm::vec3 n = triangle_normal(mesh, r.triangle);
            EXPECT_NEAR(glm::dot(r.normal, n), 1.0f, 1e-5f);
            // The position seen in the atlas: the texel centre, or the nearest chart point to it.
            const glm::dvec2 uv(
                (glm::dot(glm::dvec3(r.position), glm::dvec3(chart.u_axis)) - chart.origin.x) / ts +
                    chart.x,
                (glm::dot(glm::dvec3(r.position), glm::dvec3(chart.v_axis)) - chart.origin.y) / ts +
                    chart.y);
            const double from_centre = glm::length(uv - glm::dvec2(r.x + 0.5, r.y + 0.5));
            EXPECT_LE(from_centre, 0.7072);
            if (from_centre > 1e-3) {
                ++snapped;
                EXPECT_GT(std::min({w.x, w.y, w.z}), 0.0) << "snapped strictly inside";
            }
        }
    }
    EXPECT_GT(snapped, 0) << "texels at chart borders are snapped";
}

TEST(Atlas, TexelAreasSumToSurfaceArea) {
    for (const auto& [name, scene] : invariant_scenes()) {
        SCOPED_TRACE(name);
        std::vector<double> sums(scene.surfaces.size(), 0.0);
        for (const TexelRecord& r : scene.atlas.texels) {
            EXPECT_GT(r.area, 0.0f);
            EXPECT_LE(r.area, 1.2 * scene.atlas.texel_size * scene.atlas.texel_size);
            sums[size_t(r.surface)] += r.area;
        }
        for (size_t s = 0; s < scene.surfaces.size(); ++s)
            EXPECT_NEAR(sums[s], scene.surfaces[s].area, 0.01 * scene.surfaces[s].area)
                << "surface " << s;
    }
}

TEST(Atlas, DefaultTexelSizeIsATenthOfTheScene) {
    Scene scene = make_scene({make_box({10.0f, 2.0f, 2.0f})}, 0.0f);
    EXPECT_FLOAT_EQ(scene.atlas.texel_size, 1.0f);
    // A 10×2 face gets 10 texels plus a margin column, centred; a 2×2 end 2 plus a margin.
    int longest = 0, shortest = 100;
    for (const Chart& chart : scene.atlas.charts) {
        longest = std::max({longest, chart.width, chart.height});
        shortest = std::min({shortest, chart.width, chart.height});
    }
    EXPECT_EQ(longest, 11);
    EXPECT_EQ(shortest, 3);
}

bool same_atlas(const LightmapAtlas& a, const LightmapAtlas& b) {
    if (a.width != b.width || a.height != b.height || a.texel_size != b.texel_size ||
        a.texel_index != b.texel_index || a.corner_uvs != b.corner_uvs ||
        a.charts.size() != b.charts.size() || a.texels.size() != b.texels.size())
        return false;
    for (size_t i = 0; i < a.charts.size(); ++i) {
        const Chart &x = a.charts[i], &y = b.charts[i];
        if (x.triangles != y.triangles || x.axis != y.axis || x.origin != y.origin || x.x != y.x ||
            x.y != y.y || x.width != y.width || x.height != y.height ||
            x.texel_size != y.texel_size)
            return false;
    }
    for (size_t i = 0; i < a.texels.size(); ++i) {
        const TexelRecord &x = a.texels[i], &y = b.texels[i];
        if (x.triangle != y.triangle || x.position != y.position || x.area != y.area ||
            x.x != y.x || x.y != y.y)
            return false;
    }
    return true;
}

// Adaptive density (issue #12 item 4): the floor under the dynamic box and the box's faces that
// reach the floor get half-size texels; the box's top (2 above the floor, beyond the one-texel
// contact distance) and the wall standing apart keep the base size; a budget that cannot afford
// the floor leaves it coarse; refine_factor 1 is the uniform layout. Fails if density is uniform.
TEST(Atlas, ChartsTouchingADynamicObjectGetFinerTexels) {
    const Scene uniform = make_contact_scene(1, 4.0f);
    for (const Chart& c : uniform.atlas.charts) EXPECT_EQ(c.texel_size, 0.5f);
    const Scene scene = make_contact_scene(2, 4.0f);
    int finer_box_faces = 0;
    for (const Chart& c : scene.atlas.charts) {
        const std::string& name = scene.objects[size_t(c.object)].name;
        SCOPED_TRACE(name);
        if (name == "floor") {
            EXPECT_EQ(c.texel_size, 0.25f);
        } else if (name == "wall") {
            EXPECT_EQ(c.texel_size, 0.5f);
        } else if (c.axis.y > 0.9f) {
            EXPECT_EQ(c.texel_size, 0.5f) << "the box's top touches nothing";
        } else {
            finer_box_faces += c.texel_size == 0.25f;
        }
    }
    EXPECT_GE(finer_box_faces, 4) << "the four sides reach the floor";
    // Texel records follow: about four times as many on the floor (17² → 33² with the margins).
    const auto floor_texels = [](const Scene& s) {
        int n = 0;
        for (const TexelRecord& r : s.atlas.texels) n += r.object == 0;
        return n;
    };
    EXPECT_GT(floor_texels(scene), 3.5 * floor_texels(uniform));
    // The budget holds: the floor alone (16² → 32² texels) is over 1.5× the uniform atlas.
    const Scene tight = make_contact_scene(2, 1.5f);
    double uniform_total = 0.0, tight_total = 0.0;
    for (const Chart& c : uniform.atlas.charts)
        uniform_total += double(c.width + 2) * double(c.height + 2);
    for (const Chart& c : tight.atlas.charts) {
        tight_total += double(c.width + 2) * double(c.height + 2);
        if (tight.objects[size_t(c.object)].name == "floor") {
            EXPECT_EQ(c.texel_size, 0.5f);
        }
    }
    EXPECT_LE(tight_total, 1.5 * uniform_total);
    EXPECT_GT(tight_total, uniform_total) << "the box's faces still fit";
}

// Density within a chart (lightmap.refine_tile): the floor is cut along its base texel grid into
// tiles of 2 × 2 texels; the tiles within a texel of the box (not under it) become a chart of
// quarter-size texels, the rest stays at the base size on the very grid the uniform layout has;
// the split mesh is watertight (the only edges used once are the quad's outline); laying out
// again starts from the mesh as loaded, and refine_tile 0 gives back the uniform layout. Fails
// if the floor is refined whole, if the rest moves off its grid, or if a cut leaves a crack.
TEST(Atlas, TilesNearAContactGetFinerTexelsAndTheRestKeepsItsGrid) {
    const Scene uniform = make_contact_scene(1, 20.0f);
    const Scene whole = make_contact_scene(4, 20.0f);
    Scene scene = make_contact_scene(4, 20.0f, 2);
    const auto floor_charts = [](const Scene& s) {
        std::vector<const Chart*> out;
        for (const Chart& c : s.atlas.charts)
            if (c.object == 0) out.push_back(&c);
        return out;
    };
    const std::vector<const Chart*> parts = floor_charts(scene);
    ASSERT_EQ(parts.size(), 2u) << "one coarse rest and one fine patch around the box";
    const Chart& base = *floor_charts(uniform).front();
    const Chart& rest = *parts[0];
    const Chart& fine = *parts[1];
    EXPECT_EQ(rest.tile_group, fine.tile_group);
    EXPECT_GE(rest.tile_group, 0);
    EXPECT_EQ(rest.texel_size, 0.5f);
    EXPECT_EQ(fine.texel_size, 0.125f);
    EXPECT_EQ(rest.origin, base.origin) << "the rest keeps the uniform grid";
    EXPECT_EQ(rest.width, base.width);
    EXPECT_EQ(rest.height, base.height);
    // The patch lies on a tile corner of that grid less one fine texel of margin and spans whole
    // tiles (2 texels = 8 fine) plus the margins.
    const glm::vec2 offset = (fine.origin + 0.125f - rest.origin) / 1.0f;  // tiles are 1.0 wide
    EXPECT_NEAR(offset.x, std::round(offset.x), 1e-4);
    EXPECT_NEAR(offset.y, std::round(offset.y), 1e-4);
    EXPECT_EQ((fine.width - 2) % 8, 0);
    EXPECT_EQ((fine.height - 2) % 8, 0);

    int fine_texels = 0, whole_fine_texels = 0;
    for (const TexelRecord& r : scene.atlas.texels) {
        if (&scene.atlas.charts[size_t(r.chart)] != &fine) continue;
        ++fine_texels;
        // Every fine texel lies within a tile (1.0) plus the contact distance (0.5) of the box
        // (±1 around the origin, in the floor's object space).
        EXPECT_LE(std::abs(r.position.x), 2.5f + 1e-3f);
        EXPECT_LE(std::abs(r.position.z), 2.5f + 1e-3f);
    }
    for (const TexelRecord& r : whole.atlas.texels) whole_fine_texels += r.object == 0;
    EXPECT_GT(fine_texels, 0);
    EXPECT_LT(fine_texels, whole_fine_texels / 2) << "only the tiles near the box are fine";

    // Watertight: every edge of the split floor is shared by two triangles except the outline.
    const Mesh& mesh = scene.objects[0].mesh;
    EXPECT_GT(mesh.triangles.size(), 2u);
    std::map<std::pair<unsigned, unsigned>, int> uses;
    for (const glm::uvec3& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            const unsigned a = t[k], b = t[(k + 1) % 3];
            ++uses[{std::min(a, b), std::max(a, b)}];
        }
    double outline = 0.0;
    for (const auto& [edge, count] : uses) {
        EXPECT_LE(count, 2);
        if (count == 1)
            outline += glm::length(mesh.positions[edge.first] - mesh.positions[edge.second]);
    }
    EXPECT_NEAR(outline, 32.0, 1e-4) << "a crack inside the floor adds to the outline";
    EXPECT_NEAR(mesh_area(mesh), 64.0, 1e-3);

    // Again from the loaded mesh: the same atlas; without tiles, the whole-chart layout.
    const size_t triangles = mesh.triangles.size();
    make_surfaces_and_atlas(scene);
    EXPECT_EQ(scene.objects[0].mesh.triangles.size(), triangles);
    EXPECT_TRUE(same_atlas(scene.atlas, make_contact_scene(4, 20.0f, 2).atlas));
    scene.settings.lightmap.refine_tile = 0;
    make_surfaces_and_atlas(scene);
    EXPECT_EQ(scene.objects[0].mesh.triangles.size(), 2u);
    EXPECT_TRUE(same_atlas(scene.atlas, whole.atlas));
}

// lightmap.refine_reach: the tiles within reach × the box's height (2) of the box get the fine
// texels too, while whether the floor is cut still follows the contact (a texel): so the fine
// patch reaches further than the contact band (a fine texel beyond it), the floor is still cut
// (fewer fine texels than the whole floor refined) and stays on its grid. Fails if reach is
// ignored (no fine texel beyond 2.5 of the origin) or if it made the floor refine whole.
TEST(Atlas, TilesWithinReachOfAPartnerAreRefinedWithTheContact) {
    const Scene whole = make_contact_scene(4, 20.0f);
    const Scene contact = make_contact_scene(4, 20.0f, 2);
    const Scene reach = make_contact_scene(4, 20.0f, 2, 1.0f);
    const auto fine_reach = [](const Scene& s, int* count) {
        float far = 0.0f;
        *count = 0;
        for (const TexelRecord& r : s.atlas.texels) {
            if (r.object != 0 || s.atlas.charts[size_t(r.chart)].texel_size != 0.125f) continue;
            ++*count;
            far = std::max({far, std::abs(r.position.x), std::abs(r.position.z)});
        }
        return far;
    };
    int whole_count = 0, contact_count = 0, reach_count = 0;
    fine_reach(whole, &whole_count);
    EXPECT_LE(fine_reach(contact, &contact_count), 2.5f + 1e-3f);
    // The box's sides stand 1 from its centre and 2 high: reach 1 takes tiles within 3 of the
    // centre, whole tiles of 1.0 (4 of the floor's 8 on each side): up to 4 from the centre.
    const float far = fine_reach(reach, &reach_count);
    EXPECT_GT(far, 2.5f) << "no fine texel beyond the contact band";
    EXPECT_LE(far, 4.0f);
    EXPECT_GT(reach_count, contact_count);
    EXPECT_LT(reach_count, whole_count) << "the floor is still cut";
    for (const Chart& c : reach.atlas.charts)
        if (c.object == 0 && c.texel_size == 0.5f) {
            EXPECT_EQ(c.origin, contact.atlas.charts[0].origin) << "the rest keeps its grid";
        }
    // Reach 0 is the contact layout.
    EXPECT_TRUE(same_atlas(make_contact_scene(4, 20.0f, 2, 0.0f).atlas, contact.atlas));
}

// A cut puts vertices on the floor's edge that the wall (another chart of the same mesh) shares:
// the wall's triangles are split at them too, so the mesh has no T-junction: the only edges used
// once are the L's outline (the floor's three free edges and the wall's, 48), the area is kept
// and the wall is still one chart of base texels. Fails without the neighbour's split (the shared
// edge then counts three times: 48 + 16).
TEST(Atlas, ACutSplitsTheNeighbouringChartsTrianglesToo) {
    const Scene uncut = make_l_room_scene(0);
    const Scene scene = make_l_room_scene(1);
    const Mesh& mesh = scene.objects[0].mesh;
    EXPECT_NEAR(open_edge_length(uncut.objects[0].mesh), 48.0, 1e-4);
    EXPECT_GT(mesh.triangles.size(), uncut.objects[0].mesh.triangles.size());
    EXPECT_NEAR(open_edge_length(mesh), 48.0, 1e-4) << "a T-junction on the shared edge";
    EXPECT_NEAR(mesh_area(mesh), 128.0, 1e-3);
    int wall_triangles = 0, fine_charts = 0;
    for (const Chart& c : scene.atlas.charts) {
        if (c.object != 0) continue;
        fine_charts += c.texel_size < 0.5f;
        if (c.axis.z < -0.5f) {
            EXPECT_EQ(c.texel_size, 0.5f) << "the wall is not refined";
            wall_triangles += int(c.triangles.size());
        }
    }
    EXPECT_GT(fine_charts, 0) << "the floor was cut";
    EXPECT_GT(wall_triangles, 2) << "the wall's triangles were split at the cut's vertices";
    for (const glm::uvec3& t : mesh.triangles) {
        const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
        EXPECT_GT(glm::length(glm::cross(b - a, c - a)), 1e-6f) << "no degenerate triangle";
    }
}

TEST(Atlas, Deterministic) {
    auto first = invariant_scenes(), second = invariant_scenes();
    for (size_t i = 0; i < first.size(); ++i) {
        SCOPED_TRACE(first[i].first);
        EXPECT_TRUE(same_atlas(first[i].second.atlas, second[i].second.atlas));
        EXPECT_EQ(first[i].second.triangle_surface, second[i].second.triangle_surface);
    }
}

TEST(Atlas, EmptySceneGivesEmptyAtlas) {
    const Scene scene = make_scene({Mesh{}}, 0.0f);
    EXPECT_TRUE(scene.surfaces.empty());
    EXPECT_TRUE(scene.atlas.charts.empty());
    EXPECT_TRUE(scene.atlas.texels.empty());
}

// Larsen's bumpy floor at two sizes: reports wall-clock time (no threshold: tests count, they do
// not time) and checks the distortion bound on the large one.
TEST(Atlas, BumpyFloors13kAnd133k) {
    for (int resolution : {81, 258}) {
        const Mesh floor = make_bumpy_plane(10.0f, 10.0f, resolution, 0.5f, 1);
        const size_t triangles = floor.triangles.size();
        const auto start = std::chrono::steady_clock::now();
        const Scene scene = make_scene({floor}, 0.05f);
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf(
            "[   INFO   ] bumpy floor, %zu triangles: %zu surfaces, %zu charts, %dx%d atlas, "
            "%zu texels, %.3f s\n",
            triangles, scene.surfaces.size(), scene.atlas.charts.size(), scene.atlas.width,
            scene.atlas.height, scene.atlas.texels.size(), seconds);
        double area = 0.0;
        for (const TexelRecord& r : scene.atlas.texels) area += r.area;
        EXPECT_NEAR(area, mesh_area(floor), 1e-3 * mesh_area(floor));
    }
}

// A texel size far too small for the scene is refused before the atlas is allocated, naming the
// setting and the limit: by texel count, and by side (a long thin chart packs into a wide atlas).
TEST(Atlas, TooManyTexelsAreRefusedNamingTheSettingAndTheLimit) {
    auto error = [](const Mesh& mesh, float texel_size) {
        try {
            make_scene({mesh}, texel_size);
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    std::string err = error(make_quad(10.0f, 10.0f), 0.001f);  // 10^8 texels
    EXPECT_NE(err.find("settings.lightmap.texel_size"), std::string::npos) << err;
    EXPECT_NE(err.find("expected at most " + std::to_string(kMaxAtlasTexels)), std::string::npos)
        << err;
    // 30,000 × 1 texels: few texels, but 32768 wide.
    err = error(make_quad(30000.0f, 1.0f), 1.0f);
    EXPECT_NE(err.find("settings.lightmap.texel_size"), std::string::npos) << err;
    EXPECT_NE(err.find("expected at most " + std::to_string(kMaxAtlasSide) + " on a side"),
              std::string::npos)
        << err;
    // Just inside both bounds: accepted.
    EXPECT_EQ(error(make_quad(10000.0f, 1.0f), 1.0f), "");
}

// The contact samples find a partner's triangles through runs of 16 with their bounds, or a grid
// where the samples are many (shared/texel_density.cpp); every sample must be classified as
// testing each triangle would. A box standing on a wavy floor of 2 × kN² triangles with one huge
// triangle far below it (too large for the grid's cells: tested by every sample), against a
// brute-force test of every floor triangle. With `bottom_only`, only the box's bottom chart; with
// `cache`, one ContactCache for all its charts.
void check_contact_samples_against_every_triangle(int kN, bool bottom_only, bool cache) {
    Scene scene;
    Object floor;
    floor.name = "floor";
    for (int z = 0; z <= kN; ++z)
        for (int x = 0; x <= kN; ++x) {
            const float fx = -4.0f + 8.0f * float(x) / kN, fz = -4.0f + 8.0f * float(z) / kN;
            floor.mesh.positions.push_back(
                {fx, 0.05f * std::sin(3.0f * fx) * std::cos(2.0f * fz), fz});
        }
    for (int z = 0; z < kN; ++z)
        for (int x = 0; x < kN; ++x) {
            const uint32_t i = uint32_t(z * (kN + 1) + x);
            floor.mesh.triangles.push_back({i, i + kN + 1, i + 1});
            floor.mesh.triangles.push_back({i + 1, i + kN + 1, i + kN + 2});
        }
    const uint32_t big = uint32_t(floor.mesh.positions.size());
    floor.mesh.positions.push_back({-500.0f, -5.0f, -500.0f});
    floor.mesh.positions.push_back({-500.0f, -5.0f, 500.0f});
    floor.mesh.positions.push_back({500.0f, -5.0f, 0.0f});
    floor.mesh.triangles.push_back({big, big + 1, big + 2});
    scene.objects.push_back(std::move(floor));
    Object box;
    box.name = "box";
    box.mesh = make_box({2.0f, 2.0f, 2.0f});
    box.transform.translation = {0.5f, 1.02f, -0.3f};
    box.dynamic = true;
    scene.objects.push_back(std::move(box));
    scene.settings.lightmap.texel_size = 0.5f;
    make_surfaces_and_atlas(scene);

    // Every partner triangle in world space, as the samples see them.
    struct Tri {
        glm::dvec3 a, b, c;
    };
    std::vector<Tri> tris;
    glm::dvec3 lo(1e300), hi(-1e300);
    const Object& f = scene.objects[0];
    for (const glm::vec3& p : f.mesh.positions) {
        lo = glm::min(lo, glm::dvec3(f.transform.apply_point(p)));
        hi = glm::max(hi, glm::dvec3(f.transform.apply_point(p)));
    }
    for (const glm::uvec3& t : f.mesh.triangles)
        tris.push_back({glm::dvec3(f.transform.apply_point(f.mesh.positions[t.x])),
                        glm::dvec3(f.transform.apply_point(f.mesh.positions[t.y])),
                        glm::dvec3(f.transform.apply_point(f.mesh.positions[t.z]))});
    // Closest point on a triangle by projection and edge clamping (independent of the library's).
    const auto dist2 = [](const glm::dvec3& p, const Tri& t) {
        const glm::dvec3 n = glm::normalize(glm::cross(t.b - t.a, t.c - t.a));
        const glm::dvec3 q = p - glm::dot(p - t.a, n) * n;
        const auto inside = [&](const glm::dvec3& u, const glm::dvec3& v) {
            return glm::dot(glm::cross(v - u, q - u), n) >= 0.0;
        };
        if (inside(t.a, t.b) && inside(t.b, t.c) && inside(t.c, t.a)) return glm::dot(p - q, p - q);
        double best = 1e300;
        for (const auto& [u, v] : {std::pair{t.a, t.b}, {t.b, t.c}, {t.c, t.a}}) {
            const double s = std::clamp(glm::dot(p - u, v - u) / glm::dot(v - u, v - u), 0.0, 1.0);
            const glm::dvec3 e = u + s * (v - u);
            best = std::min(best, glm::dot(p - e, p - e));
        }
        return best;
    };
    const double distance = 0.25, reach = 1.0;
    const double grow = std::max(distance, reach * glm::length(hi - lo));
    const Object& b = scene.objects[1];
    int samples = 0, near = 0, covered = 0, within = 0;
    ContactCache shared;
    for (const Chart& chart : scene.atlas.charts) {
        if (chart.object != 1 || (bottom_only && !(chart.axis.y < -0.9f))) continue;
        for_each_contact_sample(
            scene, chart, distance, 0.1, reach,
            [&](const glm::dvec3& object_point, double, const ContactSample& s) {
                const glm::dvec3 p(b.transform.apply_point(glm::vec3(object_point)));
                // The sample's chart normal: the box face it lies on (the largest coordinate).
                const glm::dvec3 o = object_point;
                const int axis = std::abs(o.x) >= std::abs(o.y) && std::abs(o.x) >= std::abs(o.z)
                                     ? 0
                                 : std::abs(o.y) >= std::abs(o.z) ? 1
                                                                  : 2;
                glm::dvec3 normal(0.0);
                normal[axis] = o[axis] > 0.0 ? 1.0 : -1.0;
                double top = -1e300;
                for (const glm::vec3& w : f.mesh.positions)
                    top = std::max(top, glm::dot(glm::dvec3(f.transform.apply_point(w)), normal));
                const double height = std::max(0.0, top - glm::dot(p, normal));
                double min2 = 1e300;
                bool in_reach = false;
                for (const Tri& t : tris) {
                    const double e2 = dist2(p, t);
                    min2 = std::min(min2, e2);
                    const glm::dvec3 tlo = glm::min(glm::min(t.a, t.b), t.c) - grow;
                    const glm::dvec3 thi = glm::max(glm::max(t.a, t.b), t.c) + grow;
                    const bool in_box = glm::all(glm::greaterThanEqual(p, tlo)) &&
                                        glm::all(glm::lessThanEqual(p, thi));
                    in_reach = in_reach || (in_box && e2 <= reach * reach * height * height);
                }
                const bool want_covered = min2 <= 1e-12 * distance * distance;
                const bool want_near = min2 <= distance * distance;
                ++samples;
                near += want_near;
                covered += want_covered;
                EXPECT_EQ(s.covered, want_covered) << "at " << p.x << ' ' << p.y << ' ' << p.z;
                if (want_covered) return;
                EXPECT_EQ(s.near, want_near) << "at " << p.x << ' ' << p.y << ' ' << p.z;
                if (want_near) return;
                within += in_reach;
                EXPECT_EQ(s.within_reach, in_reach) << "at " << p.x << ' ' << p.y << ' ' << p.z;
            },
            cache ? &shared : nullptr);
    }
    EXPECT_GT(samples, 1000);
    EXPECT_GT(near, 0) << "the box's bottom rim is within the contact distance of the floor";
    if (bottom_only) return;  // the bottom is near the floor everywhere
    EXPECT_GT(samples - near, 0);
    EXPECT_GT(within, 0);
}

// Every face of the box over 1,152 triangles: near, covered and within reach.
TEST(Atlas, ContactSamplesThroughTheGridMatchTestingEveryTriangle) {
    check_contact_samples_against_every_triangle(24, false, false);
}

// The box's bottom over a floor of 8,192 triangles: about 800 of them lie within the contact
// distance of its chart, and its 1,682 samples make the triangle grid worth building over them
// (the samples test the candidates' runs of 16 otherwise); through one cache for the charts.
TEST(Atlas, ContactSamplesOnAFineFloorThroughTheCacheMatchTestingEveryTriangle) {
    check_contact_samples_against_every_triangle(64, true, true);
}

}  // namespace
}  // namespace ag
