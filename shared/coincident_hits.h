// The closest hit among coincident faces, the rule of cpu/ray_tracer.cpp (every CPU tracer's
// closest hit goes through it; the flat BVH gpu_pm walks does not follow it yet). Float rounding
// (vertices placed by a transform, a ray taken into an instance's space, t itself) puts coplanar
// faces a few float steps apart in either order, so "the nearest" among them is an accident of
// rounding and traversal order. Faces whose hits lie within a tolerance of the nearest one,
// measured along its normal, are coincident; among them a face the ray meets from behind wins (a
// closed object stays closed where one of its faces lies in another surface's plane: a lamp in a
// box flush with the ceiling lights nothing), then the lowest object, then the lowest triangle.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>
#include <limits>

namespace ag {

// The tolerance (world units): kCoincidentRelative × the scene's diagonal (a tenth of the ray
// offset the tracers use, 10⁻⁵ of it) or kCoincidentSteps float steps of the ray origin's largest
// coordinate, whichever is larger (far from the origin a float step outgrows the first).
inline constexpr float kCoincidentRelative = 1e-6f;
inline constexpr float kCoincidentSteps = 8.0f * std::numeric_limits<float>::epsilon();
// Along a ray that grazes a face the window is tolerance / cos; below this cosine it stops
// growing, so the traversal's extra reach stays bounded.
inline constexpr float kMinCoincidentCos = 1e-3f;

inline float coincident_tolerance(float scene_diagonal, const glm::vec3& origin) {
    const glm::vec3 o = glm::abs(origin);
    return std::max(kCoincidentRelative * scene_diagonal,
                    kCoincidentSteps * std::max({o.x, o.y, o.z}));
}

// One face a ray meets. No initialisers: CoincidentHits holds kMax of them per ray, and filling
// them for every ray cost more than the rule's own work (bench photons).
struct HitCandidate {
    float t;
    uint32_t object, triangle;
    bool back;  // the ray meets the face from behind (direction · normal > 0)
    float cos;  // |cos| between the ray and the face
};

// The facing and cosine of a hit, from the ray's direction and the face's (unnormalised) normal
// in the same space.
inline void set_facing(HitCandidate& c, const glm::vec3& direction, const glm::vec3& normal) {
    const float d = glm::dot(direction, normal);
    c.back = d > 0.0f;
    c.cos = std::abs(d) / (glm::length(direction) * glm::length(normal));
}

inline bool preferred(const HitCandidate& a, const HitCandidate& b) {
    if (a.back != b.back) return a.back;
    if (a.object != b.object) return a.object < b.object;
    return a.triangle < b.triangle;
}

// Collects the faces a ray meets within the window of the nearest so far; a traversal culls
// everything beyond cull_t(). Because the nearest t only decreases, what it keeps is every face
// within the window of the true nearest hit, whatever order the traversal meets them in (up to
// kMax faces meeting at one point: beyond that the farthest drop). Payload: what the caller needs
// to make its hit (barycentrics, normal).
template <class Payload, int kMax = 8>
class CoincidentHits {
public:
    // tolerance: coincident_tolerance(); speed: |direction|.
    CoincidentHits(float tolerance, float speed)
        : tolerance_(tolerance), speed_(speed), window_(tolerance / (speed * kMinCoincidentCos)) {}

    void add(const HitCandidate& c, const Payload& p) {
        for (int i = 0; i < count_; ++i)  // spatial splits put one triangle in several leaves
            if (hits_[size_t(i)].object == c.object && hits_[size_t(i)].triangle == c.triangle)
                return;
        near_ = std::min(near_, c.t);
        int kept = 0;
        for (int i = 0; i < count_; ++i)
            if (hits_[size_t(i)].t <= near_ + window_) {
                hits_[size_t(kept)] = hits_[size_t(i)];
                payloads_[size_t(kept++)] = payloads_[size_t(i)];
            }
        count_ = kept;
        int slot = count_;
        if (count_ < kMax) {
            ++count_;
        } else {
            slot = int(std::max_element(hits_.begin(), hits_.end(),
                                        [](const auto& a, const auto& b) { return a.t < b.t; }) -
                       hits_.begin());
            if (!(c.t < hits_[size_t(slot)].t)) return;
        }
        hits_[size_t(slot)] = c;
        payloads_[size_t(slot)] = p;
    }

    // Faces beyond this cannot be coincident with the nearest one.
    float cull_t() const { return near_ + window_; }
    bool empty() const { return count_ == 0; }

    // The nearest face (ties by the rule), then the preferred face coincident with it: within
    // the tolerance along the nearest face's normal. Null when the ray met nothing.
    const Payload* best(HitCandidate* chosen = nullptr) const {
        if (count_ == 0) return nullptr;
        int nearest = 0;
        for (int i = 1; i < count_; ++i) {
            const HitCandidate &a = hits_[size_t(i)], &b = hits_[size_t(nearest)];
            if (a.t < b.t || (a.t == b.t && preferred(a, b))) nearest = i;
        }
        const HitCandidate& n = hits_[size_t(nearest)];
        const float limit = n.t + tolerance_ / (speed_ * std::max(n.cos, kMinCoincidentCos));
        int best = nearest;
        for (int i = 0; i < count_; ++i)
            if (hits_[size_t(i)].t <= limit && preferred(hits_[size_t(i)], hits_[size_t(best)]))
                best = i;
        if (chosen) *chosen = hits_[size_t(best)];
        return &payloads_[size_t(best)];
    }

private:
    float tolerance_, speed_, window_;
    float near_ = std::numeric_limits<float>::infinity();
    int count_ = 0;
    std::array<HitCandidate, size_t(kMax)> hits_;  // [0, count_) hold faces
    std::array<Payload, size_t(kMax)> payloads_;
};

}  // namespace ag
