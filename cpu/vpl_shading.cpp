#include "cpu/vpl_shading.h"

#include <algorithm>
#include <glm/gtc/constants.hpp>

#include "shared/camera.h"

namespace ag::cpu {

float vpl_geometry(const Vpl& vpl, const glm::vec3& x, const glm::vec3& n, float clamp,
                   float* unclamped) {
    if (unclamped) *unclamped = 0.0f;
    const glm::vec3 d = vpl.position - x;
    const float d2 = glm::dot(d, d);
    if (d2 <= 0.0f) return 0.0f;
    const float inv = 1.0f / std::sqrt(d2);
    const float cos_x = glm::dot(n, d) * inv;
    const float cos_l = -glm::dot(vpl.normal, d) * inv;
    if (cos_x <= 0.0f || cos_l <= 0.0f) return 0.0f;
    if (unclamped) *unclamped = cos_x * cos_l / d2;
    return cos_x * cos_l / std::max(d2, clamp * clamp);
}

std::vector<SurfacePoint> camera_points(const Scene& scene, const RayTracer& rays, int width,
                                        int height, ThreadPool& pool, std::vector<RayHit>* hits) {
    std::vector<SurfacePoint> points(size_t(width) * size_t(height));
    if (hits) hits->assign(points.size(), RayHit{});
    const Camera& cam = scene.camera;
    pool.parallel_for(
        size_t(height),
        [&](size_t y) {
            for (int x = 0; x < width; ++x) {
                const float px = (float(x) + 0.5f) * float(cam.width) / float(width);
                const float py = (float(y) + 0.5f) * float(cam.height) / float(height);
                const glm::vec3 dir = camera_ray_direction(cam, px, py);
                const RayHit hit = rays.intersect({cam.eye, dir});
                if (hits) (*hits)[y * size_t(width) + size_t(x)] = hit;
                if (!hit.hit) continue;
                if (scene.objects[size_t(hit.object)].material.type != MaterialType::diffuse)
                    continue;
                SurfacePoint& p = points[y * size_t(width) + size_t(x)];
                p.position = hit.position;
                p.normal = glm::dot(dir, hit.normal) < 0.0f ? hit.normal : -hit.normal;
            }
        },
        1);
    return points;
}

bool vpl_visible(const RayTracer& rays, const Vpl& vpl, const glm::vec3& x, const glm::vec3& n) {
    const float eps = rays.epsilon();
    const glm::vec3 from = x + eps * n;
    const glm::vec3 to = vpl.position + eps * vpl.normal;
    Ray r{from, to - from, 0.0f, 1.0f - 1e-4f};
    return !rays.occluded(r);
}

void add_vpl_irradiance(const RayTracer& rays, const std::vector<SurfacePoint>& points,
                        const Vpl* vpls, size_t count, float clamp, glm::vec3* out,
                        ThreadPool& pool, VplShadeStats* stats) {
    struct PointStats {
        double energy = 0.0, clamped = 0.0;
        uint32_t rays = 0;
    };
    std::vector<PointStats> per_point(stats ? points.size() : 0);
    pool.parallel_for(
        points.size(),
        [&](size_t i) {
            const SurfacePoint& p = points[i];
            if (p.normal == glm::vec3(0.0f)) return;
            glm::vec3 e(0.0f);
            PointStats ps;
            for (size_t k = 0; k < count; ++k) {
                const Vpl& v = vpls[k];
                float full = 0.0f;
                const float g = vpl_geometry(v, p.position, p.normal, clamp, &full);
                if (full <= 0.0f) continue;
                ++ps.rays;
                if (!vpl_visible(rays, v, p.position, p.normal)) continue;
                const glm::vec3 radiant = v.power * glm::one_over_pi<float>();
                e += radiant * g;
                const double mean = (double(radiant.x) + radiant.y + radiant.z) / 3.0;
                ps.energy += mean * full;
                ps.clamped += mean * (double(full) - double(g));
            }
            out[i] += e;
            if (stats) per_point[i] = ps;
        },
        64);
    if (!stats) return;
    for (const PointStats& ps : per_point) {
        stats->energy += ps.energy;
        stats->clamped += ps.clamped;
        stats->rays += ps.rays;
    }
}

}  // namespace ag::cpu
