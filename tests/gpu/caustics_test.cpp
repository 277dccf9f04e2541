// Screen-space caustics (Larsen ch. 12): tile culling changes nothing, brightness holds under zoom.
#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "gl_fixture.h"
#include "gpu/caustics_renderer.h"
#include "shared/charts.h"
#include "shared/scene_edit.h"
#include "shared/shapes.h"

namespace ag::gpu {

namespace {

// A floor seen from above by a camera at `distance`, with photons in a disc of radius r around
// (cx, 0, cz): a synthetic caustic.
Scene floor_scene(float distance) {
    Scene s;
    s.path = "caustics_test";
    Object floor;
    floor.name = "floor";
    floor.mesh = make_quad(40.0f, 40.0f);
    floor.material.albedo = glm::vec3(0.6f, 0.5f, 0.4f);
    s.objects.push_back(floor);
    s.camera.eye = glm::vec3(0.0f, distance, -0.3f * distance);
    s.camera.target = glm::vec3(0.0f);
    s.camera.fov_y = 40.0f;
    s.camera.width = s.camera.height = 256;
    s.settings.lightmap.texel_size = 4.0f;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

void disc_photons(float r, int n, std::vector<glm::vec3>& positions,
                  std::vector<glm::vec3>& powers) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < n; ++i) {
        const float a = 6.2831853f * u(rng), d = r * std::sqrt(u(rng));
        positions.push_back({d * std::cos(a), 0.0f, d * std::sin(a)});
        powers.push_back(glm::vec3(1.0f, 0.8f, 0.5f) / float(n));
    }
}

}  // namespace

class CausticsTest : public test::GlTest {};

TEST_F(CausticsTest, TileCullingChangesNothing) {
    const Scene scene = floor_scene(12.0f);
    SceneMeshes meshes(scene);
    CausticsRenderer caustics(scene, meshes, 256, 256);
    std::vector<glm::vec3> positions, powers;
    disc_photons(0.6f, 4000, positions, powers);
    caustics.render(positions, powers, false);
    const std::vector<glm::vec3> full = caustics.read_radiance();
    EXPECT_EQ(caustics.tiles_filtered(), caustics.tiles_total());
    caustics.render(positions, powers, true);
    const std::vector<glm::vec3> culled = caustics.read_radiance();
    EXPECT_LE(caustics.tiles_filtered(), caustics.tiles_total() / 4);
    EXPECT_GT(caustics.tiles_filtered(), 0);
    double total = 0.0;
    for (size_t i = 0; i < full.size(); ++i) {
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(culled[i][c], full[i][c], 1e-6f * std::max(1.0f, full[i][c])) << i;
        total += full[i].x;
    }
    EXPECT_GT(total, 0.0);
}

TEST_F(CausticsTest, SummedWorldRadianceHoldsWhenTheCameraZoomsOut) {
    std::vector<glm::vec3> positions, powers;
    disc_photons(0.8f, 6000, positions, powers);
    double sums[2];
    for (int i = 0; i < 2; ++i) {
        const Scene scene = floor_scene(10.0f * float(i + 1));
        SceneMeshes meshes(scene);
        CausticsRenderer caustics(scene, meshes, 256, 256);
        caustics.render(positions, powers, true);
        const std::vector<glm::vec3> radiance = caustics.read_radiance();
        const std::vector<float> area = caustics.read_pixel_area();
        double sum = 0.0;  // ∫ L dA over the visible floor, in world units
        for (size_t p = 0; p < radiance.size(); ++p) sum += double(radiance[p].x) * double(area[p]);
        sums[i] = sum;
    }
    // All the flux lands on the floor: ∫ L dA = ρ/π · Φ at any zoom.
    const double expected = 0.6 / std::numbers::pi * 1.0;
    std::printf("∫L dA at x1: %.4f, at x2: %.4f, expected %.4f\n", sums[0], sums[1], expected);
    EXPECT_NEAR(sums[1] / sums[0], 1.0, 0.10);
    EXPECT_NEAR(sums[0] / expected, 1.0, 0.10);
}

}  // namespace ag::gpu
