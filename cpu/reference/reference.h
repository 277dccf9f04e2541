// Reference renderers for the GPU frame (Larsen ch. 4, Fig. 14.3 and 14.5): a path tracer and
// traditional photon mapping, both split into the frame's components (eq. 13.2, docs/reference.md)
// and both progressive, multi-threaded and deterministic. Also the direct light they share.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <glm/glm.hpp>
#include <string>

#include "cpu/media_tracking.h"
#include "cpu/ray_tracer.h"
#include "cpu/sampling.h"
#include "shared/frame_terms.h"
#include "shared/image.h"
#include "shared/parallel.h"
#include "shared/qmc.h"
#include "shared/scene.h"

namespace ag::cpu {

enum class ReferenceMethod { path_tracing, photon_mapping };
inline constexpr std::array kReferenceMethodNames = {"pt", "pm"};

// Radiance of one camera sample, by frame term (shared/frame_terms.h: defined at the first
// diffuse point x seen from the camera).
struct ComponentRadiance {
    std::array<glm::vec3, kFrameTermCount> value{};

    glm::vec3& operator[](FrameTerm c) { return value[size_t(c)]; }
    const glm::vec3& operator[](FrameTerm c) const { return value[size_t(c)]; }
    glm::vec3 full() const {
        glm::vec3 sum = value[0];
        for (size_t c = 1; c < value.size(); ++c) sum += value[c];
        return sum;
    }
};

// A rectangle of the camera's pixels (a tile of a distributed reference render); width 0 = all.
struct PixelRegion {
    int x = 0, y = 0, width = 0, height = 0;
};

struct ReferenceSettings {
    ReferenceMethod method = ReferenceMethod::path_tracing;
    int spp = 0;              // stop after this many samples per pixel; 0 = no sample limit
    double time_limit = 0.0;  // stop after this many seconds (photon maps included); 0 = none.
                              // At least one pass always completes; with neither, one pass.
    uint32_t seed = 1;        // scrambles every sequence; same seed, same image
    int max_depth = 256;      // path length cap (Russian roulette ends paths long before)
    // Diffuse bounces between the light and the visible point x that the indirect term keeps:
    // 1 = light reflected by one surface on its way to x (the single-bounce methods' term),
    // 0 = no indirect light, < 0 = all. Direct light, caustics (L S+ D x) and what mirrors show
    // keep their definitions; bounces are counted at diffuse vertices after x (docs/reference.md).
    int indirect_bounces = -1;
    // Only these pixels are rendered and the result is this size; each pixel's samples depend on
    // its place in the whole image only, so tiles merge into exactly the whole image.
    PixelRegion region;
    int volume_bounces = 256;  // pt: scattering events in media per path (1: single scattering)
    // pt: light tracing from point, spot and sun lights through mirrors and glass (paths
    // L S+ D ... that next-event estimation cannot sample; light_tracer.h). Active when the scene
    // has such a light, a mirror or glass object and no media.
    bool light_tracing = true;
    int64_t light_paths = 0;  // light paths per pass; 0 = one per pixel of the whole image

    // Photon mapping only.
    int photons = 1000000;          // global map: photons emitted from all lights together
    int caustic_photons = 1000000;  // caustic map: photons aimed at mirror and glass objects
    int knn = 100;                  // nearest photons per global-map density estimate
    int caustic_knn = 50;           // nearest photons per caustic estimate
    float caustic_radius = 0.0f;    // caustic search radius cap; 0 = 1% of the scene diagonal
    int gather_rays = 64;           // final-gather rays per camera sample (× spp per pixel)
    int area_light_samples = 16;    // shadow rays per quad light per camera sample
};

// What a progress display needs; reported from worker threads, at most a few times a second.
struct ReferenceProgress {
    std::string stage;      // "photons" or "render"
    double fraction = 0.0;  // of the stage (render: of the sample budget, or of the time limit)
    int passes_done = 0;
    double elapsed = 0.0;  // seconds since the start
    double eta = -1.0;     // seconds to go; < 0 = unknown
};
using ReferenceProgressFn = std::function<void(const ReferenceProgress&)>;

struct ReferenceResult {
    Image full;                                      // = sum of the components
    std::array<Image, kFrameTermCount> components;   // indexed by FrameTerm
    int spp = 0;                                     // completed passes (one sample each)
    double seconds = 0.0;                            // wall clock, photon maps included
    double photon_seconds = 0.0;                     // photon tracing and map building (pm)
    size_t global_photons = 0, caustic_photons = 0;  // stored photons (pm)
    uint64_t light_paths = 0;                        // pt: light paths traced (all passes)
    std::string light_tracing_skipped;  // pt: why there was no light tracing ("" = there was)
};

// Renders scene.camera at its resolution (or settings.region of it; std::invalid_argument if the
// region is not inside the image). Samples are QMC points seeded per pixel and sample
// index, so the image does not depend on the thread count; a time limit only decides how many
// whole passes are kept (an interrupted pass is dropped).
ReferenceResult render_reference(const Scene& scene, const ReferenceSettings& settings,
                                 ThreadPool& pool, const ReferenceProgressFn& progress = {});

// Irradiance E at the front side (p, n) straight from the scene's enabled lights: point lights
// with a hard shadow (I cos / d²), quad lights by `quad_samples` shadow rays on a rotated 2D
// lattice (rotation u1, u2). The reflected radiance is albedo/π · E.
// With `media` (and its number stream `more`), each light's share is attenuated by the
// transmittance of the world's media between p and the light.
glm::vec3 direct_irradiance(const Scene& scene, const RayTracer& rays, const glm::vec3& p,
                            const glm::vec3& n, int quad_samples, float u1, float u2,
                            const MediaTracker* media = nullptr, HashedStream* more = nullptr);

// The same lights' radiance scattered at p inside a medium towards the direction of travel
// `forward` reversed: Σ ∫ p_Schlick(forward · ω) L(ω) T dω (single scattering's integrand,
// Pfeuti eq. 2.5), attenuated by the world's media on the way to each light.
glm::vec3 direct_inscattering(const Scene& scene, const RayTracer& rays, const glm::vec3& p,
                              const glm::vec3& forward, float phase_k, int quad_samples, float u1,
                              float u2, const MediaTracker& media, HashedStream& more);

// Radiance of the nearest quad light whose front the ray meets before `tmax`, or zero. Lights are
// not geometry: only the path tracer asks, for rays that left a specular vertex (caustics).
glm::vec3 quad_light_radiance(const Scene& scene, const Ray& ray, float tmax);

// Diagonal of the world bounding box of all objects (1 for an empty scene): the scale of search
// radii.
float scene_diagonal(const Scene& scene);

}  // namespace ag::cpu
