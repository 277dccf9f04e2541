// Quadric-error decimation: the vertex target is met and the surface kept closed and in place.
#include "shared/mesh_decimate.h"

#include <gtest/gtest.h>

#include <map>
#include <numbers>
#include <utility>

#include "shared/shapes.h"

namespace ag {
namespace {

double enclosed_volume(const Mesh& m) {  // divergence theorem; positive when facing outward
    double v = 0.0;
    for (const glm::uvec3& t : m.triangles)
        v += glm::dot(m.positions[t.x], glm::cross(m.positions[t.y], m.positions[t.z])) / 6.0;
    return v;
}

// Fails if the target is not met, a hole or flipped face appears (an edge not used once each
// way), or the shape shrinks or moves (volume, vertices off the sphere).
TEST(MeshDecimate, SphereToAFifthOfItsVerticesStaysClosedAndInPlace) {
    const Mesh sphere = make_sphere(1.0f, 4);  // 2562 vertices
    const Mesh d = decimate_mesh(sphere, 500);
    EXPECT_LE(d.positions.size(), 500u);
    EXPECT_GE(d.positions.size(), 450u);
    std::map<std::pair<unsigned, unsigned>, int> directed;
    for (const glm::uvec3& t : d.triangles)
        for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
    for (const auto& [edge, count] : directed) {
        ASSERT_EQ(count, 1);
        ASSERT_EQ(directed.count({edge.second, edge.first}), 1u);
    }
    for (const glm::vec3& p : d.positions) EXPECT_NEAR(glm::length(p), 1.0f, 0.02f);
    EXPECT_NEAR(enclosed_volume(d), enclosed_volume(sphere), 0.03 * enclosed_volume(sphere));
    EXPECT_EQ(decimate_mesh(sphere, 5000).positions.size(), sphere.positions.size());
}

}  // namespace
}  // namespace ag
