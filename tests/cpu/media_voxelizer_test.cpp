// Voxelisation by ray parity (cpu/media_voxelizer.h): a glass sphere's covered volume, its index
// and interior medium, the world medium outside it, open meshes left alone.
#include "cpu/media_voxelizer.h"

#include <gtest/gtest.h>

#include <numbers>

#include "shared/shapes.h"

namespace ag::cpu {
namespace {

Scene glass_ball_in_fog(float radius, float ior) {
    Scene s;
    s.path = "ball_in_fog";
    Object ball;
    ball.name = "ball";
    ball.mesh = make_sphere(radius, 5);
    ball.material.type = MaterialType::glass;
    ball.material.ior = ior;
    ball.material.has_interior = true;
    ball.material.interior.sigma_s = 3.0f;
    ball.material.interior.sigma_a = 1.0f;
    ball.transform.translation = {0.1f, 0.0f, -0.05f};
    s.objects.push_back(ball);
    Medium fog;
    fog.bounds.min = glm::vec3(-1.0f);
    fog.bounds.max = glm::vec3(1.0f);
    fog.sigma_s = 0.5f;
    fog.sigma_a = 0.25f;
    s.media.push_back(fog);
    return s;
}

TEST(MediaVoxelizer, SphereCoverageIndexAndMedia) {
    const float radius = 0.5f, ior = 1.5f;
    const Scene s = glass_ball_in_fog(radius, ior);
    const RayTracer rays(s);
    Bounds b;
    b.min = glm::vec3(-1.0f);
    b.max = glm::vec3(1.0f);
    const MediaGrid g = voxelize_media(s, rays, b, glm::ivec3(48));
    const glm::vec3 voxel = g.voxel_size();
    const double voxel_volume = double(voxel.x) * voxel.y * voxel.z;
    double covered = 0.0, scattering = 0.0;
    for (size_t i = 0; i < g.voxel_count(); ++i) {
        covered += double(g.n[i] - 1.0f) / double(ior - 1.0f) * voxel_volume;
        scattering += double(g.sigma_s[i]) * voxel_volume;
    }
    const double sphere = 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
    // The icosphere (5 subdivisions) holds 0.2% less than the true sphere.
    EXPECT_NEAR(covered, sphere, 0.02 * sphere);
    EXPECT_NEAR(scattering, 3.0 * sphere + 0.5 * (8.0 - sphere), 0.02 * scattering);
    // Deep inside: glass; far outside: fog.
    const glm::ivec3 centre = glm::ivec3((glm::vec3(0.1f, 0.0f, -0.05f) - b.min) / voxel);
    EXPECT_FLOAT_EQ(g.n[g.index(centre.x, centre.y, centre.z)], ior);
    EXPECT_FLOAT_EQ(g.sigma_t[g.index(centre.x, centre.y, centre.z)], 4.0f);
    EXPECT_FLOAT_EQ(g.n[g.index(1, 1, 1)], 1.0f);
    EXPECT_FLOAT_EQ(g.sigma_t[g.index(1, 1, 1)], 0.75f);
}

}  // namespace
}  // namespace ag::cpu
