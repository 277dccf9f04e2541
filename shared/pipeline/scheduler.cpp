#include "shared/pipeline/scheduler.h"

#include <algorithm>
#include <cmath>

namespace ag {

namespace {
// The workers share the cores with the GL thread (and a software GL rasteriser): they aim at
// this share of the frame, so the hand-over rarely waits.
constexpr double kWorkerShare = 0.8;

int fit(double ms, const RunningCost& cost, int fallback) {
    if (!cost.known() || cost.value() <= 0.0) return fallback;
    const double n = std::floor(std::max(0.0, ms) / cost.value());
    return int(std::min<double>(n, FrameBudgets::kUnlimited));
}
}  // namespace

FrameBudgets FrameScheduler::budgets(const Settings& settings, int iim_texels_total, bool edited,
                                     bool catching_up, bool draws_caustics, int relit_faces) const {
    FrameBudgets b;
    const double target = settings.schedule.frame_ms;
    if (target <= 0.0) {
        b.retrace_photons = settings.photons.retrace_budget;
        b.aim_surfaces = settings.aim.surfaces_per_frame;
        b.iim_texels = settings.gather.texels_per_frame;
        return b;
    }
    // GL thread: what drawing leaves of the target goes to gathering (at least a share of it).
    // Until a cost is known, gather the fixed count once to measure it.
    const double usual = draw_ms_.known() ? draw_ms_.value() : 0.5 * target;
    const double own = catching_up ? std::max({usual, last_drawing_[0], last_drawing_[1]}) : usual;
    const double draw =
        own + (draws_caustics && caustics_draw_ms_.known() ? caustics_draw_ms_.value() : 0.0) +
        (relit_face_ms_.known() ? relit_faces * relit_face_ms_.value() : 0.0);
    const double share = std::max(target - draw, kMinGatherShare * target);
    // The frame of an edit draws every light's shadows anew (what frames that did so cost:
    // priming's first frames, earlier edits) and moved geometry besides (shadow volumes, cube-map
    // faces; not known in advance, twice the usual drawing): the larger of the two.
    const double edit_draw =
        std::max(direct_draw_ms_.known() ? direct_draw_ms_.value() : 0.0, kEditDrawFactor * draw);
    const double gather_ms =
        edited ? std::max(target - edit_draw, kMinGatherShare * target) : share;
    b.gather_ms = gather_ms;
    b.iim_texels = gather_texels(settings, gather_ms, iim_texels_total);
    // Workers: photons first, AIMs with the rest (aim_texels_left, measured as they go).
    b.worker_ms = kWorkerShare * target;
    const double caustics = caustic_ms_.known() ? caustic_ms_.value() : 0.0;
    b.retrace_photons =
        std::max(1, fit(b.worker_ms - caustics, photon_ms_, settings.photons.retrace_budget));
    b.aim_surfaces = FrameBudgets::kUnlimited;
    if (settings.schedule.counts_cap) {
        b.retrace_photons = std::min(b.retrace_photons, settings.photons.retrace_budget);
        b.aim_surfaces = settings.aim.surfaces_per_frame;
    }
    return b;
}

FrameBudgets FrameScheduler::after_drawing(const Settings& settings, int iim_texels_total,
                                           double elapsed_ms) const {
    FrameBudgets b = budgets(settings, iim_texels_total);
    const double target = settings.schedule.frame_ms;
    if (target <= 0.0) return b;
    b.gather_ms = std::max(target - elapsed_ms, kMinGatherShare * target);
    b.iim_texels = gather_texels(settings, b.gather_ms, iim_texels_total);
    return b;
}

int FrameScheduler::gather_texels(const Settings& settings, double gather_ms,
                                  int iim_texels_total) const {
    const int n = std::clamp(fit(gather_ms, gather_ms_per_texel_, settings.gather.texels_per_frame),
                             1, std::max(1, iim_texels_total));
    return settings.schedule.counts_cap ? std::min(n, settings.gather.texels_per_frame) : n;
}

int FrameScheduler::aim_texels_left(const Settings& settings, double elapsed_ms) const {
    const double target = settings.schedule.frame_ms;
    if (target <= 0.0) return FrameBudgets::kUnlimited;
    const double caustics = caustic_ms_.known() ? caustic_ms_.value() : 0.0;
    return std::max(1, fit(kWorkerShare * target - caustics - elapsed_ms, aim_ms_per_texel_,
                           FrameBudgets::kUnlimited));
}

void FrameScheduler::seed(int texels, double gather_ms, int photons, double photon_ms,
                          int aim_texels, double aim_ms) {
    if (texels > 0) gather_ms_per_texel_.add(gather_ms / texels);
    if (photons > 0) photon_ms_.add(photon_ms / photons);
    if (aim_texels > 0) aim_ms_per_texel_.add(aim_ms / aim_texels);
}

void FrameScheduler::measure(const PipelineStats& s) {
    // A unit's cost is measured as the time over the units; with few units the fixed costs of a
    // batch dominate, so such a sample is only an upper bound of the unit cost. It is taken when
    // it is below the estimate (the estimate is then provably too high): otherwise one slow frame
    // (an edit's first gather, a BVH rebuild) could shrink a budget below the size that measures,
    // and the budget would never grow back.
    auto sample = [](RunningCost& cost, double ms, int units, int enough) {
        if (units <= 0) return;
        const double per_unit = ms / units;
        if (units >= enough || (cost.known() && per_unit < cost.value())) cost.add(per_unit);
    };
    // gather_ms holds the gathers and the uploads around them; the per-texel cost, and the rest
    // is counted as drawing.
    const int texels = s.iim_texels_gathered;
    sample(gather_ms_per_texel_, s.texel_gather_ms >= 0.0 ? s.texel_gather_ms : s.gather_ms, texels,
           4);
    const double gather_part =
        gather_ms_per_texel_.known() ? texels * gather_ms_per_texel_.value() : 0.0;
    // A frame whose accumulated mean was complete draws nothing (a few ms of overhead): drawing's
    // cost is learnt from frames that drew, or the first frame after a quiet spell (an edit's)
    // would plan its gathering for a frame that costs nothing to draw (two_rooms: 9 ms against
    // 20 ms).
    // The caustics' drawing and the re-lit cube-map faces are learnt apart: only some frames
    // draw them.
    const double relit_ms = s.cube_faces_relit > 0 ? s.cube_faces_ms : 0.0;
    const double drawing = std::max(0.0, s.draw_ms - s.caustics_draw_ms - relit_ms) +
                           std::max(0.0, s.gather_ms - s.gather_wait_ms - gather_part);
    if (s.caustics_drawn && s.caustics_draw_ms > 0.0) caustics_draw_ms_.add(s.caustics_draw_ms);
    if (s.cube_faces_relit > 0) relit_face_ms_.add(relit_ms / s.cube_faces_relit);
    // The first frame compiles the shaders (llvmpipe compiles at a program's first draw) and
    // fills the textures: on bumpy_133k_box it drew in 156 ms, every later frame that drew the
    // direct light anew in 27-48 ms, and the edit's frame planned for 156 ms of drawing.
    const bool first = s.frame == 1;
    if ((s.drawn && !first) || !draw_ms_.known()) draw_ms_.add(drawing);
    last_drawing_[1] = last_drawing_[0];
    last_drawing_[0] = drawing;
    if (s.drawn_direct && !first) direct_draw_ms_.add(drawing);
    // Only frames that re-traced groups measure a photon's cost: a frame of verification alone
    // (one photon a group) is dominated by its fixed costs (edits, the moved-object query).
    const int photons = s.photons.photons_verified + s.photons.photons_retraced;
    if (s.photons.photons_retraced > 0)
        sample(photon_ms_, s.photon_ms, photons, s.photons.photons_retraced >= 500 ? 1 : 1 << 30);
    sample(aim_ms_per_texel_, s.aim_ms, s.photons.aim_texels_rebuilt, 4);
    // A frame the workers ran on through hands nothing over: no sample of what a frame costs.
    if (s.hand_overs > 0) caustic_ms_.add(s.caustic_ms / s.hand_overs);
}

}  // namespace ag
