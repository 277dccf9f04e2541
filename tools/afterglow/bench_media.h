// afterglow bench media: Pfeuti 2009's Tables 4.1–4.5 and the adaptive pipeline's photons at
// equal RMSE, each row with its RMSE against a many-photon reference (docs/media.md).
#pragma once

#include <string>

#include "tools/afterglow/cli.h"

namespace ag::cli {

// With a GL context current: on SCENE (a point light) at width × height, the reference and the
// adaptive pipeline at doubling photon counts against a --ref-photons (default 2M) marched
// reference, the photons each needs at equal RMSE, his Table 4.2's passes at his counts and
// Table 4.1's sampling orders, Table 4.5's marching of uniform, adaptive and complement photons.
// --full: a 128³ grid, one more count each, and Tables 4.3 and 4.4
// on the cube and bunny scenes. Exit 0: it measures.
int bench_media(const Args& args, const std::string& scene_path, int width, int height);

}  // namespace ag::cli
