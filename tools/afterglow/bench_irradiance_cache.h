// afterglow bench irradiance_cache: Gautron 2006's Table 5.1 and 5.2 on our scenes.
#pragma once

#include <string>

#include "tools/afterglow/cli.h"

namespace ag::cli {

// SCENE (and its script) for --frames frames at width × height with --indirect irradiance_cache:
// temporal caching as the scene sets it, recomputation every frame (a new cache each frame,
// Gautron's baseline) and records kept forever; records made, record and splat time, speed-up,
// flicker over static pixels, error against single-bounce pt references at a few frames, and
// the reprojection error of the next frame's irradiance (Table 5.1).
int bench_irradiance_cache(const Args& args, const std::string& scene_path, int width, int height);

// --versus-cpu: Gautron's Table 4.2 without Radiance: one still frame by an irradiance cache in
// Radiance's manner (eye rays, scanline order, octree lookups, records gathered at once on a miss,
// all on the CPU) against our GL G-buffer, GPU scan and splatting with the same record gather and
// the same a; records, record and interpolation time, speed-up, and how far the terms differ.
int bench_irradiance_cache_versus_cpu(const Args& args, const std::string& scene_path, int width,
                                      int height);

}  // namespace ag::cli
