// An atlas-sized float lightmap on the GPU (AIM or IIM). Unused texels around charts are filled
// from their chart's texels (dilation) so bilinear filtering never darkens chart borders, and only
// the rectangle around changed texels is uploaded.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "shared/lightmap.h"

namespace ag::gpu {

// GLSL: bilinear lightmap lookup over the four nearest texel centres that belong to `chart`
// (weights renormalised; the nearest texel if none does): the same rule as the CPU's
// sample_lightmap, so both gathers read the AIMs alike and nothing bleeds across charts.
inline constexpr const char* kChartLightmapGlsl = R"(
vec3 chart_lightmap(sampler2D values, sampler2D charts, vec2 uv, float chart) {
    ivec2 size = textureSize(values, 0);
    vec2 f = uv * vec2(size) - 0.5;
    ivec2 p0 = ivec2(floor(f));
    vec2 t = f - vec2(p0);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            ivec2 p = p0 + ivec2(dx, dy);
            if (p.x < 0 || p.y < 0 || p.x >= size.x || p.y >= size.y) continue;
            if (abs(texelFetch(charts, p, 0).r - chart) > 0.5) continue;
            float w = (dx == 1 ? t.x : 1.0 - t.x) * (dy == 1 ? t.y : 1.0 - t.y);
            sum += w * texelFetch(values, p, 0).rgb;
            weight += w;
        }
    if (weight > 0.0) return sum / weight;
    return texelFetch(values, clamp(ivec2(uv * vec2(size)), ivec2(0), size - 1), 0).rgb;
}
)";

class LightmapTexture {
public:
    explicit LightmapTexture(const LightmapAtlas& atlas);

    // Uploads `values` (atlas-sized) at the given atlas texel indices (y·width + x) and the gutter
    // texels that copy them. An empty list uploads nothing; `all` uploads everything.
    void update(const std::vector<glm::vec3>& values, const std::vector<int>& changed);
    void update_all(const std::vector<glm::vec3>& values);
    GLuint id() const { return texture_.get(); }
    // Chart id per texel (R channel; −1 for unused texels), for chart_lightmap() in shaders.
    GLuint charts() const { return charts_.get(); }
    size_t texels_uploaded() const { return uploaded_; }

private:
    const LightmapAtlas& atlas_;
    Texture texture_, charts_;
    std::vector<float> rgba_;                   // CPU mirror, dilated
    std::vector<std::vector<int>> gutter_of_;   // used texel -> unused neighbours it feeds
    std::vector<std::vector<int>> sources_of_;  // unused texel -> used neighbours (averaged)
    size_t uploaded_ = 0;
};

}  // namespace ag::gpu
