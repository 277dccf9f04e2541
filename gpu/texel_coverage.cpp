#include "gpu/texel_coverage.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "gpu/g_buffer.h"
#include "shared/lightmap_sample.h"

namespace ag::gpu {

namespace {

// x, y: where the pixel reads the lightmap, in texels; w = 1 where a lightmapped surface is seen.
const std::string kCoverageFragment = R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
uniform vec2 atlas_size;
uniform int lightmapped;
layout(location = 0) out vec4 out_texel;
void main() {
    out_texel = lightmapped != 0 ? vec4(v_uv * atlas_size, 0.0, 1.0) : vec4(0.0);
}
)";

}  // namespace

TexelCoverage::TexelCoverage(const Scene& scene, const SceneMeshes& meshes, int width, int height,
                             int max_side)
    : scene_(scene), meshes_(meshes) {
    const float scale = std::min(1.0f, float(max_side) / float(std::max({width, height, 1})));
    width_ = std::max(1, int(std::lround(float(width) * scale)));
    height_ = std::max(1, int(std::lround(float(height) * scale)));
    program_ = Program("texel coverage", kSceneVertex, kCoverageFragment);
    target_ = make_float_texture(width_, height_);
    depth_ = make_renderbuffer();
    gl::BindRenderbuffer(GL_RENDERBUFFER, depth_.get());
    gl::RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH32F_STENCIL8, width_, height_);
    fbo_ = framebuffer_with({target_.get()}, depth_.get(), "texel coverage");
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    coverage_.assign(scene_.atlas.texels.size(), 0.0f);
    check_gl("TexelCoverage");
}

const std::vector<float>& TexelCoverage::update() {
    const GBuffer::View view = GBuffer::view_of(scene_, width_, height_);
    begin_scene_pass(fbo_.get(), 1, width_, height_, glm::vec4(0.0f));
    program_.use();
    program_.set("view_projection", view.view_projection);
    program_.set("atlas_size", glm::vec2(float(scene_.atlas.width), float(scene_.atlas.height)));
    for (size_t o = 0; o < scene_.objects.size(); ++o) {
        const Object& obj = scene_.objects[o];
        program_.set("model", model_matrix(obj));
        const bool lightmapped = obj.material.type == MaterialType::diffuse &&
                                 o < scene_.atlas.corner_uvs.size() &&
                                 !scene_.atlas.corner_uvs[o].empty();
        program_.set("lightmapped", lightmapped ? 1 : 0);
        meshes_.draw(o);
    }
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("TexelCoverage::update");
    const std::vector<float> rgba =
        read_rgba(fbo_.get(), GL_COLOR_ATTACHMENT0, 0, 0, width_, height_);
    std::fill(coverage_.begin(), coverage_.end(), 0.0f);
    const float pixel = 1.0f / float(size_t(width_) * size_t(height_));
    for (size_t p = 0; p < size_t(width_) * size_t(height_); ++p) {
        const float* texel = &rgba[4 * p];
        if (texel[3] > 0.0f)
            add_lookup_coverage(scene_.atlas, glm::vec2(texel[0], texel[1]), pixel, coverage_);
    }
    return coverage_;
}

}  // namespace ag::gpu
