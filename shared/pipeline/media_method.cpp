#include "shared/pipeline/media_method.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "cpu/media_voxelizer.h"
#include "gpu/media_view.h"
#include "shared/media_grid.h"

namespace ag {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

MediaMethodResult render_media(const Scene& scene, const MediaMethodSettings& settings) {
    Bounds bounds;
    for (const Medium& m : scene.media) {
        bounds.add(m.bounds.min);
        bounds.add(m.bounds.max);
    }
    for (const Object& o : scene.objects)
        if (o.material.type == MaterialType::glass)
            for (const glm::vec3& p : o.mesh.positions) bounds.add(o.transform.apply_point(p));
    if (bounds.empty())
        throw std::invalid_argument(scene.path + ": the media method needs media or glass");
    // The first enabled point or spot light (spot cones ignored), else the first quad light.
    const Light* light = nullptr;
    for (const Light& l : scene.lights)
        if (l.enabled && (l.type == LightType::point || l.type == LightType::spot)) {
            light = &l;
            break;
        }
    for (const Light& l : scene.lights)
        if (!light && l.enabled && l.type == LightType::quad) light = &l;
    if (!light)
        throw std::invalid_argument(
            scene.path + ": the media method needs an enabled point, spot or quad light");
    // Cubic voxels, `grid` along the longest side.
    const glm::vec3 extent = bounds.extent();
    const float voxel = std::max({extent.x, extent.y, extent.z}) / float(settings.grid);
    const glm::ivec3 size = glm::max(glm::ivec3(glm::ceil(extent / voxel)), glm::ivec3(1));
    bounds.max = bounds.min + glm::vec3(size) * voxel;

    MediaMethodResult result;
    result.grid = size;
    Clock::time_point start = Clock::now();
    const cpu::RayTracer rays(scene);
    MediaGrid grid = cpu::voxelize_media(scene, rays, bounds, size);
    result.timing.voxelisation = since(start);
    start = Clock::now();
    gaussian_smooth(grid.n, grid.size, 9, 1.5f);  // his 9³ Gaussian, σ = 9/6
    result.timing.smoothing = since(start);
    start = Clock::now();
    // The mean of the light's RGB value: the method is grey (Medium is grey).
    const float intensity = glm::dot(light->value(), glm::vec3(1.0f / 3.0f));
    // His photon plane for a point light outside the grid; from the light itself where it is
    // inside; from its surface for a quad light.
    const bool inside = glm::all(glm::greaterThan(light->position, bounds.min)) &&
                        glm::all(glm::lessThan(light->position, bounds.max));
    const std::vector<MediaPhoton> photons =
        light->type == LightType::quad
            ? quad_photons(light->corners, intensity, bounds, settings.photons)
        : inside ? sphere_photons(light->position, intensity, settings.photons)
                 : plane_photons(light->position, intensity, bounds, settings.photons);
    result.photons_marched = photons.size();
    result.timing.photon_generation = since(start);

    gpu::MediaMarchSettings march;
    march.step = settings.march_step;
    march.deposit = settings.deposit;
    const gpu::MediaMarchResult marched = gpu::MediaMarcher().march(grid, photons, march);
    result.timing.photon_marching = marched.seconds;

    // The view march stops at the first surface the camera ray meets (the volume term's
    // definition; the straight ray, as the frame's other terms see it).
    const Camera& camera = scene.camera;
    std::vector<float> max_distance(size_t(camera.width) * size_t(camera.height));
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const cpu::RayHit hit = rays.intersect(
                {camera.eye, camera_ray_direction(camera, float(x) + 0.5f, float(y) + 0.5f)});
            max_distance[size_t(y) * size_t(camera.width) + size_t(x)] = hit.hit ? hit.t : 1e30f;
        }
    gpu::MediaViewSettings view;
    view.step = settings.view_step;
    view.phase_k = scene.media.empty() ? 0.0f : scene.media[0].phase_k;
    start = Clock::now();
    result.volume =
        gpu::MediaView().render(grid, marched.fluence, marched.flow, camera, view, max_distance);
    result.timing.viewing = since(start);
    result.grids = std::move(grid);
    result.fluence = marched.fluence;
    // Grey to the light's colour.
    const glm::vec3 tint = intensity > 0.0f ? light->value() / intensity : glm::vec3(0.0f);
    for (int y = 0; y < result.volume.height; ++y)
        for (int x = 0; x < result.volume.width; ++x)
            result.volume.set_rgb(x, y, result.volume.rgb(x, y) * tint);
    return result;
}

}  // namespace ag
