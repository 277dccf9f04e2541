// Screen-space caustics (Larsen ch. 12): draw the scene's depth, splat the caustic photons
// additively as points with their RGB power in float (no 8-bit limit on colour or count), mark them
// in the stencil buffer, find the screen tiles that hold photons with one occlusion query each,
// and filter only those tiles with eq. 12.1, c = s·Σ t(x+i, y+j)·√(1 + 2k² − (i² + j²)), divided by
// the world area of the pixel (eq. 12.2) so the caustic keeps its brightness under zoom and tilt.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "gpu/g_buffer.h"
#include "gpu/gl_objects.h"
#include "gpu/scene_meshes.h"
#include "shared/scene.h"

namespace ag::gpu {

class CausticsRenderer {
public:
    // Draws its own G-buffer each render, or with `shared` (width × height) reads one the caller
    // has rendered for this frame; the splats then mark that buffer's stencil.
    CausticsRenderer(const Scene& scene, const SceneMeshes& meshes, int width, int height,
                     GBuffer* shared = nullptr);
    ~CausticsRenderer();
    CausticsRenderer(const CausticsRenderer&) = delete;
    CausticsRenderer& operator=(const CausticsRenderer&) = delete;

    // Renders L_caustics for the scene's camera (resized to width × height) from photons
    // (world positions and flux in W). `cull` filters only tiles that hold photons (and their
    // neighbours); without it every tile is filtered (same image).
    void render(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& powers,
                bool cull = true);

    GLuint texture() const { return result_.get(); }  // caustic radiance, screen-sized RGBA32F
    // Changes whenever a render may have changed the texture's contents (other photons, view,
    // scene version or filter settings than the render before); never 0.
    uint64_t revision() const { return revision_; }
    int tiles_total() const { return tiles_x_ * tiles_y_; }
    int tiles_filtered() const { return tiles_filtered_; }
    // Times of the last render's passes (ms, after glFinish): the filter alone and the queries.
    double filter_ms() const { return filter_ms_; }
    double query_ms() const { return query_ms_; }

    // For tests: caustic radiance and each pixel's world area (0 where no surface), rows top-first.
    std::vector<glm::vec3> read_radiance() const;
    std::vector<float> read_pixel_area() const;

private:
    const Scene& scene_;
    int width_, height_, tiles_x_, tiles_y_, tile_;
    std::unique_ptr<GBuffer> own_g_buffer_;
    GBuffer* g_buffer_;
    Program splat_, query_, footprint_, filter_;
    Texture splat_texture_, result_, footprint_texture_;
    Framebuffer splat_fbo_, result_fbo_, footprint_fbo_;
    Buffer photon_vbo_;
    VertexArray photon_vao_, empty_vao_;
    std::vector<GLuint> queries_;
    int tiles_filtered_ = 0;
    // What the last render drew from, for revision().
    struct Inputs {
        std::vector<float> photons;  // position and power per photon
        glm::mat4 view_projection{0.0f};
        uint64_t scene_version = 0;
        int kernel_k = -1, kernel_photons = -1;
        bool cull = false;
        bool operator==(const Inputs&) const = default;
    } last_inputs_;
    uint64_t revision_ = 0;
    // The own G-buffer's last drawing: the scene version it showed (its view is last_view()).
    bool g_buffer_drawn_ = false;
    uint64_t g_buffer_version_ = 0;
    bool showing_none_ = false;  // the texture holds zeros from a render without photons
    double filter_ms_ = 0.0, query_ms_ = 0.0;
};

}  // namespace ag::gpu
