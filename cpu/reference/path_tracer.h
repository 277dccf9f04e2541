// Path tracer with next-event estimation for the reference images (docs/reference.md): the
// unbiased answer for everything except caustics of point lights, which it cannot sample.
// Participating media (Pfeuti 2009) by delta tracking, single and multiple scattering.
#pragma once

#include <vector>

#include "cpu/media_tracking.h"
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
    int volume_bounces_;
    uint32_t seed_;
    MediaTracker media_;
    int media_dims_;  // Halton dimensions for free-flight distances: 0 without media
    Halton halton_;
    std::vector<int> object_lights_;  // per object: its mesh light, or -1

    int vertex_dim(int depth) const;  // first sample dimension of vertex `depth`
    int medium_dim(int depth) const;  // its free-flight dimension
};

}  // namespace ag::cpu
