// Radiance cache splatting (Gautron 2006 ch. 4, Algorithms 3 and 4): a G-buffer of the camera
// view (world position, normal), each irradiance record's zone of influence (radius a·R_k) drawn
// as one screen quad whose fragments add Ward's weight w and w·E_k(p) (gradient extrapolation)
// into an RGBA32F splat buffer by float blending, and the normalisation Σ w E / Σ w into the
// screen-space indirect term (E/π). Pixels left uncovered (Σ w < a) are found either by reading
// the buffer back and scanning on the CPU (the thesis) or on the GPU: a pass marks, per tile, the
// first uncovered pixel, and only that short list comes back.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "gpu/scene_meshes.h"
#include "shared/irradiance_record.h"
#include "shared/scene.h"

namespace ag::gpu {

class RadianceCacheSplat {
public:
    RadianceCacheSplat(const Scene& scene, const SceneMeshes& meshes, int width, int height);

    int width() const { return width_; }
    int height() const { return height_; }

    // Draws the G-buffer of scene.camera (the frame's projection): diffuse surfaces get their
    // world position (alpha 1) and the normal facing the camera; mirrors, glass and background
    // alpha 0.
    void render_gbuffer();
    // The G-buffer as splat pixels, rows bottom-up (GL order; index = y·width + x).
    std::vector<SplatPixel> read_gbuffer() const;

    void clear();  // Σ w E = Σ w = 0 everywhere
    // Adds `records` at accuracy a and `frame` (temporal extrapolation) by float blending.
    void splat(const std::vector<IrradianceRecord>& records, float accuracy, int frame);
    std::vector<glm::vec4> read_sums() const;  // rows bottom-up
    // The term texture ← Σ w E / Σ w (0 where Σ w = 0); RGBA32F, width × height.
    void normalise();
    GLuint term() const { return term_.get(); }
    std::vector<glm::vec3> read_term() const;  // rows bottom-up
    GLuint sums_texture() const { return sums_.get(); }

    // GPU scan: for each tile × tile block the first uncovered pixel (row-major inside the tile,
    // Σ w < a on a covered pixel), as pixel indices in tile order; only this list is read back.
    std::vector<int> uncovered_per_tile(float accuracy, int tile);

    // New records where the splat buffer (holding the sums of `records`) leaves covered pixels
    // with Σ w < a; afterwards it holds the sums of all of them. Returns the number added.
    // The thesis's way: read the buffer back, scan on the CPU (ag::add_records_by_scan), splat
    // the new records on the GPU.
    int add_records_cpu_scan(std::vector<IrradianceRecord>& records,
                             const std::vector<SplatPixel>& pixels, float accuracy, int frame,
                             const MakeRecord& make, int max_new);
    // Without reading the buffer back: rounds of uncovered_per_tile(); a round's candidates
    // become records in tile order unless a record made earlier in the same round already
    // covers them (checked at that pixel only), are splatted, and the next round scans again.
    int add_records_gpu_scan(std::vector<IrradianceRecord>& records,
                             const std::vector<SplatPixel>& pixels, float accuracy, int frame,
                             const MakeRecord& make, int max_new, int tile = 8);
    int last_rounds() const { return rounds_; }  // scan rounds of the last add_records_gpu_scan

    // A picture of the records for the viewer: each record's zone of influence (w ≥ 1/a) in a
    // colour of its own, mixed by weight, brighter towards the record, the record itself white;
    // into the texture record_view() (RGBA32F, width × height).
    void render_record_view(const std::vector<IrradianceRecord>& records, float accuracy);
    GLuint record_view() const { return view_.get(); }

    // Records drawn by the last splat() (zero-area quads included).
    int last_splatted() const { return last_splatted_; }

private:
    void draw_records(const Program& program, GLuint framebuffer,
                      const std::vector<IrradianceRecord>& records, float accuracy, int frame);
    void normalise_into(GLuint sums, GLuint framebuffer);

    const Scene& scene_;
    const SceneMeshes& meshes_;
    int width_, height_;
    Program gbuffer_, splat_, normalise_, scan_, view_program_;
    Texture position_, normal_, sums_, term_, view_, view_sums_;
    Renderbuffer depth_;
    Framebuffer gbuffer_fbo_, splat_fbo_, term_fbo_, view_fbo_, view_sums_fbo_;
    Buffer records_, tiles_;
    VertexArray empty_;
    int last_splatted_ = 0;
    int rounds_ = 0;
};

}  // namespace ag::gpu
