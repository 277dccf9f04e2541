// JSON scene files (docs/scene-format.md). One reader builds the Scene; every problem is an
// InputError naming the file, the JSON path (e.g. /objects/2/shape/size) and what was expected.
#pragma once

#include <string>

#include "shared/scene.h"

namespace ag {

// Reads, validates and builds the scene, including surfaces, charts and the atlas.
Scene load_scene(const std::string& path);

// Same from text; `path` is used for messages and to resolve relative mesh/script paths.
Scene parse_scene(const std::string& json_text, const std::string& path);

}  // namespace ag
