#include "tools/afterglow/view_renderer.h"

#include <algorithm>
#include <glm/gtc/matrix_transform.hpp>

#include "shared/camera.h"
#include "shared/host_device_shared.h"

namespace ag::cli {

namespace {

// mode 0: an atlas (AIM radiance or IIM) on the scene, plus emission; 1: surfaces in unique
// colours; 2: a flat tint (the selection).
const char* kSceneFragment = R"(
in vec3 v_normal;
in vec3 v_world;
in vec2 v_uv;
uniform int mode;
uniform sampler2D atlas;
uniform sampler2D surface_ids;
uniform int triangle_offset;
uniform int diffuse;
uniform vec3 emission;
uniform vec3 eye;
uniform vec4 tint;
out vec4 color;
vec3 hsv(float h, float s, float v) {
    vec3 k = clamp(abs(mod(h * 6.0 + vec3(0.0, 4.0, 2.0), 6.0) - 3.0) - 1.0, 0.0, 1.0);
    return v * mix(vec3(1.0), k, s);
}
void main() {
    if (mode == 2) { color = tint; return; }
    if (mode == 0) {
        color = vec4(emission + (diffuse != 0 ? texture(atlas, v_uv).rgb : vec3(0.0)), 1.0);
        return;
    }
    int t = triangle_offset + gl_PrimitiveID;
    float id = texelFetch(surface_ids, ivec2(t % kIdTextureWidth, t / kIdTextureWidth), 0).r;
    // Golden-ratio hues: neighbouring ids get far-apart colours.
    vec3 c = hsv(fract(id * 0.618034 + 0.1), 0.6 + 0.3 * fract(id * 0.377), 0.9);
    float shade = 0.35 + 0.65 * abs(dot(normalize(v_normal), normalize(eye - v_world)));
    color = vec4(c * c * shade, 1.0);  // roughly linear, so the sRGB curve shows the hues
}
)";

const char* kCopyFragment = R"(
uniform sampler2D source;
out vec4 color;
void main() { color = vec4(texelFetch(source, ivec2(gl_FragCoord.xy), 0).rgb, 1.0); }
)";

const char* kPointsVertex = R"(
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 point_color;
uniform mat4 view_projection;
uniform vec3 eye;
uniform float size;
out vec3 v_color;
void main() {
    // Photons and texel centres lie on surfaces: pull them a little towards the eye so the
    // surface does not hide them.
    vec3 p = mix(position, eye, 0.004);
    gl_Position = view_projection * vec4(p, 1.0);
    gl_PointSize = size;
    v_color = point_color;
}
)";
const char* kPointsFragment = R"(
in vec3 v_color;
out vec4 color;
void main() {
    if (length(gl_PointCoord - vec2(0.5)) > 0.5) discard;
    color = vec4(v_color, 1.0);
}
)";

// Exposure, then the sRGB curve (IEC 61966-2-1), as write_image does for PNGs.
const char* kPresentFragment = R"(
uniform sampler2D display;
uniform vec4 rect;
uniform float scale;
out vec4 color;
float encode(float x) {
    x = clamp(x, 0.0, 1.0);
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}
void main() {
    vec2 uv = (gl_FragCoord.xy - rect.xy) / rect.zw;
    vec3 c = texture(display, uv).rgb * scale;
    color = vec4(encode(c.r), encode(c.g), encode(c.b), 1.0);
}
)";

}  // namespace

ViewRenderer::ViewRenderer(const Scene& scene, const gpu::SceneMeshes& meshes, int width,
                           int height)
    : scene_(scene), meshes_(meshes), width_(width), height_(height) {
    scene_program_ = gpu::Program("view scene", gpu::kSceneVertex, kSceneFragment);
    copy_program_ = gpu::Program("view copy", gpu::kFullScreenTriangleVertex, kCopyFragment);
    points_program_ = gpu::Program("view points", kPointsVertex, kPointsFragment);
    present_program_ =
        gpu::Program("view present", gpu::kFullScreenTriangleVertex, kPresentFragment);

    display_ = gpu::make_float_texture(width, height);
    gpu::gl::BindTexture(GL_TEXTURE_2D, display_.get());
    gpu::gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gpu::gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    depth_ = gpu::make_renderbuffer();
    gpu::gl::BindRenderbuffer(GL_RENDERBUFFER, depth_.get());
    gpu::gl::RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
    fbo_ = gpu::make_framebuffer();
    gpu::gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    gpu::gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                                  display_.get(), 0);
    gpu::gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                                     depth_.get());
    if (gpu::gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw gpu::GlError("view: display framebuffer incomplete");
    gpu::gl::BindFramebuffer(GL_FRAMEBUFFER, 0);

    // Surface id of every triangle, objects back to back (Larsen ch. 8 surfaces).
    std::vector<float> ids;
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        triangle_offset_.push_back(int(ids.size() / 4));
        const size_t n = scene.objects[o].mesh.triangles.size();
        for (size_t t = 0; t < n; ++t) {
            const bool known =
                o < scene.triangle_surface.size() && t < scene.triangle_surface[o].size();
            ids.insert(ids.end(),
                       {known ? float(scene.triangle_surface[o][t]) : -1.0f, 0.0f, 0.0f, 1.0f});
        }
    }
    const int rows = std::max(1, int((ids.size() / 4 + kIdTextureWidth - 1) / kIdTextureWidth));
    ids.resize(size_t(rows) * kIdTextureWidth * 4, 0.0f);
    surface_ids_ = gpu::make_float_texture(kIdTextureWidth, rows, false, ids.data());

    empty_vao_ = gpu::make_vertex_array();
    points_vao_ = gpu::make_vertex_array();
    points_vbo_ = gpu::make_buffer();
    gpu::gl::BindVertexArray(points_vao_.get());
    gpu::gl::BindBuffer(GL_ARRAY_BUFFER, points_vbo_.get());
    gpu::gl::EnableVertexAttribArray(0);
    gpu::gl::VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(ViewPoint), nullptr);
    gpu::gl::EnableVertexAttribArray(1);
    gpu::gl::VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(ViewPoint),
                                 reinterpret_cast<void*>(sizeof(glm::vec3)));
    gpu::gl::BindVertexArray(0);

    Bounds b;
    for (const Object& o : scene.objects)
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    near_ = 1e-3f * (b.empty() ? 1.0f : glm::length(b.extent()));
    gpu::check_gl("ViewRenderer");
}

void ViewRenderer::draw_scene(int mode) {
    scene_program_.use();
    scene_program_.set("mode", mode);
    scene_program_.set("view_projection", view_projection_);
    scene_program_.set("atlas", 0);
    scene_program_.set("surface_ids", 1);
    scene_program_.set("eye", scene_.camera.eye);
    for (size_t o = 0; o < scene_.objects.size(); ++o) {
        const Object& obj = scene_.objects[o];
        scene_program_.set("model", gpu::model_matrix(obj));
        scene_program_.set("triangle_offset", triangle_offset_[o]);
        scene_program_.set("diffuse", obj.material.type == MaterialType::diffuse ? 1 : 0);
        scene_program_.set("emission", obj.material.emission);
        meshes_.draw(o);
    }
}

void ViewRenderer::draw_points(const std::vector<ViewPoint>& points, float size) {
    if (points.empty()) return;
    gpu::gl::BindBuffer(GL_ARRAY_BUFFER, points_vbo_.get());
    gpu::gl::BufferData(GL_ARRAY_BUFFER, GLsizeiptr(points.size() * sizeof(ViewPoint)),
                        points.data(), GL_STREAM_DRAW);
    points_program_.use();
    points_program_.set("view_projection", view_projection_);
    points_program_.set("eye", scene_.camera.eye);
    points_program_.set("size", size);
    gpu::gl::BindVertexArray(points_vao_.get());
    gpu::gl::DrawArrays(GL_POINTS, 0, GLsizei(points.size()));
}

void ViewRenderer::render(ViewMode mode, GLuint source, const std::vector<ViewPoint>& points,
                          const std::vector<ViewPoint>& markers, float point_size, int highlight) {
    Camera camera = scene_.camera;
    camera.width = width_;
    camera.height = height_;
    view_projection_ = glm::infinitePerspective(glm::radians(camera.fov_y),
                                                float(width_) / float(height_), near_) *
                       view_matrix(camera);

    gpu::gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    const GLenum draw = GL_COLOR_ATTACHMENT0;
    gpu::gl::DrawBuffers(1, &draw);
    gpu::gl::Viewport(0, 0, width_, height_);
    gpu::gl::Disable(GL_BLEND);
    gpu::gl::Disable(GL_STENCIL_TEST);
    gpu::gl::Disable(GL_CULL_FACE);
    gpu::gl::Disable(GL_SCISSOR_TEST);
    gpu::gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gpu::gl::DepthMask(GL_TRUE);
    gpu::gl::ClearColor(0, 0, 0, 1);
    gpu::gl::ClearDepth(1.0);
    gpu::gl::Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    gpu::gl::ActiveTexture(GL_TEXTURE1);
    gpu::gl::BindTexture(GL_TEXTURE_2D, surface_ids_.get());
    gpu::gl::ActiveTexture(GL_TEXTURE0);
    gpu::gl::BindTexture(GL_TEXTURE_2D, source);

    const bool own_scene =
        mode == ViewMode::aim || mode == ViewMode::iim || mode == ViewMode::surfaces;
    gpu::gl::Enable(GL_DEPTH_TEST);
    gpu::gl::DepthFunc(GL_LESS);
    if (own_scene) {
        draw_scene(mode == ViewMode::surfaces ? 1 : 0);
    } else {
        gpu::gl::Disable(GL_DEPTH_TEST);
        copy_program_.use();
        copy_program_.set("source", 0);
        gpu::gl::BindVertexArray(empty_vao_.get());
        gpu::gl::DrawArrays(GL_TRIANGLES, 0, 3);
        // Depth only, for the overlays.
        gpu::gl::Enable(GL_DEPTH_TEST);
        gpu::gl::ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
        draw_scene(2);
        gpu::gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    }

    if (highlight >= 0 && highlight < int(scene_.objects.size())) {
        gpu::gl::DepthFunc(GL_LEQUAL);
        gpu::gl::DepthMask(GL_FALSE);
        gpu::gl::Enable(GL_BLEND);
        gpu::gl::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        scene_program_.use();
        scene_program_.set("mode", 2);
        scene_program_.set("view_projection", view_projection_);
        scene_program_.set("tint", glm::vec4(1.0f, 0.75f, 0.1f, 0.2f));
        scene_program_.set("model", gpu::model_matrix(scene_.objects[size_t(highlight)]));
        meshes_.draw(size_t(highlight));
        gpu::gl::Disable(GL_BLEND);
        gpu::gl::DepthMask(GL_TRUE);
    }

    gpu::gl::Enable(GL_PROGRAM_POINT_SIZE);
    gpu::gl::DepthFunc(GL_LEQUAL);
    draw_points(points, point_size);
    gpu::gl::Disable(GL_DEPTH_TEST);
    draw_points(markers, 3.0f * point_size);
    gpu::gl::Disable(GL_PROGRAM_POINT_SIZE);
    gpu::gl::BindVertexArray(0);
    gpu::gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    gpu::check_gl("ViewRenderer::render");
}

void ViewRenderer::present(const ViewRect& rect, float exposure) {
    gpu::gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    gpu::gl::Viewport(rect.x, rect.y, rect.width, rect.height);
    gpu::gl::Disable(GL_DEPTH_TEST);
    gpu::gl::Disable(GL_BLEND);
    gpu::gl::Disable(GL_STENCIL_TEST);
    gpu::gl::Disable(GL_SCISSOR_TEST);
    present_program_.use();
    present_program_.set("display", 0);
    present_program_.set(
        "rect", glm::vec4(float(rect.x), float(rect.y), float(rect.width), float(rect.height)));
    present_program_.set("scale", std::exp2(exposure));
    gpu::gl::ActiveTexture(GL_TEXTURE0);
    gpu::gl::BindTexture(GL_TEXTURE_2D, display_.get());
    gpu::gl::BindVertexArray(empty_vao_.get());
    gpu::gl::DrawArrays(GL_TRIANGLES, 0, 3);
    gpu::gl::BindVertexArray(0);
    gpu::check_gl("ViewRenderer::present");
}

Image ViewRenderer::read_back() const {
    const std::vector<float> rgba =
        gpu::read_rgba(fbo_.get(), GL_COLOR_ATTACHMENT0, 0, 0, width_, height_);
    Image image(width_, height_, 3);
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
            const float* p = &rgba[(size_t(height_ - 1 - y) * size_t(width_) + size_t(x)) * 4];
            image.set_rgb(x, y, {p[0], p[1], p[2]});
        }
    return image;
}

Image ViewRenderer::read_window(int width, int height) {
    std::vector<unsigned char> rgba(size_t(width) * size_t(height) * 4);
    gpu::gl::BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    gpu::gl::ReadBuffer(GL_BACK);
    gpu::gl::PixelStorei(GL_PACK_ALIGNMENT, 1);
    gpu::gl::ReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    Image image(width, height, 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const unsigned char* p =
                &rgba[(size_t(height - 1 - y) * size_t(width) + size_t(x)) * 4];
            image.set_rgb(x, y,
                          {srgb_decode(p[0] / 255.0f), srgb_decode(p[1] / 255.0f),
                           srgb_decode(p[2] / 255.0f)});
        }
    gpu::check_gl("ViewRenderer::read_window");
    return image;
}

}  // namespace ag::cli
