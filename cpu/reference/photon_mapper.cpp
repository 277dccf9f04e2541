#include "cpu/reference/photon_mapper.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <numbers>

#include "cpu/reference/light_tracer.h"
#include "shared/camera.h"
#include "shared/metrics.h"

namespace ag::cpu {

namespace {
constexpr int kChunk = 2048;         // photons per work item
constexpr int kQmcBounces = 16;      // photon bounces with Halton numbers
constexpr float kNormalCos = 0.5f;   // photons on surfaces turned further away are not counted
constexpr int kCameraDims = 4 + 16;  // pixel, quad-light lattice, Fresnel choices
constexpr int kGlobalEmitDims = 4;   // direction, point on a quad light
constexpr int kCausticEmitDims = 5;  // cone choice, direction in it, point on a quad light
constexpr uint64_t kGatherKey = 0x2545f4914f6cdd1dull;
constexpr int kIrradianceStride = 8;  // every 8th global photon carries a precomputed estimate
constexpr int kCacheCandidates = 8;   // nearest cache points tried for one facing the same way
constexpr int kGuideResolution = 16;  // guiding histogram: 16 × 16 cells of the concentric square
constexpr int kGuidePhotons = 400;    // nearest photons feeding the histogram

// Photons per enabled light, in proportion to its power (luminance), at least one each.
std::vector<int> photon_split(const Scene& scene, int total) {
    std::vector<int> n(scene.lights.size(), 0);
    double sum = 0.0;
    for (const Light& l : scene.lights)
        sum += l.enabled ? std::max(0.0f, luminance(l.power())) : 0.0f;
    if (!(sum > 0.0) || total <= 0) return n;
    for (size_t l = 0; l < n.size(); ++l) {
        const double lum =
            scene.lights[l].enabled ? std::max(0.0f, luminance(scene.lights[l].power())) : 0.0f;
        if (lum > 0.0) n[l] = std::max(1, int(std::lround(double(total) * lum / sum)));
    }
    return n;
}

}  // namespace

PhotonMapper::PhotonMapper(const Scene& scene, const RayTracer& rays,
                           const ReferenceSettings& settings, ThreadPool& pool,
                           const std::function<void(double)>& progress)
    : scene_(scene),
      rays_(rays),
      settings_(settings),
      camera_halton_(kCameraDims, hash_u32(settings.seed) | 1u),
      gather_halton_(2, hash_u32(settings.seed + 0x9e3779b9u) | 1u),
      photon_halton_(kCausticEmitDims + 3 * kQmcBounces,
                     hash_u32(settings.seed + 0x3c6ef372u) | 1u),
      object_lights_(object_lights(scene)) {
    const float r =
        settings.caustic_radius > 0.0f ? settings.caustic_radius : 0.01f * scene_diagonal(scene);
    caustic_r2_ = r * r;
    specular_bounds_ = specular_bounding_spheres(scene);

    // Work items: (map, light, first photon, count), traced in parallel into their own slots
    // and appended in item order, so the maps are the same for any thread count.
    struct Item {
        bool caustic;
        int light, first, count, total;
    };
    std::vector<Item> items;
    const std::vector<int> global_split = photon_split(scene, settings.photons);
    const std::vector<int> caustic_split = specular_bounds_.empty()
                                               ? std::vector<int>(scene.lights.size(), 0)
                                               : photon_split(scene, settings.caustic_photons);
    for (int pass = 0; pass < 2; ++pass) {
        const std::vector<int>& split = pass == 0 ? global_split : caustic_split;
        for (size_t l = 0; l < split.size(); ++l)
            for (int first = 0; first < split[l]; first += kChunk)
                items.push_back(
                    {pass == 1, int(l), first, std::min(kChunk, split[l] - first), split[l]});
    }
    std::vector<std::vector<Photon>> traced(items.size());
    std::atomic<size_t> items_done{0};
    pool.parallel_for(items.size(), [&](size_t i) {
        const Item& it = items[i];
        if (it.caustic)
            emit_caustic(it.light, it.total, it.first, it.count, traced[i]);
        else
            emit_global(it.light, it.total, it.first, it.count, traced[i]);
        if (progress) progress(0.8 * double(++items_done) / double(items.size()));
    });
    for (size_t i = 0; i < items.size(); ++i) {
        PhotonMap& map = items[i].caustic ? caustic_ : global_;
        for (const Photon& p : traced[i]) {
            map.position.push_back(p.position);
            map.normal.push_back(p.normal);
            map.power.push_back(p.power);
            map.incoming.push_back(p.incoming);
            map.indirect.push_back(p.indirect ? 1 : 0);
        }
        std::vector<Photon>().swap(traced[i]);
    }
    global_.index.build(global_.position);
    caustic_.index.build(caustic_.position);
    if (progress) progress(0.85);

    for (size_t i = 0; i < global_.position.size(); i += kIrradianceStride) {
        cache_.position.push_back(global_.position[i]);
        cache_.normal.push_back(global_.normal[i]);
    }
    cache_.irradiance.resize(cache_.position.size());
    std::atomic<size_t> cached{0};
    constexpr size_t kCacheChunk = 4096;
    pool.parallel_for((cache_.position.size() + kCacheChunk - 1) / kCacheChunk, [&](size_t c) {
        const size_t end = std::min(cache_.position.size(), (c + 1) * kCacheChunk);
        for (size_t i = c * kCacheChunk; i < end; ++i)
            cache_.irradiance[i] = global_irradiance(cache_.position[i], cache_.normal[i]);
        if (progress)
            progress(0.85 + 0.14 * double(cached += end - c * kCacheChunk) /
                                double(cache_.position.size()));
    });
    cache_.index.build(cache_.position);
    if (progress) progress(1.0);
}

void PhotonMapper::trace(Ray ray, glm::vec3 power, const Sampler& s, int dim, bool caustic,
                         std::vector<Photon>& out) const {
    const float eps = rays_.epsilon();
    bool specular_seen = false, diffuse_seen = false;
    int diffuse_hits = 0;  // stored in the global map so far
    for (int bounce = 0; bounce < settings_.max_depth; ++bounce, dim += 3) {
        const RayHit hit = rays_.intersect(ray);
        if (!hit.hit) return;
        const Material& m = scene_.objects[size_t(hit.object)].material;
        if (m.type != MaterialType::diffuse) {
            specular_seen = true;
            ray = specular_bounce(m, hit, ray.direction, s.get(dim), eps);
            continue;
        }
        // Light reaching a back face is absorbed, as in the photon tracer.
        if (glm::dot(ray.direction, hit.normal) >= 0.0f) return;
        const Photon photon{hit.position, hit.normal, power, -glm::normalize(ray.direction),
                            diffuse_seen};
        if (caustic) {
            if (specular_seen) out.push_back(photon);
            return;
        }
        // With --indirect-bounces N the global map keeps the light that has made at most N − 1
        // diffuse bounces: read at a final-gather hit it reaches x after at most N.
        const int limit = settings_.indirect_bounces;
        if (limit >= 0 && diffuse_hits >= limit) return;
        out.push_back(photon);
        diffuse_seen = true;
        if (limit >= 0 && ++diffuse_hits >= limit) return;
        // Russian roulette by albedo (Jensen): survive with p = max ρ, carry ρ/p.
        const glm::vec3 albedo =
            albedo_at(scene_.objects[size_t(hit.object)], hit.triangle, hit.barycentric);
        const float p = std::min(1.0f, std::max({albedo.x, albedo.y, albedo.z}));
        if (!(p > 0.0f) || s.get(dim) >= p) return;
        power *= albedo / p;
        ray = {hit.position + eps * hit.normal,
               cosine_direction(hit.normal, s.get(dim + 1), s.get(dim + 2))};
    }
}

void PhotonMapper::emit_global(int light, int count, int first, int n,
                               std::vector<Photon>& out) const {
    const Light& l = scene_.lights[size_t(light)];
    const glm::vec3 power = l.power() / float(count);
    const uint64_t key = mix64(uint64_t(settings_.seed) * 0x100000001b3ull + uint64_t(light));
    for (int i = first; i < first + n; ++i) {
        const Sampler s(photon_halton_, key, uint64_t(i));
        const EmissionRay e =
            emission_ray(scene_, l, {s.get(0), s.get(1)}, {s.get(2), s.get(3)}, rays_.epsilon());
        if (e.weight > 0.0f) trace(e.ray, power * e.weight, s, kGlobalEmitDims, false, out);
    }
}

void PhotonMapper::emit_caustic(int light, int count, int first, int n,
                                std::vector<Photon>& out) const {
    // Directions from the union of the cones around the specular objects' bounding spheres,
    // weighted exactly where they overlap (aimed_emission, shared with the light tracer).
    const Light& l = scene_.lights[size_t(light)];
    const uint64_t key =
        mix64(uint64_t(settings_.seed) * 0x100000001b3ull + uint64_t(light) + 0x51ed27ull);
    for (int i = first; i < first + n; ++i) {
        const Sampler s(photon_halton_, key, uint64_t(i));
        const float u[5] = {s.get(0), s.get(1), s.get(2), s.get(3), s.get(4)};
        const AimedRay a = aimed_emission(scene_, l, specular_bounds_, u, rays_.epsilon());
        if (a.valid) trace(a.ray, a.power / float(count), s, kCausticEmitDims, true, out);
    }
}

glm::vec3 PhotonMapper::estimate(const PhotonMap& map, const glm::vec3& p, const glm::vec3& n,
                                 int k, float max_r2) const {
    // ΣΦ / (π r²) with r the distance to the k-th nearest photon counts the k-th, which lies on
    // the circle, as if it were inside: +1/(2k) too bright (+2.5% at k = 20, measured on a plane
    // under a point light, tests/cpu/reference_test.cpp). Half of it is inside on average for
    // photons as evenly spread as QMC emission makes them, so it counts half. (For a Poisson
    // process the unbiased count would leave it out: E[(k − 1) / (π r²)] = λ; with QMC photons
    // that reads 2% dark at k = 20, and leaving out the photon an estimate is made at, 7%.)
    thread_local std::vector<int> indices;
    thread_local std::vector<float> dist2;
    const int found = map.index.query(p, k, indices, dist2);
    if (found == 0) return glm::vec3(0.0f);
    float r2 = dist2[size_t(found) - 1];
    float last = 0.5f;  // the k-th photon's share, on the circle
    if (max_r2 > 0.0f && max_r2 < r2) {
        r2 = max_r2;  // capped: a fixed disc, every photon in it counts
        last = 1.0f;
    }
    if (!(r2 > 0.0f)) return glm::vec3(0.0f);
    glm::vec3 sum(0.0f);
    for (int i = 0; i < found; ++i) {
        const size_t j = size_t(indices[size_t(i)]);
        if (dist2[size_t(i)] <= r2 && glm::dot(map.normal[j], n) > kNormalCos)
            sum += (i + 1 == found ? last : 1.0f) * map.power[j];
    }
    return sum / (std::numbers::pi_v<float> * r2);
}

glm::vec3 PhotonMapper::global_irradiance(const glm::vec3& p, const glm::vec3& n) const {
    return estimate(global_, p, n, settings_.knn, 0.0f);
}

glm::vec3 PhotonMapper::caustic_irradiance(const glm::vec3& p, const glm::vec3& n) const {
    return estimate(caustic_, p, n, settings_.caustic_knn, caustic_r2_);
}

glm::vec3 PhotonMapper::cached_irradiance(const glm::vec3& p, const glm::vec3& n) const {
    thread_local std::vector<int> indices;
    thread_local std::vector<float> dist2;
    const int found = cache_.index.query(p, kCacheCandidates, indices, dist2);
    for (int i = 0; i < found; ++i) {
        const size_t j = size_t(indices[size_t(i)]);
        if (glm::dot(cache_.normal[j], n) > kNormalCos) return cache_.irradiance[j];
    }
    return global_irradiance(p, n);
}

glm::vec3 PhotonMapper::gather_ray(Ray ray, uint64_t key) const {
    // Larsen ch. 4.5: the radiance of the gather hits comes from the global map, so only light
    // that has met a diffuse surface before x is counted here: exactly the indirect light.
    glm::vec3 radiance(0.0f);
    for (int depth = 0; depth < settings_.max_depth; ++depth) {
        const RayHit hit = rays_.intersect(ray);
        if (!hit.hit) break;
        const Material& m = scene_.objects[size_t(hit.object)].material;
        const bool front = glm::dot(ray.direction, hit.normal) < 0.0f;
        // A mesh light seen from x is direct light (next-event estimation), or after a specular
        // bounce a caustic (the caustic map): only a lamp that lights nothing shows here.
        if (front && object_lights_[size_t(hit.object)] < 0) radiance += m.emission;
        if (m.type == MaterialType::diffuse) {
            if (front)
                radiance +=
                    albedo_at(scene_.objects[size_t(hit.object)], hit.triangle, hit.barycentric) /
                    std::numbers::pi_v<float> * cached_irradiance(hit.position, hit.normal);
            break;
        }
        ray = specular_bounce(m, hit, ray.direction, hashed_uniform(key, uint64_t(depth)),
                              rays_.epsilon());
    }
    return radiance;
}

glm::vec3 PhotonMapper::gather(const glm::vec3& p, const glm::vec3& n, uint64_t key,
                               uint64_t index) const {
    constexpr int kCells = kGuideResolution * kGuideResolution;
    glm::vec3 t, b;
    orthonormal_basis(n, t, b);

    // Guiding histogram over the concentric square: flux of nearby photons that have met a
    // diffuse surface, by the direction they came from.
    std::array<float, kCells> cdf{};
    {
        thread_local std::vector<int> indices;
        thread_local std::vector<float> dist2;
        std::array<float, kCells> histogram{};
        const int found = global_.index.query(p, kGuidePhotons, indices, dist2);
        for (int i = 0; i < found; ++i) {
            const size_t j = size_t(indices[size_t(i)]);
            if (!global_.indirect[j] || glm::dot(global_.normal[j], n) <= kNormalCos) continue;
            const glm::vec3& w = global_.incoming[j];
            const glm::vec3 local(glm::dot(w, t), glm::dot(w, b), glm::dot(w, n));
            if (!(local.z > 0.0f)) continue;
            const glm::ivec2 cell =
                glm::ivec2(cosine_hemisphere_to_square(local) * float(kGuideResolution));
            histogram[size_t(cell.y * kGuideResolution + cell.x)] += luminance(global_.power[j]);
        }
        float total = 0.0f;
        for (int c = 0; c < kCells; ++c)
            cdf[size_t(c)] = total += std::max(0.0f, histogram[size_t(c)]);
    }
    const float total = cdf.back();
    const int rays = std::max(1, settings_.gather_rays);
    const int guided = total > 0.0f && rays >= 4 ? rays - rays / 4 : 0;
    const int cosine = rays - guided;

    const float eps = rays_.epsilon();
    const uint64_t gather_key = key ^ kGatherKey;
    glm::vec3 sum(0.0f);
    for (int j = 0; j < rays; ++j) {
        const uint64_t ray_index = index * uint64_t(rays) + uint64_t(j);
        const Sampler s(gather_halton_, gather_key, ray_index);
        glm::vec2 u(s.get(0), s.get(1));
        if (j >= cosine) {
            // Pick a cell by the CDF with u.x; what is left of u.x places the point inside it.
            const float target = u.x * total;
            const size_t c = size_t(std::upper_bound(cdf.begin(), cdf.end(), target) - cdf.begin());
            const size_t cell = std::min(c, size_t(kCells - 1));
            const float below = cell > 0 ? cdf[cell - 1] : 0.0f, width = cdf[cell] - below;
            const float within =
                width > 0.0f ? std::clamp((target - below) / width, 0.0f, 1.0f) : 0.5f;
            u = (glm::vec2(float(cell % kGuideResolution), float(cell / kGuideResolution)) +
                 glm::vec2(within, u.y)) /
                float(kGuideResolution);
            u = glm::min(u, glm::vec2(0x1.fffffep-1f));
        }
        // Balance heuristic over both strategies; in the square the cosine density is 1.
        float guided_pdf = 0.0f;
        if (guided > 0) {
            const glm::ivec2 cell = glm::ivec2(u * float(kGuideResolution));
            const size_t c = size_t(cell.y * kGuideResolution + cell.x);
            guided_pdf = (cdf[c] - (c > 0 ? cdf[c - 1] : 0.0f)) / total * float(kCells);
        }
        const glm::vec3 local = square_to_cosine_hemisphere(u);
        const glm::vec3 dir = glm::normalize(local.x * t + local.y * b + local.z * n);
        const glm::vec3 radiance = gather_ray({p + eps * n, dir}, mix64(gather_key ^ ray_index));
        sum += radiance / (float(cosine) + float(guided) * guided_pdf);
    }
    return sum;
}

ComponentRadiance PhotonMapper::sample(int x, int y, uint64_t index) const {
    const Camera& camera = scene_.camera;
    const uint64_t key = pixel_key(settings_.seed, x, y);
    const Sampler s(camera_halton_, key, index);
    Ray ray{camera.eye, camera_ray_direction(camera, float(x) + s.get(0), float(y) + s.get(1))};
    ComponentRadiance out;
    for (int depth = 0; depth < settings_.max_depth; ++depth) {
        const RayHit hit = rays_.intersect(ray);
        if (!hit.hit) break;
        const Material& m = scene_.objects[size_t(hit.object)].material;
        const bool front = glm::dot(ray.direction, hit.normal) < 0.0f;
        const FrameTerm seen = depth == 0 ? FrameTerm::direct : FrameTerm::specular;
        if (front) out[seen] += m.emission;
        if (m.type != MaterialType::diffuse) {
            ray = specular_bounce(m, hit, ray.direction, s.get(4 + depth), rays_.epsilon());
            continue;
        }
        if (!front) break;
        const glm::vec3 albedo =
            albedo_at(scene_.objects[size_t(hit.object)], hit.triangle, hit.barycentric);
        const glm::vec3 brdf = albedo / std::numbers::pi_v<float>;
        const glm::vec3 direct =
            brdf * direct_irradiance(scene_, rays_, hit.position, hit.normal,
                                     settings_.area_light_samples, s.get(2), s.get(3));
        const glm::vec3 caustics = brdf * caustic_irradiance(hit.position, hit.normal);
        // Cosine-weighted gather: ρ/π · E = ρ/π · π · mean(L) = ρ · mean(L).
        const glm::vec3 indirect = settings_.indirect_bounces == 0
                                       ? glm::vec3(0.0f)
                                       : albedo * gather(hit.position, hit.normal, key, index);
        if (depth == 0) {
            out[FrameTerm::direct] += direct;
            out[FrameTerm::caustics] += caustics;
            out[FrameTerm::indirect] += indirect;
        } else {
            out[FrameTerm::specular] += direct + caustics + indirect;
        }
        break;
    }
    return out;
}

}  // namespace ag::cpu
