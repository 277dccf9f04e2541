#include "cpu/cpu_gather.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "cpu/sampling.h"
#include "shared/lightmap_sample.h"
#include "shared/qmc.h"

namespace ag::cpu {

namespace {

// A per-texel toroidal shift in [0, 1)² (Cranley–Patterson rotation): every texel gets its own
// deterministic randomisation of the same point set, so neighbouring texels do not share the
// same ray directions (structured error would show as patterns across the IIM).
glm::vec2 texel_shift(uint32_t seed, int record) {
    const uint32_t h0 = hash_u32(hash_u32(seed ^ 0x6a09e667u) ^ (uint32_t(record) * 0x9e3779b9u));
    const uint32_t h1 = hash_u32(h0 ^ 0xbb67ae85u);
    return glm::vec2(to_unit_float(h0), to_unit_float(h1));
}

float wrap(float x) { return x >= 1.0f ? x - 1.0f : x; }

}  // namespace

CpuGather::CpuGather(const Scene& scene, const RayTracer& rays, ThreadPool& pool,
                     const std::vector<glm::vec3>* aim)
    : scene_(scene), rays_(rays), pool_(pool), aim_(aim) {}

CpuGather::CpuGather(const Scene& scene, ThreadPool& pool, const std::vector<glm::vec3>* aim)
    : scene_(scene),
      own_rays_(std::make_unique<RayTracer>(scene)),
      rays_(*own_rays_),
      pool_(pool),
      aim_(aim) {}

CpuGather::~CpuGather() = default;

GatherResult CpuGather::gather_texel(int record, const std::vector<glm::vec3>& aim_radiance) const {
    const LightmapAtlas& atlas = scene_.atlas;
    const TexelRecord& texel = atlas.texels[size_t(record)];
    const Transform& transform = scene_.objects[size_t(texel.object)].transform;
    const glm::vec3 n = glm::normalize(transform.apply_vector(texel.normal));
    const glm::vec3 origin = transform.apply_point(texel.position) + rays_.epsilon() * n;
    glm::vec3 t, b;
    orthonormal_basis(n, t, b);
    const glm::vec2 shift = texel_shift(scene_.settings.seed, record);

    glm::vec3 sum(0.0f);
    int back_faces = 0;
    for (const glm::vec2& p : points_) {
        // The concentric map keeps the QMC points' strata compact, which matters at a few hundred
        // rays.
        const glm::vec3 d = square_to_cosine_hemisphere({wrap(p.x + shift.x), wrap(p.y + shift.y)});
        const glm::vec3 direction = d.x * t + d.y * b + d.z * n;
        const RayHit hit = rays_.intersect({origin, direction, 0.0f, 1e30f});
        if (!hit.hit) continue;
        // Mirrors and glass have no AIM: light reaching the texel through them (L D S x paths)
        // is not in the IIM; caustics (ch. 12) and the frame's reflections carry those.
        if (scene_.objects[size_t(hit.object)].material.type != MaterialType::diffuse) continue;
        // A diffuse back face reflects nothing (photons reaching it are absorbed); seeing many
        // means the texel's centre is inside or behind geometry.
        if (glm::dot(direction, hit.normal) > 0.0f) {
            ++back_faces;
            continue;
        }
        sum += sample_lightmap(atlas, aim_radiance, hit.object, hit.triangle, hit.barycentric);
    }
    // Cosine-weighted directions make E = π · mean(L) (eq. 11.1); the IIM holds E / π.
    GatherResult result;
    result.iim = sum / float(points_.size());
    result.back_fraction = float(back_faces) / float(points_.size());
    return result;
}

std::vector<GatherResult> CpuGather::gather(const std::vector<int>& texels) {
    assert(aim_ && "CpuGather: gather(texels) needs the AIM given at construction");
    return gather(texels, *aim_);
}

std::vector<GatherResult> CpuGather::gather(const std::vector<int>& texels,
                                            const std::vector<glm::vec3>& aim_radiance) {
    assert(aim_radiance.size() == size_t(scene_.atlas.width) * size_t(scene_.atlas.height));
    if (own_rays_) own_rays_->update(scene_);

    // A 2D Hammersley set: (i + ½)/N against the base-2 radical inverse.
    const int count = std::max(1, scene_.settings.gather.cpu_rays);
    if (int(points_.size()) != count) {
        points_.resize(size_t(count));
        for (int i = 0; i < count; ++i)
            points_[size_t(i)] =
                glm::vec2((float(i) + 0.5f) / float(count), float(radical_inverse(2, uint64_t(i))));
    }

    std::vector<GatherResult> results(texels.size());
    pool_.parallel_for(
        texels.size(), [&](size_t i) { results[i] = gather_texel(texels[i], aim_radiance); }, 4);

    stats_.texels = int(texels.size());
    stats_.invalid = 0;
    for (const GatherResult& r : results)
        stats_.invalid += r.back_fraction > kBackFaceInvalidFraction;
    stats_.rays = uint64_t(texels.size()) * uint64_t(count);
    return results;
}

}  // namespace ag::cpu
