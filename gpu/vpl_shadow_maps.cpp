#include "gpu/vpl_shadow_maps.h"

#include <algorithm>
#include <cmath>

#include "gpu/gl.h"

namespace ag::gpu {

const char* const kVplMapGlsl = R"(
layout(std430, binding = 0) readonly buffer Vpls { vec4 vpl_data[]; };
vec3 vpl_position(int i) { return vpl_data[3 * i].xyz; }
vec3 vpl_normal(int i) { return vpl_data[3 * i + 1].xyz; }
vec3 vpl_power(int i) { return vpl_data[3 * i + 2].xyz; }
void vpl_basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}
// World offset d from VPL i in its frame (z along the normal).
vec3 vpl_local(int i, vec3 d) {
    vec3 t, b;
    vpl_basis(vpl_normal(i), t, b);
    return vec3(dot(d, t), dot(d, b), dot(d, vpl_normal(i)));
}
// Map coordinates in [0,1]² of a local direction with p.z ≥ 0. Octahedral (kind 0):
// o = p / (|x| + |y| + z) fills the diamond |o.x| + |o.y| ≤ 1, turned 45° onto the square.
// Paraboloid (kind 1): d.xy / (1 + d.z).
vec2 vpl_map_uv(vec3 p, int kind) {
    if (kind == 0) {
        vec2 o = p.xy / (abs(p.x) + abs(p.y) + p.z);
        return 0.5 * vec2(o.x + o.y, o.x - o.y) + 0.5;
    }
    vec3 d = normalize(p);
    return 0.5 * d.xy / (1.0 + d.z) + 0.5;
}
// Whether VPL i's map (layer i of `maps`) sees the point x with normal n at distance r from it.
// The point is moved off its surface by about a texel's footprint at that distance (normal
// offset: `offset_scale` is half a texel's angle) and compared with a small relative bias: no
// self-shadowing acne. Points behind the VPL's plane are not in its map (seen).
bool vpl_map_visible(sampler2DArray maps, int i, vec3 x, vec3 n, float r, int kind,
                     float offset_scale, float relative_bias) {
    vec3 p = vpl_local(i, x + n * (r * offset_scale) - vpl_position(i));
    if (p.z <= 0.0) return true;
    float stored = texture(maps, vec3(vpl_map_uv(p, kind), float(i))).r;
    return length(p) <= stored * (1.0 + relative_bias);
}
)";

namespace {

const char* const kMapVertex = R"(
layout(location = 0) in vec3 position;
uniform mat4 model;
uniform int first, kind;
uniform float near_distance, far_distance;
out vec3 v_local;
out vec3 v_clip;
flat out int v_layer;
void main() {
    int faces = kind == 0 ? 4 : 1;
    int vi = first + gl_InstanceID / faces;
    int face = gl_InstanceID % faces;
    vec3 p = vpl_local(vi, (model * vec4(position, 1.0)).xyz - vpl_position(vi));
    v_local = p;
    v_layer = vi;
    if (kind == 0) {
        // Face (sx, sy): the perspective projection onto the plane sx·x + sy·y + z = 1, whose
        // depth w = sx·x + sy·y + z is the octahedral norm there; clipped to its octant.
        float sx = (face & 1) != 0 ? -1.0 : 1.0;
        float sy = (face & 2) != 0 ? -1.0 : 1.0;
        float w = sx * p.x + sy * p.y + p.z;
        float n = near_distance, f = far_distance;
        gl_Position = vec4(p.x + p.y, p.x - p.y, (w * (f + n) - 2.0 * f * n) / (f - n), w);
        v_clip = vec3(sx * p.x, sy * p.y, p.z);
    } else {
        float r = length(p);
        vec3 d = p / max(r, 1e-30);
        gl_Position = vec4(d.xy / (1.0 + d.z), 2.0 * r / far_distance - 1.0, 1.0);
        v_clip = vec3(1.0, 1.0, p.z);
    }
}
)";

const char* const kMapGeometry = R"(
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;
in vec3 v_local[];
in vec3 v_clip[];
flat in int v_layer[];
out vec3 f_local;
out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[3];
};
void main() {
    // Wholly outside the face's octant (or below the horizon): nothing to clip, nothing to draw.
    for (int c = 0; c < 3; ++c)
        if (v_clip[0][c] < 0.0 && v_clip[1][c] < 0.0 && v_clip[2][c] < 0.0) return;
    for (int i = 0; i < 3; ++i) {
        gl_Position = gl_in[i].gl_Position;
        gl_ClipDistance[0] = v_clip[i].x;
        gl_ClipDistance[1] = v_clip[i].y;
        gl_ClipDistance[2] = v_clip[i].z;
        gl_Layer = v_layer[0];
        f_local = v_local[i];
        EmitVertex();
    }
    EndPrimitive();
}
)";

const char* const kMapFragment = R"(
in vec3 f_local;
layout(location = 0) out float out_distance;
void main() { out_distance = length(f_local); }
)";

}  // namespace

VplShadowMaps::VplShadowMaps(const Scene& scene, const SceneMeshes& meshes, int size,
                             VplMapKind kind, float near_distance)
    : scene_(scene),
      meshes_(meshes),
      size_(size),
      kind_(kind),
      near_(near_distance),
      program_("vpl shadow map", std::string(kVplMapGlsl) + kMapVertex, kMapGeometry, kMapFragment),
      vpl_buffer_(make_buffer()),
      layered_(make_framebuffer()),
      single_(make_framebuffer()) {
    Bounds b;
    for (const Object& o : scene.objects)
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    // Moved objects stay within a few scene diagonals; the far plane only bounds the depth range.
    far_ = 4.0f * std::max(1e-3f, glm::length(b.extent()));
}

void VplShadowMaps::bind_buffer() const {
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, vpl_buffer_.get());
}

void VplShadowMaps::set_vpls(const std::vector<Vpl>& vpls) {
    std::vector<glm::vec4> data;
    data.reserve(vpls.size() * 3 + 3);
    for (const Vpl& v : vpls) {
        data.emplace_back(v.position, 1.0f);
        data.emplace_back(v.normal, 0.0f);
        data.emplace_back(v.power, 0.0f);
    }
    if (data.empty()) data.resize(3, glm::vec4(0.0f));
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, vpl_buffer_.get());
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(data.size() * sizeof(glm::vec4)),
                   data.data(), GL_DYNAMIC_DRAW);
    count_ = int(vpls.size());
    if (count_ <= capacity_) return;
    // Grow (with room) and start the new arrays cleared: nothing drawn reads as unoccluded.
    capacity_ = std::max(count_, capacity_ + capacity_ / 2);
    distance_ = make_texture();
    gl::BindTexture(GL_TEXTURE_2D_ARRAY, distance_.get());
    gl::TexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_R32F, size_, size_, capacity_);
    gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    const float far = 1e30f;
    gl::ClearTexImage(distance_.get(), 0, GL_RED, GL_FLOAT, &far);
    depth_ = make_texture();
    gl::BindTexture(GL_TEXTURE_2D_ARRAY, depth_.get());
    gl::TexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_DEPTH_COMPONENT32F, size_, size_, capacity_);
    gl::BindFramebuffer(GL_FRAMEBUFFER, layered_.get());
    gl::FramebufferTexture(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, distance_.get(), 0);
    gl::FramebufferTexture(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, depth_.get(), 0);
    const GLenum status = gl::CheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("VPL shadow-map framebuffer incomplete: " + std::to_string(status));
    check_gl("VplShadowMaps::set_vpls");
}

void VplShadowMaps::render(int first, int count) {
    count = std::min(count, count_ - first);
    if (count <= 0) return;
    // Clear just these layers (the layered framebuffer would clear them all).
    gl::BindFramebuffer(GL_FRAMEBUFFER, single_.get());
    const GLenum buffer = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &buffer);
    gl::DepthMask(GL_TRUE);
    gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl::Disable(GL_SCISSOR_TEST);
    const float far[4] = {1e30f, 0.0f, 0.0f, 0.0f};
    for (int l = first; l < first + count; ++l) {
        gl::FramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, distance_.get(), 0, l);
        gl::FramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, depth_.get(), 0, l);
        gl::ClearBufferfv(GL_COLOR, 0, far);
        const float one = 1.0f;
        gl::ClearBufferfv(GL_DEPTH, 0, &one);
    }
    gl::BindFramebuffer(GL_FRAMEBUFFER, layered_.get());
    gl::DrawBuffers(1, &buffer);
    gl::Viewport(0, 0, size_, size_);
    gl::Enable(GL_DEPTH_TEST);
    gl::DepthFunc(GL_LESS);
    gl::Disable(GL_BLEND);
    gl::Disable(GL_STENCIL_TEST);
    gl::Disable(GL_CULL_FACE);  // both sides occlude
    for (int c = 0; c < 3; ++c) gl::Enable(GL_CLIP_DISTANCE0 + GLenum(c));
    program_.use();
    bind_buffer();
    program_.set("first", first);
    program_.set("kind", int(kind_));
    program_.set("near_distance", near_);
    program_.set("far_distance", far_);
    const int faces = kind_ == VplMapKind::octahedral ? 4 : 1;
    for (size_t i = 0; i < scene_.objects.size(); ++i) {
        program_.set("model", model_matrix(scene_.objects[i]));
        meshes_.draw_instanced(i, count * faces);
        vertices_ += uint64_t(scene_.objects[i].mesh.positions.size()) * uint64_t(count * faces);
    }
    for (int c = 0; c < 3; ++c) gl::Disable(GL_CLIP_DISTANCE0 + GLenum(c));
    check_gl("VplShadowMaps::render");
}

std::vector<float> VplShadowMaps::read_layer(int layer) const {
    gl::BindFramebuffer(GL_READ_FRAMEBUFFER, single_.get());
    gl::FramebufferTextureLayer(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, distance_.get(), 0,
                                layer);
    gl::ReadBuffer(GL_COLOR_ATTACHMENT0);
    std::vector<float> out(size_t(size_) * size_t(size_));
    gl::PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl::ReadPixels(0, 0, size_, size_, GL_RED, GL_FLOAT, out.data());
    return out;
}

}  // namespace ag::gpu
