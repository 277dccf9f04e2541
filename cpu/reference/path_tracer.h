// Path tracer with next-event estimation for the reference images (docs/reference.md): the
// unbiased answer for everything except caustics of point lights, which it cannot sample.
#pragma once

#include <vector>

#include "cpu/reference/reference.h"

namespace ag::cpu {

class PathTracer {
public:
    PathTracer(const Scene& scene, const RayTracer& rays, const ReferenceSettings& settings);

    // Sample `index` of pixel (x, y): a pure function of the scene, the seed and its arguments.
    ComponentRadiance sample(int x, int y, uint64_t index) const;

private:
    const Scene& scene_;
    const RayTracer& rays_;
    int max_depth_;
    int indirect_bounces_;  // < 0: all
    uint32_t seed_;
    Halton halton_;
    std::vector<int> object_lights_;  // per object: its mesh light, or -1
};

}  // namespace ag::cpu
