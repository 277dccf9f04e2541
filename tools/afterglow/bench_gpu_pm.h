// afterglow bench gpu_pm: Jimenez Kwast's Table 6.1 grid (photon paths × radius) for GPU photon
// mapping and its scaling tables B.1–B.4, times as mean and σ over many frames, with the thesis's
// 8-bit metrics against a reference when one is given; Table 6.2 (paths chosen per radius for a
// fixed time) with --budget.
#pragma once

#include <string>

#include "tools/afterglow/cli.h"

namespace ag::cli {

// For each cell: every frame the G-buffer, new photons (his frames trace anew), binning, the
// estimate and (unless --no-direct) the composed frame (direct + indirect), glFinish; --frames
// timed after 2 untimed.
int bench_gpu_pm(const Args& args, const std::string& scene_path, int width, int height);

}  // namespace ag::cli
