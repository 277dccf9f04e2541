// afterglow bench gpu_pm: Jimenez Kwast's Table 6.1 grid (photon paths × radius) for GPU photon
// mapping, frame time as mean and σ over many frames, with the thesis's 8-bit metrics against a
// reference when one is given.
#pragma once

#include <string>

#include "tools/afterglow/cli.h"

namespace ag::cli {

// For each cell: every frame the G-buffer, new photons (his frames trace anew), binning, the
// estimate and the composed frame (direct + indirect), glFinish; --frames timed after 2 untimed.
int bench_gpu_pm(const Args& args, const std::string& scene_path, int width, int height);

}  // namespace ag::cli
