#include "cpu/reference/point_reference.h"

#include <algorithm>
#include <numbers>

#include "cpu/reference/reference.h"
#include "cpu/sampling.h"

namespace ag::cpu {

namespace {

constexpr int kRouletteDepth = 3;  // vertices before Russian roulette starts, as in pt

// Radiance arriving at a point along `ray`, which leaves that point's diffuse surface: emission
// and next-event estimation at every diffuse vertex met, mirrors and glass followed.
glm::vec3 incoming_radiance(const Scene& scene, const RayTracer& rays, Ray ray, uint64_t key) {
    const float eps = rays.epsilon();
    glm::vec3 sum(0.0f), throughput(1.0f);
    bool after_specular = false;
    int dim = 0;
    auto next = [&] { return hashed_uniform(key, uint64_t(dim++)); };
    for (int depth = 0; depth < 256; ++depth) {
        const RayHit hit = rays.intersect(ray);
        // Quad lights are found by rays leaving a specular vertex only (pt's rule).
        if (after_specular)
            sum += throughput * quad_light_radiance(scene, ray, hit.hit ? hit.t : 1e30f);
        if (!hit.hit) break;
        const Material& m = scene.objects[size_t(hit.object)].material;
        const bool front = glm::dot(ray.direction, hit.normal) < 0.0f;
        if (front) sum += throughput * m.emission;
        const float u0 = next(), u1 = next(), u2 = next(), u3 = next();
        if (m.type == MaterialType::diffuse) {
            if (!front) break;  // back faces absorb
            const float v0 = next(), v1 = next();
            const glm::vec3 albedo =
                albedo_at(scene.objects[size_t(hit.object)], hit.triangle, hit.barycentric);
            sum += throughput * albedo / std::numbers::pi_v<float> *
                   direct_irradiance(scene, rays, hit.position, hit.normal, 1, v0, v1);
            throughput *= albedo;
            ray = {hit.position + eps * hit.normal, cosine_direction(hit.normal, u0, u1)};
            after_specular = false;
        } else {
            ray = specular_bounce(m, hit, ray.direction, u2, eps);
            after_specular = true;
        }
        if (depth + 1 >= kRouletteDepth) {
            const float p = std::min(0.95f, std::max({throughput.x, throughput.y, throughput.z}));
            if (!(p > 0.0f) || u3 >= p) break;
            throughput /= p;
        }
    }
    return sum;
}

}  // namespace

std::vector<PointIrradiance> path_traced_irradiance(const Scene& scene, const RayTracer& rays,
                                                    const std::vector<SurfacePoint>& points,
                                                    int paths, int direct_samples, uint32_t seed,
                                                    ThreadPool& pool) {
    std::vector<PointIrradiance> out(points.size());
    const float eps = rays.epsilon();
    pool.parallel_for(
        points.size(),
        [&](size_t i) {
            const SurfacePoint& p = points[i];
            const glm::vec3 n = glm::normalize(p.normal);
            const uint64_t key = mix64(mix64(uint64_t(seed) * 0x9e3779b97f4a7c15ull) ^ i);
            out[i].direct = direct_irradiance(scene, rays, p.position, n, direct_samples,
                                              hashed_uniform(key, 1), hashed_uniform(key, 2));
            // Stratified cosine directions (a Hammersley set with a per-point rotation), each
            // continued by a path: E_indirect = π · mean(L).
            glm::dvec3 sum(0.0);
            const float s0 = hashed_uniform(key, 3), s1 = hashed_uniform(key, 4);
            for (int k = 0; k < paths; ++k) {
                float u = (float(k) + 0.5f) / float(paths) + s0;
                float v = float(radical_inverse(2, uint64_t(k))) + s1;
                u -= u >= 1.0f ? 1.0f : 0.0f;
                v -= v >= 1.0f ? 1.0f : 0.0f;
                const glm::vec3 d = cosine_direction(n, u, v);
                sum += glm::dvec3(incoming_radiance(scene, rays, {p.position + eps * n, d},
                                                    mix64(key ^ (uint64_t(k) << 20))));
            }
            out[i].indirect = glm::vec3(std::numbers::pi * sum / double(std::max(1, paths)));
        },
        1);
    return out;
}

}  // namespace ag::cpu
