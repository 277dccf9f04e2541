// Irradiance cache records by ray casting (Gautron 2006 §4.4 with Ward & Heckbert 1992's
// stratified hemisphere): M × N cosine-weighted strata (sin²θ uniform in M rows, φ in N columns)
// about a point and normal give E/π, the harmonic mean distance R_k and the rotation and
// translation gradients. What the rays see is the record's source: the AIMs (all bounces,
// `rc.source: aim`) or the lights' direct light on the surfaces hit (one bounce, `direct`).
#pragma once

#include <functional>
#include <glm/glm.hpp>
#include <vector>

#include "cpu/ray_tracer.h"
#include "shared/gather.h"
#include "shared/irradiance_record.h"
#include "shared/parallel.h"
#include "shared/scene.h"

namespace ag::cpu {

// Outgoing radiance towards the gather point of what `hit` shows (front faces of diffuse surfaces).
using RecordRadiance = std::function<glm::vec3(const RayHit& hit)>;

// The two sources of settings.rc.source: the AIM radiance (atlas-sized) read where a ray lands, or
// albedo/π × the lights' direct irradiance there (`shadow_samples` shadow rays per area light).
RecordRadiance aim_radiance_source(const Scene& scene, const std::vector<glm::vec3>& aim);
RecordRadiance direct_radiance_source(const Scene& scene, const RayTracer& rays,
                                      int shadow_samples);

struct RecordGatherOptions {
    int theta = 8;              // M: strata in sin²θ
    int phi = 32;               // N: strata in φ
    float min_distance = 0.0f;  // R_k is clamped to [min, max] (Tabellion & Lamorlette 2004)
    float max_distance = 1e30f;
    uint32_t seed = 1;
};

// What one stratum's ray saw, kept for reprojection (Gautron §5.2.4): its radiance, distance and
// the hit in its object's own space (object −1: the ray left the scene).
struct RecordSample {
    glm::vec3 radiance{0.0f};
    float distance = 0.0f;
    int object = -1;
    glm::vec3 local{0.0f};
    glm::vec3 local_normal{0.0f};  // the hit's geometric normal, object space
    bool shaded = false;           // a diffuse front face (the source gave its radiance)
    int triangle = -1;             // for the albedo (texture) when shaded again
    glm::vec2 barycentric{0.0f};
};

struct RecordGatherStats {
    uint64_t rays = 0;
    int records = 0;
};

class IrradianceGather {
public:
    IrradianceGather(const Scene& scene, const RayTracer& rays, ThreadPool& pool);
    // One record per point (normal from the point), each with its own jitter from point.key.
    std::vector<IrradianceRecord> gather(const std::vector<GatherPoint>& points,
                                         const RecordRadiance& radiance,
                                         const RecordGatherOptions& options);
    // `samples`, if given, receives the M × N strata (index j·N + k).
    IrradianceRecord gather_one(const GatherPoint& point, const RecordRadiance& radiance,
                                const RecordGatherOptions& options,
                                std::vector<RecordSample>* samples = nullptr) const;
    const RecordGatherStats& stats() const { return stats_; }

private:
    const Scene& scene_;
    const RayTracer& rays_;
    ThreadPool& pool_;
    RecordGatherStats stats_;
};

// E(t0+1)/π of a record by reprojection (Gautron §5.2.4, the render cache of Walter et al.): each
// stratum's hit moves with its object from `now` to `next` (per object, this and the next frame's
// transforms; hits on objects that stay keep their stratum exactly) and
// carries its radiance; per stratum the nearest arrival wins; strata nothing lands in take the
// farthest of their neighbours (the background, Gautron's hole filling) or keep their own value.
// With `next_radiance` (the source at t0+1: the next frame's lights and materials) each moved
// hit is shaded again there, as Gautron's GPU reprojection shades the reprojected points at
// t+1 (§5.2.4), so a moving light's change is foreseen too; without it each keeps its radiance.
glm::vec3 reproject_record(const IrradianceRecord& record, const std::vector<RecordSample>& samples,
                           const std::vector<Transform>& now, const std::vector<Transform>& next,
                           int theta, int phi, const RecordRadiance* next_radiance = nullptr);

// Gautron eq. 5.5-5.8: the frames a record made now may live, min(δt_max, a^t / |τ − 1|) with
// τ = E(t0+1)/E(t0) on luminance, at least 1.
int record_lifespan(const glm::vec3& now, const glm::vec3& next, float temporal_accuracy,
                    int max_lifespan);

}  // namespace ag::cpu
