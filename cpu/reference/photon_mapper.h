// Traditional photon mapping (Jensen 1996) as Larsen compares against (ch. 4, Fig. 14.3, 14.5):
// a global photon map read through a ray-traced final gather, a caustic map of photons aimed at
// the specular objects read by density estimation at the visible point, direct light by shadow
// rays. The reference for caustics of point lights, which the path tracer cannot produce.
#pragma once

#include <functional>
#include <vector>

#include "cpu/knn.h"
#include "cpu/reference/light_tracer.h"
#include "cpu/reference/reference.h"

namespace ag::cpu {

class PhotonMapper {
public:
    // Traces the photons and builds both maps on the pool; `progress` gets the fraction done.
    PhotonMapper(const Scene& scene, const RayTracer& rays, const ReferenceSettings& settings,
                 ThreadPool& pool, const std::function<void(double)>& progress = {});

    // Sample `index` of pixel (x, y): a pure function of the scene, the settings and its
    // arguments (the maps are built in a fixed order whatever the thread count).
    ComponentRadiance sample(int x, int y, uint64_t index) const;

    size_t global_size() const { return global_.power.size(); }
    size_t caustic_size() const { return caustic_.power.size(); }

    // Irradiance density estimates (Larsen eq. 4.2 without the BRDF) at a front-facing point
    // (p, n): ΣΦ / (π r²) over the k nearest photons whose surface faces the same way.
    glm::vec3 global_irradiance(const glm::vec3& p, const glm::vec3& n) const;
    glm::vec3 caustic_irradiance(const glm::vec3& p, const glm::vec3& n) const;
    // The global estimate precomputed at every kIrradianceStride-th photon (Christensen 1999)
    // and looked up at the nearest one facing the same way: what final-gather rays read.
    glm::vec3 cached_irradiance(const glm::vec3& p, const glm::vec3& n) const;

private:
    struct PhotonMap {
        std::vector<glm::vec3> position, normal, power;
        std::vector<glm::vec3> incoming;  // unit, towards where the photon came from
        std::vector<uint8_t> indirect;    // a diffuse vertex precedes this hit
        KnnIndex index;
    };
    struct Photon {
        glm::vec3 position, normal, power, incoming;
        bool indirect;
    };
    struct IrradianceCache {
        std::vector<glm::vec3> position, normal, irradiance;
        KnnIndex index;
    };

    // Follows one photon from `ray` with flux `power`; its numbers come from `s` starting at
    // dimension `dim`. The global map takes every diffuse front hit, the caustic map only the
    // first diffuse hit after one or more specular ones (L S+ D).
    void trace(Ray ray, glm::vec3 power, const Sampler& s, int dim, bool caustic,
               std::vector<Photon>& out) const;
    void emit_global(int light, int count, int first, int n, std::vector<Photon>& out) const;
    void emit_caustic(int light, int count, int first, int n, std::vector<Photon>& out) const;
    // ΣΦ/(π r²) over the k nearest photons facing the same way, r the k-th's distance (capped at
    // √max_r2 when > 0); the k-th, on the circle, counts half.
    glm::vec3 estimate(const PhotonMap& map, const glm::vec3& p, const glm::vec3& n, int k,
                       float max_r2) const;
    // Cosine-weighted mean of the radiance arriving at (p, n) that has met a diffuse surface:
    // final-gather rays read the global map at their hits. A quarter of the rays are cosine
    // distributed, the rest follow a histogram of nearby photons' incoming directions (Jensen
    // 1995, Larsen ch. 4.6 [64]), combined by the balance heuristic: bright small sources such
    // as the spot a point light makes on a ceiling are found without fireflies.
    glm::vec3 gather(const glm::vec3& p, const glm::vec3& n, uint64_t key, uint64_t index) const;
    // Radiance arriving along `ray` from the first diffuse surface, through mirrors and glass.
    glm::vec3 gather_ray(Ray ray, uint64_t key) const;

    const Scene& scene_;
    const RayTracer& rays_;
    ReferenceSettings settings_;
    float caustic_r2_;
    Halton camera_halton_, gather_halton_, photon_halton_;
    std::vector<BoundingSphere> specular_bounds_;  // world bounding spheres of mirrors and glass
    std::vector<int> object_lights_;               // per object: its mesh light, or -1
    PhotonMap global_, caustic_;
    IrradianceCache cache_;
};

}  // namespace ag::cpu
