// Model files: meshes that bring their own materials (OBJ + MTL through tinyobjloader). One part
// per material, so a scene object per part keeps Afterglow's one-material-per-object rule.
#pragma once

#include <string>
#include <vector>

#include "shared/mesh.h"
#include "shared/scene.h"

namespace ag {

struct ModelPart {
    std::string name;  // OBJ: the material's name ("default" without one); glTF: the node's
    Mesh mesh;
    Material material;  // from the file (material.name is the file's); mapped as documented
};

// A camera of the file, in its world space.
struct ModelCamera {
    std::string name;
    glm::vec3 eye{0.0f}, target{0.0f, 0.0f, -1.0f}, up{0.0f, 1.0f, 0.0f};
    float fov_y = 40.0f;  // degrees
};

struct Model {
    std::vector<ModelPart> parts;  // OBJ: in the order materials first appear; never empty
    std::vector<Light> lights;     // glTF KHR_lights_punctual, world space
    std::vector<ModelCamera> cameras;
};

// Reads an OBJ with its MTL library: faces grouped by `usemtl`, `Kd` as albedo, `Ke` as emission,
// `illum` 5 (and 3 with a reflective Ks) as mirror, `illum` 4/6/7/9 as glass with `Ni`; a
// missing MTL file or material is a warning and the default material (diffuse 0.75). Other
// formats: glTF through load_gltf (shared/gltf_io.h); PLY, OFF, STL give one part "default"
// through load_mesh. Errors are InputErrors
// naming the file and line. A glTF node tree may place at most `max_triangles` (every instance
// counted); other formats are bounded by their files' sizes.
Model load_model(const std::string& path, int64_t max_triangles = kMaxSceneTriangles);

}  // namespace ag
