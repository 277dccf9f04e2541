#include "gpu/g_buffer.h"

#include <cmath>
#include <string>

namespace ag::gpu {

namespace {

// Position, surface (albedo and the world area the pixel covers there: eq. 12.2, with the pixel's
// footprint growing as 1/cos of the angle between the surface normal and the view direction),
// normal with view depth, ids.
const std::string kGBufferFragment = std::string(kAlbedoGlsl) + R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
uniform vec3 eye;
uniform vec3 view_axis;  // unit view direction (−z of the eye)
uniform vec3 albedo;
uniform float pixel_at_unit_distance;  // 2 tan(fov_y / 2) / height
uniform int diffuse;  // 0: mirror or glass, which receives no caustic (area 0)
uniform ivec3 ids;    // object, material id, material type
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_surface;
layout(location = 2) out vec4 out_normal;
layout(location = 3) out vec4 out_ids;
void main() {
    vec3 to_eye = eye - v_world;
    float d = length(to_eye);
    vec3 n = normalize(v_normal);
    float cos_n = abs(dot(n, to_eye / d));
    float side = d * pixel_at_unit_distance;
    out_position = vec4(v_world, 1.0);
    out_surface = vec4(surface_albedo(albedo), diffuse != 0 ? side * side / max(cos_n, 0.05) : 0.0);
    out_normal = vec4(dot(n, to_eye) < 0.0 ? -n : n, dot(v_world - eye, view_axis));
    out_ids = vec4(vec3(ids), 1.0);
}
)";

}  // namespace

Framebuffer framebuffer_with(const std::vector<GLuint>& colors, GLuint depth_stencil,
                             const char* what) {
    Framebuffer f = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, f.get());
    for (size_t i = 0; i < colors.size(); ++i)
        gl::FramebufferTexture2D(GL_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + i), GL_TEXTURE_2D,
                                 colors[i], 0);
    if (depth_stencil)
        gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                                    depth_stencil);
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError(std::string(what) + ": framebuffer incomplete");
    return f;
}

std::vector<int> material_ids(const Scene& scene) {
    std::vector<int> ids(scene.objects.size());
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        const Material& m = scene.objects[o].material;
        ids[o] = int(o);
        for (size_t p = 0; p < o; ++p) {
            const Material& q = scene.objects[p].material;
            if (q.type == m.type && q.albedo == m.albedo && q.ior == m.ior &&
                q.emission == m.emission && q.albedo_map == m.albedo_map) {
                ids[o] = ids[p];
                break;
            }
        }
    }
    return ids;
}

GBuffer::GBuffer(const Scene& scene, const SceneMeshes& meshes, int width, int height)
    : scene_(scene), meshes_(meshes), width_(width), height_(height) {
    program_ = Program("g-buffer", kSceneVertex, kGBufferFragment);
    std::vector<GLuint> colors;
    for (Texture& t : targets_) {
        t = make_float_texture(width, height);
        colors.push_back(t.get());
    }
    depth_stencil_ = make_renderbuffer();
    gl::BindRenderbuffer(GL_RENDERBUFFER, depth_stencil_.get());
    gl::RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH32F_STENCIL8, width, height);
    fbo_ = framebuffer_with(colors, depth_stencil_.get(), "g-buffer");
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("GBuffer");
}

GBuffer::View GBuffer::view() const { return view_of(scene_, width_, height_); }

GBuffer::View GBuffer::view_of(const Scene& scene, int width, int height) {
    View v;
    v.camera = scene.camera;
    v.camera.width = width;
    v.camera.height = height;
    const Bounds bounds = scene.world_bounds();
    const float diagonal = scene.diagonal();
    v.near_plane = kNearPlanePerDiagonal * diagonal;
    v.far_plane = glm::length(v.camera.eye - bounds.center()) + 2.0f * diagonal;
    v.view = view_matrix(v.camera);
    v.projection = projection_matrix(v.camera, v.near_plane, v.far_plane);
    v.view_projection = v.projection * v.view;
    return v;
}

void GBuffer::render() {
    last_view_ = view();
    const Camera& camera = last_view_.camera;
    const std::vector<int> materials = material_ids(scene_);
    begin_scene_pass(fbo_.get(), kGBufferTargets, width_, height_, glm::vec4(0.0f));
    program_.use();
    program_.set("view_projection", last_view_.view_projection);
    program_.set("eye", camera.eye);
    program_.set("view_axis", glm::normalize(camera.target - camera.eye));
    program_.set("pixel_at_unit_distance",
                 2.0f * std::tan(glm::radians(camera.fov_y) * 0.5f) / float(height_));
    for (size_t o = 0; o < scene_.objects.size(); ++o) {
        const Object& obj = scene_.objects[o];
        const bool diffuse = obj.material.type == MaterialType::diffuse;
        program_.set("model", model_matrix(obj));
        program_.set("albedo", diffuse ? base_albedo(obj) : glm::vec3(0.0f));
        meshes_.bind_albedo(program_, o, kAlbedoUnit);
        program_.set("diffuse", diffuse ? 1 : 0);
        gl::Uniform3i(program_.location("ids"), int(o), materials[o], int(obj.material.type));
        meshes_.draw(o);
    }
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("GBuffer::render");
}

std::vector<glm::vec4> GBuffer::read(GBufferTarget t) const {
    const std::vector<float> rgba =
        read_rgba(fbo_.get(), GLenum(GL_COLOR_ATTACHMENT0 + int(t)), 0, 0, width_, height_);
    std::vector<glm::vec4> out(size_t(width_) * size_t(height_));
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
            const float* p = &rgba[(size_t(height_ - 1 - y) * size_t(width_) + size_t(x)) * 4];
            out[size_t(y) * size_t(width_) + size_t(x)] = {p[0], p[1], p[2], p[3]};
        }
    return out;
}

}  // namespace ag::gpu
