#include "cpu/vpl_source.h"

#include <algorithm>

#include "cpu/sampling.h"
#include "shared/qmc.h"

namespace ag::cpu {

void group_vpls(const Scene& /*scene*/, const PhotonMaps& maps, int light, int group, int photons,
                std::vector<Vpl>& out) {
    const PhotonGroup& g = maps.group(light, group);
    if (!g.traced || g.photon_begin.size() < 2) return;
    const int count = int(g.photon_begin.size()) - 1;
    const int used = std::clamp(photons, 1, count);
    // The first `used` photons of the group stand for all `count`: their stratum of the group's
    // emission domain is the start of its 1D QMC sequence, an unbiased subsample.
    const float scale = float(count) / float(used);
    for (uint32_t v = g.photon_begin[0]; v < g.photon_begin[size_t(used)]; ++v) {
        const PathVertex& pv = g.vertices[v];
        if (pv.hit < 0) continue;
        const PhotonHit& hit = maps.surface(pv.surface).hits[size_t(pv.hit)];
        Vpl vpl;
        vpl.position = pv.position;
        vpl.normal = pv.normal;
        // The albedo where the photon landed (the texel's on a textured surface), kept with its
        // path: an albedo edit retraces the groups with hits on the object.
        vpl.power = hit.power * pv.albedo * scale;
        vpl.light = light;
        vpl.group = group;
        vpl.bounce = hit.bounce;
        if (vpl.power != glm::vec3(0.0f)) out.push_back(vpl);
    }
}

std::vector<Vpl> random_walk_vpls(const Scene& scene, const RayTracer& rays, int paths, int bounces,
                                  uint32_t seed) {
    std::vector<Vpl> out;
    const float eps = rays.epsilon();
    constexpr int kHaltonDims = 16;
    for (size_t li = 0; li < scene.lights.size(); ++li) {
        const Light& light = scene.lights[li];
        if (!light.enabled || paths <= 0) continue;
        const Halton halton(kHaltonDims, seed ^ hash_u32(uint32_t(li) + 0x9e37u));
        const glm::vec3 path_power = light.power() / float(paths);
        for (int p = 0; p < paths; ++p) {
            const Sampler s(halton, mix64(uint64_t(seed) * 0x51ull + li), uint64_t(p));
            const EmissionRay e =
                emission_ray(scene, light, {s.get(0), s.get(1)}, {s.get(2), s.get(3)}, eps);
            Ray ray = e.ray;
            glm::vec3 power = path_power * e.weight;
            int stored = 0;
            // Specular vertices do not count against the VPL budget but are capped too.
            for (int vertex = 0; stored < bounces && vertex < bounces + 16; ++vertex) {
                ray.tmin = 0.0f;
                ray.tmax = 1e30f;
                const RayHit hit = rays.intersect(ray);
                if (!hit.hit) break;
                const Material& m = scene.objects[size_t(hit.object)].material;
                const bool front = glm::dot(ray.direction, hit.normal) < 0.0f;
                const glm::vec3 facing = front ? hit.normal : -hit.normal;
                const int dim = 4 + 2 * vertex;
                if (m.type == MaterialType::diffuse) {
                    if (!front) break;  // back faces absorb, as in the photon tracer
                    // Thesis: the VPL's intensity is the path's power times the BRDF (× π for
                    // the cosine lobe normalisation), and the walk carries power × albedo on.
                    power *=
                        albedo_at(scene.objects[size_t(hit.object)], hit.triangle, hit.barycentric);
                    out.push_back(Vpl{hit.position, facing, power, int(li), p, stored});
                    ++stored;
                    ray.origin = hit.position + eps * facing;
                    ray.direction = cosine_direction(facing, s.get(dim), s.get(dim + 1));
                } else {
                    ray = specular_bounce(m, hit, ray.direction, s.get(dim), eps);
                }
            }
        }
    }
    return out;
}

glm::dvec3 total_power(const std::vector<Vpl>& vpls) {
    glm::dvec3 sum(0.0);
    for (const Vpl& v : vpls) sum += glm::dvec3(v.power);
    return sum;
}

}  // namespace ag::cpu
