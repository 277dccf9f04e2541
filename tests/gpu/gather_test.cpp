// Hemi-plane gathering (Larsen ch. 11, eq. 11.2) against analytic answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "gl_fixture.h"
#include "gpu/hemi_plane_gather.h"
#include "gpu/lightmap_texture.h"
#include "shared/charts.h"
#include "shared/scene_edit.h"
#include "shared/shapes.h"

namespace ag::gpu {

TEST(HemiPlaneWeights, SumToTheAnalyticCoverage) {
    for (float a : {1.0f, 2.0f, 5.0f}) {
        for (int r : {8, 16, 32}) {
            const std::vector<float> w = hemi_plane_weights(r, a, BorderCorrection::none);
            double sum = 0.0;
            for (float v : w) sum += v;
            EXPECT_NEAR(sum, hemi_plane_coverage(a), 1e-4) << "a " << a << " r " << r;
            for (BorderCorrection c : {BorderCorrection::renormalize, BorderCorrection::stretch,
                                       BorderCorrection::stretch_radial}) {
                double corrected = 0.0;
                for (float v : hemi_plane_weights(r, a, c)) corrected += v;
                EXPECT_NEAR(corrected, 1.0, 1e-3) << kBorderCorrectionNames[size_t(c)];
            }
            // The band: the plane uncorrected plus the wider view's weights, which hold the rest.
            double plane = 0.0, band = 0.0;
            for (float v : hemi_plane_weights(r, a, BorderCorrection::band)) plane += v;
            for (float v : hemi_band_weights(r, a, 4.0f * a)) band += v;
            EXPECT_NEAR(plane, hemi_plane_coverage(a), 1e-4);
            EXPECT_NEAR(band, 1.0 - hemi_plane_coverage(a), 1e-4) << "a " << a << " r " << r;
        }
    }
    EXPECT_NEAR(hemi_plane_coverage(2.0f), 0.83, 0.005);  // DESIGN.md: 83% at a = 2
    EXPECT_NEAR(hemi_plane_coverage(5.0f), 0.97, 0.005);  // 97% at a = 5
}

TEST(HemiPlaneWeights, StretchOnlyAddsToTheBorder) {
    const int r = 16;
    const std::vector<float> none = hemi_plane_weights(r, 2.0f, BorderCorrection::none);
    const std::vector<float> stretch = hemi_plane_weights(r, 2.0f, BorderCorrection::stretch);
    for (int j = 0; j < r; ++j)
        for (int i = 0; i < r; ++i) {
            const bool border = i == 0 || j == 0 || i == r - 1 || j == r - 1;
            const size_t k = size_t(j) * r + size_t(i);
            if (border)
                EXPECT_GT(stretch[k], none[k]);
            else
                EXPECT_FLOAT_EQ(stretch[k], none[k]);
        }
}

// The stretched border takes exactly the cosine-weighted solid angle of the missing directions
// that clamp onto it in plane coordinates (the CPU gather's `stretch`): a 4096² midpoint
// quadrature of the whole plane in x = tan α, y = tan β, each point outside the square clamped to
// the border pixel it reads (measured within 0.3%, held to 1%). The radial stretch (same azimuth)
// fails it: its corner pixels get 0.35 of these, its mid-edge pixels 1.54.
TEST(HemiPlaneWeights, StretchHoldsTheDirectionsThatClampOntoEachBorderPixel) {
    const int r = 8;
    const float a = 2.0f;
    const std::vector<float> none = hemi_plane_weights(r, a, BorderCorrection::none);
    const std::vector<float> stretch = hemi_plane_weights(r, a, BorderCorrection::stretch);
    std::vector<double> expected(size_t(r) * r, 0.0);
    constexpr int kSteps = 4096;
    const double h = std::numbers::pi / kSteps;
    for (int j = 0; j < kSteps; ++j) {
        const double beta = -std::numbers::pi / 2 + (j + 0.5) * h, y = std::tan(beta);
        for (int i = 0; i < kSteps; ++i) {
            const double alpha = -std::numbers::pi / 2 + (i + 0.5) * h, x = std::tan(alpha);
            if (std::abs(x) <= a && std::abs(y) <= a) continue;
            const double d = 1.0 + x * x + y * y;
            const double measure = h * h /
                                   (std::cos(alpha) * std::cos(alpha) * std::cos(beta) *
                                    std::cos(beta) * std::numbers::pi * d * d);
            const int pi =
                std::clamp(int((std::clamp(x, -double(a), double(a)) + a) / (2 * a) * r), 0, r - 1);
            const int pj =
                std::clamp(int((std::clamp(y, -double(a), double(a)) + a) / (2 * a) * r), 0, r - 1);
            expected[size_t(pj) * r + size_t(pi)] += measure;
        }
    }
    double missing = 0.0;
    for (double v : expected) missing += v;
    EXPECT_NEAR(missing, 1.0 - hemi_plane_coverage(a), 1e-3);
    for (int j = 0; j < r; ++j)
        for (int i = 0; i < r; ++i) {
            const size_t k = size_t(j) * r + size_t(i);
            EXPECT_NEAR(stretch[k] - none[k], expected[k], 1e-2 * expected[k])
                << "pixel " << i << ", " << j;
        }
}

// The band view's pixels wholly inside the first plane weigh nothing; those wholly outside weigh
// their whole cosine-weighted solid angle (an r×r plane of half-width 8 against a = 2; the plain
// table is integrated by 8×8 midpoints, within 0.12% of the closed form here, held to 0.3%).
TEST(HemiPlaneWeights, TheBandWeighsOnlyWhatThePlaneMisses) {
    const int r = 16;
    const float a = 2.0f, b = 8.0f;
    const std::vector<float> band = hemi_band_weights(r, a, b);
    const std::vector<float> whole = hemi_plane_weights(r, b, BorderCorrection::none);
    for (int j = 1; j < r - 1; ++j)
        for (int i = 1; i < r - 1; ++i) {
            const size_t k = size_t(j) * r + size_t(i);
            const float x0 = -b + i * 2 * b / r, y0 = -b + j * 2 * b / r, x1 = x0 + 2 * b / r,
                        y1 = y0 + 2 * b / r;
            if (x0 >= -a && x1 <= a && y0 >= -a && y1 <= a) {
                EXPECT_EQ(band[k], 0.0f) << i << ", " << j;
            } else if (x1 <= -a || x0 >= a || y1 <= -a || y0 >= a) {
                EXPECT_NEAR(band[k], whole[k], 3e-3 * whole[k]) << i << ", " << j;
            }
        }
}

namespace {

// A small receiver quad facing +y at the origin and a large emitter-like quad at height h facing
// down, whose AIM radiance is set to L directly (no photons needed).
Scene receiver_under_plane(float h, float half_size, BorderCorrection correction) {
    Scene s;
    s.path = "gather_test";
    Object receiver;
    receiver.name = "receiver";
    receiver.mesh = make_quad(1.0f, 1.0f);
    s.objects.push_back(receiver);
    Object plane;
    plane.name = "plane";
    plane.mesh = make_quad(2.0f * half_size, 2.0f * half_size);
    plane.transform.translation = {0.0f, h, 0.0f};
    plane.transform.rotation =
        glm::angleAxis(glm::radians(180.0f), glm::vec3(1, 0, 0));  // face down
    s.objects.push_back(plane);
    s.settings.lightmap.texel_size = 0.5f;
    s.settings.gather.plane_resolution = 32;
    s.settings.gather.plane_half_width = 2.0f;
    s.settings.gather.border_correction = correction;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

// The AIM of receiver_under_plane's scene: the plane (object 1) at `radiance`, everything else
// dark. Returns the receiver's (object 0's) texels.
std::vector<int> light_the_plane(const Scene& scene, LightmapTexture& aim, glm::vec3 radiance) {
    std::vector<glm::vec3> values(size_t(scene.atlas.width) * size_t(scene.atlas.height),
                                  glm::vec3(0.0f));
    std::vector<int> receiver_texels;
    for (int i = 0; i < int(scene.atlas.texels.size()); ++i) {
        const TexelRecord& t = scene.atlas.texels[size_t(i)];
        if (t.object == 1)
            values[size_t(t.y) * size_t(scene.atlas.width) + size_t(t.x)] = radiance;
        else if (t.object == 0)
            receiver_texels.push_back(i);
    }
    aim.update_all(values);
    return receiver_texels;
}

}  // namespace

class HemiPlaneGatherTest : public test::GlTest {};

TEST_F(HemiPlaneGatherTest, UniformPlaneFillingTheViewGivesPiLTimesCoverage) {
    const glm::vec3 radiance(2.0f, 1.0f, 0.5f);
    for (BorderCorrection c :
         {BorderCorrection::none, BorderCorrection::renormalize, BorderCorrection::stretch}) {
        // The plane reaches far beyond the frustum (|x| < 2h at a = 2) so it fills the view.
        const Scene scene = receiver_under_plane(1.0f, 50.0f, c);
        SceneMeshes meshes(scene);
        LightmapTexture aim(scene.atlas);
        const std::vector<int> receiver_texels = light_the_plane(scene, aim, radiance);
        HemiPlaneGather gather(scene, meshes, 16);
        const std::vector<GatherResult> r = gather.gather(receiver_texels, aim.id());
        ASSERT_FALSE(r.empty());
        const double expected_fraction =
            c == BorderCorrection::none ? hemi_plane_coverage(2.0f) : 1.0;
        for (const GatherResult& g : r) {
            // E = π L · fraction, and the IIM stores E / π.
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(g.iim[k], radiance[k] * expected_fraction,
                            0.01 * radiance[k] * expected_fraction)
                    << kBorderCorrectionNames[size_t(c)];
            EXPECT_EQ(g.back_fraction, 0.0f);
        }
    }
}

// A surface whose hemi-plane sees only a dark square and the light beyond it (a face looking out
// of an open room towards a lit far room, docs/fidelity.md "Session 14"): the border stretch
// spreads the dark border over the missing band and reads nearly nothing; the band's second view
// sees the light there. Exact: L (1 − the dark square's form factor), in closed form (the form
// factor of a parallel rectangle with a corner above the point). The receiver's 9 texels sit at
// 0 and ±0.5, so the square's edges lie 1.79–2.84 plane half-widths out, in the band. Measured:
// stretch reads 0 at the centre texel (off by 1.000); the band 0.8–12.5% low, worst at the centre
// texel, whose edge (2.32) falls inside one of the band's 0.5-wide pixels (b = 8 over 32 pixels),
// which reads it dark: the band's point sampling, bound 15%.
TEST_F(HemiPlaneGatherTest, TheBandSeesTheLightBeyondADarkPlane) {
    const float h = 0.95f, dark = 2.2f;
    const glm::vec3 radiance(1.0f);
    auto corner = [](double x, double y) {
        const double sx = std::sqrt(1.0 + x * x), sy = std::sqrt(1.0 + y * y);
        return (x / sx * std::atan(y / sx) + y / sy * std::atan(x / sy)) / (2.0 * std::numbers::pi);
    };
    auto rectangle = [&](double x0, double x1, double y0, double y1) {
        return corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0);
    };
    for (BorderCorrection c : {BorderCorrection::stretch, BorderCorrection::band}) {
        Scene scene = receiver_under_plane(1.0f, 50.0f, c);
        Object square;
        square.name = "dark square";
        square.mesh = make_quad(2.0f * dark, 2.0f * dark);
        square.transform.translation = {0.0f, h, 0.0f};
        square.transform.rotation = glm::angleAxis(glm::radians(180.0f), glm::vec3(1, 0, 0));
        scene.objects.push_back(square);
        init_versions(scene);
        make_surfaces_and_atlas(scene);
        SceneMeshes meshes(scene);
        LightmapTexture aim(scene.atlas);
        const std::vector<int> receiver_texels = light_the_plane(scene, aim, radiance);
        HemiPlaneGather gather(scene, meshes, 16);
        const std::vector<GatherResult> r = gather.gather(receiver_texels, aim.id());
        ASSERT_FALSE(r.empty());
        double worst = 0.0;
        for (size_t k = 0; k < r.size(); ++k) {
            const glm::vec3 p = scene.atlas.texels[size_t(receiver_texels[k])].position;
            const double exact = 1.0 - rectangle((-dark - p.x) / h, (dark - p.x) / h,
                                                 (-dark - p.z) / h, (dark - p.z) / h);
            worst = std::max(worst, std::abs(r[k].iim.x / exact - 1.0));
        }
        std::printf("%s: worst texel off by %.3f\n", kBorderCorrectionNames[size_t(c)], worst);
        if (c == BorderCorrection::band) {
            EXPECT_LT(worst, 0.15);
        } else {
            EXPECT_GT(worst, 0.5);  // the stretch: what the band is for
        }
    }
}

// plane_resolution 1024 is documented as valid: 256 tiles of 1024² would need a 16k² framebuffer
// (GL_OUT_OF_MEMORY), so the gather takes fewer tiles per pass instead.
TEST_F(HemiPlaneGatherTest, LargestPlaneResolutionFitsTheFramebuffer) {
    Scene scene = receiver_under_plane(1.0f, 50.0f, BorderCorrection::renormalize);
    scene.settings.gather.plane_resolution = 1024;
    SceneMeshes meshes(scene);
    LightmapTexture aim(scene.atlas);
    const std::vector<int> all = light_the_plane(scene, aim, glm::vec3(1.0f));
    const std::vector<int> receiver_texels(
        all.begin(), all.begin() + std::min<std::ptrdiff_t>(2, std::ssize(all)));
    HemiPlaneGather gather(scene, meshes, 256);
    EXPECT_LE(gather.tiles_per_pass(), 4);  // at most 2×2 tiles of 1024²
    const std::vector<GatherResult> r = gather.gather(receiver_texels, aim.id());
    ASSERT_EQ(r.size(), receiver_texels.size());
    for (const GatherResult& g : r) EXPECT_NEAR(g.iim.x, 1.0, 0.01);
}

TEST_F(HemiPlaneGatherTest, TexelUnderABackFaceIsFlagged) {
    // The plane above faces up (away from the receiver): the receiver sees only its back.
    Scene scene = receiver_under_plane(1.0f, 50.0f, BorderCorrection::renormalize);
    scene.objects[1].transform.rotation = glm::quat(1, 0, 0, 0);
    SceneMeshes meshes(scene);
    LightmapTexture aim(scene.atlas);
    std::vector<int> receiver_texels;
    for (int i = 0; i < int(scene.atlas.texels.size()); ++i)
        if (scene.atlas.texels[size_t(i)].object == 0) receiver_texels.push_back(i);
    HemiPlaneGather gather(scene, meshes, 16);
    for (const GatherResult& g : gather.gather(receiver_texels, aim.id()))
        EXPECT_GT(g.back_fraction, 0.9f);
}

TEST_F(HemiPlaneGatherTest, BatchedAndSingleGathersAgree) {
    const Scene scene =
        receiver_under_plane(1.0f, 3.0f, BorderCorrection::stretch);  // partial view
    SceneMeshes meshes(scene);
    LightmapTexture aim(scene.atlas);
    std::vector<glm::vec3> values(size_t(scene.atlas.width) * size_t(scene.atlas.height),
                                  glm::vec3(1.0f));
    aim.update_all(values);
    std::vector<int> all(scene.atlas.texels.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = int(i);
    HemiPlaneGather batched(scene, meshes, 64), single(scene, meshes, 1);
    single.set_max_per_pass(1);
    const auto a = batched.gather(all, aim.id()), b = single.gather(all, aim.id());
    for (size_t i = 0; i < all.size(); ++i)
        EXPECT_NEAR(a[i].iim.x, b[i].iim.x, 1e-4f) << "texel " << i;
}

}  // namespace ag::gpu
