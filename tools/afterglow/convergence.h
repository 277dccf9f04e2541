// Convergence runs, shared by `afterglow converge` and `afterglow bench settle`: the cached pm
// reference of a scene's final state, one progressive run recording the error after every frame,
// and the settle rule (docs/convergence.md): the settled value is the mean of the last tenth of
// the frames (at least 3); the run has settled at the first frame from the last edit on after
// which the error stays within 10% of that value.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "shared/image.h"
#include "shared/pipeline/pipeline.h"
#include "shared/scene.h"

namespace ag::cli {

// The EXR of one component beside a reference's full image: REF.COMPONENT.exr ("full": REF).
std::string component_path(const std::string& exr, const std::string& component);

struct ReferenceRequest {
    std::string name;  // file-name stem in the cache (the scene's)
    std::string cache = "out/reference-cache";
    int spp = 64, photons = 400000;
    int threads = 0;            // worker threads of the reference renderer
    int indirect_bounces = -1;  // the reference's indirect term: this many bounces (< 0 = all)
    bool path_traced = false;   // the pt reference instead of pm (`photons` is then unused)
    std::string log_prefix = "afterglow converge";  // for the messages on stderr
};

// The pm (or pt) reference of `scene`'s state after `script_path` (may be empty) has run for
// `frames` frames on a copy, at the scene camera's size: rendered into CACHE/NAME-HASH.exr (with
// every component beside it) unless already there; HASH covers everything the image depends on,
// and a small render of the scene by this build's renderer (a cache another build filled whose
// renderer draws differently is not read back).
// Returns the full image's path.
std::string cached_reference(const Scene& scene, const std::string& script_path, int frames,
                             const ReferenceRequest& request);

// The reference's `component` image, checked to be width × height (InputError otherwise).
Image read_reference(const std::string& reference_path, const std::string& component, int width,
                     int height);

struct FrameRecord {
    int frame = 0;
    double wall_s = 0.0;    // script and pipeline time since the run started, after this frame
    double frame_ms = 0.0;  // the pipeline's own frame time (PipelineStats::frame_ms)
    bool edited = false;    // the scene changed before this frame
    double relmse = 0.0, rmse = 0.0, ssim = 0.0;
    uint64_t groups_invalidated = 0, photons_retraced = 0, aim_texels = 0;
    int iim_texels = 0, iim_pending = 0;
    // CPU gather rays of the frame's IIM texels: traced, and re-read from the ray cache.
    uint64_t rays_traced = 0, rays_reused = 0;
    // The frame ended with its photon work still running (a frame-time target: it did not wait).
    bool workers_behind = false;
    // Where the frame's time went on the GL thread (PipelineStats): gathering (with its uploads),
    // drawing, waiting for the workers or an edit's wait for them; and the gathering the
    // scheduler planned (0 without a frame-time target).
    double gather_ms = 0.0, draw_ms = 0.0, wait_ms = 0.0, gather_plan_ms = 0.0;
    // The photon work handed over in this frame: the workers' time on it, and whether it was
    // taken over during the gather (selective) rather than at the frame's end.
    double photon_ms = 0.0, aim_ms = 0.0;
    bool early_hand_over = false;
    uint64_t photons_grown = 0;  // photons traced for the next refinement layer
    int layers = 1;              // photon sets in the maps (photons.refine_layers)
    bool converged = false;      // Pipeline::converged() after the frame
    // Of draw_ms: the caustics drawn again (0 when kept), and the cube-map faces that drew their
    // direct light again (after an edit, one a frame).
    double caustics_draw_ms = 0.0;
    int faces_relit = 0;
};

struct SettleAnalysis {
    double settled = 0.0;  // mean relMSE of the last tenth of the frames (at least 3)
    int first_edit = -1;   // -1: the scene was never edited (then last_edit is 0)
    int last_edit = 0;
    // First frame from last_edit on after which the error stays within 10% of `settled`; -1 if
    // none.
    int within = -1;
    int frames = -1;  // within − last_edit (0: the edit's own frame is already within), or −1
    // Wall time from the start of the last edit's frame (the moment the edit is made) to the end
    // of frame `within`, or −1. It includes the edit's own frame, where most repair work lands: a
    // mode that settles in that frame settles in that frame's time, not in no time.
    double seconds = -1.0;
    bool settled_ok() const { return within >= 0; }
};

// Wall time at the start of frame i of a run (the end of frame i − 1; `first_start_s`, the
// start of frames[0], for the first frame).
inline double frame_start_s(const std::vector<FrameRecord>& frames, size_t i,
                            double first_start_s = 0.0) {
    return i > 0 && i <= frames.size() ? frames[i - 1].wall_s : first_start_s;
}

struct ConvergenceRun {
    PipelineMode mode = PipelineMode::selective;
    IndirectMethodKind indirect = IndirectMethodKind::iim;
    std::string component;
    std::vector<FrameRecord> frames;
    SettleAnalysis settle;
    double wall_s = 0.0;  // of the whole run
};

// With `target` > 0 (the error of the converged final state, converged_error()) a run settles
// when its error is back within 10% of that; otherwise within 10% of its own plateau.
// `first_start_s`: the wall time at the start of frames[0] (non-zero for a slice of a run).
SettleAnalysis analyse_settle(const std::vector<FrameRecord>& frames, double target = 0.0,
                              double first_start_s = 0.0);

// The relMSE against `reference` of the converged final state: `scene` after `frames` frames of
// the script, primed at once (Pipeline::prime) and drawn. Every mode converges to it (repair ==
// rebuild), so it is the settled value that runs of different modes are measured against.
// `mask` (may be null): only its non-zero pixels are scored.
double converged_error(const Scene& scene, const std::string& script_path, int frames, int width,
                       int height, const std::string& component, const Image& reference,
                       int threads, const Image* mask = nullptr);

// The pixels where `after` differs from `before` by more than `fraction` of the larger of the
// two (Rec. 709 luminance), among those brighter than 1% of `after`'s mean: 1 there, 0 elsewhere.
Image changed_region(const Image& before, const Image& after, double fraction);

// Runs `frames` frames of `scene` (a copy; its camera size is overwritten by width × height) with
// the script (may be empty) in `mode`, comparing `component` ("full" or a frame term) with
// `reference` after every frame; wall time counts the script and the pipeline, not the read-back
// and metrics. A GL context must be current. `on_frame` (may be empty) is called after each frame
// with the number done. threads < 0: settings.threads. `lead_in` frames are drawn after priming
// and before the script's first frame, untimed and unrecorded: a mode that sweeps round robin
// (full-budget) then meets the edit at another point of its sweep.
ConvergenceRun run_convergence(Scene scene, const std::string& script_path, PipelineMode mode,
                               int frames, int width, int height, const std::string& component,
                               const Image& reference, int threads, bool prime,
                               const std::function<void(int)>& on_frame = {}, int lead_in = 0);

// The same with a reference per frame (`reference_at(frame)`: the image of the state that frame
// converges to) and `on_image(frame, image)`, called with each frame's compared image outside
// the timed part (for further metrics: other references, flicker, memory).
using ReferenceAt = std::function<const Image&(int frame)>;
ConvergenceRun run_convergence(Scene scene, const std::string& script_path, PipelineMode mode,
                               int frames, int width, int height, const std::string& component,
                               const ReferenceAt& reference_at, int threads, bool prime,
                               const std::function<void(int)>& on_frame,
                               const std::function<void(int, const Image&)>& on_image,
                               int lead_in = 0);

// Resident set size of this process in bytes (/proc/self/statm).
double resident_bytes();

// Mean and 95th percentile (0 for none).
double mean(const std::vector<double>& v);
double p95(std::vector<double> v);

// The CSV of a run as `afterglow converge` writes it (header and one row a frame).
std::string convergence_csv(const ConvergenceRun& run);

class Args;
// afterglow bench settle [SCENE:SCRIPT ...] (bench_settle.cpp), at width × height.
int bench_settle(const Args& args, int width, int height);

}  // namespace ag::cli
