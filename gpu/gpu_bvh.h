// The flat BVH (shared/flat_bvh.h) on the GPU: nodes and triangles in storage buffers and the
// closest-hit walk as GLSL for compute shaders (kBvhTraversalGlsl), the same logic as the CPU's
// ag::intersect. Photon tracing (Jimenez Kwast 2016 §5.3.2) runs on it without OptiX.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "shared/flat_bvh.h"

namespace ag::gpu {

// Storage-buffer bindings the traversal reads.
inline constexpr GLuint kBvhNodeBinding = 6, kBvhTriangleBinding = 7;

// `bool bvh_intersect(vec3 origin, vec3 direction, float tmin, float tmax, out BvhHit hit)` with
// BvhHit {float t; uint object; uint triangle; uint index (into bvh_triangles); vec2 barycentric;};
// `bvh_count` says
// whether there are any nodes.
extern const char* const kBvhTraversalGlsl;

class GpuBvh {
public:
    GpuBvh() = default;
    void upload(const FlatBvh& bvh);
    void bind() const;  // at kBvhNodeBinding and kBvhTriangleBinding
    bool empty() const { return node_count_ == 0; }
    size_t bytes() const;

    struct Ray {
        glm::vec3 origin{0.0f};
        float tmin = 0.0f;
        glm::vec3 direction{0.0f};
        float tmax = 1e30f;
    };
    // Traces rays in a compute pass and reads the hits back (tests and diagnostics only).
    std::vector<BvhHit> trace(const std::vector<Ray>& rays);

private:
    Buffer nodes_, triangles_;
    size_t node_count_ = 0, triangle_count_ = 0;
    Program trace_;
};

}  // namespace ag::gpu
