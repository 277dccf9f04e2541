// Final gathering by ray casting (Larsen ch. 11), the CPU backend beside the GL hemi-plane
// gather: cosine-weighted QMC rays from a texel's centre read the AIMs where they land, giving
// the texel's indirect irradiance. IIM convention (both backends): iim = E_indirect / π, so a
// diffuse surface of albedo ρ reflects L_indirect = ρ · iim.
#pragma once

#include <atomic>
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "cpu/ray_tracer.h"
#include "shared/gather.h"
#include "shared/parallel.h"
#include "shared/scene.h"

namespace ag::cpu {

struct CpuGatherStats {
    int texels = 0;     // texels gathered by the last call
    int invalid = 0;    // of those, with more back faces than kBackFaceInvalidFraction
    uint64_t rays = 0;  // gather rays of the last call
    // Of `rays`, those whose first hit came from the texel's ray cache instead of being traced.
    uint64_t rays_reused = 0;
};

class CpuGather final : public Gatherer {
public:
    // Casts rays with `rays`, which must reflect the scene's current transforms when gather()
    // runs. `aim` (atlas-sized, as Aim::radiance()) is what gather(texels) reads; it may be null
    // when only the two-argument form is used.
    CpuGather(const Scene& scene, const RayTracer& rays, ThreadPool& pool,
              const std::vector<glm::vec3>* aim = nullptr);
    // Owns its ray tracer and brings it up to date before every gather (the pipeline's photon
    // simulation updates its own tracer on the workers while the gather runs).
    CpuGather(const Scene& scene, ThreadPool& pool, const std::vector<glm::vec3>* aim);
    ~CpuGather() override;

    GatherBackend backend() const override { return GatherBackend::cpu; }
    std::vector<GatherResult> gather(const std::vector<int>& texels) override;
    // The same with an explicit AIM: settings.gather.cpu_rays cosine-distributed QMC rays per
    // texel (over the whole hemisphere, or through the hemi-plane: settings.gather.hemisphere)
    // read `aim_radiance` where they land, through settings.gather.specular_bounces mirror and
    // glass bounces.
    std::vector<GatherResult> gather(const std::vector<int>& texels,
                                     const std::vector<glm::vec3>& aim_radiance);
    // The same gather at arbitrary surface points (texel footprints, per-pixel gathering).
    std::vector<GatherResult> gather_points(const std::vector<GatherPoint>& points) override;
    std::vector<GatherResult> gather_points(const std::vector<GatherPoint>& points,
                                            const std::vector<glm::vec3>& aim_radiance);
    const CpuGatherStats& last_stats() const { return stats_; }
    // Rays and re-read rays of every gather(texels) call so far (texels and invalid unused).
    const CpuGatherStats& totals() const { return totals_; }
    // The ray cache (settings.gather.ray_cache_mb) on or off: the brute-force baselines trace
    // every ray, as recomputing everything does.
    void use_ray_cache(bool on) { ray_cache_allowed_ = on; }
    // How much of the screen each texel record covers (gpu::TexelCoverage's measure, by rays):
    // one ray through each pixel centre of the scene's camera at `width` × `height`, counted by
    // add_lookup_coverage where it meets a lightmapped surface first. On llvmpipe the raster
    // pass costs what drawing the scene costs (bumpy_133k_box: 18 ms); the rays cost a
    // fraction of it. Sums in pixel order: the same on any thread count.
    std::vector<float> texel_coverage(int width, int height);

private:
    // A gather ray's first hit as last traced (settings.gather.ray_cache_mb).
    struct CachedHit {
        float t = 0.0f;  // along the unit direction; +inf: the ray left the scene
        int32_t object = -1;
        int32_t triangle = -1;
        glm::vec2 barycentric{0.0f};
        bool back = false;  // the back of the triangle
    };
    // One texel record's cached rays, in the order of points_, and the move epoch they were
    // traced at (0: none).
    struct TexelRays {
        std::vector<CachedHit> hits;
        uint64_t epoch = 0;
    };

    void prepare();  // brings the tracer, the point set and the move log up to date
    // Notes objects whose transform changed since the last call (a new epoch each): a cached
    // ray stays valid while it neither hit an object moved since it was traced nor crosses such
    // an object's bounds where it is now.
    void track_moves();
    // `reused` (null: no cache) counts the rays read from the cache instead of traced.
    GatherResult gather_texel(int record, const std::vector<glm::vec3>& aim_radiance,
                              std::atomic<uint64_t>* reused);
    // Whether a cached hit traced at `epoch` is what tracing `ray` would find now.
    bool still_valid(const CachedHit& hit, const Ray& ray, uint64_t epoch) const;
    // `cache` (may be null): the texel's cached rays, re-read where still valid, re-traced and
    // stored where not. The sum runs in ray order either way, so it is the same to the bit.
    GatherResult gather_point(const GatherPoint& point, glm::vec2 shift,
                              const std::vector<glm::vec3>& aim_radiance,
                              TexelRays* cache = nullptr, uint64_t* reused = nullptr) const;
    // The radiance a ray brings from its first hit `hit`: AIM radiance at the front of a diffuse
    // surface, mirror and glass followed, nothing at a back face (which sets `back_face`).
    glm::vec3 radiance_at(const RayHit& hit, const Ray& ray,
                          const std::vector<glm::vec3>& aim_radiance, int bounces_left,
                          float weight, bool& back_face) const;
    // AIM radiance seen along `ray`, which carries `weight` of its gather ray, through up to
    // `bounces_left` mirror/glass bounces; sets `back_face` when the ray itself meets the back
    // of a diffuse surface.
    glm::vec3 radiance_along(const Ray& ray, const std::vector<glm::vec3>& aim_radiance,
                             int bounces_left, float weight, bool& back_face) const;
    // The same at `hit`, the first surface along `ray`, before the media on the way.
    glm::vec3 surface_radiance(const Ray& ray, const RayHit& hit,
                               const std::vector<glm::vec3>& aim_radiance, int bounces_left,
                               float weight, bool& back_face) const;

    const Scene& scene_;
    std::unique_ptr<RayTracer> own_rays_;
    const RayTracer& rays_;
    ThreadPool& pool_;
    const std::vector<glm::vec3>* aim_;
    std::vector<glm::vec2> points_;  // unscrambled 2D Hammersley set, settings.gather.cpu_rays
    CpuGatherStats stats_, totals_;
    // The ray cache: per texel record (empty when off), and the moves it is checked against.
    std::vector<TexelRays> cache_;
    std::vector<Transform> seen_transform_;  // per object, at the last track_moves()
    std::vector<uint64_t> moved_at_;         // per object: epoch of its last move (0: never)
    std::vector<Bounds> moved_to_;           // per object: world bounds after its last move
    std::vector<int> moved_objects_;         // objects with moved_at_ > 0
    uint64_t epoch_ = 1;
    bool ray_cache_allowed_ = true;
};

}  // namespace ag::cpu
