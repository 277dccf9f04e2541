// Reference renderers (docs/reference.md): known answers first (furnace, analytic direct light and
// mirror caustics), then path tracing against photon mapping on the Cornell scene.
#include "cpu/reference/reference.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <glm/gtc/quaternion.hpp>
#include <numbers>

#include "cpu/reference/photon_mapper.h"
#include "shared/camera.h"
#include "shared/metrics.h"
#include "test_scenes.h"

namespace ag::cpu {

namespace {

glm::vec3 image_mean(const Image& image) {
    glm::dvec3 sum(0.0);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) sum += glm::dvec3(image.rgb(x, y));
    return glm::vec3(sum / double(image.width * image.height));
}

Camera looking_at(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up, float fov,
                  int size) {
    Camera c;
    c.eye = eye;
    c.target = target;
    c.up = up;
    c.fov_y = fov;
    c.width = c.height = size;
    return c;
}

// A closed cube of side 2 around the origin, faces inwards, albedo ρ, emitting Le everywhere, no
// lights, seen from its centre: every ray sees Le + ρ Le + ρ² Le + ... = Le / (1 − ρ).
Scene furnace(float albedo, float emission) {
    Scene s;
    s.path = "furnace";
    Object box;
    box.name = "box";
    box.mesh = make_box(glm::vec3(2.0f));
    for (glm::uvec3& t : box.mesh.triangles) std::swap(t.y, t.z);  // inward
    box.material.albedo = glm::vec3(albedo);
    box.material.emission = glm::vec3(emission);
    s.objects.push_back(box);
    s.camera = looking_at({0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, {0.0f, 1.0f, 0.0f}, 90.0f, 16);
    return s;
}

Object quad_object(const std::string& name, float size, float height, bool facing_down,
                   MaterialType type, float albedo) {
    Object o;
    o.name = name;
    o.mesh = make_quad(size, size);
    o.material.type = type;
    o.material.albedo = glm::vec3(albedo);
    o.transform.translation = {0.0f, height, 0.0f};
    if (facing_down)
        o.transform.rotation =
            glm::angleAxis(std::numbers::pi_v<float>, glm::vec3(1.0f, 0.0f, 0.0f));
    return o;
}

// A square quad light of side `side` centred at (0, height, 0), emitting downwards.
Light quad_light(float side, float height, float radiance) {
    Light l;
    l.name = "panel";
    l.type = LightType::quad;
    const float h = 0.5f * side;
    // edge01 × edge03 = (side, 0, 0) × (0, 0, side) points down (−y).
    l.corners = {glm::vec3(-h, height, -h), glm::vec3(h, height, -h), glm::vec3(h, height, h),
                 glm::vec3(-h, height, h)};
    l.radiance = glm::vec3(radiance);
    return l;
}

// Irradiance under the centre of a parallel square emitter of radiance L, half-side s, at distance
// h: four corner rectangles, each E = L · A/√(1+A²) · atan(A/√(1+A²)) with A = s/h.
float square_irradiance(float radiance, float half_side, float distance) {
    const double a = half_side / distance, q = std::sqrt(1.0 + a * a);
    return float(4.0 * radiance * 0.5 * 2.0 * (a / q) * std::atan(a / q));
}

ReferenceResult render(const Scene& scene, ReferenceSettings settings, int threads = 2) {
    ThreadPool pool(threads);
    return render_reference(scene, settings, pool);
}

ReferenceSettings pt(int spp) {
    ReferenceSettings s;
    s.method = ReferenceMethod::path_tracing;
    s.spp = spp;
    return s;
}

ReferenceSettings pm(int spp, int photons, int gather_rays) {
    ReferenceSettings s;
    s.method = ReferenceMethod::photon_mapping;
    s.spp = spp;
    s.photons = photons;
    s.caustic_photons = photons / 4;
    s.gather_rays = gather_rays;
    return s;
}

// relMSE of two images after averaging `block` × `block` pixel blocks.
double block_rel_mse(const Image& test, const Image& reference, int block) {
    Image a(test.width / block, test.height / block), b(a.width, a.height);
    for (int y = 0; y < a.height * block; ++y)
        for (int x = 0; x < a.width * block; ++x) {
            const float w = 1.0f / float(block * block);
            a.set_rgb(x / block, y / block, a.rgb(x / block, y / block) + w * test.rgb(x, y));
            b.set_rgb(x / block, y / block, b.rgb(x / block, y / block) + w * reference.rgb(x, y));
        }
    return compare_images(a, b).rel_mse;
}

// The box-filtered mean over pixel (x, y) of f(point where the ray meets the plane y = plane_y),
// by 8 × 8 subsamples: what a converged render's pixel holds.
float pixel_mean(const Camera& camera, int x, int y, float plane_y,
                 const std::function<float(const glm::vec3&)>& f) {
    double sum = 0.0;
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
            const glm::vec3 d = camera_ray_direction(camera, float(x) + (float(i) + 0.5f) / 8.0f,
                                                     float(y) + (float(j) + 0.5f) / 8.0f);
            sum += f(camera.eye + d * ((plane_y - camera.eye.y) / d.y));
        }
    return float(sum / 64.0);
}

// ρ/π · I cosθ / d² at p on a plane with unit normal n, from a point light at `light`.
float point_lit_radiance(const glm::vec3& p, const glm::vec3& n, const glm::vec3& light,
                         float intensity, float albedo) {
    const glm::vec3 to = light - p;
    const float d2 = glm::dot(to, to);
    return albedo / std::numbers::pi_v<float> * intensity * std::abs(glm::dot(n, to)) /
           std::sqrt(d2) / d2;
}

bool slow_tests() {
    const char* v = std::getenv("AG_SLOW");
    return v && std::string(v) == "1";
}

}  // namespace

TEST(Reference, ConcentricMapRoundTrips) {
    for (float u = 0.01f; u < 1.0f; u += 0.0731f)
        for (float v = 0.01f; v < 1.0f; v += 0.0617f) {
            const glm::vec3 d = square_to_cosine_hemisphere({u, v});
            EXPECT_NEAR(glm::length(d), 1.0f, 1e-5f);
            const glm::vec2 back = cosine_hemisphere_to_square(d);
            EXPECT_NEAR(back.x, u, 1e-4f);
            EXPECT_NEAR(back.y, v, 1e-4f);
        }
}

TEST(Reference, FurnacePathTracerGivesLeOverOneMinusAlbedo) {
    const float albedo = 0.5f, le = 1.0f;
    const ReferenceResult r = render(furnace(albedo, le), pt(256));
    const glm::vec3 full = image_mean(r.full);
    const glm::vec3 direct = image_mean(r.components[size_t(FrameTerm::direct)]);
    const glm::vec3 indirect = image_mean(r.components[size_t(FrameTerm::indirect)]);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(full[c], le / (1.0f - albedo), 0.01f * le / (1.0f - albedo));
        EXPECT_NEAR(direct[c], le, 1e-5f);  // x's own emission
        EXPECT_NEAR(indirect[c], le * albedo / (1.0f - albedo), 0.01f * le / (1.0f - albedo));
    }
    EXPECT_EQ(image_mean(r.components[size_t(FrameTerm::caustics)]), glm::vec3(0.0f));
    EXPECT_EQ(image_mean(r.components[size_t(FrameTerm::specular)]), glm::vec3(0.0f));
    EXPECT_EQ(r.spp, 256);
}

// Direct light in the renderer's units: a plane of albedo ρ at distance h under a point light of
// intensity I has radiance ρ/π · I cosθ / d² (d, θ from the light to the pixel's point).
// The photon map's density estimates are unbiased: on a plane under a point light, the kNN
// irradiance at arbitrary points and the one precomputed at photons (what final-gather rays read)
// average to I cosθ / d² within 1.5% (noise ~0.6%) with k = 20, where ΣΦ/(π r²) over the k
// nearest, the k-th counted whole, read +3.5% and +2.6%.
TEST(Reference, PhotonMapIrradianceEstimatesAreUnbiased) {
    const float height = 1.0f, intensity = 10.0f;
    const Scene scene = test::plane_under_light(2.0f, height, intensity, 0.5f);
    ReferenceSettings settings = pm(1, 400000, 1);
    settings.knn = 20;
    settings.caustic_photons = 0;
    ThreadPool pool(2);
    const RayTracer rays(scene);
    const PhotonMapper mapper(scene, rays, settings, pool);
    const glm::vec3 up(0.0f, 1.0f, 0.0f), light(0.0f, height, 0.0f);
    double at_points = 0.0, cached = 0.0;
    constexpr int kGrid = 40;
    for (int j = 0; j < kGrid; ++j)
        for (int i = 0; i < kGrid; ++i) {
            const glm::vec3 p((float(i) + 0.5f) / kGrid - 0.5f, 0.0f,
                              (float(j) + 0.5f) / kGrid - 0.5f);
            const float d2 = glm::dot(p - light, p - light);
            const double expected = intensity * height / (d2 * std::sqrt(d2));
            at_points += mapper.global_irradiance(p, up).x / expected;
            cached += mapper.cached_irradiance(p, up).x / expected;
        }
    at_points /= kGrid * kGrid;
    cached /= kGrid * kGrid;
    std::printf("mean estimate / exact: at points %.4f, precomputed at photons %.4f\n", at_points,
                cached);
    EXPECT_NEAR(at_points, 1.0, 0.015);
    EXPECT_NEAR(cached, 1.0, 0.015);
}

TEST(Reference, PointLightDirectMatchesAnalytic) {
    const float height = 2.0f, intensity = 10.0f, albedo = 0.6f;
    Scene scene = test::plane_under_light(20.0f, height, intensity, albedo);
    const int size = 9;
    scene.camera =
        looking_at({0.0f, 4.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, 30.0f, size);
    const auto lit = [&](const glm::vec3& p) {
        return point_lit_radiance(p, {0.0f, 1.0f, 0.0f}, {0.0f, height, 0.0f}, intensity, albedo);
    };
    for (const ReferenceSettings& settings : {pt(64), pm(64, 20000, 1)}) {
        const ReferenceResult r = render(scene, settings);
        const Image& direct = r.components[size_t(FrameTerm::direct)];
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const float expected = pixel_mean(scene.camera, x, y, 0.0f, lit);
                EXPECT_NEAR(direct.rgb(x, y).g, expected, 0.01f * expected) << x << ", " << y;
            }
    }
}

TEST(Reference, QuadLightDirectMatchesAnalytic) {
    const float height = 1.0f, side = 1.0f, radiance = 3.0f, albedo = 0.5f;
    Scene scene;
    scene.objects.push_back(
        quad_object("floor", 40.0f, 0.0f, false, MaterialType::diffuse, albedo));
    scene.lights.push_back(quad_light(side, height, radiance));
    // Close above the floor's centre, below the light (lights are invisible to camera rays).
    scene.camera = looking_at({0.0f, 0.5f, 0.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, 4.0f, 5);
    const float expected =
        albedo / std::numbers::pi_v<float> * square_irradiance(radiance, 0.5f * side, height);
    for (const ReferenceSettings& settings : {pt(256), pm(16, 20000, 16)}) {
        const ReferenceResult r = render(scene, settings);
        EXPECT_NEAR(image_mean(r.components[size_t(FrameTerm::direct)]).r, expected,
                    0.01f * expected);
    }
}

// Mirror caustics. A mirror floor at y = 0 under a light at height 1 and a diffuse ceiling at
// height 2: the ceiling sees the light's mirror image at distance 3, which is all its caustic.
Scene mirror_room(const Light& light) {
    Scene scene;
    scene.objects.push_back(quad_object("mirror", 40.0f, 0.0f, false, MaterialType::mirror, 1.0f));
    scene.objects.push_back(quad_object("ceiling", 40.0f, 2.0f, true, MaterialType::diffuse, 0.5f));
    scene.lights.push_back(light);
    scene.camera = looking_at({0.0f, 1.5f, 0.0f}, {0.0f, 2.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, 10.0f, 9);
    return scene;
}

TEST(Reference, PointLightCausticsFromPhotonMappingAndLightTracing) {
    const float intensity = 5.0f;
    Light lamp;
    lamp.name = "lamp";
    lamp.position = {0.0f, 1.0f, 0.0f};
    lamp.intensity = glm::vec3(intensity);
    Scene scene = mirror_room(lamp);
    scene.camera.fov_y = 60.0f;  // a wide patch of ceiling: many independent density estimates
    const glm::vec3 down(0.0f, -1.0f, 0.0f);
    float expected_direct = 0.0f, expected_caustic = 0.0f;
    for (int y = 0; y < scene.camera.height; ++y)
        for (int x = 0; x < scene.camera.width; ++x) {
            expected_direct += pixel_mean(scene.camera, x, y, 2.0f, [&](const glm::vec3& p) {
                return point_lit_radiance(p, down, lamp.position, intensity, 0.5f);
            });
            expected_caustic += pixel_mean(scene.camera, x, y, 2.0f, [&](const glm::vec3& p) {
                return point_lit_radiance(p, down, -lamp.position, intensity,
                                          0.5f);  // mirror image
            });
        }
    expected_direct /= float(scene.camera.width * scene.camera.height);
    expected_caustic /= float(scene.camera.width * scene.camera.height);

    // The path tracer's caustics come from its light tracing (off: none). The light sits inside
    // the mirror's bounding sphere, so light paths leave in every direction: 20,000 per pass.
    ReferenceSettings path_settings = pt(16);
    path_settings.light_paths = 20000;
    const ReferenceResult path = render(scene, path_settings);
    EXPECT_NEAR(image_mean(path.components[size_t(FrameTerm::caustics)]).r, expected_caustic,
                0.01f * expected_caustic);
    EXPECT_NEAR(image_mean(path.components[size_t(FrameTerm::direct)]).r, expected_direct,
                0.01f * expected_direct);
    path_settings.light_tracing = false;
    EXPECT_EQ(image_mean(render(scene, path_settings).components[size_t(FrameTerm::caustics)]),
              glm::vec3(0.0f));

    ReferenceSettings settings = pm(4, 2000, 1);
    settings.caustic_photons = 1600000;
    settings.caustic_knn = 200;
    const ReferenceResult photons = render(scene, settings);
    EXPECT_NEAR(image_mean(photons.components[size_t(FrameTerm::direct)]).r, expected_direct,
                0.01f * expected_direct);
    EXPECT_NEAR(image_mean(photons.components[size_t(FrameTerm::caustics)]).r, expected_caustic,
                0.03f * expected_caustic);
}

// A quad light facing the mirror lights the ceiling only through it: the path tracer finds the
// light after the mirror bounce, the photon mapper by caustic photons; both match the analytic
// irradiance of the mirror image of the quad.
TEST(Reference, QuadLightCausticsAgreeWithAnalytic) {
    const float radiance = 2.0f, side = 1.0f;
    const Scene scene = mirror_room(quad_light(side, 1.0f, radiance));
    const float expected =
        0.5f / std::numbers::pi_v<float> * square_irradiance(radiance, 0.5f * side, 3.0f);

    const ReferenceResult path = render(scene, pt(1024));
    EXPECT_NEAR(image_mean(path.components[size_t(FrameTerm::caustics)]).r, expected,
                0.03f * expected);
    EXPECT_EQ(image_mean(path.components[size_t(FrameTerm::direct)]),
              glm::vec3(0.0f));  // faces away

    // One density estimate covers the small patch the camera sees: k = 2000 photons, ~2% noise.
    ReferenceSettings settings = pm(1, 2000, 1);
    settings.caustic_photons = 1600000;
    settings.caustic_knn = 2000;
    const ReferenceResult photons = render(scene, settings);
    EXPECT_NEAR(image_mean(photons.components[size_t(FrameTerm::caustics)]).r, expected,
                0.05f * expected);
}

TEST(Reference, ComponentsSumToFullAndResultIgnoresThreadCount) {
    const Scene scene = load_scene(test::scene_path("cornell.json"));
    Scene small = scene;
    small.camera.width = small.camera.height = 16;
    for (const ReferenceSettings& settings : {pt(4), pm(1, 20000, 8)}) {
        const ReferenceResult a = render(small, settings, 1);
        const ReferenceResult b = render(small, settings, 3);
        EXPECT_EQ(a.full.pixels, b.full.pixels);
        for (FrameTerm t : kFrameTerms)
            EXPECT_EQ(a.components[size_t(t)].pixels, b.components[size_t(t)].pixels)
                << frame_term_name(t);
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x) {
                glm::vec3 sum(0.0f);
                for (const Image& component : a.components) sum += component.rgb(x, y);
                EXPECT_EQ(sum, a.full.rgb(x, y));
            }
    }
}

// A region holds exactly the pixels it has in the whole image (tiles of a distributed reference
// merge bit for bit), for both methods; regions outside the image are refused.
TEST(Reference, RegionsAreExactlyTheirPixelsOfTheWholeImage) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    scene.camera.width = 13;
    scene.camera.height = 9;
    for (ReferenceSettings settings : {pt(2), pm(1, 20000, 8)}) {
        const ReferenceResult whole = render(scene, settings, 2);
        for (const PixelRegion region : {PixelRegion{0, 0, 5, 4}, PixelRegion{5, 4, 8, 5}}) {
            settings.region = region;
            const ReferenceResult part = render(scene, settings, 1);
            ASSERT_EQ(part.full.width, region.width);
            ASSERT_EQ(part.full.height, region.height);
            for (int y = 0; y < region.height; ++y)
                for (int x = 0; x < region.width; ++x) {
                    EXPECT_EQ(part.full.rgb(x, y), whole.full.rgb(region.x + x, region.y + y));
                    for (FrameTerm t : kFrameTerms)
                        EXPECT_EQ(part.components[size_t(t)].rgb(x, y),
                                  whole.components[size_t(t)].rgb(region.x + x, region.y + y));
                }
        }
        settings.region = {10, 0, 4, 9};  // one column past the right edge
        EXPECT_THROW(render(scene, settings, 1), std::invalid_argument);
    }
}

TEST(Reference, TimeLimitKeepsWholePasses) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    scene.camera.width = scene.camera.height = 8;
    ReferenceSettings settings = pt(0);
    settings.time_limit = 0.2;
    const ReferenceResult r = render(scene, settings);
    EXPECT_GE(r.spp, 1);
    // The kept passes are exactly what a fixed sample count gives.
    const ReferenceResult fixed = render(scene, pt(r.spp));
    EXPECT_EQ(r.full.pixels, fixed.full.pixels);
}

// Larsen Fig. 14.5 compares indirect light with a ray-traced final gather; here the path tracer
// and photon mapping must agree on the Cornell scene's indirect component: relMSE < 0.01 per
// pixel, and < 0.005 on 2 × 2 block averages (noise shrinks there, bias does not). Both carry
// light that passed the glass sphere (L S+ D ... x): the path tracer by light tracing (here a
// quarter of its default light paths, to keep the test short).
// Default: 32 × 32 (about 10 s); AG_SLOW=1: 48 × 48 and 8× the samples (docs/reference.md).
TEST(Reference, CornellIndirectPathTracingAgreesWithPhotonMapping) {
    const bool slow = slow_tests();
    Scene scene = load_scene(test::scene_path("cornell.json"));
    scene.camera.width = scene.camera.height = slow ? 48 : 32;
    ReferenceSettings path_settings = pt(slow ? 32768 : 4096);
    path_settings.light_paths = scene.camera.width * scene.camera.height / 4;
    const ReferenceResult path = render(scene, path_settings);
    const ReferenceResult photons = render(scene, pm(slow ? 128 : 32, slow ? 1000000 : 300000, 64));
    const Image& a = photons.components[size_t(FrameTerm::indirect)];
    const Image& b = path.components[size_t(FrameTerm::indirect)];
    const double pixel_rel_mse = compare_images(a, b).rel_mse, block = block_rel_mse(a, b, 2);
    std::printf(
        "Cornell indirect, %dx%d: relMSE(pm, pt) = %.5f per pixel, %.5f on 2x2 blocks (pt %d spp "
        "%.1f s, "
        "pm %d spp %.1f s)\n",
        scene.camera.width, scene.camera.height, pixel_rel_mse, block, path.spp, path.seconds,
        photons.spp, photons.seconds);
    EXPECT_LT(pixel_rel_mse, 0.01);
    EXPECT_LT(block, 0.005);
    // No bias: mean indirect within 4%.
    const glm::vec3 ma = image_mean(a), mb = image_mean(b);
    std::printf("mean indirect pm / pt: %.4f %.4f %.4f\n", ma.x / mb.x, ma.y / mb.y, ma.z / mb.z);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(ma[c], mb[c], 0.04f * mb[c]);
    // The caustic component is the light focused by the sphere: photon mapping's and the path
    // tracer's (its light tracing) hold it.
    EXPECT_GT(image_mean(photons.components[size_t(FrameTerm::caustics)]).r, 0.0f);
    EXPECT_GT(image_mean(path.components[size_t(FrameTerm::caustics)]).r, 0.0f);
}

}  // namespace ag::cpu

namespace ag::cpu {

// --indirect-bounces N keeps the light that reached x after at most N diffuse bounces. In the
// furnace the k-th vertex after x contributes ρ^k Le having bounced k − 1 times, so N bounces give
// Le (ρ + ... + ρ^(N+1)); direct light (x's own emission) does not change.
TEST(Reference, IndirectBouncesTruncateTheFurnaceSeries) {
    const float albedo = 0.5f, le = 1.0f;
    for (int bounces : {0, 1, 2}) {
        ReferenceSettings settings = pt(256);
        settings.indirect_bounces = bounces;
        const ReferenceResult r = render(furnace(albedo, le), settings);
        float expected = 0.0f;
        for (int k = 1; k <= bounces + 1; ++k) expected += le * std::pow(albedo, float(k));
        const glm::vec3 indirect = image_mean(r.components[size_t(FrameTerm::indirect)]);
        const glm::vec3 direct = image_mean(r.components[size_t(FrameTerm::direct)]);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(indirect[c], expected, 0.01f * expected) << bounces << " bounces";
            EXPECT_NEAR(direct[c], le, 1e-5f);
        }
    }
}

// Path tracing and photon mapping agree on single-bounce (and two-bounce) indirect light in the
// Cornell box without its glass sphere (without light tracing, which --indirect-bounces also
// truncates, the path tracer could not follow the light the glass focuses onto the bounce
// surface).
// Each truncation is darker than the next and than the full term; N = 0 leaves no indirect light.
TEST(Reference, IndirectBouncesAgreeBetweenPathTracingAndPhotonMapping) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    std::erase_if(scene.objects, [](const Object& o) { return o.name == "sphere"; });
    scene.camera.width = scene.camera.height = 24;
    glm::vec3 previous(0.0f);
    for (int bounces : {0, 1, 2, -1}) {
        ReferenceSettings a = pt(1024), b = pm(4, 100000, 64);
        a.indirect_bounces = b.indirect_bounces = bounces;
        const glm::vec3 ma = image_mean(render(scene, a).components[size_t(FrameTerm::indirect)]);
        // (Photon mapping's full term is held to the path tracer's by the test above.)
        const glm::vec3 mb =
            bounces < 0 ? ma : image_mean(render(scene, b).components[size_t(FrameTerm::indirect)]);
        std::printf("%d bounces: mean indirect pt (%.4f %.4f %.4f), pm (%.4f %.4f %.4f)\n", bounces,
                    ma.x, ma.y, ma.z, mb.x, mb.y, mb.z);
        for (int c = 0; c < 3; ++c) {
            if (bounces == 0) {
                EXPECT_EQ(ma[c], 0.0f);
                EXPECT_EQ(mb[c], 0.0f);
                continue;
            }
            EXPECT_NEAR(mb[c], ma[c], 0.02f * ma[c]) << bounces << " bounces, channel " << c;
            EXPECT_GT(ma[c], 1.1f * previous[c]) << bounces << " bounces, channel " << c;
        }
        previous = ma;
    }
}

}  // namespace ag::cpu

namespace ag::cpu {

// A sun's caustic photons: parallel light at 45° onto a mirror floor is reflected onto a ceiling
// panel beside the beam that the sun itself cannot light (it faces down). The panel's irradiance
// is E cos 45°, so photon mapping's caustic term is ρ/π · E/√2 there; direct light is zero.
TEST(Reference, SunCausticsFromAMirrorMatchTheReflectedIrradiance) {
    const float irradiance = 4.0f, albedo = 0.5f;
    Scene scene;
    scene.path = "sun_mirror";
    scene.objects.push_back(quad_object("mirror", 2.0f, 0.0f, false, MaterialType::mirror, 1.0f));
    Object panel = quad_object("panel", 2.0f, 2.0f, true, MaterialType::diffuse, albedo);
    panel.transform.translation.x = 2.0f;
    scene.objects.push_back(panel);
    Light sun;
    sun.name = "sun";
    sun.type = LightType::sun;
    sun.direction = glm::normalize(glm::vec3(1.0f, -1.0f, 0.0f));
    sun.irradiance = glm::vec3(irradiance);
    scene.lights.push_back(sun);
    update_sun_discs(scene);
    scene.camera =
        looking_at({2.0f, 0.5f, 0.0f}, {2.0f, 2.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, 40.0f, 16);

    ReferenceSettings settings = pm(2, 1000, 1);
    settings.caustic_photons = 400000;
    settings.caustic_knn = 100;
    const ReferenceResult photons = render(scene, settings);
    const float expected = albedo / std::numbers::pi_v<float> * irradiance / std::sqrt(2.0f);
    EXPECT_NEAR(image_mean(photons.components[size_t(FrameTerm::caustics)]).r, expected,
                0.03f * expected);
    EXPECT_EQ(image_mean(photons.components[size_t(FrameTerm::direct)]), glm::vec3(0.0f));
}

}  // namespace ag::cpu

namespace ag::cpu {

namespace {

// A point light at (0, 1, 0) over a diffuse floor (y = 0, albedo 0.5) with a 1 × 1 vertical mirror
// beside it in the plane x = 1 (y in [0, 1], z in [−0.5, 0.5]), the camera looking down at the
// floor between them. The mirror shows the light's image at (2, 1, 0): the floor's caustic is
// ρ/π · I cosθ' / d'² from that virtual light wherever the line to it crosses the mirror.
Scene mirror_beside_light(float intensity) {
    Scene scene;
    scene.path = "mirror_beside_light";
    scene.objects.push_back(quad_object("floor", 4.0f, 0.0f, false, MaterialType::diffuse, 0.5f));
    Object mirror = quad_object("mirror", 1.0f, 0.0f, false, MaterialType::mirror, 1.0f);
    // The quad's normal +y turned to −x, then lifted so it spans y in [0, 1].
    mirror.transform.rotation =
        glm::angleAxis(0.5f * std::numbers::pi_v<float>, glm::vec3(0.0f, 0.0f, 1.0f));
    mirror.transform.translation = {1.0f, 0.5f, 0.0f};
    scene.objects.push_back(mirror);
    Light lamp;
    lamp.name = "lamp";
    lamp.position = {0.0f, 1.0f, 0.0f};
    lamp.intensity = glm::vec3(intensity);
    scene.lights.push_back(lamp);
    scene.camera =
        looking_at({0.2f, 3.0f, 0.0f}, {0.2f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, 30.0f, 12);
    return scene;
}

float mirror_caustic(const glm::vec3& p, float intensity) {
    const glm::vec3 image(2.0f, 1.0f, 0.0f);
    if (!(p.x < 1.0f)) return 0.0f;
    const float t = (1.0f - p.x) / (image.x - p.x);
    const glm::vec3 q = p + t * (image - p);
    if (q.y < 0.0f || q.y > 1.0f || std::abs(q.z) > 0.5f) return 0.0f;
    return point_lit_radiance(p, {0.0f, 1.0f, 0.0f}, image, intensity, 0.5f);
}

// The box-filtered caustic over pixel (x, y) by 32 × 32 subsamples (the mirror's edges cross
// pixels); where the camera ray meets the mirror first, the pixel shows the mirror, not the floor.
float mirror_caustic_pixel(const Camera& camera, int x, int y, float intensity) {
    constexpr int kSub = 32;
    double sum = 0.0;
    for (int j = 0; j < kSub; ++j)
        for (int i = 0; i < kSub; ++i) {
            const glm::vec3 d =
                camera_ray_direction(camera, float(x) + (float(i) + 0.5f) / float(kSub),
                                     float(y) + (float(j) + 0.5f) / float(kSub));
            const float t_floor = -camera.eye.y / d.y;
            if (d.x > 0.0f) {
                const float t_mirror = (1.0f - camera.eye.x) / d.x;
                const glm::vec3 m = camera.eye + t_mirror * d;
                if (t_mirror < t_floor && m.y >= 0.0f && m.y <= 1.0f && std::abs(m.z) <= 0.5f)
                    continue;
            }
            sum += mirror_caustic(camera.eye + t_floor * d, intensity);
        }
    return float(sum / double(kSub * kSub));
}

}  // namespace

// Light tracing completes the path tracer for delta lights through delta BSDFs: every pixel's
// caustic matches the mirror image's analytic radiance (box-filtered over the pixel) within its
// noise, and the image mean within 0.5% (without light tracing the caustic term is empty).
TEST(Reference, PointLightCausticsThroughAMirrorMatchTheVirtualLight) {
    const float intensity = 2.0f;
    const Scene scene = mirror_beside_light(intensity);
    const Camera& camera = scene.camera;
    ReferenceSettings settings = pt(64);
    settings.light_paths = 4000;
    const ReferenceResult r = render(scene, settings);
    const Image& caustics = r.components[size_t(FrameTerm::caustics)];
    double sum = 0.0, expected_sum = 0.0, worst = 0.0;
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const float expected = mirror_caustic_pixel(camera, x, y, intensity);
            const float got = caustics.rgb(x, y).r;
            sum += got;
            expected_sum += expected;
            worst = std::max(worst, double(std::abs(got - expected)) / (expected + 0.01));
        }
    std::printf(
        "mirror caustic: mean %.5f, analytic %.5f; worst pixel |error| / (value + 0.01) "
        "%.4f\n",
        sum / (camera.width * camera.height), expected_sum / (camera.width * camera.height), worst);
    EXPECT_GT(expected_sum, 0.0);
    // Measured over seeds 1-6: the mean within 0.03%, the worst pixel 0.025-0.037.
    EXPECT_NEAR(sum, expected_sum, 0.005 * expected_sum);
    EXPECT_LT(worst, 0.06);

    settings.light_tracing = false;
    EXPECT_EQ(image_mean(render(scene, settings).components[size_t(FrameTerm::caustics)]),
              glm::vec3(0.0f));
}

}  // namespace ag::cpu

namespace ag::cpu {

// The caustics scene (a glass ball under the lamp) lit by a small downward quad light, which the
// path tracer finds through the glass by itself (rays leaving a specular vertex meet the quad),
// against a spot light at its centre with the same intensity L·A cosθ (inner cone 0°, outer 90°:
// a linear falloff in cosθ is exactly the quad's Lambertian lobe), whose light through the glass
// only light tracing finds. Measured at 16², quad 8192 spp on seeds 1-3 against the spot at
// 512 spp: caustics 1.32 / 1.23 / 0.93, indirect 1.003 / 1.035 / 1.098 (the quad's caustics
// through a lens are heavy-tailed for the path tracer); without light tracing the spot's
// caustics are 0 and its indirect light 0.665 of what it is with.
TEST(Reference, LightTracingOfASpotMatchesPathTracingOfASmallQuad) {
    Scene scene = load_scene(test::scene_path("caustics.json"));
    scene.camera.width = scene.camera.height = 16;
    const Light lamp = scene.lights.at(0);
    const float side = 20.0f, h = 0.5f * side;
    const glm::vec3 c = lamp.position;
    Light quad;
    quad.name = "panel";
    quad.type = LightType::quad;
    quad.corners = {c + glm::vec3(-h, 0.0f, -h), c + glm::vec3(h, 0.0f, -h),
                    c + glm::vec3(h, 0.0f, h), c + glm::vec3(-h, 0.0f, h)};
    quad.radiance = lamp.intensity / (side * side);
    Light spot;
    spot.name = "spot";
    spot.type = LightType::spot;
    spot.position = c;
    spot.direction = {0.0f, -1.0f, 0.0f};
    spot.cone_inner = 0.0f;
    spot.cone_outer = 90.0f;
    spot.intensity = lamp.intensity;
    Scene with_quad = scene, with_spot = scene;
    with_quad.lights = {quad};
    with_spot.lights = {spot};

    ReferenceSettings quad_settings = pt(8192);
    quad_settings.seed = 2;
    const ReferenceResult a = render(with_quad, quad_settings);
    const ReferenceResult b = render(with_spot, pt(512));
    for (FrameTerm t : {FrameTerm::caustics, FrameTerm::indirect}) {
        const glm::vec3 ma = image_mean(a.components[size_t(t)]);
        const glm::vec3 mb = image_mean(b.components[size_t(t)]);
        std::printf("%s: quad (%.5f %.5f %.5f), spot (%.5f %.5f %.5f)\n", frame_term_name(t), ma.x,
                    ma.y, ma.z, mb.x, mb.y, mb.z);
        const float tolerance = t == FrameTerm::caustics ? 0.4f : 0.12f;
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(mb[k], ma[k], tolerance * ma[k]) << frame_term_name(t) << " " << k;
    }
}

}  // namespace ag::cpu
