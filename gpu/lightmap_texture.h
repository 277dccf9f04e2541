// An atlas-sized float lightmap on the GPU (AIM or IIM). Unused texels around charts are filled
// from their chart's texels (dilation) so bilinear filtering never darkens chart borders, and only
// the rectangle around changed texels is uploaded.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "gpu/gl_objects.h"
#include "shared/lightmap.h"

namespace ag::gpu {

class LightmapTexture {
public:
    explicit LightmapTexture(const LightmapAtlas& atlas);

    // Uploads `values` (atlas-sized) at the given atlas texel indices (y·width + x) and the gutter
    // texels that copy them. An empty list uploads nothing; `all` uploads everything.
    void update(const std::vector<glm::vec3>& values, const std::vector<int>& changed);
    void update_all(const std::vector<glm::vec3>& values);
    GLuint id() const { return texture_.get(); }
    size_t texels_uploaded() const { return uploaded_; }

private:
    const LightmapAtlas& atlas_;
    Texture texture_;
    std::vector<float> rgba_;                   // CPU mirror, dilated
    std::vector<std::vector<int>> gutter_of_;   // used texel -> unused neighbours it feeds
    std::vector<std::vector<int>> sources_of_;  // unused texel -> used neighbours (averaged)
    size_t uploaded_ = 0;
};

}  // namespace ag::gpu
