// Selective photon tracing (Larsen ch. 9): a photon simulation of the scene that is repaired, not
// recomputed, when the scene changes. Each frame one photon per QMC group is re-traced (round
// robin) and compared with its stored path; a diverged group is invalidated, its hits subtracted,
// and it waits in a queue that is worked off under a per-frame photon budget.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "cpu/photon_map.h"
#include "cpu/photon_tracer.h"
#include "cpu/ray_tracer.h"
#include "shared/parallel.h"
#include "shared/scene.h"

namespace ag::cpu {

struct PhotonFrameStats {
    uint64_t frame = 0;
    int photons_verified = 0;
    int groups_invalidated = 0;   // by verification, light moves, albedo edits, switching on
    int photons_retraced = 0;
    int groups_retraced = 0;
    int groups_queued = 0;        // still waiting after this frame
    int aim_texels_rebuilt = 0;   // filled in by the AIM stage
    int aim_surfaces_rebuilt = 0;
};

struct LightGroupState {
    int valid = 0;    // traced and not queued
    int invalid = 0;  // not holding hits of the current state (never traced, or cleared)
    int queued = 0;   // waiting for a retrace
};

class PhotonSimulation {
public:
    // Traces nothing yet: every group of every enabled light starts queued, so the first frames
    // fill the maps under the budget (or call trace_all()).
    PhotonSimulation(const Scene& scene, ThreadPool& pool);

    // One frame of photon work on the pool's worker threads: applies the scene's edits since the
    // last frame, verifies one photon per group, re-traces queued groups within the budget.
    PhotonFrameStats frame();
    // The same with another retrace budget (photons) than settings.photons.retrace_budget.
    PhotonFrameStats frame(int retrace_budget);
    // Queues every group of every enabled light for a retrace (brute force: nothing is trusted);
    // returns how many were queued.
    int invalidate_all();

    // Traces every group from scratch in the current scene (a fresh simulation's state).
    void trace_all();

    bool settled() const { return queue_.empty(); }
    const PhotonMaps& maps() const { return maps_; }
    PhotonMaps& maps() { return maps_; }
    const Scene& scene() const { return scene_; }
    const RayTracer& rays() const { return *rays_; }
    LightGroupState light_state(int light) const;
    uint64_t frame_index() const { return frame_; }
    // Groups of `light` invalidated since construction (verification, edits), for diagnostics.
    uint64_t invalidations(int light) const { return invalidations_[size_t(light)]; }

private:
    void apply_changes(PhotonFrameStats& stats);
    void invalidate(int light, int group, PhotonFrameStats& stats);
    void retrace_groups(const std::vector<std::pair<int, int>>& groups);
    bool same_path(const PhotonGroup& group, int photon, const std::vector<TracedVertex>& path) const;

    const Scene& scene_;
    ThreadPool& pool_;
    std::unique_ptr<RayTracer> rays_;
    std::unique_ptr<PhotonTracer> tracer_;
    PhotonMaps maps_;
    std::deque<std::pair<int, int>> queue_;  // (light, group), FIFO
    uint64_t seen_sequence_ = 0;
    uint64_t frame_ = 0;
    float tolerance_ = 0.0f;                 // world units
    std::vector<glm::vec3> traced_power_;    // per light: photon power the stored hits carry
    std::vector<uint64_t> invalidations_;    // per light
    std::vector<std::vector<TracedVertex>> traced_;  // re-used path buffers, one per photon job
};

}  // namespace ag::cpu
