// Caustic photons (Larsen ch. 12): per light, QMC photons aimed only at the specular objects (the
// cones their bounding spheres subtend, each carrying its share of the light's flux), followed
// through mirrors and glass and stored at the first diffuse hit after at least one specular
// bounce (paths L S+ D), attenuated by Beer–Lambert through the scene's media. Progressive: each
// frame re-traces 1/N of the photons, so a moving glass object leaves at most an N-frame trail.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "cpu/media_tracking.h"
#include "cpu/ray_tracer.h"
#include "shared/parallel.h"
#include "shared/qmc.h"
#include "shared/scene.h"

namespace ag::cpu {

struct CausticPhoton {
    glm::vec3 position{0.0f};  // world space
    glm::vec3 power{0.0f};     // flux, W (zero: the slot holds no photon)
    glm::vec3 normal{0.0f};    // the receiving surface's normal, facing the photon
    uint32_t frame = 0;        // frame in which it was traced
};

struct CausticStats {
    int traced = 0;        // photons emitted this frame
    int hit_specular = 0;  // of those, how many reached a specular object first
    int stored = 0;        // and how many were stored (an L S+ D path)
};

class CausticTracer {
public:
    // Uses its own ray tracer (kept up to date with the scene) and the caller's pool.
    CausticTracer(const Scene& scene, ThreadPool& pool);

    // Brings the BVH up to date with the scene and re-traces the frame's slice of photons.
    CausticStats frame();
    // Re-traces every photon (a fresh, complete caustic map).
    CausticStats trace_all();

    // Fixed slots: caustics.photons per light; empty slots have zero power.
    const std::vector<CausticPhoton>& photons() const { return photons_; }
    uint32_t frame_index() const { return frame_; }

private:
    struct Cone {
        int object;
        glm::vec3 centre;
        double one_minus_cos;  // 1 − cos(half angle), kept exact for the tiny cones of far lights
        float solid_angle;
    };
    std::vector<Cone> cones(const glm::vec3& from) const;
    // For a sun: the specular objects' bounding spheres as discs across its direction (centre,
    // and the disc's area in solid_angle; one_minus_cos holds the radius).
    std::vector<Cone> discs() const;
    CausticStats trace_slice(int slice, int slices);
    CausticPhoton trace_photon(int light, int index, const std::vector<Cone>& cones,
                               const MediaTracker& media, bool& hit_specular) const;

    const Scene& scene_;
    ThreadPool& pool_;
    std::unique_ptr<RayTracer> rays_;
    std::vector<CausticPhoton> photons_;
    std::vector<Halton> halton_;  // per light, scrambled with the seed and the light index
    uint32_t frame_ = 0;
};

}  // namespace ag::cpu
