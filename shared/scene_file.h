// JSON scene files (docs/scene-format.md). One reader builds the Scene; every problem is an
// InputError naming the file, the JSON path (e.g. /objects/2/shape/size) and what was expected.
#pragma once

#include <string>

#include "shared/scene.h"

namespace ag {

// Reads, validates and builds the scene, including surfaces, charts and the atlas.
Scene load_scene(const std::string& path);

// Same from text; `path` is used for messages and to resolve relative mesh/script paths.
// `max_triangles` bounds the triangles every object places together.
Scene parse_scene(const std::string& json_text, const std::string& path,
                  int64_t max_triangles = kMaxSceneTriangles);

// After scene.settings changed on a loaded scene (--set, the Python bindings): the checks loading
// makes where settings meet the scene (light samples, photon budget), then the surfaces and atlas
// rebuilt if the lightmap settings differ from `before`. InputError naming scene.path.
void settings_changed(Scene& scene, const LightmapSettings& before);

// Overwrites the settings `json_text` holds (the shape of a scene file's "settings" block) on a
// loaded scene, then settings_changed(). InputError naming `source`, the JSON path and what was
// expected; the scene is unchanged then.
void apply_settings_json(Scene& scene, const std::string& json_text, const std::string& source);

}  // namespace ag
