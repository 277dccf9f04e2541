// afterglow bench vpl: Barczak 2006's speed claims measured on our VPL path (docs/vpl.md).
#pragma once

#include <string>

#include "tools/afterglow/cli.h"

namespace ag::cli {

// With a GL context current: at 300 VPLs on SCENE at width × height, the naive frame (every
// shadow map re-rendered, every pixel summing every VPL) against each optimisation we have
// (K = 50/100/150 map updates a frame by priority; static maps; no visibility as the floor;
// exact Embree rays for scale); fps against the number of VPLs; shadow-map update cost against
// the vertex count of a mover. Best of `repeat`. Exit 0: it measures.
int bench_vpl(const Args& args, const std::string& scene_path, int width, int height, int repeat);

}  // namespace ag::cli
