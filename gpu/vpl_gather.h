// Per-pixel sum over virtual point lights with shadow-map visibility (Barczak 2006 §4.3):
// E(x) = Σ_i Φ_i/π · cos θ_l cos θ_x / max(d², clamp²) · V_i(x), V_i read from VPL i's
// hemispherical shadow map (gpu::VplShadowMaps) at points given per pixel (a G-buffer).
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "gpu/vpl_shadow_maps.h"

namespace ag::gpu {

class VplGather {
public:
    VplGather(int width, int height);

    // World positions and unit normals per pixel, rows bottom-first; a zero normal: no point.
    // `patches` (optional): each pixel's patch index into the labels of set_labels().
    void set_points(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                    const std::vector<int>& patches = {});
    // Visibility labels per (patch, VPL), patch-major (Barczak §4.3.1): 0 unoccluded (no
    // shadow-map lookup), 1 partly occluded (lookup), 2 or more no light (skipped). Used by
    // shade() when `labelled`.
    void set_labels(const std::vector<uint32_t>& labels);
    // Writes scale · E at every point from the maps' VPLs; `visibility` off ignores the maps
    // (the unshadowed sum).
    void shade(const VplShadowMaps& maps, float clamp, float scale, bool visibility = true,
               bool labelled = false);

    GLuint texture() const { return output_.get(); }
    // scale · E per pixel, rows bottom-first.
    std::vector<glm::vec3> read_back() const;
    int width() const { return width_; }
    int height() const { return height_; }

private:
    int width_, height_;
    Program program_;
    Texture positions_, normals_, output_;
    Framebuffer fbo_;
    Buffer labels_;
    VertexArray empty_vao_;
};

}  // namespace ag::gpu
