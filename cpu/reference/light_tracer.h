// Light tracing for the path-tracing reference (docs/reference.md, "Light through mirrors and
// glass"): the paths a path tracer with next-event estimation cannot sample, a delta light (point,
// spot, sun) seen through a delta BSDF (mirror, glass), L S+ D ... E. Light sub-paths are aimed at
// the specular objects' bounding spheres (the caustic photons' cone-union density, shared with
// the photon mapper), follow specular bounces, and every diffuse front-face vertex reached after
// them is connected to the pinhole camera. pt + this complement count every path except those the
// camera sees through a mirror or glass (L S+ ... D S+ E), which neither can sample.
#pragma once

#include <cstdint>
#include <vector>

#include "cpu/reference/reference.h"

namespace ag::cpu {

// World bounding sphere of one mirror or glass object.
struct BoundingSphere {
    glm::vec3 center{0.0f};
    float radius = 0.0f;
};
// The bounding spheres of the scene's mirror and glass objects (radius enlarged by 1e-4).
std::vector<BoundingSphere> specular_bounding_spheres(const Scene& scene);

// One ray from `light` aimed at the union of `bounds` (point and spot: the cones they subtend,
// picked by solid angle, uniform inside, overlaps counted once; a light inside a sphere emits
// everywhere; sun: the union of their discs across its direction; quad and mesh: a point by area
// (u[3], u[4]), then the cones from it). `power` is the flux the ray carries for one ray emitted
// (divide by the number emitted); valid = false when the light emits nothing this way.
struct AimedRay {
    Ray ray;
    glm::vec3 power{0.0f};
    bool valid = false;
};
AimedRay aimed_emission(const Scene& scene, const Light& light,
                        const std::vector<BoundingSphere>& bounds, const float u[5], float epsilon);

// One pixel value the light tracer adds (already divided by the pass's path count).
struct LightSplat {
    uint32_t pixel;  // index into the rendered region, row-major
    FrameTerm term;  // caustics (first diffuse vertex) or indirect (later ones)
    glm::vec3 value;
};

class LightTracer {
public:
    // `region` is the rendered part of scene.camera's image (whole-image pixel coordinates).
    LightTracer(const Scene& scene, const RayTracer& rays, const ReferenceSettings& settings,
                const PixelRegion& region);

    // Why there is no complement ("" when there is one): no delta light, no mirror or glass,
    // media in the scene, or turned off.
    const std::string& skipped() const { return skipped_; }
    bool active() const { return skipped_.empty() && !chunks_.empty(); }
    // Light paths per pass (over all delta lights together) and work items per pass.
    uint64_t paths_per_pass() const { return paths_per_pass_; }
    size_t chunks() const { return chunks_.size(); }
    // Traces work item `chunk` of pass `pass`: a pure function of the scene, the settings and its
    // arguments. Splats are appended in path order.
    void trace(int pass, size_t chunk, std::vector<LightSplat>& out) const;

private:
    struct Chunk {
        int light;
        uint64_t first, count, per_pass;  // paths [first, first + count) of per_pass
    };
    const Scene& scene_;
    const RayTracer& rays_;
    uint32_t seed_;
    int max_depth_;
    int indirect_bounces_;
    PixelRegion region_;
    std::string skipped_;
    uint64_t paths_per_pass_ = 0;
    std::vector<BoundingSphere> bounds_;
    std::vector<Chunk> chunks_;
    Halton halton_;
    // Camera frame: forward, right, up; the image plane at distance 1 spans ±tan_half·aspect by
    // ±tan_half, one pixel covers pixel_area_ of it.
    glm::vec3 forward_, right_, up_;
    float tan_half_, aspect_, pixel_area_;

    void connect(const glm::vec3& p, const glm::vec3& n, const glm::vec3& f_power, FrameTerm term,
                 std::vector<LightSplat>& out) const;
};

}  // namespace ag::cpu
