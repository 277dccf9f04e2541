#include "cpu/irradiance_cache_cpu.h"

#include <chrono>

#include "shared/camera.h"

namespace ag::cpu {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

IrradianceOctree scene_octree(const Scene& scene, float accuracy) {
    Bounds b;
    for (const Object& o : scene.objects)
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    const glm::vec3 e = b.empty() ? glm::vec3(1.0f) : b.extent();
    const float half = 0.5f * std::max(e.x, std::max(e.y, e.z)) * 1.01f + 1e-3f;
    return IrradianceOctree(b.empty() ? glm::vec3(0.0f) : b.center(), half, accuracy);
}
}  // namespace

std::vector<SplatPixel> eye_ray_pixels(const Scene& scene, const RayTracer& rays, int width,
                                       int height) {
    Camera camera = scene.camera;
    camera.width = width;
    camera.height = height;
    std::vector<SplatPixel> out(size_t(width) * size_t(height));
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            Ray ray;
            ray.origin = camera.eye;
            ray.direction = camera_ray_direction(camera, float(x) + 0.5f, float(y) + 0.5f);
            const RayHit hit = rays.intersect(ray);
            SplatPixel& px = out[size_t(y) * size_t(width) + size_t(x)];
            if (!hit.hit) continue;
            if (scene.objects[size_t(hit.object)].material.type != MaterialType::diffuse) continue;
            px.position = hit.position;
            px.normal = glm::dot(hit.normal, ray.direction) > 0.0f ? -hit.normal : hit.normal;
            px.covered = true;
        }
    return out;
}

CpuCacheFrame render_irradiance_cache_cpu(const Scene& scene, const RayTracer& rays,
                                          const IrradianceGather& gather,
                                          const RecordRadiance& radiance,
                                          const RecordGatherOptions& options, float accuracy,
                                          int width, int height) {
    const Clock::time_point t0 = Clock::now();
    std::vector<SplatPixel> pixels = eye_ray_pixels(scene, rays, width, height);
    const double eye_ms = ms_since(t0);
    CpuCacheFrame f = render_irradiance_cache_cpu(scene, std::move(pixels), gather, radiance,
                                                  options, accuracy, width, height);
    f.eye_ms = eye_ms;
    return f;
}

CpuCacheFrame render_irradiance_cache_cpu(const Scene& scene, std::vector<SplatPixel> pixels,
                                          const IrradianceGather& gather,
                                          const RecordRadiance& radiance,
                                          const RecordGatherOptions& options, float accuracy,
                                          int width, int height) {
    CpuCacheFrame f;
    f.width = width;
    f.height = height;
    f.pixels = std::move(pixels);
    const Clock::time_point t1 = Clock::now();
    IrradianceOctree octree = scene_octree(scene, accuracy);
    f.term.assign(f.pixels.size(), glm::vec3(0.0f));
    uint32_t key = 0;
    for (size_t i = 0; i < f.pixels.size(); ++i) {
        const SplatPixel& px = f.pixels[i];
        if (!px.covered) continue;
        glm::vec4 sum = octree.lookup(px.position, px.normal);
        if (needs_record(sum, accuracy)) {
            const Clock::time_point tr = Clock::now();
            const IrradianceRecord r =
                gather.gather_one({px.position, px.normal, key++}, radiance, options);
            f.record_ms += ms_since(tr);
            octree.insert(r);
            sum = octree.lookup(px.position, px.normal);
        }
        if (sum.a > 0.0f) f.term[i] = glm::vec3(sum) / sum.a;
    }
    f.lookup_ms = ms_since(t1) - f.record_ms;
    f.records = octree.records();
    return f;
}

std::vector<glm::vec3> interpolate_cpu(const Scene& scene,
                                       const std::vector<IrradianceRecord>& records,
                                       const std::vector<SplatPixel>& pixels, float accuracy) {
    IrradianceOctree octree = scene_octree(scene, accuracy);
    for (const IrradianceRecord& r : records) octree.insert(r);
    std::vector<glm::vec3> out(pixels.size(), glm::vec3(0.0f));
    for (size_t i = 0; i < pixels.size(); ++i) {
        if (!pixels[i].covered) continue;
        const glm::vec4 sum = octree.lookup(pixels[i].position, pixels[i].normal);
        if (sum.a > 0.0f) out[i] = glm::vec3(sum) / sum.a;
    }
    return out;
}

}  // namespace ag::cpu
