// Scheduling by time, not by counts (DESIGN.md): the thesis's per-frame counts (≤ 20 texels, a
// few AIM surfaces) were sized for a 2004 GPU. With a frame-time target the scheduler measures,
// frame by frame, what drawing took and what one unit of each kind of work cost (a photon traced,
// an AIM texel rebuilt, an IIM texel gathered by the backend in use) and sizes the next frame's
// work to fill the target: on the GL thread IIM texels after drawing; on the workers invalid
// photon groups first, then AIM texels with what is left.
#pragma once

#include <limits>

#include "shared/pipeline/pipeline_stats.h"
#include "shared/settings.h"

namespace ag {

// An exponentially weighted running mean; empty until the first sample.
class RunningCost {
public:
    void add(double x) {
        value_ = samples_ == 0 ? x : value_ + 0.3 * (x - value_);
        ++samples_;
    }
    bool known() const { return samples_ > 0; }
    double value() const { return value_; }

private:
    double value_ = 0.0;
    int samples_ = 0;
};

struct FrameBudgets {
    static constexpr int kUnlimited = std::numeric_limits<int>::max();
    int retrace_photons = kUnlimited;  // photons re-traced for invalid groups (workers)
    int aim_surfaces = kUnlimited;     // AIM surfaces rebuilt (workers)
    int iim_texels = kUnlimited;       // IIM texels gathered (GL thread)
    double gather_ms = 0.0;            // the GL thread's time share for gathering; 0: none
    double worker_ms = 0.0;            // time target for the workers' photon + AIM work; 0: none
};

class FrameScheduler {
public:
    // Budgets for the next frame: the fixed counts of the settings without a target; with one,
    // what the measured costs say fits (the counts then cap them only with counts_cap). In the
    // frame of an edit after frames without one (`edited`) drawing costs more than the running
    // estimate says: it draws every light's shadows anew (a settled frame keeps its complete
    // direct mean), and moved geometry besides (shadow volumes, cube-map faces). The GL thread
    // then leaves for drawing the larger of what the last frames that drew the direct light anew
    // cost (the conference room at 64²: 154 ms against 50 ms for a settled frame) and
    // kEditDrawFactor times the usual estimate (two_rooms' door: 16–27 ms against 12 ms), and
    // gathers with the rest, at least kMinGatherShare of the target. The gathering reads the
    // edit's AIMs as soon as the workers hand them over (between chunks).
    // In the frames after such an edit (`catching_up`: while the caustic photons are traced again,
    // drawn every other frame, and the cube-map faces re-lit one a frame) drawing stays above the
    // running estimate too: they plan for the largest of that estimate and the last two frames'
    // drawing (two_rooms' door at 96²: 28-46 ms of drawing in the three frames after the edit's,
    // planned as 16-19 ms). The caustics' drawing and the cube-map faces that draw their direct
    // light again are learnt apart from the frame's own drawing: a frame that is to draw them
    // (`draws_caustics`, `relit_faces`) plans for what they cost on top.
    FrameBudgets budgets(const Settings& settings, int iim_texels_total, bool edited = false,
                         bool catching_up = false, bool draws_caustics = false,
                         int relit_faces = 0) const;
    // The GL thread's gathering for a frame that has drawn already, `elapsed_ms` into it: what
    // is left of the target, at least kMinGatherShare of it (Pipeline: the edit's frame).
    FrameBudgets after_drawing(const Settings& settings, int iim_texels_total,
                               double elapsed_ms) const;
    static constexpr double kEditDrawFactor = 2.0;
    // When drawing alone overruns the target, gathering still gets this share of it: the frame
    // rate cannot hold there, and the picture keeps converging.
    static constexpr double kMinGatherShare = 0.25;
    // AIM texels the workers may still rebuild, `elapsed_ms` into their frame.
    int aim_texels_left(const Settings& settings, double elapsed_ms) const;
    // Learns from a finished frame.
    void measure(const PipelineStats& stats);
    // Learns unit costs from bulk work done outside the frames (Pipeline::prime): batches large
    // enough that their fixed costs are amortised, so the first frame after them (often an
    // edit's, with its one-time costs) does not have to be the first measurement.
    void seed(int texels, double gather_ms, int photons, double photon_ms, int aim_texels,
              double aim_ms);

    const RunningCost& draw_ms() const { return draw_ms_; }
    const RunningCost& caustics_draw_ms() const { return caustics_draw_ms_; }
    const RunningCost& relit_face_ms() const { return relit_face_ms_; }
    const RunningCost& direct_draw_ms() const { return direct_draw_ms_; }
    const RunningCost& gather_ms_per_texel() const { return gather_ms_per_texel_; }
    const RunningCost& photon_ms() const { return photon_ms_; }
    const RunningCost& aim_ms_per_texel() const { return aim_ms_per_texel_; }

private:
    // IIM texels that fit `gather_ms` at the measured cost (at least one, at most all; capped
    // by the fixed count with counts_cap).
    int gather_texels(const Settings& settings, double gather_ms, int iim_texels_total) const;

    RunningCost draw_ms_;              // GL thread, besides gathering and caustics: frame, uploads
    RunningCost caustics_draw_ms_;     // GL thread, a drawing of the caustics
    RunningCost relit_face_ms_;        // GL thread, a cube-map face re-lit
    RunningCost direct_draw_ms_;       // the same, frames that drew the direct light anew
    RunningCost gather_ms_per_texel_;  // GL thread, per IIM texel, with the backend in use
    RunningCost photon_ms_;            // workers, per photon traced (verified or re-traced)
    RunningCost aim_ms_per_texel_;     // workers, per AIM texel rebuilt
    RunningCost caustic_ms_;           // workers, caustic photons (a fixed share per frame)
    double last_drawing_[2] = {0.0, 0.0};  // the last two measured frames' drawing (ms)
};

}  // namespace ag
