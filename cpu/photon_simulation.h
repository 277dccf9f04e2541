// Selective photon tracing (Larsen ch. 9): a photon simulation of the scene that is repaired, not
// recomputed, when the scene changes. A moved object invalidates at once every group whose stored
// path crosses its old or new placement; each frame one photon per QMC group is also re-traced
// (round robin) and compared with its stored path as a safety net. Invalid groups wait in a queue,
// largest flux first, worked off under a per-frame photon budget.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <utility>
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
    int groups_invalidated = 0;  // by all causes: query, verification, light and albedo edits
    int groups_invalidated_by_query = 0;  // paths crossing a moved object's old or new placement
    int objects_moved = 0;                // objects whose placement the query tested
    uint64_t query_segments_tested = 0;   // path segments tested exactly (narrow phase)
    double query_ms = 0.0;                // wall time of the moved-object query
    int photons_retraced = 0;
    int groups_retraced = 0;
    int groups_queued = 0;       // still waiting after this frame
    int photons_grown = 0;       // photons traced for the next refinement layer
    int layers = 1;              // complete photon sets the maps hold after this frame
    int aim_texels_rebuilt = 0;  // filled in by the AIM stage
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
    // The same with another retrace budget (photons) than settings.photons.retrace_budget. With
    // `grow`, a settled simulation spends what the budget has left on refinement
    // (photons.refine_layers): one more photon set for as many groups as it affords, the groups
    // with the fewest sets first, each joining the maps at once.
    PhotonFrameStats frame(int retrace_budget, bool grow = true);
    // Queues every group of every enabled light for a retrace (brute force: nothing is trusted);
    // returns how many were queued.
    int invalidate_all();

    // Traces every group from scratch in the current scene (a fresh simulation's state), grown to
    // every refinement layer when growth is on.
    void trace_all();

    // Nothing queued and, with growth on, every refinement layer in the maps.
    bool settled() const { return queue_.empty() && !growth_pending(); }
    // Progressive photon refinement on or off (on by construction; it does nothing while
    // photons.refine_layers is 1). Off drops the extra sets at the next frame. An edit drops
    // the extra sets of the groups it re-traces only.
    void set_growth(bool on) { growth_on_ = on; }
    bool growth_pending() const { return growth_on_ && layers() < target_layers(); }
    // The fewest photon sets any group holds: the complete sets in the maps.
    int layers() const { return maps_.layers(); }
    // photons.refine_layers, at most what the maps were made for (the setting at construction).
    int target_layers() const {
        return std::clamp(scene_.settings.photons.refine_layers, 1, max_layers_);
    }
    // Off: moved objects are found only by round-robin verification (for measurements and tests).
    void set_query_invalidation(bool on) { query_on_ = on; }
    // Off: no round-robin verification either (a brute-force baseline that trusts nothing and
    // re-traces everything in turn).
    void set_verification(bool on) { verify_on_ = on; }
    // Photons waiting in the retrace queue.
    int queued_photons() const {
        return int(queue_.size()) * scene_.settings.photons.photons_per_group;
    }
    // (light, group) of every group invalidated during the last frame(), in invalidation order.
    const std::vector<std::pair<int, int>>& invalidated_last_frame() const { return invalidated_; }
    const PhotonMaps& maps() const { return maps_; }
    PhotonMaps& maps() { return maps_; }
    const Scene& scene() const { return scene_; }
    const RayTracer& rays() const { return *rays_; }
    LightGroupState light_state(int light) const;
    uint64_t frame_index() const { return frame_; }
    // The last entry of scene.changes applied (its sequence): older ones may be trimmed.
    uint64_t changes_seen() const { return seen_sequence_; }
    // Groups of `light` invalidated since construction (verification, edits), for diagnostics.
    uint64_t invalidations(int light) const { return invalidations_[size_t(light)]; }

private:
    // A group's place in the retrace queue: largest flux first, then (light, group) for a fixed
    // order.
    struct QueuedGroup {
        double flux = 0.0;
        int light = 0, group = 0;
        bool operator<(const QueuedGroup& o) const {
            if (flux != o.flux) return flux > o.flux;
            return std::pair(light, group) < std::pair(o.light, o.group);
        }
    };
    // What edit queries need of a group's stored paths beyond its vertices.
    struct GroupSegments {
        Bounds bounds;               // every finite segment, emission origins included
        std::vector<PathEnds> ends;  // per photon
        bool escapes = false;        // some photon's last ray left the scene (unbounded)
    };

    void apply_changes(PhotonFrameStats& stats);
    // Invalidates every traced group with a path segment crossing a moved object at its transform
    // before (given) or now (the object's bounds in its own frame, padded: conservative).
    void invalidate_crossing(const std::vector<std::pair<int, Transform>>& moved,
                             PhotonFrameStats& stats);
    double group_flux(int light, int group) const;
    void invalidate(int light, int group, PhotonFrameStats& stats);
    // Traces the groups' photons into traced_ / traced_ends_ (set sets[i] of group i; set 0
    // when `sets` is empty) on the pool's threads.
    void trace_groups(const std::vector<std::pair<int, int>>& groups, const std::vector<int>& sets);
    // Re-traces the groups: their first set, the other sets leaving the maps; or with
    // photons.retrace_all_sets every set each holds.
    void retrace_groups(const std::vector<std::pair<int, int>>& groups);
    // Photon sets a re-trace of the group traces (retrace_groups).
    int retrace_sets(int light, int group) const;
    // Traces one more photon set for each group and adds it to the maps.
    void grow_groups(const std::vector<std::pair<int, int>>& groups);
    // Groups that may grow a set, the fewest sets first, then in (light, group) order.
    std::vector<std::pair<int, int>> groups_to_grow() const;
    // Every group keeps at most `most` sets.
    void trim_sets(int most);
    // Group `group` of `light` keeps its first `keep` sets; the others' hits and segments go.
    void clear_sets(int light, int group, int keep);
    // The edit query's segments of set-group `set_group` (set k · groups + group) of light l.
    void store_segments(int l, int set_group, const PathEnds* ends);
    size_t segment_index(int light, int set_group) const;
    bool same_path(const PhotonGroup& group, int photon,
                   const std::vector<TracedVertex>& path) const;

    const Scene& scene_;
    ThreadPool& pool_;
    std::unique_ptr<RayTracer> rays_;
    std::unique_ptr<PhotonTracer> tracer_;
    PhotonMaps maps_;
    std::set<QueuedGroup> queue_;
    std::vector<std::pair<int, int>> invalidated_;  // during the last frame
    std::vector<GroupSegments> segments_;           // [(light · max sets + set) · groups + group]
    std::vector<Transform> placed_;      // per object: the transform the paths were traced in
    std::vector<Bounds> object_bounds_;  // per object, in its own frame
    bool query_on_ = true;
    bool verify_on_ = true;
    bool changed_ = false;  // the last apply_changes() saw an edit other than the camera's
    uint64_t seen_sequence_ = 0;
    uint64_t frame_ = 0;
    float tolerance_ = 0.0f;               // world units
    std::vector<glm::vec3> traced_power_;  // per light: photon power the stored hits carry
    std::vector<uint64_t> invalidations_;  // per light
    std::vector<std::vector<TracedVertex>> traced_;  // re-used path buffers, one per photon job
    std::vector<PathEnds> traced_ends_;              // their ends
    bool growth_on_ = true;
    int max_layers_ =
        1;  // photon sets the maps have room for (photons.refine_layers at construction)
};

}  // namespace ag::cpu
