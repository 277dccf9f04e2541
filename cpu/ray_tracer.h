// Ray casting against the scene through Embree 3. All Embree API use lives in ray_tracer.cpp (so a
// move to Embree 4 touches one file). Static objects share one BVH; every dynamic object has its
// own BVH placed by an instance transform, so moving an object re-commits only the top level.
// Hits at the same distance are ordered by one rule (intersect, below), not by Embree's traversal.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "shared/scene.h"

namespace ag::cpu {

struct RayHit {
    bool hit = false;
    float t = 0.0f;
    int object = -1;
    int triangle = -1;
    glm::vec2 barycentric{0.0f};  // Embree's (u, v): p = (1-u-v)·v0 + u·v1 + v·v2
    glm::vec3 position{0.0f};     // world space
    glm::vec3 normal{0.0f};       // world-space unit geometric normal of the triangle's front
};

struct Ray {
    glm::vec3 origin{0.0f};
    glm::vec3 direction{0.0f};  // need not be unit; t is in units of |direction|
    float tmin = 0.0f;
    float tmax = 1e30f;
};

class RayTracer {
public:
    // Builds the BVHs for `scene` as it is now. Thread-safe for queries after construction.
    explicit RayTracer(const Scene& scene);
    ~RayTracer();
    RayTracer(const RayTracer&) = delete;
    RayTracer& operator=(const RayTracer&) = delete;

    // Brings transforms up to date with the scene (cheap for dynamic objects: instance
    // transforms and a top-level commit; a moved static object rebuilds the static BVH).
    // Returns true if anything changed. Not thread-safe against concurrent queries.
    bool update(const Scene& scene);

    // The closest hit. Among faces that lie within float resolution of the nearest one along the
    // ray (coplanar faces of two objects, a shared edge), the one the ray meets from behind wins,
    // then the lowest object and triangle: a closed object stays closed where one of its faces
    // lies in another surface's plane (a lamp in a box flush with the ceiling lights nothing),
    // and the answer depends on the geometry only, not on the order the BVH visits it.
    RayHit intersect(const Ray& ray) const;
    // Embree's own closest hit among coincident faces (whichever its traversal meets first), for
    // `afterglow bench photons` to measure what the rule above costs. Not for rendering.
    RayHit intersect_unordered(const Ray& ray) const;
    // Any hit in [tmin, tmax]: which coincident face blocks the ray does not matter.
    bool occluded(const Ray& ray) const;

    // Offset along the normal that keeps a new ray from re-hitting the surface it leaves.
    float epsilon() const { return epsilon_; }
    uint64_t rays_cast() const;  // total intersect + occluded calls (for benchmarks)

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    float epsilon_ = 1e-4f;
    float coincident_ = 1e-5f;  // the scene's part of the coincident-face tolerance (world units)
};

}  // namespace ag::cpu
