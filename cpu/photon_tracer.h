// Tracing one QMC photon through the scene (Larsen ch. 6.3, 9): emission from a stratum of the
// light's domain, diffuse bounces with Russian roulette by albedo, mirror and glass without
// storing; Beer–Lambert through the scene's participating media on every segment (the path
// itself is not changed by them: media only attenuate these photons). A pure function of (scene,
// light, group, photon): re-tracing gives the same path, which is what lets selective tracing
// compare a new path with the stored one.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "cpu/media_tracking.h"
#include "cpu/ray_tracer.h"
#include "shared/qmc.h"
#include "shared/scene.h"

namespace ag::cpu {

// One interaction along a photon path.
struct TracedVertex {
    int object = -1;
    int surface = -1;
    glm::vec3 position{0.0f};        // world space (path comparison)
    glm::vec3 local_position{0.0f};  // object space (photon maps live in object space)
    glm::vec3 normal{0.0f};          // world-space unit normal on the side the photon arrived from
    glm::vec3 power{0.0f};           // incident flux carried by the photon, W
    glm::vec3 albedo{0.0f};          // diffuse: the albedo where it landed (the texel's, if any)
    uint8_t bounce = 0;              // 0: straight from the light
    bool stored = false;             // deposited as a photon hit (front side of a diffuse surface)
};

// Where a traced path starts and whether its last ray left the scene: with the stored vertices
// these give every segment the photon travelled, which edit queries test against moved objects.
struct PathEnds {
    glm::vec3 origin{0.0f};  // the emission ray's origin
    glm::vec3 escape{
        0.0f};  // direction of a last ray that hit nothing; zero if the path ended on a hit
};

// Maps t ∈ [0,1) along a Hilbert curve to the unit square. The curve preserves area, so an
// interval of length 1/G is a compact stratum of area 1/G: the emission domain of one group.
glm::vec2 hilbert_point(double t);

class PhotonTracer {
public:
    PhotonTracer(const Scene& scene, const RayTracer& rays);

    // Rebinds to the scene's current lights/materials (call after edits; cheap).
    void refresh();

    // Traces photon `index` of group `group` of light `light`, appending its vertices to `out`.
    // Layer L ≥ 1 (photons.refine_layers) is another complete set of G × P photons: its group g
    // takes the next P points of the same 1D sequence inside stratum g, and the light's Halton
    // points L·G·P.. for its other numbers, so the layers together are the first (L+1)·G·P
    // points of one QMC set. Layer 0 is the set without refinement, unchanged by it.
    PathEnds trace(int light, int group, int index, std::vector<TracedVertex>& out,
                   int layer = 0) const;

    // Flux of one photon of `light` as emitted (Φ / (G·P)); zero for a switched-off light.
    glm::vec3 photon_power(int light) const;
    int dimensions() const { return dimensions_; }

private:
    // QMC number `dim` of photon k (global index within the light, over all layers), in [0, 1).
    float sample(int light, uint64_t k, int dim) const;

    const Scene& scene_;
    const RayTracer& rays_;
    int groups_, per_group_, max_bounces_, dimensions_;
    std::vector<Halton> halton_;  // per light, scrambled with the scene seed and the light index
    std::vector<std::vector<float>> tables_;  // per light: tabulated numbers of every photon
    std::unique_ptr<MediaTracker> media_;     // the scene's media as of the last refresh()
};

}  // namespace ag::cpu
