// How the progressive pipeline gets its indirect term (DESIGN.md "Indirect methods on one scene
// graph"): one interface, selected by settings.indirect.method. The IIM lightmaps of Larsen
// ch. 8-11 (ag::IimMethod) are the first implementation; a method supplies its term in lightmap
// space or in screen space and the frame composes either (gpu::IndirectTerm).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>

#include "cpu/photon_simulation.h"
#include "gpu/frame_renderer.h"
#include "shared/pipeline/pipeline_stats.h"

namespace ag {

// selective: Larsen's method, work by priority (invalid groups by flux, AIM surfaces by Δf/A, IIM
// texels by Δi) under the budgets. The baselines an edit's settling time is held against, run by
// the same code: full redoes every photon group, AIM surface and IIM texel every frame; full_budget
// redoes everything round robin, with no knowledge of what changed, within the same frame-time
// budget (settings.schedule.frame_ms) as selective. Neither blends.
enum class PipelineMode { selective, full, full_budget };
inline constexpr std::array kPipelineModeNames = {"selective", "full", "full-budget"};

// What a method may read on the GL thread while this frame's photon work runs on the workers:
// only state handed over at the end of the previous frame.
struct IndirectInputs {
    uint64_t frame = 0;
    bool aim_changed = false;  // the AIM texture (and the staged AIM values) changed this frame
    PipelineMode mode = PipelineMode::selective;
    int budget = 0;  // units of work (IIM texels) this frame, from the scheduler
    // With a frame-time target: the GL thread's share of it for this work, in ms (0: none, do
    // `budget` units). The work then goes in chunks, sized by what this frame's chunks cost,
    // until the share is spent: `budget` is the scheduler's plan, the share the limit.
    double work_ms = 0.0;
    // Between chunks: hands this frame's photon work over if the workers have finished it (never
    // waits) and says whether new AIMs arrived, so the rest of the frame reads them.
    std::function<bool()> poll_hand_over;
    // When the work has run out before the share: waits at most `ms` for the workers' repair of
    // an edit (never for verification or refinement alone), hands it over and says whether new
    // AIMs arrived. Unset: never waits.
    std::function<bool(double ms)> wait_hand_over;
};

class IndirectMethod {
public:
    virtual ~IndirectMethod() = default;
    virtual IndirectMethodKind kind() const = 0;
    // GL thread, before the frame is drawn: bring the term up to date within the budgets.
    virtual void update(const IndirectInputs& in, PipelineStats& stats) = 0;
    // After the hand-over, with the workers idle: read what the photon work of this frame
    // produced (deltas, hits) to plan the next frames.
    virtual void hand_over(cpu::PhotonSimulation& photons, PipelineStats& stats) = 0;
    // Forget everything: the next update() recomputes the whole term (brute-force baseline).
    virtual void invalidate_all() = 0;
    // Untimed, with the workers idle and the AIM texture current: compute the whole term from
    // `photons` now and show it at once, consuming every pending delta and scene change (the
    // converged state a benchmark measures an edit from).
    virtual void prime(cpu::PhotonSimulation& photons, uint64_t frame) = 0;
    // The term for this frame's compose.
    virtual gpu::IndirectTerm term() const = 0;
    // Nothing left to repair or refine.
    virtual bool settled() const = 0;
    // The last entry of scene.changes this method has read (its sequence), so the pipeline can
    // trim the log; a method that never reads the log has nothing to wait for.
    virtual uint64_t changes_seen() const { return std::numeric_limits<uint64_t>::max(); }
    // Whether the method reads the CPU photon maps and AIMs; if not, the pipeline traces no
    // diffuse photons and builds no AIMs (caustic photons are traced either way).
    virtual bool uses_photon_maps() const { return true; }
    // Methods that plan with the next frame's scene (temporal radiance caching, Gautron ch. 5)
    // say so; the frame loop then keeps a copy of the scene one script frame ahead and hands it
    // over before every frame (null where there is no script).
    virtual bool wants_lookahead() const { return false; }
    virtual void set_lookahead(const Scene* /*next*/) {}
};

}  // namespace ag
