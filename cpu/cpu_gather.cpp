#include "cpu/cpu_gather.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <limits>

#include "cpu/sampling.h"
#include "shared/camera.h"
#include "shared/lightmap_sample.h"
#include "shared/media.h"  // ray_box, mean_media_transmittance
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

glm::vec3 CpuGather::radiance_along(const Ray& ray, const std::vector<glm::vec3>& aim_radiance,
                                    int bounces_left, float weight, bool& back_face) const {
    return radiance_at(rays_.intersect(ray), ray, aim_radiance, bounces_left, weight, back_face);
}

glm::vec3 CpuGather::radiance_at(const RayHit& hit, const Ray& ray,
                                 const std::vector<glm::vec3>& aim_radiance, int bounces_left,
                                 float weight, bool& back_face) const {
    if (!hit.hit) return glm::vec3(0.0f);
    // The media between the gather point and what it sees dim it (as pt's paths and the GL
    // gather): Beer–Lambert at the boxes' mean density.
    if (!scene_.media.empty())
        return mean_media_transmittance(scene_.media, ray.origin, ray.direction, hit.t) *
               surface_radiance(ray, hit, aim_radiance, bounces_left, weight, back_face);
    return surface_radiance(ray, hit, aim_radiance, bounces_left, weight, back_face);
}

glm::vec3 CpuGather::surface_radiance(const Ray& ray, const RayHit& hit,
                                      const std::vector<glm::vec3>& aim_radiance, int bounces_left,
                                      float weight, bool& back_face) const {
    const Material& m = scene_.objects[size_t(hit.object)].material;
    if (m.type != MaterialType::diffuse) {
        // Mirrors and glass have no AIM: follow the bounce to the diffuse surface behind it, both
        // branches weighted by Fresnel (L D S+ x paths, the light through glass and off mirrors).
        if (bounces_left <= 0) return glm::vec3(0.0f);
        const SpecularSplit split = specular_split(m, hit, ray.direction, rays_.epsilon());
        bool ignored = false;  // back faces behind glass say nothing about the texel's placement
        glm::vec3 l(0.0f);
        // Branches that would carry under 1% of the gather ray are dropped: a few bounces carry
        // nearly everything a glass ball or a mirror shows.
        constexpr float kMinWeight = 0.01f;
        const float reflected = weight * split.reflectance, refracted = weight - reflected;
        if (reflected >= kMinWeight)
            l += split.reflectance * radiance_along(split.reflected, aim_radiance, bounces_left - 1,
                                                    reflected, ignored);
        if (refracted >= kMinWeight)
            l += (1.0f - split.reflectance) * radiance_along(split.refracted, aim_radiance,
                                                             bounces_left - 1, refracted, ignored);
        return l;
    }
    // A diffuse back face reflects nothing (photons reaching it are absorbed); seeing many means
    // the texel's centre is inside or behind geometry.
    if (glm::dot(ray.direction, hit.normal) > 0.0f) {
        back_face = true;
        return glm::vec3(0.0f);
    }
    return sample_lightmap(scene_.atlas, aim_radiance, hit.object, hit.triangle, hit.barycentric);
}

GatherResult CpuGather::gather_texel(int record, const std::vector<glm::vec3>& aim_radiance,
                                     std::atomic<uint64_t>* reused) {
    const TexelRecord& texel = scene_.atlas.texels[size_t(record)];
    const Transform& transform = scene_.objects[size_t(texel.object)].transform;
    TexelRays* cache = nullptr;
    if (reused) {
        cache = &cache_[size_t(record)];
        // The texel's own object moved: every ray starts elsewhere.
        if (moved_at_[size_t(texel.object)] > cache->epoch) cache->epoch = 0;
    }
    uint64_t n = 0;
    const GatherResult r =
        gather_point({transform.apply_point(texel.position), transform.apply_vector(texel.normal)},
                     texel_shift(scene_.settings.seed, record), aim_radiance, cache, &n);
    if (reused) *reused += n;
    return r;
}

bool CpuGather::still_valid(const CachedHit& hit, const Ray& ray, uint64_t epoch) const {
    if (hit.object >= 0 && moved_at_[size_t(hit.object)] > epoch) return false;
    const float end = hit.object >= 0 ? hit.t : 1e30f;
    for (int o : moved_objects_) {
        if (moved_at_[size_t(o)] <= epoch) continue;
        float enter = 0.0f, exit = 0.0f;
        if (ray_box(moved_to_[size_t(o)], ray.origin, ray.direction, 0.0f, end, enter, exit))
            return false;
    }
    return true;
}

void CpuGather::track_moves() {
    const size_t n = scene_.objects.size();
    if (seen_transform_.size() != n) {
        // Objects came or went: nothing cached can be trusted.
        seen_transform_.clear();
        for (const Object& o : scene_.objects) seen_transform_.push_back(o.transform);
        moved_at_.assign(n, 0);
        moved_to_.assign(n, Bounds{});
        moved_objects_.clear();
        for (TexelRays& t : cache_) t.epoch = 0;
        return;
    }
    for (size_t i = 0; i < n; ++i) {
        const Transform& now = scene_.objects[i].transform;
        Transform& seen = seen_transform_[i];
        if (now.translation == seen.translation && now.rotation == seen.rotation) continue;
        seen = now;
        if (moved_at_[i] == 0) moved_objects_.push_back(int(i));
        moved_at_[i] = ++epoch_;
        // Padded, so that a ray grazing the object's new place counts as crossing it.
        Bounds b;
        for (const glm::vec3& p : scene_.objects[i].mesh.positions) b.add(now.apply_point(p));
        const glm::vec3 pad =
            1e-3f * glm::max(b.extent(), glm::vec3(1e-6f)) + glm::vec3(4.0f * rays_.epsilon());
        b.min -= pad;
        b.max += pad;
        moved_to_[i] = b;
    }
}

GatherResult CpuGather::gather_point(const GatherPoint& point, glm::vec2 shift,
                                     const std::vector<glm::vec3>& aim_radiance, TexelRays* cache,
                                     uint64_t* reused) const {
    const GatherSettings& settings = scene_.settings.gather;
    const glm::vec3 n = glm::normalize(point.normal);
    const glm::vec3 origin = point.position + rays_.epsilon() * n;
    glm::vec3 t, b;
    orthonormal_basis(n, t, b);
    const bool plane = settings.hemisphere == GatherHemisphere::plane;
    const float a = settings.plane_half_width;
    // With the band, the directions within the wider plane are seen as they are and only those
    // beyond it are stretched, onto the wider plane's border (the GL gather's second view).
    const bool band = settings.border_correction == BorderCorrection::band;
    const float edge_width = band ? std::max(a, settings.band_half_width) : a;
    const int bounces = std::max(0, settings.specular_bounces);

    // The cached hits are this texel's as last traced when the cache holds all of them.
    const bool have = cache && cache->epoch > 0 && cache->hits.size() == points_.size();
    if (cache && !have) cache->hits.assign(points_.size(), CachedHit{});
    uint64_t reused_here = 0;
    // Nothing moved since the hits were traced (a light or an albedo edit since): a hit on a
    // diffuse surface is read without working out its ray's direction.
    // Media dim each hit by the fog along its ray, which needs the direction too.
    bool quick = have && !plane && scene_.media.empty();
    for (int o : moved_objects_) quick = quick && moved_at_[size_t(o)] <= cache->epoch;

    glm::vec3 sum(0.0f);
    int back_faces = 0, counted = 0;
    for (size_t i = 0; i < points_.size(); ++i) {
        if (quick) {
            const CachedHit& c = cache->hits[i];
            if (c.object < 0 ||
                scene_.objects[size_t(c.object)].material.type == MaterialType::diffuse) {
                // The same sum as the full path below: the same values in the same order.
                ++counted;
                ++reused_here;
                glm::vec3 l(0.0f);
                if (c.object >= 0 && !c.back)
                    l = sample_lightmap(scene_.atlas, aim_radiance, c.object, c.triangle,
                                        c.barycentric);
                sum += l;
                back_faces += c.object >= 0 && c.back;
                continue;
            }
        }
        const glm::vec2& p = points_[i];
        // The concentric map keeps the QMC points' strata compact, which matters at a few hundred
        // rays.
        glm::vec3 d = square_to_cosine_hemisphere({wrap(p.x + shift.x), wrap(p.y + shift.y)});
        if (plane && std::max(std::abs(d.x), std::abs(d.y)) > edge_width * d.z) {
            // A direction the hemi-plane misses (Larsen ch. 11; Gautron 2006, Table 4.1): none
            // counts it as black, renormalise leaves it out of the mean, stretch reads the plane
            // point nearest to it in plane coordinates (clamp-to-edge), stretch_radial the border
            // point it leaves the plane through (same azimuth), as the GL gather's stretched
            // border pixels do.
            if (settings.border_correction == BorderCorrection::none) {
                ++counted;
                continue;
            }
            if (settings.border_correction == BorderCorrection::renormalize) continue;
            if (settings.border_correction == BorderCorrection::stretch || band) {
                const float z = std::max(d.z, 1e-7f);  // grazing: clamps to the border anyway
                const float e = edge_width;
                d = glm::normalize(
                    glm::vec3(std::clamp(d.x / z, -e, e), std::clamp(d.y / z, -e, e), 1.0f));
            } else {
                const float r = std::sqrt(d.x * d.x + d.y * d.y);
                const float edge = a / std::max(std::abs(d.x), std::abs(d.y)) * r;  // border
                d = glm::normalize(glm::vec3(d.x / r * edge, d.y / r * edge, 1.0f));
            }
        }
        ++counted;
        const glm::vec3 direction = d.x * t + d.y * b + d.z * n;
        const Ray ray{origin, direction, 0.0f, 1e30f};
        bool back_face = false;
        glm::vec3 l(0.0f);
        if (!cache) {
            l = radiance_along(ray, aim_radiance, bounces, 1.0f, back_face);
        } else if (CachedHit& c = cache->hits[i]; have && still_valid(c, ray, cache->epoch)) {
            // What radiance_at gives for the same hit: tracing the ray again finds it.
            const bool specular = c.object >= 0 && scene_.objects[size_t(c.object)].material.type !=
                                                       MaterialType::diffuse;
            if (specular)
                l = radiance_along(ray, aim_radiance, bounces, 1.0f, back_face);
            else if (c.object >= 0 && c.back)
                back_face = true;
            else if (c.object >= 0 && scene_.media.empty())
                l = sample_lightmap(scene_.atlas, aim_radiance, c.object, c.triangle,
                                    c.barycentric);
            else if (c.object >= 0)  // as radiance_at: the fog between dims what is seen
                l = mean_media_transmittance(scene_.media, ray.origin, ray.direction, c.t) *
                    sample_lightmap(scene_.atlas, aim_radiance, c.object, c.triangle,
                                    c.barycentric);
            reused_here += specular ? 0 : 1;
        } else {
            const RayHit hit = rays_.intersect(ray);
            c.t = hit.hit ? hit.t : std::numeric_limits<float>::infinity();
            c.object = hit.hit ? hit.object : -1;
            c.triangle = hit.triangle;
            c.barycentric = hit.barycentric;
            c.back = hit.hit && glm::dot(ray.direction, hit.normal) > 0.0f;
            l = radiance_at(hit, ray, aim_radiance, bounces, 1.0f, back_face);
        }
        sum += l;
        back_faces += back_face;
    }
    if (cache) cache->epoch = epoch_;
    if (reused) *reused += reused_here;
    // Cosine-weighted directions make E = π · mean(L) (eq. 11.1); the IIM holds E / π.
    GatherResult result;
    const float n_rays = float(std::max(1, counted));
    result.iim = sum / n_rays;
    result.back_fraction = float(back_faces) / n_rays;
    return result;
}

std::vector<GatherResult> CpuGather::gather(const std::vector<int>& texels) {
    assert(aim_ && "CpuGather: gather(texels) needs the AIM given at construction");
    return gather(texels, *aim_);
}

void CpuGather::prepare() {
    if (own_rays_) own_rays_->update(scene_);
    track_moves();
    // A 2D Hammersley set: (i + ½)/N against the base-2 radical inverse.
    const int count = std::max(1, scene_.settings.gather.cpu_rays);
    const size_t records = scene_.atlas.texels.size();
    const size_t cache_bytes = records * size_t(count) * sizeof(CachedHit);
    const int cache_mb = scene_.settings.gather.ray_cache_mb;
    if (!ray_cache_allowed_ || cache_mb <= 0 || cache_bytes > (size_t(cache_mb) << 20))
        cache_.clear();
    else if (cache_.size() != records || int(points_.size()) != count)
        cache_.assign(records, TexelRays{});
    if (int(points_.size()) != count) {
        points_.resize(size_t(count));
        for (int i = 0; i < count; ++i)
            points_[size_t(i)] =
                glm::vec2((float(i) + 0.5f) / float(count), float(radical_inverse(2, uint64_t(i))));
    }
}

std::vector<GatherResult> CpuGather::gather_points(const std::vector<GatherPoint>& points) {
    assert(aim_ && "CpuGather: gather_points(points) needs the AIM given at construction");
    return gather_points(points, *aim_);
}

std::vector<GatherResult> CpuGather::gather_points(const std::vector<GatherPoint>& points,
                                                   const std::vector<glm::vec3>& aim_radiance) {
    assert(aim_radiance.size() == size_t(scene_.atlas.width) * size_t(scene_.atlas.height));
    prepare();
    std::vector<GatherResult> results(points.size());
    pool_.parallel_for(
        points.size(),
        [&](size_t i) {
            // Shifts of their own (another seed), apart from every texel record's.
            const glm::vec2 shift =
                texel_shift(scene_.settings.seed ^ 0x5bd1e995u, int(points[i].key));
            results[i] = gather_point(points[i], shift, aim_radiance);
        },
        4);
    return results;
}

std::vector<GatherResult> CpuGather::gather(const std::vector<int>& texels,
                                            const std::vector<glm::vec3>& aim_radiance) {
    assert(aim_radiance.size() == size_t(scene_.atlas.width) * size_t(scene_.atlas.height));
    prepare();
    const int count = int(points_.size());

    // The cache is written per record: only for a list without repeats.
    bool cached = !cache_.empty();
    if (cached) {
        std::vector<char> seen(cache_.size(), 0);
        for (int t : texels) {
            if (seen[size_t(t)]) cached = false;
            seen[size_t(t)] = 1;
        }
    }
    std::atomic<uint64_t> reused{0};
    std::vector<GatherResult> results(texels.size());
    pool_.parallel_for(
        texels.size(),
        [&](size_t i) {
            results[i] = gather_texel(texels[i], aim_radiance, cached ? &reused : nullptr);
        },
        4);

    stats_.rays_reused = reused.load();
    stats_.texels = int(texels.size());
    stats_.invalid = 0;
    for (const GatherResult& r : results)
        stats_.invalid += r.back_fraction > kBackFaceInvalidFraction;
    stats_.rays = uint64_t(texels.size()) * uint64_t(count);
    totals_.rays += stats_.rays;
    totals_.rays_reused += stats_.rays_reused;
    return results;
}

std::vector<float> CpuGather::texel_coverage(int width, int height) {
    prepare();
    Camera camera = scene_.camera;
    camera.width = width;
    camera.height = height;
    const size_t pixels = size_t(width) * size_t(height);
    // Per pixel: the lookup in atlas texel coordinates, or x < 0 where no lightmap is seen.
    std::vector<glm::vec2> lookups(pixels, glm::vec2(-1.0f));
    pool_.parallel_for(
        pixels,
        [&](size_t p) {
            const int x = int(p % size_t(width)), y = int(p / size_t(width));
            Ray ray;
            ray.origin = camera.eye;
            ray.direction = camera_ray_direction(camera, float(x) + 0.5f, float(y) + 0.5f);
            const RayHit hit = rays_.intersect(ray);
            if (!hit.hit) return;
            const Object& o = scene_.objects[size_t(hit.object)];
            const bool lightmapped = o.material.type == MaterialType::diffuse &&
                                     size_t(hit.object) < scene_.atlas.corner_uvs.size() &&
                                     !scene_.atlas.corner_uvs[size_t(hit.object)].empty();
            if (lightmapped)
                lookups[p] = lightmap_uv(scene_.atlas, hit.object, hit.triangle, hit.barycentric);
        },
        64);
    std::vector<float> coverage(scene_.atlas.texels.size(), 0.0f);
    const float pixel = 1.0f / float(pixels);
    for (const glm::vec2& l : lookups)
        if (l.x >= 0.0f) add_lookup_coverage(scene_.atlas, l, pixel, coverage);
    return coverage;
}

}  // namespace ag::cpu
