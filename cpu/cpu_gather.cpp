#include "cpu/cpu_gather.h"

#include "cpu/sampling.h"

#include <algorithm>
#include <cassert>
#include <cmath>

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

CpuGather::CpuGather(const Scene& scene, const RayTracer& rays, ThreadPool& pool)
    : scene_(scene), rays_(rays), pool_(pool) {
    valid_.assign(scene_.atlas.texels.size(), 0);
}

CpuGather::TexelResult CpuGather::gather_texel(int record,
                                               const std::vector<glm::vec3>& aim_radiance) const {
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
    TexelResult result;
    result.iim = sum / float(points_.size());
    result.valid = float(back_faces) <= kBackFaceInvalidFraction * float(points_.size());
    return result;
}

void CpuGather::gather(const std::vector<int>& texel_ids,
                       const std::vector<glm::vec3>& aim_radiance, std::vector<glm::vec3>& iim) {
    const LightmapAtlas& atlas = scene_.atlas;
    const size_t atlas_size = size_t(atlas.width) * size_t(atlas.height);
    assert(aim_radiance.size() == atlas_size && iim.size() == atlas_size);
    (void)atlas_size;
    if (valid_.size() != atlas.texels.size()) valid_.assign(atlas.texels.size(), 0);

    // A 2D Hammersley set: (i + ½)/N against the base-2 radical inverse.
    const int count = std::max(1, scene_.settings.gather.cpu_rays);
    if (int(points_.size()) != count) {
        points_.resize(size_t(count));
        for (int i = 0; i < count; ++i)
            points_[size_t(i)] =
                glm::vec2((float(i) + 0.5f) / float(count), float(radical_inverse(2, uint64_t(i))));
    }

    std::vector<TexelResult> results(texel_ids.size());
    pool_.parallel_for(
        texel_ids.size(), [&](size_t i) { results[i] = gather_texel(texel_ids[i], aim_radiance); },
        4);

    std::vector<int> invalid;
    for (size_t i = 0; i < texel_ids.size(); ++i) {
        const int r = texel_ids[i];
        valid_[size_t(r)] = results[i].valid;
        const TexelRecord& texel = atlas.texels[size_t(r)];
        if (results[i].valid)
            iim[size_t(texel.y) * size_t(atlas.width) + size_t(texel.x)] = results[i].iim;
        else
            invalid.push_back(r);
    }
    if (!invalid.empty()) repair_invalid_texels(atlas, iim, valid_, invalid);

    stats_.texels = int(texel_ids.size());
    stats_.invalid = int(invalid.size());
    stats_.rays = uint64_t(texel_ids.size()) * uint64_t(count);
}

}  // namespace ag::cpu
