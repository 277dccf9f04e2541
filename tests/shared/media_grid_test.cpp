// Media grids (shared/media_grid.h): the Gaussian smoothing, the photon plane's geometry.
#include "shared/media_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace ag {
namespace {

TEST(MediaGrid, GaussianKeepsConstantsAndSums) {
    const glm::ivec3 size(12, 9, 7);
    std::vector<float> flat(size_t(size.x * size.y * size.z), 1.5f);
    gaussian_smooth(flat, size, 9, 1.5f);
    for (float v : flat) EXPECT_NEAR(v, 1.5f, 1e-5f);
    // A spike in the middle spreads but keeps its sum (far from the borders).
    std::vector<float> spike(flat.size(), 0.0f);
    Bounds b;
    b.min = glm::vec3(0.0f);
    b.max = glm::vec3(1.0f);
    MediaGrid g = make_media_grid(b, {21, 21, 21});
    g.n.assign(g.voxel_count(), 0.0f);
    g.n[g.index(10, 10, 10)] = 1.0f;
    gaussian_smooth(g.n, g.size, 9, 1.5f);
    double sum = 0.0;
    for (float v : g.n) sum += v;
    EXPECT_NEAR(sum, 1.0, 1e-5);
    EXPECT_NEAR(g.n[g.index(11, 10, 10)] / g.n[g.index(10, 10, 10)], std::exp(-0.5 / 2.25), 1e-4);
}

TEST(MediaGrid, BoxSolidAngle) {
    Bounds b;
    b.min = glm::vec3(0.0f);
    b.max = glm::vec3(1.0f);
    // One face from where the cube's centre would see it: a sixth of the sphere.
    EXPECT_NEAR(box_solid_angle(b, {0.5f, 0.5f, -0.5f}), 4.0 * std::numbers::pi / 6.0, 1e-6);
    // Far away: the projected area over d², one face (1 at 999.5) or three (√3 along the
    // diagonal, at distance √3 · 500).
    EXPECT_NEAR(box_solid_angle(b, {0.5f, 1000.5f, 0.5f}), 1.0 / (999.5 * 999.5), 1e-11);
    EXPECT_NEAR(box_solid_angle(b, glm::vec3(500.5f)), std::sqrt(3.0) / (3.0 * 500.0 * 500.0),
                1e-3 * std::sqrt(3.0) / (3.0 * 500.0 * 500.0));
}

}  // namespace
}  // namespace ag
