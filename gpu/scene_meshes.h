// The scene's geometry on the GPU: one vertex buffer per object (triangle soup in object space
// with face normals and atlas UVs, so charts keep their own UVs), drawn with the object's current
// transform. Uploaded once; rigid edits only change the model matrix.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "shared/scene.h"

namespace ag::gpu {

// Vertex layout: location 0 position (vec3), 1 normal (vec3), 2 lightmap uv (vec2, [0,1]),
// 3 the triangle's chart id (float; −1 without a lightmap), for chart-aware lightmap lookups,
// 4 albedo-texture coordinates (vec2; 0 without). Albedo textures are uploaded once each
// (RGB16F, mipmapped, repeating) and bound per object by bind_albedo.
class SceneMeshes {
public:
    explicit SceneMeshes(const Scene& scene);

    size_t object_count() const { return objects_.size(); }
    // Draws object `i` (binds its VAO); the caller sets the program and uniforms.
    void draw(size_t i) const;
    // The same, `instances` times (gl_InstanceID picks what each copy is for).
    void draw_instanced(size_t i, int instances) const;
    // Triangles [first, first + count) of object `i` (in its mesh's order), `instances` times.
    void draw_instanced(size_t i, int first, int count, int instances) const;
    int triangle_count(size_t i) const { return objects_[i].triangles; }
    // Binds object `i`'s albedo texture (if any) to texture unit `unit` and sets the program's
    // `albedo_map` and `has_albedo_map` uniforms (kAlbedoGlsl).
    void bind_albedo(const Program& program, size_t i, int unit) const;

private:
    struct GpuObject {
        VertexArray vao;
        Buffer vbo;
        int triangles = 0;
        int albedo_map = -1;          // into textures_
        bool uniform_albedo = false;  // textured but without coordinates: the texture's mean
    };
    std::vector<GpuObject> objects_;
    std::vector<Texture> textures_;
};

// The texture unit scene passes bind albedo textures to (no pass uses it for anything else).
inline constexpr int kAlbedoUnit = 7;

// For fragment shaders of scene passes: the albedo at the fragment, `albedo` times the object's
// texture at its texture coordinates when it has one.
inline constexpr const char* kAlbedoGlsl = R"(
in vec2 v_texcoord;
uniform sampler2D albedo_map;
uniform int has_albedo_map;
vec3 surface_albedo(vec3 albedo) {
    return has_albedo_map != 0 ? albedo * texture(albedo_map, v_texcoord).rgb : albedo;
}
)";

// The vertex shader of every scene pass over these meshes (world position, normal, atlas uv out):
// identical position math keeps depth equal between passes.
inline constexpr const char* kSceneVertex = R"(
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;
layout(location = 4) in vec2 texcoord;
uniform mat4 model, view_projection;
out vec3 v_world;
out vec3 v_normal;
out vec2 v_uv;
out vec2 v_texcoord;
invariant gl_Position;
void main() {
    vec4 world = model * vec4(position, 1.0);
    v_world = world.xyz;
    v_normal = mat3(model) * normal;
    v_uv = uv;
    v_texcoord = texcoord;
    gl_Position = view_projection * world;
}
)";

// The model matrix of an object (world = M · object).
inline glm::mat4 model_matrix(const Object& o) { return o.transform.matrix(); }

}  // namespace ag::gpu
