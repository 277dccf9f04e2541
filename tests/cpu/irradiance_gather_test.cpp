// Irradiance cache records by ray casting (Gautron 2006 §4.4; Ward & Heckbert 1992): E/π against
// the analytic form factor, the harmonic mean distance of a point under a plane, and the rotation
// and translation gradients against finite differences of the exact irradiance.
#include "cpu/irradiance_gather.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/quaternion.hpp>
#include <numbers>

#include "gather_scenes.h"

namespace ag::cpu {

namespace {

using test::atlas_index;
using test::atlas_values;
using test::finish;
using test::kFacingDown;
using test::quad_object;

// A floor of side 6 at y = 0 and a square emitter of side 2·kHalf at height 1, centred at
// kEmitterCentre and facing down, with AIM radiance 1.
constexpr float kHalf = 0.5f;
const glm::vec3 kEmitterCentre(0.7f, 1.0f, 0.2f);

struct EmitterScene {
    Scene scene;
    std::vector<glm::vec3> aim;
    EmitterScene() {
        Scene s;
        s.path = "emitter over floor";
        s.objects.push_back(quad_object("floor", 6.0f, glm::vec3(0.0f)));
        s.objects.push_back(quad_object("emitter", 2.0f * kHalf, kEmitterCentre, kFacingDown));
        scene = finish(s, 0.25f);
        aim = atlas_values(scene);
        for (const TexelRecord& t : scene.atlas.texels)
            if (t.object == 1) aim[atlas_index(scene.atlas, t)] = glm::vec3(1.0f);
    }
};

// E/π at (p, n) from the emitter by midpoint quadrature over its area: (1/π) ∫ L cos θ cos θ' / r².
double exact_iim(const glm::vec3& p, const glm::vec3& n, const glm::vec3& centre = kEmitterCentre) {
    constexpr int kSteps = 600;
    const double step = 2.0 * kHalf / kSteps;
    double sum = 0.0;
    for (int j = 0; j < kSteps; ++j)
        for (int i = 0; i < kSteps; ++i) {
            const glm::dvec3 q(centre.x - kHalf + (i + 0.5) * step, centre.y,
                               centre.z - kHalf + (j + 0.5) * step);
            const glm::dvec3 d = q - glm::dvec3(p);
            const double r2 = glm::dot(d, d), r = std::sqrt(r2);
            const double cos_p = std::max(0.0, glm::dot(glm::dvec3(n), d) / r);
            const double cos_q = d.y / r;  // the emitter faces down
            sum += cos_p * cos_q / r2;
        }
    return sum * step * step / std::numbers::pi;
}

RecordGatherOptions fine() {
    RecordGatherOptions o;
    o.theta = 48;
    o.phi = 192;
    return o;
}

}  // namespace

TEST(IrradianceGather, IrradianceAndHarmonicDistanceUnderAnEmitter) {
    EmitterScene e;
    RayTracer rays(e.scene);
    ThreadPool pool(2);
    IrradianceGather gather(e.scene, rays, pool);
    const glm::vec3 p(0.1f, 0.0f, -0.1f), n(0.0f, 1.0f, 0.0f);
    const IrradianceRecord r =
        gather.gather_one({p, n, 3}, aim_radiance_source(e.scene, e.aim), fine());
    EXPECT_NEAR(r.iim.x, exact_iim(p, n), 0.01 * exact_iim(p, n));
    // Only the emitter is above the floor: the rays that hit it are at 1/cos θ; the harmonic mean
    // over all strata counts misses as infinitely far, so R_k ≥ the emitter's height.
    EXPECT_GT(r.harmonic_distance, 1.0f);
    EXPECT_EQ(gather.stats().rays, 0u);  // gather_one keeps no statistics
}

TEST(IrradianceGather, RotationGradientMatchesFiniteDifferences) {
    EmitterScene e;
    RayTracer rays(e.scene);
    ThreadPool pool(2);
    IrradianceGather gather(e.scene, rays, pool);
    const glm::vec3 p(-0.2f, 0.0f, 0.3f), n(0.0f, 1.0f, 0.0f);
    const IrradianceRecord r =
        gather.gather_one({p, n, 11}, aim_radiance_source(e.scene, e.aim), fine());
    const float delta = 0.02f;
    glm::vec3 fd(0.0f);
    for (const glm::vec3 axis : {glm::vec3(1, 0, 0), glm::vec3(0, 0, 1)}) {
        const glm::vec3 plus = glm::angleAxis(delta, axis) * n,
                        minus = glm::angleAxis(-delta, axis) * n;
        // d E / d angle about `axis` is the component of ∇_r along it: (n × n') = δ·axis.
        fd += axis * float((exact_iim(p, plus) - exact_iim(p, minus)) / (2.0 * delta));
    }
    const glm::vec3 got = r.rotation_gradient[0];
    ASSERT_GT(glm::length(fd), 0.0f);
    EXPECT_LT(glm::length(got - fd), 0.1f * glm::length(fd))
        << got.x << " " << got.y << " " << got.z << " vs " << fd.x << " " << fd.y << " " << fd.z;
}

TEST(IrradianceGather, TranslationGradientMatchesFiniteDifferences) {
    EmitterScene e;
    RayTracer rays(e.scene);
    ThreadPool pool(2);
    IrradianceGather gather(e.scene, rays, pool);
    for (const glm::vec3 p : {glm::vec3(-0.2f, 0.0f, 0.3f), glm::vec3(1.4f, 0.0f, -0.5f)}) {
        const glm::vec3 n(0.0f, 1.0f, 0.0f);
        const IrradianceRecord r =
            gather.gather_one({p, n, 5}, aim_radiance_source(e.scene, e.aim), fine());
        const float delta = 0.01f;
        glm::vec3 fd(0.0f);
        for (const glm::vec3 axis : {glm::vec3(1, 0, 0), glm::vec3(0, 0, 1)})
            fd += axis * float((exact_iim(p + delta * axis, n) - exact_iim(p - delta * axis, n)) /
                               (2.0 * delta));
        const glm::vec3 got = r.translation_gradient[0];
        ASSERT_GT(glm::length(fd), 0.0f);
        EXPECT_LT(glm::length(got - fd), 0.1f * glm::length(fd))
            << got.x << " " << got.y << " " << got.z << " vs " << fd.x << " " << fd.y << " "
            << fd.z;
    }
}

// Without gradients the extrapolation is flat; with them a record predicts its neighbours'
// irradiance better than its own value does (the point of gradients, Ward & Heckbert 1992).
TEST(IrradianceGather, GradientsImproveTheExtrapolation) {
    EmitterScene e;
    RayTracer rays(e.scene);
    ThreadPool pool(2);
    IrradianceGather gather(e.scene, rays, pool);
    const glm::vec3 p(0.0f, 0.0f, 0.0f), n(0.0f, 1.0f, 0.0f);
    const IrradianceRecord r =
        gather.gather_one({p, n, 7}, aim_radiance_source(e.scene, e.aim), fine());
    double flat = 0.0, extrapolated = 0.0;
    for (const glm::vec3 q :
         {glm::vec3(0.1f, 0, 0), glm::vec3(-0.1f, 0, 0.05f), glm::vec3(0.05f, 0, -0.1f)}) {
        const double truth = exact_iim(q, n);
        flat += std::abs(r.iim.x - truth);
        extrapolated += std::abs(extrapolate(r, q, n).x - truth);
    }
    EXPECT_LT(extrapolated, 0.5 * flat);
}

// Gautron §5.2.4: the next frame's irradiance from the record's own samples moved with their
// objects; a still scene reprojects to itself (τ = 1, the longest life).
TEST(IrradianceGather, ReprojectionFollowsAMovingEmitter) {
    EmitterScene e;
    RayTracer rays(e.scene);
    ThreadPool pool(2);
    IrradianceGather gather(e.scene, rays, pool);
    RecordGatherOptions o;
    o.theta = 16;
    o.phi = 64;
    const glm::vec3 p(-0.3f, 0.0f, 0.1f), n(0.0f, 1.0f, 0.0f);
    std::vector<RecordSample> samples;
    const IrradianceRecord r =
        gather.gather_one({p, n, 9}, aim_radiance_source(e.scene, e.aim), o, &samples);
    std::vector<Transform> now, next;
    for (const Object& obj : e.scene.objects) now.push_back(obj.transform);
    EXPECT_EQ(reproject_record(r, samples, now, now, o.theta, o.phi), r.iim);
    EXPECT_EQ(record_lifespan(r.iim, r.iim, 0.05f, 20), 20);
    next = now;
    const glm::vec3 shift(-0.1f, 0.0f, 0.0f);  // a frame's move, closer to overhead
    next[1].translation += shift;
    const float moved = reproject_record(r, samples, now, next, o.theta, o.phi).x;
    const double truth = exact_iim(p, n, kEmitterCentre + shift);
    ASSERT_GT(truth, 1.1 * r.iim.x);  // a real change
    EXPECT_NEAR(moved, truth, 0.05 * truth);
    EXPECT_LT(record_lifespan(r.iim, glm::vec3(moved), 0.05f, 20), 2);
}

// Gautron §5.2.4 with the hits shaded again at t+1: a record under a ceiling sees a floor lit by
// a point light that moves; the reprojection that shades the hits with the next frame's light
// predicts the gather at t+1 (same strata), the one that carries each hit's radiance does not.
// Fails if the re-shading is dropped, uses this frame's light or maps the normals wrongly.
TEST(IrradianceGather, ReprojectionShadesAgainForAMovingLight) {
    Scene s;
    s.path = "point light over a floor";
    s.objects.push_back(quad_object("floor", 6.0f, glm::vec3(0.0f)));
    s.objects.push_back(quad_object("ceiling", 6.0f, glm::vec3(0.0f, 1.0f, 0.0f), kFacingDown));
    Light lamp;
    lamp.name = "lamp";
    lamp.type = LightType::point;
    lamp.position = glm::vec3(0.4f, 0.5f, 0.0f);
    lamp.intensity = glm::vec3(1.0f);
    s.lights.push_back(lamp);
    const Scene scene = finish(s, 0.5f);
    Scene next_scene = scene;
    next_scene.lights[0].position += glm::vec3(-0.15f, 0.0f, 0.1f);  // a frame's move

    RayTracer rays(scene);
    ThreadPool pool(1);
    IrradianceGather gather(scene, rays, pool);
    RecordGatherOptions o;
    o.theta = 16;
    o.phi = 64;
    const GatherPoint at{glm::vec3(0.1f, 1.0f, 0.2f), glm::vec3(0.0f, -1.0f, 0.0f), 5};
    std::vector<RecordSample> samples;
    const IrradianceRecord r =
        gather.gather_one(at, direct_radiance_source(scene, rays, 1), o, &samples);
    const IrradianceRecord truth =
        gather.gather_one(at, direct_radiance_source(next_scene, rays, 1), o);
    ASSERT_GT(std::abs(truth.iim.x - r.iim.x), 0.05f * truth.iim.x);  // a real change

    std::vector<Transform> now;
    for (const Object& obj : scene.objects) now.push_back(obj.transform);
    const RecordRadiance next_radiance = direct_radiance_source(next_scene, rays, 1);
    const glm::vec3 shaded = reproject_record(r, samples, now, now, o.theta, o.phi, &next_radiance);
    const glm::vec3 carried = reproject_record(r, samples, now, now, o.theta, o.phi);
    EXPECT_NEAR(shaded.x, truth.iim.x, 0.005f * truth.iim.x);
    EXPECT_NEAR(carried.x, r.iim.x, 1e-5f * r.iim.x);  // the same sum in another order
    // τ from the shaded prediction shortens the life as the light's move demands.
    EXPECT_NEAR(record_lifespan(r.iim, shaded, 0.05f, 20),
                record_lifespan(r.iim, truth.iim, 0.05f, 20), 1);
    EXPECT_LT(record_lifespan(r.iim, shaded, 0.05f, 20), 20);
}

}  // namespace ag::cpu
