// Final gathering behind one interface (Larsen ch. 11): gpu::HemiPlaneGather renders hemi-planes,
// cpu::CpuGather casts rays. Both read the AIMs they are bound to and return, per texel record,
// E_indirect/π and the share of the view that showed back faces. What a result means for the IIM
// (valid or not, repaired from neighbours, blended in) is decided once, by cpu::Iim.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "shared/settings.h"

namespace ag {

struct GatherResult {
    glm::vec3 iim{0.0f};         // E_indirect / π: a diffuse surface reflects albedo × iim
    float back_fraction = 0.0f;  // weighted share of the view that shows back faces
    // GL: the hemi-plane showed a mirror or glass, which it cannot see through; the result is
    // then to be replaced by the CPU gather's (settings.gather.specular_bounces > 0 only).
    bool sees_specular = false;
    // GL with the distance output on (gpu::HemiPlaneGather): the cosine-weighted harmonic mean
    // distance to what the view shows, misses counting as infinitely far (Gautron's R_k; the
    // irradiance cache's record radius); 0 where not measured.
    float harmonic_distance = 0.0f;
};

// A world-space point to gather at, other than a texel centre (a texel's footprint, a pixel).
struct GatherPoint {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};  // the side to gather over
    uint32_t key = 0;        // decorrelates the CPU gather's ray set between points
};

class Gatherer {
public:
    virtual ~Gatherer() = default;
    virtual GatherBackend backend() const = 0;
    // Gathers the texel records `texels` (indices into scene.atlas.texels) from the current scene
    // and the AIMs as they are now; results in the same order. Deterministic for any thread count.
    virtual std::vector<GatherResult> gather(const std::vector<int>& texels) = 0;
    // The same at arbitrary points.
    virtual std::vector<GatherResult> gather_points(const std::vector<GatherPoint>& points) = 0;
};

// A GL gather whose texels that see mirrors or glass are gathered again by a CPU gather, which
// follows the specular bounces: light through glass and off mirrors counts at the cost of rays
// for those texels only.
class SpecularRoutedGather final : public Gatherer {
public:
    SpecularRoutedGather(Gatherer& plane, Gatherer& rays) : plane_(plane), rays_(rays) {}
    GatherBackend backend() const override { return plane_.backend(); }
    std::vector<GatherResult> gather(const std::vector<int>& texels) override {
        return route(
            texels, [&](const auto& v) { return plane_.gather(v); },
            [&](const auto& v) { return rays_.gather(v); });
    }
    std::vector<GatherResult> gather_points(const std::vector<GatherPoint>& points) override {
        return route(
            points, [&](const auto& v) { return plane_.gather_points(v); },
            [&](const auto& v) { return rays_.gather_points(v); });
    }
    int last_routed() const { return routed_; }         // texels (points) the last call handed over
    int total_routed() const { return routed_total_; }  // and all calls together

private:
    template <class T, class Plane, class Rays>
    std::vector<GatherResult> route(const std::vector<T>& items, Plane plane, Rays rays) {
        std::vector<GatherResult> out = plane(items);
        std::vector<T> again;
        std::vector<size_t> where;
        for (size_t k = 0; k < out.size(); ++k)
            if (out[k].sees_specular) {
                again.push_back(items[k]);
                where.push_back(k);
            }
        if (!again.empty()) {
            const std::vector<GatherResult> traced = rays(again);
            for (size_t j = 0; j < where.size(); ++j) out[where[j]] = traced[j];
        }
        routed_ = int(again.size());
        routed_total_ += routed_;
        return out;
    }

    Gatherer& plane_;
    Gatherer& rays_;
    int routed_ = 0, routed_total_ = 0;
};

}  // namespace ag
