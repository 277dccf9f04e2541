#include "gpu/vpl_gather.h"

#include <glm/gtc/constants.hpp>

#include "gpu/gl.h"

namespace ag::gpu {

namespace {
const char* const kGatherFragment = R"(
uniform sampler2D positions, normals;
uniform sampler2DArray maps;
uniform int count, kind, visibility, labelled;
layout(std430, binding = 1) readonly buffer Labels { uint labels[]; };
uniform float clamp2, scale, offset_scale, relative_bias;
layout(location = 0) out vec4 out_e;
void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 xw = texelFetch(positions, px, 0);
    vec3 x = xw.xyz;
    int patch_base = int(xw.w) * count;
    vec3 n = texelFetch(normals, px, 0).xyz;
    out_e = vec4(0.0, 0.0, 0.0, 1.0);
    if (n == vec3(0.0)) return;
    vec3 e = vec3(0.0);
    for (int i = 0; i < count; ++i) {
        vec3 d = vpl_position(i) - x;
        float d2 = dot(d, d);
        if (d2 <= 0.0) continue;
        float inv = inversesqrt(d2);
        float cos_x = dot(n, d) * inv, cos_l = -dot(vpl_normal(i), d) * inv;
        if (cos_x <= 0.0 || cos_l <= 0.0) continue;
        uint label = labelled != 0 ? labels[patch_base + i] : 1u;
        if (label >= 2u) continue;
        if (visibility != 0 && label == 1u) {
            // The point moved off its surface by about a texel's footprint at its distance
            // (normal offset), compared with a small relative bias: no self-shadowing acne.
            float r = d2 * inv;
            vec3 p = vpl_local(i, x + n * (r * offset_scale) - vpl_position(i));
            if (p.z > 0.0) {
                float stored = texture(maps, vec3(vpl_map_uv(p, kind), float(i))).r;
                if (length(p) > stored * (1.0 + relative_bias)) continue;
            }
        }
        e += vpl_power(i) * (cos_x * cos_l / max(d2, clamp2));
    }
    out_e.rgb = e * scale;
}
)";
}  // namespace

VplGather::VplGather(int width, int height)
    : width_(width),
      height_(height),
      program_("vpl gather", kFullScreenTriangleVertex, std::string(kVplMapGlsl) + kGatherFragment),
      fbo_(make_framebuffer()),
      labels_(make_buffer()),
      empty_vao_(make_vertex_array()) {
    positions_ = make_float_texture(width, height);
    normals_ = make_float_texture(width, height);
    output_ = make_float_texture(width, height);
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, output_.get(), 0);
    check_gl("VplGather");
}

void VplGather::set_points(const std::vector<glm::vec3>& positions,
                           const std::vector<glm::vec3>& normals, const std::vector<int>& patches) {
    auto upload = [&](const Texture& t, const std::vector<glm::vec3>& v) {
        std::vector<float> rgba(v.size() * 4, 0.0f);
        for (size_t i = 0; i < v.size(); ++i) {
            for (int c = 0; c < 3; ++c) rgba[4 * i + size_t(c)] = v[i][c];
            // Patch indices ride in alpha (exact in float up to 2^24).
            if (&v == &positions && i < patches.size()) rgba[4 * i + 3] = float(patches[i]);
        }
        gl::BindTexture(GL_TEXTURE_2D, t.get());
        gl::TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_, height_, GL_RGBA, GL_FLOAT, rgba.data());
    };
    upload(positions_, positions);
    upload(normals_, normals);
    check_gl("VplGather::set_points");
}

void VplGather::set_labels(const std::vector<uint32_t>& labels) {
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, labels_.get());
    const std::vector<uint32_t> one(1, 1u);
    const std::vector<uint32_t>& data = labels.empty() ? one : labels;
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(data.size() * sizeof(uint32_t)),
                   data.data(), GL_STATIC_DRAW);
    check_gl("VplGather::set_labels");
}

void VplGather::shade(const VplShadowMaps& maps, float clamp, float scale, bool visibility,
                      bool labelled) {
    gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    const GLenum buffer = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &buffer);
    gl::Viewport(0, 0, width_, height_);
    gl::Disable(GL_DEPTH_TEST);
    gl::Disable(GL_BLEND);
    gl::Disable(GL_STENCIL_TEST);
    gl::Disable(GL_CULL_FACE);
    program_.use();
    maps.bind_buffer();
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, positions_.get());
    gl::ActiveTexture(GL_TEXTURE1);
    gl::BindTexture(GL_TEXTURE_2D, normals_.get());
    gl::ActiveTexture(GL_TEXTURE2);
    gl::BindTexture(GL_TEXTURE_2D_ARRAY, maps.texture());
    gl::ActiveTexture(GL_TEXTURE0);
    program_.set("positions", 0);
    program_.set("normals", 1);
    program_.set("maps", 2);
    program_.set("count", maps.count());
    program_.set("kind", int(maps.kind()));
    program_.set("visibility", visibility && maps.count() > 0 ? 1 : 0);
    program_.set("labelled", labelled ? 1 : 0);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, labels_.get());
    program_.set("clamp2", clamp * clamp);
    program_.set("scale", scale * glm::one_over_pi<float>());
    // Half a texel's angle (the map spans about π over `size` texels) at unit distance.
    program_.set("offset_scale", 2.0f / float(maps.size()));
    program_.set("relative_bias", 0.01f);
    gl::BindVertexArray(empty_vao_.get());
    gl::DrawArrays(GL_TRIANGLES, 0, 3);
    check_gl("VplGather::shade");
}

std::vector<glm::vec3> VplGather::read_back() const {
    const std::vector<float> rgba =
        read_rgba(fbo_.get(), GL_COLOR_ATTACHMENT0, 0, 0, width_, height_);
    std::vector<glm::vec3> out(size_t(width_) * size_t(height_));
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = {rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]};
    return out;
}

}  // namespace ag::gpu
