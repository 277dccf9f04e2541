// How much of the screen each lightmap texel covers: one depth-tested pass over the scene at a
// small resolution writing, per pixel, the atlas texel its lightmap uv falls in, read back and
// counted. The IIM scheduler uses it to gather first the texels the camera sees (issue #11: "IIM
// texels by Δi and by how much of the screen they cover"). Mirrors and glass occlude but count
// for nothing (they have no lightmap); texels seen only through them count as unseen.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "gpu/scene_meshes.h"
#include "shared/scene.h"

namespace ag::gpu {

class TexelCoverage {
public:
    // Counts at `width` × `height` scaled down so the longer side is at most `max_side`.
    TexelCoverage(const Scene& scene, const SceneMeshes& meshes, int width, int height,
                  int max_side = 128);

    // Per texel record: the fraction of the screen's pixels that show it (sums to the fraction
    // covered by lightmapped surfaces).
    const std::vector<float>& update();
    const std::vector<float>& coverage() const { return coverage_; }
    int width() const { return width_; }
    int height() const { return height_; }

private:
    const Scene& scene_;
    const SceneMeshes& meshes_;
    int width_, height_;
    Program program_;
    Texture target_;
    Renderbuffer depth_;
    Framebuffer fbo_;
    std::vector<float> coverage_;
};

}  // namespace ag::gpu
