// What one progressive frame did and what it cost (ag::Pipeline::frame()).
#pragma once

#include <cstdint>

#include "cpu/caustic_tracer.h"
#include "cpu/photon_simulation.h"

namespace ag {

struct PipelineStats {
    uint64_t frame = 0;
    cpu::PhotonFrameStats photons;
    cpu::CausticStats caustics;
    int caustic_tiles_filtered = 0;
    // The caustics were drawn again (other photons, view or scene than their last drawing), in
    // caustics_draw_ms of draw_ms.
    bool caustics_drawn = false;
    double caustics_draw_ms = 0;
    // Cube-map faces that drew their direct light again (after an edit), and what the faces
    // drawn in a frame that re-lit any took, of draw_ms.
    int cube_faces_relit = 0;
    double cube_faces_ms = 0;
    int iim_texels_gathered = 0;
    int iim_texels_pending = 0;
    int iim_texels_invalid = 0;  // back-face texels repaired from neighbours
    // The VPL method: VPLs re-shaded this frame, shown, still stale; the clamp's relative bias.
    int vpl_updated = 0, vpl_count = 0, vpl_stale = 0;
    double vpl_clamp_bias = 0.0;
    // photon_ms and aim_ms run on the workers, overlapped with gather_ms and draw_ms on the GL
    // thread; wait_ms is what the GL thread then waited for them (at the end of the frame, or in a
    // scene edit before it: Scene::before_edit), also counted in frame_ms.
    // The scheduler's budgets for this frame (fixed counts without a frame-time target).
    int budget_iim_texels = 0, budget_photons = 0;
    double budget_gather_ms = 0;  // the GL thread's planned share for gathering (0: no target)
    // The photon work was handed over between gather chunks, not at the end of the frame: the
    // rest of this frame's gathers read its AIMs.
    bool early_hand_over = false;
    // Photon frames handed over during this frame (at its start, between gather chunks or at
    // its end; 0 when the workers ran on through it), and whether they were still running when
    // it ended (a frame-time target: the frame did not wait).
    int hand_overs = 0;
    bool workers_behind = false;
    // The frame's passes were drawn (false: the accumulated mean was complete and kept).
    bool drawn = true;
    // It drew the direct light anew (every light's shadows), as the frame of an edit does.
    bool drawn_direct = true;
    double photon_ms = 0, aim_ms = 0, caustic_ms = 0, gather_ms = 0, draw_ms = 0, wait_ms = 0,
           frame_ms = 0;
    // The part of gather_ms spent in the gatherers themselves (IIM texels), without the screen
    // coverage pass, the uploads and the repairs around them; negative where a method does not
    // tell them apart. The scheduler learns a texel's cost from it: an edit's frame spent 42 of
    // its 42 ms "gathering" 54 texels on bumpy_133k_box, half of it the coverage pass, and the
    // budgets of the frames after it stayed at a quarter of what fits.
    double texel_gather_ms = -1;
    // Of gather_ms: waiting mid-gather for the workers' repair of an edit, whose new AIMs the
    // rest of the share gathers (IndirectInputs::wait_hand_over). Neither gathering nor drawing.
    double gather_wait_ms = 0;
    // CPU gather rays of this frame's IIM texels, and how many of them were re-read from the ray
    // cache instead of traced (gather.ray_cache_mb).
    uint64_t gather_rays = 0, gather_rays_reused = 0;
};

}  // namespace ag
