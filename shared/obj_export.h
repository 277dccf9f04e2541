// The whole scene in world space as Wavefront OBJ + MTL (Kd, Ks, Ni, Ke, illum), for inspection
// in other tools. Lights are written as comment lines.
#pragma once

#include <string>

#include "shared/scene.h"

namespace ag {

// Writes `obj_path` and the .mtl beside it (same stem), both atomically.
void export_obj(const Scene& scene, const std::string& obj_path);

}  // namespace ag
