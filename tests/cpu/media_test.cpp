// Participating media in the pt reference (docs/media.md): known answers first. Slab
// transmittance (Beer–Lambert), single scattering around a point light against numerical
// quadrature, a scattering furnace, and the split of the image into components.
#include "shared/media.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "cpu/media_tracking.h"
#include "cpu/reference/reference.h"
#include "shared/camera.h"
#include "test_scenes.h"

namespace ag::cpu {

namespace {

glm::dvec3 image_mean(const Image& image) {
    glm::dvec3 sum(0.0);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) sum += glm::dvec3(image.rgb(x, y));
    return sum / double(image.width * image.height);
}

Camera looking_at(const glm::vec3& eye, const glm::vec3& target, float fov, int size) {
    Camera c;
    c.eye = eye;
    c.target = target;
    c.up = {0.0f, 1.0f, 0.0f};
    c.fov_y = fov;
    c.width = c.height = size;
    return c;
}

ReferenceResult render_pt(const Scene& scene, int spp, int volume_bounces, int threads = 2) {
    ReferenceSettings s;
    s.method = ReferenceMethod::path_tracing;
    s.spp = spp;
    s.volume_bounces = volume_bounces;
    ThreadPool pool(threads);
    return render_reference(scene, s, pool);
}

// A square emitter (diffuse, no light of its own: it is only seen) of radiance Le at z = 0 facing
// −z, a camera at z = −6 looking at it, and a slab medium z ∈ [−4, −2] covering the view.
Scene slab_scene(float sigma_s, float sigma_a, float emission) {
    Scene s;
    s.path = "slab";
    Object wall;
    wall.name = "emitter";
    wall.mesh = make_quad(40.0f, 40.0f);
    wall.material.albedo = glm::vec3(0.0f);
    wall.material.emission = glm::vec3(emission);
    // The quad faces +y; turned to face −z (towards the camera).
    wall.transform.rotation = glm::angleAxis(-0.5f * std::numbers::pi_v<float>, glm::vec3(1, 0, 0));
    s.objects.push_back(wall);
    Medium m;
    m.bounds.min = {-30.0f, -30.0f, -4.0f};
    m.bounds.max = {30.0f, 30.0f, -2.0f};
    m.sigma_s = sigma_s;
    m.sigma_a = sigma_a;
    s.media.push_back(m);
    s.camera = looking_at({0.0f, 0.0f, -6.0f}, {0.0f, 0.0f, 0.0f}, 1.0f, 16);  // all but straight
    return s;
}

TEST(MediaTracking, SlabTransmittanceIsBeerLambert) {
    const Scene scene = slab_scene(0.3f, 0.2f, 1.0f);
    const MediaTracker media(scene);
    HashedStream more(1);
    // Straight through: 2 units of σ_t = 0.5; slanted: 2 / cos θ.
    const Ray straight{{0.0f, 0.0f, -6.0f}, {0.0f, 0.0f, 1.0f}};
    EXPECT_NEAR(media.transmittance(straight, 6.0f, -1, more), std::exp(-1.0), 1e-6);
    const glm::vec3 d = glm::normalize(glm::vec3(0.5f, 0.0f, 1.0f));
    EXPECT_NEAR(media.transmittance({{0.0f, 0.0f, -6.0f}, d}, 100.0f, -1, more),
                std::exp(-0.5 * 2.0 / double(d.z)), 1e-6);
    // Stopping inside the slab, and a ray that misses it.
    EXPECT_NEAR(media.transmittance(straight, 3.0f, -1, more), std::exp(-0.5), 1e-6);
    EXPECT_EQ(media.transmittance({{0.0f, 40.0f, -6.0f}, {0.0f, 0.0f, 1.0f}}, 10.0f, -1, more),
              1.0f);
}

// A perturbed slab: ratio tracking's mean against exp(−∫σ_t ρ(x) dx) by quadrature, and delta
// tracking's escape probability against the same number.
TEST(MediaTracking, PerturbedSlabTrackingMatchesQuadrature) {
    Scene scene = slab_scene(0.6f, 0.4f, 1.0f);
    scene.media[0].noise = {0.8f, 1.3f, 5};
    const Medium& m = scene.media[0];
    const MediaTracker media(scene);
    const glm::vec3 origin(0.3f, 0.1f, -6.0f), dir(0.0f, 0.0f, 1.0f);
    double optical = 0.0;
    constexpr int kSteps = 20000;
    for (int i = 0; i < kSteps; ++i) {
        const float z = -4.0f + 2.0f * (float(i) + 0.5f) / float(kSteps);
        optical += double(m.sigma_t()) * double(m.density({origin.x, origin.y, z})) * 2.0 / kSteps;
    }
    const double expected = std::exp(-optical);
    ASSERT_GT(std::abs(expected - std::exp(-2.0)), 0.01) << "the noise should matter here";
    double ratio = 0.0, escaped = 0.0;
    constexpr int kRuns = 200000;
    for (int i = 0; i < kRuns; ++i) {
        HashedStream more(mix64(uint64_t(i)));
        ratio += media.transmittance({origin, dir}, 10.0f, -1, more);
        if (!media.sample_collision({origin, dir}, 10.0f, -1, (float(i) + 0.5f) / kRuns, more))
            escaped += 1.0;
    }
    EXPECT_NEAR(ratio / kRuns, expected, 0.005 * expected);
    EXPECT_NEAR(escaped / kRuns, expected, 0.005 * expected);
}

// The pt image of an emitter behind the slab with scattering switched off (--volume-bounces 0):
// Le · exp(−σ_t d) everywhere, within 0.5%, all of it in the direct term.
TEST(MediaPathTracer, SlabAttenuatesWithinHalfAPercent) {
    const Scene scene = slab_scene(0.3f, 0.2f, 2.0f);
    const ReferenceResult r = render_pt(scene, 137, 0);
    const double expected = 2.0 * std::exp(-0.5 * 2.0);
    EXPECT_NEAR(image_mean(r.components[size_t(FrameTerm::direct)]).x, expected, 0.005 * expected);
    EXPECT_EQ(image_mean(r.components[size_t(FrameTerm::volume)]).x, 0.0);
    // Pure absorption attenuates the same way whatever the bounce cap.
    const ReferenceResult absorbing = render_pt(slab_scene(0.0f, 0.5f, 2.0f), 137, 256);
    EXPECT_NEAR(image_mean(absorbing.full).x, expected, 0.005 * expected);
}

// Single scattering around a point light in homogeneous fog: the camera ray passes the light at
// distance h; its radiance is ∫ σ_s p(θ) I e^{−σ_t r}/r² e^{−σ_t t} dt (Pfeuti eq. 2.5), here by
// Simpson's rule. A narrow camera makes every pixel the same ray.
// Also with a very forward phase (k = 0.999, the ray 0.1 from the light): the peak of p, 159 where
// the light's direction lines up with the ray's, lies on the ray (the robustness sweep found the
// media method 100× below pt there; pt is right, docs/media.md).
void expect_single_scattering_matches_quadrature(float k, float h, bool check_multiple);

TEST(MediaPathTracer, SingleScatteringMatchesQuadrature) {
    expect_single_scattering_matches_quadrature(0.3f, 1.0f, true);
}

TEST(MediaPathTracer, SingleScatteringMatchesQuadratureWithAForwardPhase) {
    expect_single_scattering_matches_quadrature(0.999f, 0.1f, false);
}

void expect_single_scattering_matches_quadrature(float k, float h, bool check_multiple) {
    const float sigma_s = 0.2f, sigma_a = 0.05f, intensity = 10.0f;
    Scene s;
    s.path = "fog_point";
    Object sink;  // a black quad out of view: the scene needs one object
    sink.name = "sink";
    sink.mesh = make_quad(1.0f, 1.0f);
    sink.material.albedo = glm::vec3(0.0f);
    sink.transform.translation = {0.0f, -100.0f, 0.0f};
    s.objects.push_back(sink);
    Light light;
    light.name = "lamp";
    light.position = {0.0f, 0.0f, 0.0f};
    light.intensity = glm::vec3(intensity);
    s.lights.push_back(light);
    Medium m;
    m.bounds.min = glm::vec3(-20.0f);
    m.bounds.max = glm::vec3(20.0f);
    m.sigma_s = sigma_s;
    m.sigma_a = sigma_a;
    m.phase_k = k;
    s.media.push_back(m);
    const glm::vec3 eye(h, 0.0f, -5.0f);
    s.camera = looking_at(eye, {h, 0.0f, 0.0f}, 0.01f, 4);

    const double sigma_t = sigma_s + sigma_a, length = 25.0;  // the ray leaves the box at z = 20
    const auto integrand = [&](double t) {
        const glm::dvec3 x = glm::dvec3(eye) + t * glm::dvec3(0.0, 0.0, 1.0);
        const glm::dvec3 to = -x;
        const double r = glm::length(to);
        const double phase = schlick_phase(float(to.z / r), k);
        return sigma_s * phase * intensity * std::exp(-sigma_t * r) / (r * r) *
               std::exp(-sigma_t * t);
    };
    constexpr int kIntervals = 200000;  // even
    double sum = integrand(0.0) + integrand(length);
    for (int i = 1; i < kIntervals; ++i)
        sum += (i % 2 ? 4.0 : 2.0) * integrand(length * i / kIntervals);
    const double expected = sum * length / (3.0 * kIntervals);

    const ReferenceResult r = render_pt(s, 4096, 1);
    const double volume = image_mean(r.components[size_t(FrameTerm::volume)]).x;
    std::printf("k %.3f: pt %.6g against quadrature %.6g\n", k, volume, expected);
    EXPECT_NEAR(volume, expected, 0.02 * expected);
    EXPECT_EQ(image_mean(r.full).x, volume) << "nothing but the fog is seen";
    if (!check_multiple) return;
    // Multiple scattering only adds light.
    const ReferenceResult multiple = render_pt(s, 1024, 256);
    EXPECT_GT(image_mean(multiple.full).x, 1.02 * expected);
}

// A furnace filled with a conservative medium: walls of albedo ρ emitting Le inwards and fog of
// albedo 1 keep the radiance Le / (1 − ρ) everywhere, so every pixel sees it whatever the fog
// scatters; the fog's share goes to the volume term.
TEST(MediaPathTracer, ConservativeFogFurnace) {
    const float albedo = 0.5f, emission = 1.0f;
    Scene s;
    s.path = "fog_furnace";
    Object box;
    box.name = "box";
    box.mesh = make_box(glm::vec3(2.0f));
    for (glm::uvec3& t : box.mesh.triangles) std::swap(t.y, t.z);  // inward
    box.material.albedo = glm::vec3(albedo);
    box.material.emission = glm::vec3(emission);
    s.objects.push_back(box);
    Medium m;
    m.bounds.min = glm::vec3(-1.0f);
    m.bounds.max = glm::vec3(1.0f);
    m.sigma_s = 1.5f;
    m.phase_k = 0.5f;
    s.media.push_back(m);
    s.camera = looking_at({0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, 90.0f, 8);
    const ReferenceResult r = render_pt(s, 256, 256);
    const double expected = emission / (1.0 - albedo);
    EXPECT_NEAR(image_mean(r.full).x, expected, 0.01 * expected);
    const double volume = image_mean(r.components[size_t(FrameTerm::volume)]).x;
    EXPECT_GT(volume, 0.5 * expected) << "most camera rays scatter before the walls";
    EXPECT_LT(volume, expected);
}

// The components still sum to the image with media, and the image does not depend on the
// thread count (the fog-sphere scene; the noise cube for a perturbed interior medium).
TEST(MediaPathTracer, ComponentsSumToTheImageOnAnyThreadCount) {
    Scene cube = load_scene(test::scene_path("media_noise_cube.json"));
    cube.camera.width = cube.camera.height = 10;
    EXPECT_EQ(render_pt(cube, 4, 256, 1).full.pixels, render_pt(cube, 4, 256, 3).full.pixels);
    Scene scene = load_scene(test::scene_path("fog_sphere.json"));
    scene.camera.width = scene.camera.height = 12;
    const ReferenceResult r = render_pt(scene, 8, 256);
    EXPECT_EQ(r.full.pixels, render_pt(scene, 8, 256, 1).full.pixels);
    for (size_t i = 0; i < r.full.pixels.size(); ++i) {
        float sum = 0.0f;
        for (FrameTerm t : kFrameTerms) sum += r.components[size_t(t)].pixels[i];
        EXPECT_NEAR(sum, r.full.pixels[i], 1e-5f * std::max(1.0f, r.full.pixels[i]));
    }
    EXPECT_GT(image_mean(r.components[size_t(FrameTerm::volume)]).x, 0.0);
}

TEST(Media, SchlickPhaseIntegratesToOneAndSamplesItself) {
    for (float k : {-0.7f, 0.0f, 0.4f, 0.9f}) {
        // ∫ p dω = 2π ∫ p(c) dc.
        double integral = 0.0;
        constexpr int kSteps = 200000;
        for (int i = 0; i < kSteps; ++i) {
            const float c = -1.0f + 2.0f * (float(i) + 0.5f) / kSteps;
            integral += 2.0 * std::numbers::pi * schlick_phase(c, k) * 2.0 / kSteps;
        }
        EXPECT_NEAR(integral, 1.0, 1e-3) << "k = " << k;
        // The mean cosine of sampled directions against the phase function's own.
        double mean_sampled = 0.0, mean_exact = 0.0;
        const glm::vec3 forward = glm::normalize(glm::vec3(0.2f, -0.5f, 0.8f));
        constexpr int kSamples = 100000;
        for (int i = 0; i < kSamples; ++i) {
            const glm::vec3 d =
                sample_schlick(forward, k, (float(i) + 0.5f) / kSamples, hashed_uniform(7, i));
            mean_sampled += glm::dot(d, forward);
        }
        for (int i = 0; i < kSteps; ++i) {
            const float c = -1.0f + 2.0f * (float(i) + 0.5f) / kSteps;
            mean_exact += 2.0 * std::numbers::pi * c * schlick_phase(c, k) * 2.0 / kSteps;
        }
        EXPECT_NEAR(mean_sampled / kSamples, mean_exact, 2e-3) << "k = " << k;
    }
}

// The spread table (the media method's view march): Schlick's mean cosine in closed form
// against quadrature, its inverse, and the table's k at R having R times the mean cosine of k —
// entry 0 k itself, the last isotropic. Fails if the closed form, the bisection or the table's
// R = 1 − s² spacing is wrong.
TEST(Media, SchlickSpreadKeepsTheMeanCosineTimesR) {
    const auto mean_cosine = [](double k) {
        double sum = 0.0;
        constexpr int kSteps = 400000;
        for (int i = 0; i < kSteps; ++i) {
            const double c = -1.0 + 2.0 * (double(i) + 0.5) / kSteps;
            const double d = 1.0 - k * c;
            sum += c * (1.0 - k * k) / (2.0 * d * d) * 2.0 / kSteps;
        }
        return sum;
    };
    for (double k : {-0.8, -0.3, 0.0005, 0.3, 0.9, 0.999}) {
        const double g = schlick_mean_cosine(k);
        EXPECT_NEAR(g, mean_cosine(k), 1e-5) << "k = " << k;
        EXPECT_NEAR(schlick_k_for_mean_cosine(g), k, 1e-9) << "k = " << k;
    }
    EXPECT_NEAR(schlick_mean_cosine(0.999), 0.9934, 1e-4);
    for (float k : {-0.5f, 0.3f, 0.999f}) {
        const std::vector<float> table = schlick_spread_table(k, 129);
        ASSERT_EQ(table.size(), 129u);
        EXPECT_EQ(table.front(), k);
        EXPECT_NEAR(table.back(), 0.0f, 1e-6f);
        for (int i : {1, 16, 64, 100}) {
            const double s = i / 128.0, r = 1.0 - s * s;
            EXPECT_NEAR(schlick_mean_cosine(table[size_t(i)]), r * schlick_mean_cosine(k), 1e-6)
                << "k = " << k << ", entry " << i;
            EXPECT_LE(std::abs(table[size_t(i)]), std::abs(table[size_t(i - 1)])) << i;
        }
    }
}

TEST(Media, PerlinNoiseIsBoundedAndVaries) {
    double sum = 0.0, sum2 = 0.0;
    float lo = 1.0f, hi = -1.0f;
    for (int i = 0; i < 20000; ++i) {
        const glm::vec3 p(hashed_uniform(1, i) * 10.0f, hashed_uniform(2, i) * 10.0f,
                          hashed_uniform(3, i) * 10.0f);
        const float v = perlin_noise(p, 3);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        sum += v;
        sum2 += double(v) * v;
    }
    EXPECT_GE(lo, -1.0f);
    EXPECT_LE(hi, 1.0f);
    EXPECT_NEAR(sum / 20000, 0.0, 0.02);
    EXPECT_GT(std::sqrt(sum2 / 20000), 0.1);
    EXPECT_EQ(perlin_noise({1.0f, 2.0f, 3.0f}, 3), 0.0f) << "zero on the lattice";
    EXPECT_NE(perlin_noise({1.5f, 2.25f, 3.7f}, 3), perlin_noise({1.5f, 2.25f, 3.7f}, 4));
}

}  // namespace

}  // namespace ag::cpu
