// Quadric-error mesh decimation (Garland & Heckbert 1997, OpenMesh's decimater): a scanned mover
// brought to the vertex count Barczak's scenes used (bunny ~3000 vertices, 2006 §5.2).
#pragma once

#include <cstddef>

#include "shared/mesh.h"

namespace ag {

// Collapses edges in order of quadric error until at most `target_vertices` remain (or no legal
// collapse is left); boundaries are kept. Texture coordinates are dropped. The input must be a
// manifold triangle mesh (std::invalid_argument names the first face OpenMesh refuses).
Mesh decimate_mesh(const Mesh& mesh, size_t target_vertices);

}  // namespace ag
