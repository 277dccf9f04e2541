// Mesh files through OpenMesh (OBJ, PLY, OFF, STL). The only place that includes OpenMesh IO.
#pragma once

#include <string>

#include "shared/mesh.h"

namespace ag {

// Loads and triangulates; degenerate triangles are dropped with a warning naming the file.
// Missing/unreadable files, unsupported formats and empty or fully degenerate meshes throw
// InputError naming the file.
Mesh load_mesh(const std::string& path);

// Writes OBJ/PLY/OFF/STL by extension (used by tests and tools).
void save_mesh(const Mesh& mesh, const std::string& path);

}  // namespace ag
