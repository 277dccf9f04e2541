// Free-flight sampling and transmittance in the scene's participating media for the CPU
// references (Pfeuti 2009, ch. 2.2): delta (Woodcock) tracking against the majorant σ_t·(1 + a)
// for collisions, closed-form Beer–Lambert or ratio tracking for the transmittance of shadow rays.
#pragma once

#include <cstdint>
#include <optional>

#include "cpu/ray_tracer.h"
#include "cpu/sampling.h"
#include "shared/scene.h"

namespace ag::cpu {

// Whether the scene has any medium: a world box or a glass object's interior.
bool has_media(const Scene& scene);

// A stream of hashed uniforms [0, 1), a pure function of its key and how many were drawn: delta
// and ratio tracking need an unbounded count per segment.
class HashedStream {
public:
    explicit HashedStream(uint64_t key) : state_(key) {}
    float next() {
        state_ = mix64(state_ + 0x9e3779b97f4a7c15ull);
        return to_unit_float(state_);
    }

private:
    uint64_t state_;
};

// A real collision: where, in which medium.
struct MediumCollision {
    float t = 0.0f;
    const Medium* medium = nullptr;
};

class MediaTracker {
public:
    explicit MediaTracker(const Scene& scene);

    bool empty() const { return empty_; }
    // The medium filling glass object `object`, or none (clear glass, or not glass).
    const Medium* interior(int object) const;

    // The first real collision on ray (o, unit d) for t in [0, tmax), by delta tracking: inside
    // glass object `inside` (≥ 0) its interior medium, otherwise the world boxes. `u` is the
    // first uniform (a QMC number); later ones come from `more`. None if the ray gets through.
    std::optional<MediumCollision> sample_collision(const Ray& ray, float tmax, int inside, float u,
                                                    HashedStream& more) const;
    // Transmittance exp(−∫σ_t) along the same span: closed form in homogeneous media, ratio
    // tracking (unbiased, numbers from `more`) in perturbed ones.
    float transmittance(const Ray& ray, float tmax, int inside, HashedStream& more) const;

private:
    // The media the span crosses, as disjoint [enter, exit) intervals in order; returns the count.
    struct Span {
        float enter = 0.0f, exit = 0.0f;
        const Medium* medium = nullptr;
    };
    int spans(const Ray& ray, float tmax, int inside, Span* out) const;

    const Scene& scene_;
    std::vector<const Medium*> interiors_;  // per object
    bool empty_ = true;
};

}  // namespace ag::cpu
