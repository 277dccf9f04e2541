// Irradiance from virtual point lights with exact visibility (Barczak 2006 §4.3 without shadow
// maps): one Embree shadow ray per (point, VPL) pair. The CPU backend of the VPL method and the
// yardstick its GL shadow maps are checked against.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "cpu/ray_tracer.h"
#include "cpu/reference/point_reference.h"
#include "cpu/vpl_source.h"
#include "shared/parallel.h"

namespace ag::cpu {

// What the clamp took away: `clamped` is Σ (unclamped − clamped) over all visible pairs, `energy`
// Σ unclamped (channel means of E), so clamped / energy is the clamp's relative bias.
struct VplShadeStats {
    double energy = 0.0;
    double clamped = 0.0;
    uint64_t rays = 0;
    double bias() const { return energy > 0.0 ? clamped / energy : 0.0; }
};

// The geometry term of one VPL at (x, n) before visibility: cos θ_l cos θ_x / max(d², clamp²)
// (clamp 0: no clamp); 0 behind either surface. `unclamped` gets the value with 1/d².
float vpl_geometry(const Vpl& vpl, const glm::vec3& x, const glm::vec3& n, float clamp,
                   float* unclamped = nullptr);

// Adds E = Σ power/π · G · V (eq. of §4.3 with the clamp) of vpls[0..count) at each point to
// out[i]. Points with a zero normal are skipped. Deterministic on any thread count.
void add_vpl_irradiance(const RayTracer& rays, const std::vector<SurfacePoint>& points,
                        const Vpl* vpls, size_t count, float clamp, glm::vec3* out,
                        ThreadPool& pool, VplShadeStats* stats = nullptr);

// The points a w × h view of scene.camera sees at its pixel centres (rows top-first): the first
// hit's position and the normal facing the camera; a zero normal where it sees nothing or a
// mirror or glass (their light is the frame's business). Deterministic.
// `hits` (optional) gets each pixel's first hit (object, triangle, barycentrics).
std::vector<SurfacePoint> camera_points(const Scene& scene, const RayTracer& rays, int width,
                                        int height, ThreadPool& pool,
                                        std::vector<RayHit>* hits = nullptr);

// Whether the segment between x (normal n) and the VPL is unblocked (offset at both ends).
bool vpl_visible(const RayTracer& rays, const Vpl& vpl, const glm::vec3& x, const glm::vec3& n);

}  // namespace ag::cpu
