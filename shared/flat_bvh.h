// A flat bounding-volume hierarchy over the scene's world-space triangles, built on the CPU (binned
// SAH) in a layout a compute shader walks directly (Jimenez Kwast 2016 §5.3.2 traced photons with
// OptiX; here the GPU walks our own BVH, so gpu/ needs no ray-tracing library). Nodes are in
// depth-first order: an interior node's first child follows it, the second is at `link`.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "shared/scene.h"

namespace ag {

// std430-compatible (32 bytes): a leaf has `count` triangles from `link`; an interior node has
// count = kBvhInterior | split axis.
struct BvhNode {
    glm::vec3 lo{0.0f};
    uint32_t link = 0;
    glm::vec3 hi{0.0f};
    uint32_t count = 0;
};
inline constexpr uint32_t kBvhInterior = 0x80000000u;

// std430-compatible (48 bytes): v0 and the edges v1 − v0, v2 − v0 (Möller–Trumbore), with the
// object and the triangle's index in that object's mesh (Embree's geomID/primID).
struct BvhTriangle {
    glm::vec3 v0{0.0f};
    uint32_t object = 0;
    glm::vec3 e1{0.0f};
    uint32_t triangle = 0;
    glm::vec3 e2{0.0f};
    uint32_t pad = 0;
};

struct FlatBvh {
    std::vector<BvhNode> nodes;  // empty for a scene without triangles
    std::vector<BvhTriangle> triangles;
    int depth = 0;  // longest root-to-leaf path (nodes), for the traversal stack
};

inline constexpr int kBvhMaxLeaf = 4;
inline constexpr int kBvhMaxDepth = 64;  // the GPU stack size; the build never goes deeper

// Builds over every object's triangles as placed now (`objects`: which ones; all if empty).
FlatBvh build_flat_bvh(const Scene& scene);

// Closest hit on the CPU through the same nodes (the reference for the GPU walk's logic).
struct BvhHit {
    bool hit = false;
    float t = 0.0f;
    uint32_t object = 0, triangle = 0;
};
BvhHit intersect(const FlatBvh& bvh, const glm::vec3& origin, const glm::vec3& direction,
                 float tmin, float tmax);

}  // namespace ag
