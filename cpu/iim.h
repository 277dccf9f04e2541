// The indirect illumination map, IIM (Larsen ch. 11): per lightmap texel the indirect irradiance
// E/π gathered from the AIMs. Texels of surfaces whose indirect photon hits changed most (Δi) are
// re-gathered first; texels gathered with older AIMs are refreshed round robin with what is left
// of the budget; with screen coverage known, the texels the camera sees go first in each class.
// A gather that saw too many back faces is invalid and repaired from its chart's neighbours
// (unless part of its footprint can gather, see relocate); new values fade in over blend_frames
// so the picture never pops. When nothing is queued or stale, settled texels are refined:
// gathered again at other points of their footprint with other ray sets, the results averaged
// (settings.gather.refine_passes), so a static scene's IIM noise keeps falling.
#pragma once

#include <cstdint>
#include <deque>
#include <glm/glm.hpp>
#include <vector>

#include "cpu/photon_map.h"
#include "shared/charts.h"
#include "shared/gather.h"
#include "shared/scene.h"

namespace ag::cpu {

struct IimFrameStats {
    int gathered = 0;   // texels gathered this frame
    int invalid = 0;    // of those, repaired from neighbours (inside geometry, all footprint too)
    int relocated = 0;  // of those, whose centre saw too many back faces but a point of their
                        // footprint did not: gathered there instead
    int pending = 0;    // texels still queued by Δi after scheduling
    int refined = 0;    // of `gathered`, refinement passes of settled texels
};

class Iim {
public:
    // Every texel starts queued (nothing is gathered yet).
    explicit Iim(const Scene& scene);

    // A new AIM reached the gatherers: every texel gathered before is stale.
    void aim_changed() { ++aim_generation_; }
    // Queues the texels of surfaces whose indirect hits changed (Δi above aim.delta_threshold of
    // the surface's flux), largest Δi first and ahead of everything else queued but texels never
    // gathered, and resets those surfaces' Δi.
    void schedule(PhotonMaps& maps);
    // Per texel record, its indirect irradiance estimate from the photons as the AIMs now hold it
    // and the floor of a relative change (Aim::indirect_estimates, indirect_floors; −1 = never
    // built). A texel's staleness is how far its estimate moved since the texel was last gathered,
    // |E_now − E_gathered| / (E_now + E_gathered + floor): the next schedule() orders the texels
    // of changed surfaces by it, most stale first. Measured from the last gather, not from the
    // last AIM rebuild, so small changes over many frames of a continuous move add up.
    void note_indirect_estimates(const std::vector<float>& estimates,
                                 const std::vector<float>& floors);
    // The staleness above; +∞ where either estimate is not known.
    float staleness(int record) const;
    // Per texel record, the fraction of the screen it covers (gpu::TexelCoverage); empty = not
    // known. Texels the camera sees are queued and refreshed before the others of their class.
    void set_coverage(const std::vector<float>& per_record);
    // Queues every texel (brute force).
    void invalidate_all();
    // Queues the texels whose centres lie inside `regions` (world space), nearest to a region's
    // centre first: where a moved object changes what gathers see, before any photon says so.
    void queue_inside(const std::vector<Bounds>& regions);
    // Queues the texels of moved objects: what each gathered was seen from another place, so the
    // photons' estimates say little about how far off it is (after Cornell's cube jumped, its
    // front face waited 13 frames behind the floor and walls with half the image's error). Until
    // gathered they rank as if their light were all wrong (relative error 1: the pixels they
    // cover), ahead of the queue now and among the changed texels in later schedule()s.
    void queue_moved(const std::vector<int>& objects);
    // Gathers up to `budget` texels with `gatherer`: queued ones first, then stale ones round
    // robin; when there are none, refinement passes of settled texels, fewest passes first.
    // Results that saw more than kBackFaceInvalidFraction back faces are repaired from valid
    // neighbours of their chart. The new values start blending at `frame`.
    IimFrameStats gather(Gatherer& gatherer, int budget, uint64_t frame);
    // Gathers exactly `records` (validity, repair and blending as above); each starts a new mean.
    IimFrameStats gather_records(Gatherer& gatherer, const std::vector<int>& records,
                                 uint64_t frame);
    // One more refinement pass of each of `records` (settled, valid, fewer passes than
    // settings.gather.refine_passes): pass k gathers at footprint offset refine_offset(k) with the
    // ray set of (record, k) and adds to the record's mean. The settled mean depends only on the
    // record, the scene and the AIMs, never on the order passes ran in.
    IimFrameStats refine_records(Gatherer& gatherer, const std::vector<int>& records,
                                 uint64_t frame);
    // Gathers in several batches within one frame: the repair of invalid texels from their
    // neighbours (and the blends it starts) waits for repair_deferred(), once, instead of running
    // after every batch; the result is the same as one batch of all of them.
    void defer_repairs();
    void repair_deferred(uint64_t frame);
    // Advances every blend to `frame` over `blend_frames` frames; returns the atlas texels whose
    // shown value changed (to upload).
    const std::vector<int>& blend(uint64_t frame, int blend_frames);

    // Atlas-sized (width × height): what the frame shows, and the latest gathered values.
    const std::vector<glm::vec3>& shown() const { return shown_; }
    const std::vector<glm::vec3>& gathered() const { return raw_; }
    // Per texel record.
    const std::vector<char>& texel_pending() const { return is_pending_; }
    const std::vector<char>& texel_valid() const { return valid_; }
    const std::vector<int>& last_gathered() const { return last_gathered_; }  // records
    int pending() const { return int(pending_.size()); }
    // Per record: gathers in its current mean (0: never gathered).
    const std::vector<int>& texel_passes() const { return passes_; }
    // Nothing queued, blending, gathered with an older AIM than the latest, or left to refine.
    bool settled() const;
    // Nothing queued, nothing gathered with an older AIM and every valid texel refined (blends
    // may still run).
    bool complete() const;
    // Atlas offset from the texel centre of refinement pass `pass` (pass 0: the centre), a
    // Halton (2, 3) point in the texel's footprint [−½, ½]².
    static glm::vec2 refine_offset(int pass);

private:
    // Gathers each invalid texel at the nearest point of its footprint that sees few back faces;
    // those become valid, `invalid` keeps the rest (to repair from neighbours). Returns how many.
    int relocate(Gatherer& gatherer, std::vector<int>& invalid);
    // Sets a record's raw value, starting its mean at one gather.
    void start_mean(int record, glm::vec3 value, bool valid);
    // Refills invalid texels from their neighbours and starts the blends of `batch` and of every
    // repaired texel whose value changed.
    void repair_and_blend(const std::vector<int>& batch, uint64_t frame);
    // Records refine_records may take: gathered with the latest AIM, valid, not queued, and
    // fewer than refine_passes gathers in their mean.
    bool refinable(size_t record) const;

    bool seen(int t) const { return coverage_.empty() || coverage_[size_t(t)] > 0.0f; }
    // Order within the changed texels: (|E_now − E_gathered| / (E_now + floor))² × pixels
    // covered where the camera sees the texel (its share of the image's relative squared error);
    // the staleness alone where coverage is not known or the texel is not seen. A texel of a
    // moved object not gathered since: 1² × pixels, or +∞ where not seen.
    float priority(int record) const;

    const Scene& scene_;
    std::vector<float> coverage_;    // per record; empty = not known
    std::vector<int> seen_records_;  // records with coverage
    bool deferring_ = false;         // defer_repairs() until repair_deferred()
    std::vector<int> deferred_;      // records gathered meanwhile
    // Per record: the photons' indirect estimate now and when last gathered (−1 = not known),
    // and the floor of a relative change; empty = never noted.
    std::vector<float> estimate_, estimate_gathered_, estimate_floor_;
    std::deque<int> pending_;  // texel records, FIFO, each at most once
    std::vector<char> is_pending_;
    std::vector<int> last_gathered_;
    std::vector<char> valid_;                         // per record: last gather saw few back faces
    std::vector<glm::vec3> raw_, from_, to_, shown_;  // atlas-sized
    std::vector<int> blend_start_;  // per atlas texel: frame the new value arrived, −1 = done
    std::vector<int> blending_;     // atlas texels currently blending
    std::vector<int> changed_;      // returned by blend()
    int aim_generation_ = 0;
    std::vector<std::vector<FootprintPoint>> footprint_;  // per record, computed when first needed
    std::vector<int> texel_generation_;  // per record: AIM generation gathered with; −1 = never
    std::vector<char> moved_;            // per record: its object moved since it was gathered
    std::vector<std::vector<int>> object_texels_;   // per object: its texel records
    std::vector<std::vector<int>> surface_texels_;  // per surface: its texel records
    size_t sweep_ = 0;
    // Per record, the running mean of its gathers with the current inputs (refinement).
    std::vector<int> passes_;         // gathers run: the first, then refinement passes
    std::vector<glm::dvec3> sum_;     // of the valid ones
    std::vector<int> valid_samples_;  // how many were valid
    size_t refine_sweep_ = 0;
};

}  // namespace ag::cpu
