#include "cpu/reference/reference.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "cpu/reference/light_tracer.h"
#include "cpu/reference/path_tracer.h"
#include "cpu/reference/photon_mapper.h"
#include "shared/media.h"

namespace ag::cpu {

namespace {

constexpr int kTileSize = 16;

}  // namespace

namespace {

// Σ over the enabled lights of their radiance arriving at `origin` times weight(to, d) (to: the
// vector towards the light sample, d its length; weight ≤ 0 skips the sample), shadowed, and
// attenuated by the media when `media` is given. Serves surfaces (weight = cos) and media
// (weight = phase): one place for every light type.
template <class Weight>
glm::vec3 direct_light(const Scene& scene, const RayTracer& rays, const glm::vec3& origin,
                       const Weight& weight, int quad_samples, float u1, float u2,
                       const MediaTracker* media, HashedStream* more) {
    const auto attenuation = [&](const glm::vec3& dir, float d) {
        return media ? media->transmittance({origin, dir, 0.0f, d}, d, -1, *more) : 1.0f;
    };
    glm::vec3 e(0.0f);
    for (size_t l = 0; l < scene.lights.size(); ++l) {
        const Light& light = scene.lights[l];
        if (!light.enabled) continue;
        if (light.type == LightType::sun) {  // E cos, unless something lies sunwards
            const float cos_x = weight(-light.direction, 1.0f);
            if (!(cos_x > 0.0f)) continue;
            if (rays.occluded({origin, -light.direction, 0.0f, 1e30f})) continue;
            e += media ? light.irradiance * cos_x * attenuation(-light.direction, 1e30f)
                       : light.irradiance * cos_x;
            continue;
        }
        if (light.type == LightType::point || light.type == LightType::spot) {
            const glm::vec3 to = light.position - origin;
            const float d2 = glm::dot(to, to), d = std::sqrt(d2);
            const float cos_x = weight(to, d);
            if (!(cos_x > 0.0f)) continue;
            const float falloff = light.spot_factor(-glm::dot(to, light.direction) / d);
            if (!(falloff > 0.0f)) continue;
            if (rays.occluded({origin, to / d, 0.0f, d * (1.0f - 1e-5f)})) continue;
            const glm::vec3 arriving = light.intensity * (falloff * cos_x / d2);
            e += media ? arriving * attenuation(to / d, d) : arriving;
            continue;
        }
        // Quad or mesh light: E = L ∫ cos_x cos_l / d² dA, estimated by a rotated rank-1
        // lattice (its own rotation per light so that two lights do not share shadow-ray
        // patterns); a mesh light's lattice is spread over its triangles by area.
        const float area = light.area();
        const float r1 = u1 + hashed_uniform(l, 1), r2 = u2 + hashed_uniform(l, 2);
        glm::vec3 sum(0.0f);
        for (int j = 0; j < quad_samples; ++j) {
            const float a = std::fmod((float(j) + 0.5f) / float(quad_samples) + r1, 1.0f);
            const float b = std::fmod(float(j) * 0.6180339887f + r2, 1.0f);
            const LightPoint at = sample_area_light(scene, light, a, b);
            const glm::vec3 to = at.position - origin;
            const float d2 = glm::dot(to, to), d = std::sqrt(d2);
            if (!(d2 > 0.0f)) continue;
            const float cos_x = weight(to, d), cos_l = -glm::dot(at.normal, to) / d;
            if (!(cos_x > 0.0f) || !(cos_l > 0.0f)) continue;
            if (rays.occluded({origin, to / d, 0.0f, d * (1.0f - 1e-5f)})) continue;
            const glm::vec3 arriving(cos_x * cos_l / d2);
            sum += media ? arriving * attenuation(to / d, d) : arriving;
        }
        e += light.radiance * sum * (area / float(quad_samples));
    }
    return e;
}

}  // namespace

glm::vec3 direct_irradiance(const Scene& scene, const RayTracer& rays, const glm::vec3& p,
                            const glm::vec3& n, int quad_samples, float u1, float u2,
                            const MediaTracker* media, HashedStream* more) {
    return direct_light(
        scene, rays, p + rays.epsilon() * n,
        [&](const glm::vec3& to, float d) { return glm::dot(n, to) / d; }, quad_samples, u1, u2,
        media, more);
}

glm::vec3 direct_inscattering(const Scene& scene, const RayTracer& rays, const glm::vec3& p,
                              const glm::vec3& forward, float phase_k, int quad_samples, float u1,
                              float u2, const MediaTracker& media, HashedStream& more) {
    return direct_light(
        scene, rays, p,
        [&](const glm::vec3& to, float d) {
            return schlick_phase(glm::dot(forward, to) / d, phase_k);
        },
        quad_samples, u1, u2, &media, &more);
}

glm::vec3 quad_light_radiance(const Scene& scene, const Ray& ray, float tmax) {
    glm::vec3 radiance(0.0f);
    float nearest = tmax;
    for (const Light& light : scene.lights) {
        if (!light.enabled || light.type != LightType::quad) continue;
        const glm::vec3 e1 = light.corners[1] - light.corners[0];
        const glm::vec3 e3 = light.corners[3] - light.corners[0];
        const glm::vec3 cross = glm::cross(e1, e3);
        const float facing = glm::dot(ray.direction, cross);
        if (!(facing < 0.0f)) continue;  // parallel, or meeting the dark back
        const float t = glm::dot(light.corners[0] - ray.origin, cross) / facing;
        if (!(t > ray.tmin) || !(t < nearest)) continue;
        const glm::vec3 q = ray.origin + t * ray.direction - light.corners[0];
        const float inv = 1.0f / glm::dot(cross, cross);
        const float a = glm::dot(glm::cross(q, e3), cross) * inv;
        const float b = glm::dot(glm::cross(e1, q), cross) * inv;
        if (a < 0.0f || a > 1.0f || b < 0.0f || b > 1.0f) continue;
        nearest = t;
        radiance = light.radiance;
    }
    return radiance;
}

float scene_diagonal(const Scene& scene) {
    Bounds bounds;
    for (const Object& o : scene.objects)
        for (const glm::vec3& p : o.mesh.positions) bounds.add(o.transform.apply_point(p));
    return bounds.empty() ? 1.0f : std::max(1e-6f, glm::length(bounds.extent()));
}

ReferenceResult render_reference(const Scene& scene, const ReferenceSettings& settings,
                                 ThreadPool& pool, const ReferenceProgressFn& progress) {
    using Clock = std::chrono::steady_clock;
    const Clock::time_point start = Clock::now();
    const auto elapsed = [&] {
        return std::chrono::duration<double>(Clock::now() - start).count();
    };
    if (scene.camera.width <= 0 || scene.camera.height <= 0)
        throw std::invalid_argument("reference: camera resolution must be positive");
    PixelRegion region = settings.region;
    if (region.width == 0) region = {0, 0, scene.camera.width, scene.camera.height};
    if (region.x < 0 || region.y < 0 || region.width <= 0 || region.height <= 0 ||
        region.x + region.width > scene.camera.width ||
        region.y + region.height > scene.camera.height)
        throw std::invalid_argument("reference: region " + std::to_string(region.width) + "x" +
                                    std::to_string(region.height) + " at (" +
                                    std::to_string(region.x) + ", " + std::to_string(region.y) +
                                    ") is not inside the " + std::to_string(scene.camera.width) +
                                    "x" + std::to_string(scene.camera.height) + " image");
    const int width = region.width, height = region.height;

    // Progress goes out from whichever worker passes by, at most five times a second.
    std::mutex progress_mutex;
    double last_report = -1.0;
    const auto report = [&](ReferenceProgress p, bool force) {
        if (!progress) return;
        const std::lock_guard<std::mutex> lock(progress_mutex);
        p.elapsed = elapsed();
        if (!force && p.elapsed - last_report < 0.2) return;
        last_report = p.elapsed;
        progress(p);
    };

    ReferenceResult result;
    const RayTracer rays(scene);
    std::unique_ptr<PathTracer> path_tracer;
    std::unique_ptr<PhotonMapper> photon_mapper;
    std::unique_ptr<LightTracer> light_tracer;
    if (settings.method == ReferenceMethod::path_tracing) {
        path_tracer = std::make_unique<PathTracer>(scene, rays, settings);
        light_tracer = std::make_unique<LightTracer>(scene, rays, settings, region);
        result.light_tracing_skipped = light_tracer->skipped();
        if (!light_tracer->active()) light_tracer.reset();
    } else {
        photon_mapper = std::make_unique<PhotonMapper>(scene, rays, settings, pool, [&](double f) {
            report({"photons", f, 0, 0.0, -1.0}, false);
        });
        result.photon_seconds = elapsed();
        result.global_photons = photon_mapper->global_size();
        result.caustic_photons = photon_mapper->caustic_size();
    }
    const auto sample = [&](int x, int y, uint64_t index) {
        return path_tracer ? path_tracer->sample(x, y, index) : photon_mapper->sample(x, y, index);
    };

    const size_t pixels = size_t(width) * size_t(height);
    const int tiles_x = (width + kTileSize - 1) / kTileSize;
    const int tiles_y = (height + kTileSize - 1) / kTileSize;
    const size_t tiles = size_t(tiles_x) * size_t(tiles_y);
    const double time_limit = settings.time_limit > 0.0 ? settings.time_limit : 0.0;
    const int spp_limit = settings.spp > 0 ? settings.spp : (time_limit > 0.0 ? INT_MAX : 1);
    std::vector<std::array<glm::dvec3, kFrameTermCount>> sum(pixels);
    std::vector<ComponentRadiance> pass(pixels);
    // Light tracing: per pass, fixed work items after the tiles, each with its own splat list,
    // added in item order (so the image does not depend on the thread count).
    const size_t chunks = light_tracer ? light_tracer->chunks() : 0;
    std::vector<std::vector<LightSplat>> splats(chunks);
    const double render_start = elapsed();

    int done = 0;
    while (done < spp_limit) {
        if (done > 0 && time_limit > 0.0 && elapsed() >= time_limit) break;
        std::atomic<bool> interrupted{false};
        std::atomic<size_t> tiles_done{0};
        pool.parallel_for(tiles + chunks, [&](size_t item) {
            if (interrupted.load(std::memory_order_relaxed)) return;
            if (item >= tiles) {
                splats[item - tiles].clear();
                light_tracer->trace(done, item - tiles, splats[item - tiles]);
                if (done > 0 && time_limit > 0.0 && elapsed() >= time_limit) interrupted = true;
                return;
            }
            const size_t tile = item;
            const int x0 = int(tile % size_t(tiles_x)) * kTileSize;
            const int y0 = int(tile / size_t(tiles_x)) * kTileSize;
            for (int y = y0; y < std::min(height, y0 + kTileSize); ++y)
                for (int x = x0; x < std::min(width, x0 + kTileSize); ++x)
                    pass[size_t(y) * size_t(width) + size_t(x)] =
                        sample(region.x + x, region.y + y, uint64_t(done));
            const double now = elapsed();
            if (done > 0 && time_limit > 0.0 && now >= time_limit) interrupted = true;
            const double passes = done + double(++tiles_done) / double(tiles);
            const double per_pass = (now - render_start) / passes;
            ReferenceProgress p{"render", 0.0, done, 0.0, -1.0};
            if (settings.spp > 0) {
                p.fraction = passes / spp_limit;
                p.eta = (spp_limit - passes) * per_pass;
            }
            if (time_limit > 0.0) {
                p.fraction = std::max(p.fraction, now / time_limit);
                const double left = std::max(0.0, time_limit - now);
                p.eta = p.eta < 0.0 ? left : std::min(p.eta, left);
            }
            report(p, false);
        });
        if (interrupted) break;
        for (size_t i = 0; i < pixels; ++i)
            for (int c = 0; c < kFrameTermCount; ++c) sum[i][size_t(c)] += pass[i].value[size_t(c)];
        for (const std::vector<LightSplat>& list : splats)
            for (const LightSplat& splat : list)
                sum[splat.pixel][size_t(splat.term)] += glm::dvec3(splat.value);
        if (light_tracer) result.light_paths += light_tracer->paths_per_pass();
        ++done;
    }

    result.spp = done;
    result.full = Image(width, height);
    for (Image& image : result.components) image = Image(width, height);
    const double scale = 1.0 / double(std::max(done, 1));
    for (size_t i = 0; i < pixels; ++i) {
        const int x = int(i % size_t(width)), y = int(i / size_t(width));
        glm::vec3 full(0.0f);
        for (int c = 0; c < kFrameTermCount; ++c) {
            const glm::vec3 v = glm::vec3(sum[i][size_t(c)] * scale);
            result.components[size_t(c)].set_rgb(x, y, v);
            full += v;
        }
        result.full.set_rgb(x, y, full);
    }
    result.seconds = elapsed();
    report({"render", 1.0, done, 0.0, 0.0}, true);
    return result;
}

}  // namespace ag::cpu
