// Path-traced irradiance at surface points, for the fidelity budget (docs/fidelity.md): what a
// texel's AIM and IIM stand for, computed without photons or lightmaps under the scene model of
// the pt reference (docs/reference.md).
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "cpu/ray_tracer.h"
#include "shared/parallel.h"
#include "shared/scene.h"

namespace ag::cpu {

struct SurfacePoint {
    glm::vec3 position{0.0f};  // world space, on the surface
    glm::vec3 normal{0.0f};    // unit, the side that receives
};

struct PointIrradiance {
    glm::vec3 direct{0.0f};    // from the lights straight (hard shadows; quad lights sampled)
    glm::vec3 indirect{0.0f};  // everything else: after a diffuse bounce or through mirrors/glass
};

// Irradiance at each point by `paths` cosine-distributed paths (next-event estimation at every
// diffuse vertex, Fresnel-chosen specular bounces, Russian roulette) and `direct_samples` shadow
// rays per quad light. Deterministic in (scene, seed, point index); independent of thread count.
// As in pt, point lights seen through mirrors or glass (L S+ D paths) are missing.
std::vector<PointIrradiance> path_traced_irradiance(const Scene& scene, const RayTracer& rays,
                                                    const std::vector<SurfacePoint>& points,
                                                    int paths, int direct_samples, uint32_t seed,
                                                    ThreadPool& pool);

}  // namespace ag::cpu
