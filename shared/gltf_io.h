// glTF 2.0 (.gltf, .glb) through tinygltf, the only file that includes it: the default scene's
// node hierarchy flattened, every triangle primitive one model part in world space.
#pragma once

#include <string>

#include "shared/model_io.h"

namespace ag {

// Reads a glTF file into parts (baseColorFactor as albedo, emissiveFactor × emissive_strength as
// emission, KHR_materials_transmission ≥ 0.5 as glass with KHR_materials_ior, metallic 1 with
// roughness ≤ 0.1 as mirror), KHR_lights_punctual lights and perspective cameras, all in world
// space. Every feature it does not render (textures, skins, animations, morph targets,
// non-triangle primitives, orthographic cameras, unknown extensions, ...) gets a warning naming
// it; errors (unreadable file, bad accessors, a node reached twice, a tree over 256 deep, more
// than `max_triangles` placed, instances included) are InputErrors naming the file and the node.
Model load_gltf(const std::string& path, int64_t max_triangles = kMaxSceneTriangles);

}  // namespace ag
