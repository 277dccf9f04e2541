// Built-in shapes: triangle counts, areas and outward counter-clockwise winding.
#include "shared/shapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <utility>

namespace ag {
namespace {

// Every face of a convex shape centred at the origin faces away from the centre.
void expect_outward(const Mesh& mesh) {
    for (int t = 0; t < int(mesh.triangles.size()); ++t) {
        const glm::uvec3 tri = mesh.triangles[size_t(t)];
        const glm::vec3 centroid =
            (mesh.positions[tri.x] + mesh.positions[tri.y] + mesh.positions[tri.z]) / 3.0f;
        ASSERT_GT(glm::dot(triangle_normal(mesh, t), glm::normalize(centroid)), 0.0f)
            << "triangle " << t;
    }
}

// Each undirected edge used by exactly two triangles, once in each direction: closed, consistent.
void expect_closed_and_consistent(const Mesh& mesh) {
    std::map<std::pair<unsigned, unsigned>, int> directed;
    for (const glm::uvec3& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
    for (const auto& [edge, count] : directed) {
        EXPECT_EQ(count, 1) << edge.first << "-" << edge.second;
        EXPECT_EQ(directed.count({edge.second, edge.first}), 1u)
            << edge.first << "-" << edge.second;
    }
}

TEST(Shapes, BoxHasTwelveOutwardTrianglesAndItsArea) {
    const Mesh box = make_box({2.0f, 3.0f, 4.0f});
    EXPECT_EQ(box.triangles.size(), 12u);
    EXPECT_EQ(box.positions.size(), 8u);
    EXPECT_NEAR(mesh_area(box), 2.0f * (2 * 3 + 3 * 4 + 2 * 4), 1e-4f);
    const Bounds b = mesh_bounds(box);
    EXPECT_EQ(b.min, glm::vec3(-1.0f, -1.5f, -2.0f));
    EXPECT_EQ(b.max, glm::vec3(1.0f, 1.5f, 2.0f));
    expect_outward(box);
    expect_closed_and_consistent(box);
}

TEST(Shapes, SphereTriangleCountAndAreaApproachTheSphere) {
    for (int s = 0; s <= 4; ++s) {
        const Mesh sphere = make_sphere(2.0f, s);
        EXPECT_EQ(sphere.triangles.size(), size_t(20) << (2 * s));
        EXPECT_EQ(sphere.positions.size(), size_t(10) * (size_t(1) << (2 * s)) + 2);
        for (const glm::vec3& p : sphere.positions) EXPECT_NEAR(glm::length(p), 2.0f, 1e-5f);
        expect_outward(sphere);
        expect_closed_and_consistent(sphere);
    }
    // An inscribed polyhedron falls short of 4πr² by O(4^-s).
    const float exact = 4.0f * std::numbers::pi_v<float> * 4.0f;
    EXPECT_LT(mesh_area(make_sphere(2.0f, 0)), 0.8f * exact);
    EXPECT_NEAR(mesh_area(make_sphere(2.0f, 3)), exact, 0.01f * exact);
    EXPECT_NEAR(mesh_area(make_sphere(2.0f, 5)), exact, 0.001f * exact);
}

TEST(Shapes, QuadLiesInXzAndFacesUp) {
    const Mesh quad = make_quad(3.0f, 5.0f);
    EXPECT_EQ(quad.triangles.size(), 2u);
    EXPECT_NEAR(mesh_area(quad), 15.0f, 1e-5f);
    for (int t = 0; t < 2; ++t) EXPECT_EQ(triangle_normal(quad, t), glm::vec3(0, 1, 0));
    const Bounds b = mesh_bounds(quad);
    EXPECT_EQ(b.min, glm::vec3(-1.5f, 0.0f, -2.5f));
    EXPECT_EQ(b.max, glm::vec3(1.5f, 0.0f, 2.5f));
}

TEST(Shapes, BumpyPlaneIsAnUpwardHeightFieldWithinItsAmplitude) {
    const Mesh plane = make_bumpy_plane(10.0f, 20.0f, 40, 0.5f, 3);
    EXPECT_EQ(plane.triangles.size(), 2u * 40 * 40);
    EXPECT_EQ(plane.positions.size(), 41u * 41);
    float highest = 0.0f;
    for (const glm::vec3& p : plane.positions) {
        EXPECT_LE(std::fabs(p.y), 0.5f + 1e-6f);
        highest = std::max(highest, std::fabs(p.y));
    }
    EXPECT_GT(highest, 0.1f) << "the plane should actually be bumpy";
    for (int t = 0; t < int(plane.triangles.size()); ++t)
        ASSERT_GT(triangle_normal(plane, t).y, 0.5f) << "triangle " << t;
    // Edges stay at height 0 so the plane meets walls without gaps.
    for (const glm::vec3& p : plane.positions)
        if (std::fabs(std::fabs(p.x) - 5.0f) < 1e-4f || std::fabs(std::fabs(p.z) - 10.0f) < 1e-4f) {
            EXPECT_NEAR(p.y, 0.0f, 1e-5f);
        }
    const Bounds b = mesh_bounds(plane);
    EXPECT_NEAR(b.min.x, -5.0f, 1e-5f);
    EXPECT_NEAR(b.max.z, 10.0f, 1e-5f);
}

TEST(Shapes, BumpyPlaneIsDeterministicPerSeed) {
    const Mesh a = make_bumpy_plane(4.0f, 4.0f, 16, 0.3f, 11);
    const Mesh b = make_bumpy_plane(4.0f, 4.0f, 16, 0.3f, 11);
    const Mesh c = make_bumpy_plane(4.0f, 4.0f, 16, 0.3f, 12);
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_NE(a.positions, c.positions);
    const Mesh flat = make_bumpy_plane(4.0f, 4.0f, 16, 0.0f, 11);
    for (const glm::vec3& p : flat.positions) EXPECT_EQ(p.y, 0.0f);
}

TEST(Shapes, LumpySphereHitsItsTriangleTargetClosedOutwardAndWithinItsAmplitude) {
    // 12·n² triangles nearest the target: 1,000,000 → n = 289 → 1,002,252 (within 0.3%).
    EXPECT_EQ(lumpy_sphere_cells(1000000), 289);
    EXPECT_EQ(lumpy_sphere_cells(12), 1);
    EXPECT_EQ(lumpy_sphere_cells(3), 1);
    const Mesh smooth = make_lumpy_sphere(2.0f, 6, 0.0f, 1);
    EXPECT_EQ(smooth.triangles.size(), 12u * 36);
    EXPECT_EQ(smooth.positions.size(), 6u * 36 + 2);  // V = E − F + 2 on a closed genus-0 mesh
    for (const glm::vec3& p : smooth.positions) EXPECT_NEAR(glm::length(p), 2.0f, 1e-5f);
    expect_outward(smooth);
    expect_closed_and_consistent(smooth);
    const Mesh lumpy = make_lumpy_sphere(2.0f, 24, 0.3f, 5);
    expect_closed_and_consistent(lumpy);
    float lo = 10.0f, hi = 0.0f;
    for (const glm::vec3& p : lumpy.positions) {
        lo = std::min(lo, glm::length(p));
        hi = std::max(hi, glm::length(p));
    }
    EXPECT_GE(lo, 1.7f - 1e-5f);
    EXPECT_LE(hi, 2.3f + 1e-5f);
    EXPECT_GT(hi - lo, 0.2f) << "the sphere should actually be lumpy";
    // Outward on average: the enclosed volume (divergence theorem) is positive and near 4/3·π·r³.
    double volume = 0.0;
    for (const glm::uvec3& t : lumpy.triangles)
        volume +=
            glm::dot(lumpy.positions[t.x], glm::cross(lumpy.positions[t.y], lumpy.positions[t.z])) /
            6.0;
    EXPECT_NEAR(volume, 4.0 / 3.0 * std::numbers::pi * 8.0,
                0.25 * 4.0 / 3.0 * std::numbers::pi * 8.0);
    EXPECT_EQ(make_lumpy_sphere(2.0f, 8, 0.3f, 5).positions,
              make_lumpy_sphere(2.0f, 8, 0.3f, 5).positions);
    EXPECT_NE(make_lumpy_sphere(2.0f, 8, 0.3f, 5).positions,
              make_lumpy_sphere(2.0f, 8, 0.3f, 6).positions);
}

// Barczak's mover: 41 × 20 = 820 vertices. Fails if the tube is not closed (a seam where u or v
// wraps), a face points into the tube, or the surface is not where the radii put it.
TEST(Shapes, TorusIsClosedOutwardOfItsTubeAndOnItsSurface) {
    const float big = 0.7f, tube = 0.3f;
    const Mesh torus = make_torus(big, tube, 41, 20);
    EXPECT_EQ(torus.positions.size(), 820u);
    EXPECT_EQ(torus.triangles.size(), 2u * 820);
    expect_closed_and_consistent(torus);
    for (const glm::vec3& p : torus.positions) {  // (√(x²+z²) − R)² + y² = r²
        const float ring = std::sqrt(p.x * p.x + p.z * p.z) - big;
        EXPECT_NEAR(ring * ring + p.y * p.y, tube * tube, 1e-5f);
    }
    for (int t = 0; t < int(torus.triangles.size()); ++t) {  // away from the tube's centre line
        const glm::uvec3 tri = torus.triangles[size_t(t)];
        const glm::vec3 c =
            (torus.positions[tri.x] + torus.positions[tri.y] + torus.positions[tri.z]) / 3.0f;
        const glm::vec3 axis_point = big * glm::normalize(glm::vec3(c.x, 0.0f, c.z));
        ASSERT_GT(glm::dot(triangle_normal(torus, t), c - axis_point), 0.0f) << "triangle " << t;
    }
    // Enclosed volume 2π²Rr² (the polygon's a little less).
    double volume = 0.0;
    for (const glm::uvec3& t : torus.triangles)
        volume +=
            glm::dot(torus.positions[t.x], glm::cross(torus.positions[t.y], torus.positions[t.z])) /
            6.0;
    const double exact = 2.0 * std::numbers::pi * std::numbers::pi * big * tube * tube;
    EXPECT_NEAR(volume, exact, 0.03 * exact);
}

}  // namespace
}  // namespace ag
