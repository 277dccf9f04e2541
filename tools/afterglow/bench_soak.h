// afterglow bench soak: many frames of random edits, memory and frame time over the run.
#pragma once

#include <string>

#include "tools/afterglow/cli.h"

namespace ag::cli {

// N frames (--frames) of SCENE at size × size with the dynamic objects moved and the first light's
// colour toggled every frame; RSS and frame time sampled over the run into a CSV (--csv), growth
// between frame min(10,000, N/10) and the end reported. Exit 0 however much it grew: it measures.
int bench_soak(const Args& args, const std::string& scene_path, int size);

}  // namespace ag::cli
