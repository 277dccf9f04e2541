// Final gathering by ray casting (Larsen ch. 11), the CPU backend beside the GL hemi-plane
// gather: cosine-weighted QMC rays from a texel's centre read the AIMs where they land, giving
// the texel's indirect irradiance. IIM convention (both backends): iim = E_indirect / π, so a
// diffuse surface of albedo ρ reflects L_indirect = ρ · iim.
#pragma once

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
    uint64_t rays = 0;  // rays cast by the last call
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
    // How much of the screen each texel record covers (gpu::TexelCoverage's measure, by rays):
    // one ray through each pixel centre of the scene's camera at `width` × `height`, counted by
    // add_lookup_coverage where it meets a lightmapped surface first. On llvmpipe the raster
    // pass costs what drawing the scene costs (bumpy_133k_box: 18 ms); the rays cost a
    // fraction of it. Sums in pixel order: the same on any thread count.
    std::vector<float> texel_coverage(int width, int height);

private:
    void prepare();  // brings the tracer and the point set up to date
    GatherResult gather_texel(int record, const std::vector<glm::vec3>& aim_radiance) const;
    GatherResult gather_point(const GatherPoint& point, glm::vec2 shift,
                              const std::vector<glm::vec3>& aim_radiance) const;
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
    CpuGatherStats stats_;
};

}  // namespace ag::cpu
