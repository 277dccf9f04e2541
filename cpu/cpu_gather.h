// Final gathering by ray casting (Larsen ch. 11), the CPU backend beside the GL hemi-plane
// gather: cosine-weighted QMC rays from a texel's centre read the AIMs where they land, giving
// the texel's indirect irradiance. IIM convention (both backends): iim = E_indirect / π, so a
// diffuse surface of albedo ρ reflects L_indirect = ρ · iim.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "cpu/ray_tracer.h"
#include "shared/parallel.h"
#include "shared/scene.h"

namespace ag::cpu {

struct CpuGatherStats {
    int texels = 0;     // texels gathered by the last call
    int invalid = 0;    // of those, repaired from neighbours (gather started inside geometry)
    uint64_t rays = 0;  // rays cast by the last call
};

class CpuGather {
public:
    // `rays` must reflect the scene's current transforms when gather() runs (the photon
    // simulation keeps its tracer up to date each frame).
    CpuGather(const Scene& scene, const RayTracer& rays, ThreadPool& pool);

    // Gathers the texels `texel_ids` (indices into scene.atlas.texels) with
    // settings.gather.cpu_rays rays each, reading `aim_radiance` (atlas-sized, as Aim::radiance())
    // and writing E/π into `iim` (atlas-sized) at those texels only. Texels whose rays see too
    // many back faces (kBackFaceInvalidFraction) are invalid and take the value of valid
    // neighbours of their chart (repair_invalid_texels). Deterministic for any thread count.
    void gather(const std::vector<int>& texel_ids, const std::vector<glm::vec3>& aim_radiance,
                std::vector<glm::vec3>& iim);

    // Per texel record: 1 if its latest gather was valid; 0 if invalid or never gathered. Only
    // valid texels serve as sources for repairs.
    const std::vector<char>& valid() const { return valid_; }
    const CpuGatherStats& last_stats() const { return stats_; }

private:
    struct TexelResult {
        glm::vec3 iim{0.0f};
        bool valid = false;
    };
    TexelResult gather_texel(int record, const std::vector<glm::vec3>& aim_radiance) const;

    const Scene& scene_;
    const RayTracer& rays_;
    ThreadPool& pool_;
    std::vector<glm::vec2> points_;  // unscrambled 2D Hammersley set, settings.gather.cpu_rays
    std::vector<char> valid_;
    CpuGatherStats stats_;
};

}  // namespace ag::cpu
