// Caustic photons (Larsen ch. 12): a ball lens focuses, a moving lens leaves a bounded trail.
#include "cpu/caustic_tracer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "ball_lens.h"
#include "cpu/photon_tracer.h"
#include "test_scenes.h"

namespace ag::cpu {

namespace {

// A glass ball (radius 1, IOR 1.5) at the origin under a distant point light, and a receiving
// plane `depth` below the ball's centre.
Scene ball_lens(float depth) {
    Scene s;
    s.path = "ball_lens";
    Object ball;
    ball.name = "ball";
    ball.mesh = make_sphere(1.0f, 5);
    ball.material.type = MaterialType::glass;
    ball.material.ior = 1.5f;
    ball.dynamic = true;
    s.objects.push_back(ball);
    Object plane;
    plane.name = "plane";
    plane.mesh = make_quad(20.0f, 20.0f);
    plane.transform.translation = {0.0f, -depth, 0.0f};
    s.objects.push_back(plane);
    Light l;
    l.name = "sun";
    l.position = {0.0f, 2000.0f, 0.0f};
    l.intensity = glm::vec3(1e6f);
    s.lights.push_back(l);
    s.settings.caustics.photons = 20000;
    s.settings.lightmap.texel_size = 2.0f;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

struct Spot {
    glm::vec2 centre{0.0f};
    float r50 = 0.0f;   // radius holding half the caustic's power
    double peak = 0.0;  // power within 0.03 of the axis
};

Spot measure(const std::vector<CausticPhoton>& photons) {
    std::vector<std::pair<float, float>> radial;  // (radius, power)
    glm::dvec2 centre(0.0);
    double total = 0.0, peak = 0.0;
    for (const CausticPhoton& p : photons) {
        if (p.power == glm::vec3(0.0f)) continue;
        const float r = std::hypot(p.position.x, p.position.z);
        radial.emplace_back(r, p.power.x);
        centre += double(p.power.x) * glm::dvec2(p.position.x, p.position.z);
        total += p.power.x;
        if (r < 0.03f) peak += p.power.x;
    }
    std::sort(radial.begin(), radial.end());
    Spot s;
    s.centre = glm::vec2(centre / std::max(total, 1e-30));
    double acc = 0.0;
    for (const auto& [r, w] : radial)
        if ((acc += w) >= 0.5 * total) {
            s.r50 = r;
            break;
        }
    s.peak = peak;
    return s;
}

}  // namespace

TEST(CausticTracer, BallLensFocusesNearTheParaxialFocus) {
    const float n = 1.5f, r = 1.0f, f = n * r / (2.0f * (n - 1.0f));  // 1.5 R from the centre
    ThreadPool pool(2);
    Spot spots[3];
    const float depths[3] = {0.5f * f, f, 1.5f * f};
    for (int i = 0; i < 3; ++i) {
        const Scene scene = ball_lens(depths[i]);
        CausticTracer tracer(scene, pool);
        const CausticStats st = tracer.trace_all();
        EXPECT_GE(st.hit_specular,
                  st.traced * 999 / 1000);  // aimed at the ball (its bound is a bit larger)
        EXPECT_GT(st.stored, st.traced / 2);
        spots[i] = measure(tracer.photons());
        EXPECT_LT(glm::length(spots[i].centre), 0.02f)
            << "centred below the ball, depth " << depths[i];
        std::printf("depth %.2f: r50 %.4f, power within 0.03 of the axis %.3g\n", double(depths[i]),
                    double(spots[i].r50), spots[i].peak);
    }
    EXPECT_LT(spots[1].r50, spots[0].r50);
    EXPECT_LT(spots[1].r50, spots[2].r50);
    EXPECT_GT(spots[1].peak, spots[0].peak);
    EXPECT_GT(spots[1].peak, spots[2].peak);
}

// Traces 100,000 caustic photons in `scene` (a ball lens over the plane y = 0) and holds their
// power on the plane and the spot's radii around the axis to the exact sphere's.
void expect_spot_matches(Scene scene, const test::CausticSpot& exact, const char* light) {
    scene.settings.caustics.photons = 100000;
    ThreadPool pool(2);
    CausticTracer tracer(scene, pool);
    tracer.trace_all();
    test::RadialPower photons;
    for (const CausticPhoton& p : tracer.photons())
        if (p.power != glm::vec3(0.0f))
            photons.emplace_back(std::hypot(double(p.position.x), double(p.position.z)),
                                 double(p.power.x));
    const test::CausticSpot got = test::spot_of(photons);
    std::printf("%s: power %.4f (exact %.4f), r50 %.4f (%.4f), r90 %.4f (%.4f)\n", light, got.power,
                exact.power, got.r50, exact.r50, got.r90, exact.r90);
    EXPECT_NEAR(got.power / exact.power, 1.0, 0.02);
    EXPECT_NEAR(got.r50 / exact.r50, 1.0, 0.10);
    EXPECT_NEAR(got.r90 / exact.r90, 1.0, 0.10);
}

// Against the exact ball lens (tests/cpu/ball_lens.h): the photons' total power on the plane
// (transmission with Fresnel losses at both interfaces, internal and external reflections) and
// the spot's radii at the paraxial focus. The tracer sees an icosphere of 20,480 flat facets.
TEST(CausticTracer, BallLensPowerAndSpotMatchTheExactSphere) {
    test::BallLens lens;
    const double focus = lens.paraxial_image_distance();
    lens.centre_height = focus;  // the plane at the paraxial focus
    const test::CausticSpot exact = test::spot_of(test::exact_caustic(lens, 200000));
    expect_spot_matches(test::ball_lens_scene(lens, 5), exact, "point");
}

// A sun's caustic photons leave a disc across its direction over each specular object: a ball lens
// under a vertical sun, the plane at the focus f = nR / 2(n − 1), against the exact sphere.
TEST(CausticTracer, SunBallLensPowerAndSpotMatchTheExactSphere) {
    test::BallLens lens;
    const double irradiance = 50.0;
    lens.centre_height = lens.ior * lens.radius / (2.0 * (lens.ior - 1.0));
    const test::CausticSpot exact =
        test::spot_of(test::exact_sun_caustic(lens, irradiance, 200000));
    expect_spot_matches(test::sun_ball_lens_scene(lens, 5, irradiance), exact, "sun");
}

TEST(CausticTracer, OnlySpecularPathsAreStoredAndPowerIsConserved) {
    const Scene scene = ball_lens(1.5f);
    ThreadPool pool(2);
    CausticTracer tracer(scene, pool);
    tracer.trace_all();
    // All stored photons lie on the plane and face up; total power ≤ the flux into the cone.
    double total = 0.0;
    for (const CausticPhoton& p : tracer.photons()) {
        if (p.power == glm::vec3(0.0f)) continue;
        EXPECT_NEAR(p.position.y, -1.5f, 1e-3f);
        EXPECT_GT(p.normal.y, 0.99f);
        total += p.power.x;
    }
    const double d = 2000.0, cone = 2.0 * std::numbers::pi * (1.0 - std::sqrt(1.0 - 1.0 / (d * d)));
    EXPECT_LE(total, 1e6 * cone * 1.0001);
    EXPECT_GT(total, 0.8 * 1e6 * cone);  // glass passes most light (Fresnel losses ~ 10%)
}

TEST(CausticTracer, MovingTheLensLeavesAtMostAnNFrameTrail) {
    Scene scene = load_scene(test::scene_path("cornell.json"));
    ThreadPool pool(2);
    CausticTracer tracer(scene, pool);
    const int frames = scene.settings.caustics.frames;
    for (int f = 0; f < frames; ++f) tracer.frame();
    const int sphere = scene.find_object("sphere");
    ASSERT_GE(sphere, 0);
    translate_object(scene, sphere, {-40.0f, 0.0f, 30.0f});
    const uint32_t moved_at = tracer.frame_index();
    tracer.frame();
    bool old_left = false;
    for (const CausticPhoton& p : tracer.photons())
        if (p.power != glm::vec3(0.0f) && p.frame <= moved_at) old_left = true;
    EXPECT_TRUE(old_left);  // a trail while the slices catch up
    for (int f = 1; f < frames; ++f) tracer.frame();
    int stored = 0;
    for (const CausticPhoton& p : tracer.photons()) {
        if (p.power == glm::vec3(0.0f)) continue;
        ++stored;
        EXPECT_GT(p.frame, moved_at)
            << "a photon from before the move survived " << frames << " frames";
    }
    EXPECT_GT(stored, 100);
}

TEST(CausticTracer, IndependentOfThreadCount) {
    const Scene scene = load_scene(test::scene_path("cornell.json"));
    ThreadPool one(1), three(3);
    CausticTracer a(scene, one), b(scene, three);
    a.trace_all();
    b.trace_all();
    ASSERT_EQ(a.photons().size(), b.photons().size());
    for (size_t i = 0; i < a.photons().size(); ++i) {
        EXPECT_EQ(a.photons()[i].position, b.photons()[i].position);
        EXPECT_EQ(a.photons()[i].power, b.photons()[i].power);
    }
}

}  // namespace ag::cpu

namespace ag::cpu {

namespace {

// The fog tests' lamp of intensity 100 at `lamp` and, with `fog`, a box of fog 20 units across
// around the origin (σ_s 0.1, σ_a 0.05: σ_t 0.15).
void add_lamp_and_fog(Scene& s, glm::vec3 lamp, bool fog) {
    Light l;
    l.name = "lamp";
    l.position = lamp;
    l.intensity = glm::vec3(100.0f);
    s.lights.push_back(l);
    if (!fog) return;
    Medium m;
    m.bounds.min = glm::vec3(-10.0f);
    m.bounds.max = glm::vec3(10.0f);
    m.sigma_s = 0.1f;
    m.sigma_a = 0.05f;
    s.media.push_back(m);
}

}  // namespace

// Caustic photons through fog (Pfeuti's surface caustic seen through the medium): a light beside
// a vertical mirror, the caustic on the floor, all in a fog box. Each photon's path light →
// mirror → floor is as long as the straight line from the light's mirror image to where it lands,
// so the photon arrives with exp(−σ_t |p − L'|) of its power without fog, photon by photon (same
// QMC index, same path). Fails if the photons ignore the fog, attenuate only one segment or use σ_s
// for σ_t.
TEST(CausticTracer, PhotonsThroughFogLoseBeerLambert) {
    const glm::vec3 lamp(3.0f, 2.5f, 0.0f), image(-3.0f, 2.5f, 0.0f);
    const auto scene = [&](bool fog) {
        Scene s;
        s.path = "mirror_in_fog";
        Object mirror;
        mirror.name = "mirror";
        mirror.mesh = make_quad(4.0f, 4.0f);  // normal +y, turned to +x
        mirror.material.type = MaterialType::mirror;
        mirror.material.albedo = glm::vec3(1.0f);
        mirror.transform.rotation = glm::angleAxis(glm::radians(-90.0f), glm::vec3(0, 0, 1));
        mirror.transform.translation = {0.0f, 2.0f, 0.0f};
        s.objects.push_back(mirror);
        Object floor;
        floor.name = "floor";
        floor.mesh = make_quad(20.0f, 20.0f);
        s.objects.push_back(floor);
        add_lamp_and_fog(s, lamp, fog);
        s.settings.caustics.photons = 8000;
        s.settings.lightmap.texel_size = 2.0f;
        init_versions(s);
        make_surfaces_and_atlas(s);
        return s;
    };
    ThreadPool pool(2);
    const Scene clear = scene(false), foggy = scene(true);
    CausticTracer clear_tracer(clear, pool), fog_tracer(foggy, pool);
    clear_tracer.trace_all();
    fog_tracer.trace_all();
    int compared = 0;
    double worst = 0.0;
    for (size_t i = 0; i < clear_tracer.photons().size(); ++i) {
        const CausticPhoton &a = clear_tracer.photons()[i], &b = fog_tracer.photons()[i];
        ASSERT_EQ(a.power == glm::vec3(0.0f), b.power == glm::vec3(0.0f)) << "photon " << i;
        if (a.power == glm::vec3(0.0f)) continue;
        ASSERT_EQ(a.position, b.position);
        const double expected = std::exp(-0.15 * double(glm::length(b.position - image)));
        worst = std::max(worst, std::abs(double(b.power.x) / double(a.power.x) / expected - 1.0));
        ++compared;
    }
    std::printf("%d caustic photons through fog: worst relative error %.2g\n", compared, worst);
    EXPECT_GT(compared, 500);
    EXPECT_LT(worst, 1e-4);
}

// The photon tracer's photons (the AIM's and so the frame's indirect term) lose Beer–Lambert
// through the media as the caustic photons do, and keep their paths: a lamp in a fog box (σ_t
// 0.15) over a white floor and wall. Every vertex of every path is where it is without fog, and
// carries exp(−σ_t × the length of the path up to it) of its power without fog, bounced photons
// included (Russian roulette draws the same numbers). Fails if the tracer ignores the fog (the
// ratio is 1, the error up to 1 − e^{−0.15 · 12}).
TEST(PhotonTracerMedia, PhotonsThroughFogLoseBeerLambertAlongTheirPaths) {
    const glm::vec3 lamp(0.0f, 2.5f, 0.0f);
    const auto scene = [&](bool fog) {
        Scene s;
        s.path = "room_in_fog";
        Object floor;
        floor.name = "floor";
        floor.mesh = make_quad(6.0f, 6.0f);
        floor.material.albedo = glm::vec3(0.8f);
        s.objects.push_back(floor);
        Object wall;
        wall.name = "wall";
        wall.mesh = make_quad(6.0f, 6.0f);  // normal +y, turned to +x
        wall.material.albedo = glm::vec3(0.8f);
        wall.transform.rotation = glm::angleAxis(glm::radians(-90.0f), glm::vec3(0, 0, 1));
        wall.transform.translation = {-3.0f, 3.0f, 0.0f};
        s.objects.push_back(wall);
        add_lamp_and_fog(s, lamp, fog);
        s.settings.photons.groups = 64;
        s.settings.photons.photons_per_group = 64;
        s.settings.lightmap.texel_size = 1.0f;
        init_versions(s);
        make_surfaces_and_atlas(s);
        return s;
    };
    const Scene clear = scene(false), foggy = scene(true);
    const RayTracer clear_rays(clear), fog_rays(foggy);
    const PhotonTracer clear_tracer(clear, clear_rays), fog_tracer(foggy, fog_rays);
    int compared = 0, bounced = 0;
    double worst = 0.0;
    std::vector<TracedVertex> a, b;
    for (int g = 0; g < clear.settings.photons.groups; ++g)
        for (int i = 0; i < clear.settings.photons.photons_per_group; ++i) {
            a.clear();
            b.clear();
            clear_tracer.trace(0, g, i, a);
            fog_tracer.trace(0, g, i, b);
            ASSERT_EQ(a.size(), b.size()) << "group " << g << " photon " << i;
            double length = 0.0;
            glm::vec3 from = lamp;
            for (size_t v = 0; v < a.size(); ++v) {
                ASSERT_EQ(a[v].position, b[v].position);
                length += double(glm::length(b[v].position - from));
                from = b[v].position;
                const double expected = std::exp(-0.15 * length);
                worst = std::max(
                    worst, std::abs(double(b[v].power.x) / double(a[v].power.x) / expected - 1.0));
                ++compared;
                if (b[v].bounce > 0) ++bounced;
            }
        }
    std::printf("%d photon vertices through fog (%d bounced): worst relative error %.2g\n",
                compared, bounced, worst);
    EXPECT_GT(bounced, 200);
    EXPECT_LT(worst, 1e-4);
}

}  // namespace ag::cpu
