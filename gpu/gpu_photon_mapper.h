// GPU photon mapping for indirect diffuse light (Jimenez Kwast 2016, ch. 5), all on the GPU and
// nothing read back per frame: photon paths leave every light (Hammersley positions, cosine or
// uniform directions, TEA random numbers, §5.3.2) and walk our flat BVH; hits from the second
// bounce on are appended through an atomic counter; each frame the photons are binned into 8×8
// screen tiles against the tiles' depth-bounded frusta (count, GPU prefix sum, insert, §5.3.3.1)
// and the cone filter (k = 1, eq. 5.6) runs at low resolution, with pixels whose low-resolution
// neighbours differ in normal, plane or material estimated again at full resolution (§5.3.4).
// Photons accumulate over frames while the scene is static; the term holds E/π per pixel.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "gpu/g_buffer.h"
#include "gpu/gl_objects.h"
#include "gpu/gpu_bvh.h"
#include "gpu/prefix_sum.h"
#include "gpu/surface_albedo.h"
#include "shared/scene.h"

namespace ag::gpu {

inline constexpr int kPhotonTile = 8;  // tile edge, pixels (thesis: 8×8, 64 threads)

// A light primitive photons leave (std430, 80 bytes): a point or spot light, a sun's disc, a quad
// light or one triangle of a mesh light, chosen with probability cdf_hi − cdf_lo (by power).
struct PhotonEmitter {
    glm::vec3 a{0.0f};  // position / disc centre / corner / vertex
    uint32_t type = 0;  // kEmitter*
    glm::vec3 b{0.0f};  // spot axis / sun direction / first edge
    float cos_outer = -1.0f;
    glm::vec3 c{0.0f};  // second edge; sun: c.x = disc radius
    float cos_inner = -1.0f;
    glm::vec3 power{0.0f};  // Φ of this primitive (W), times the spot weight's normaliser
    float cdf_lo = 0.0f;
    glm::vec3 normal{0.0f};  // emitting side of a quad or triangle
    float cdf_hi = 0.0f;
};
enum : uint32_t { kEmitterPoint = 0, kEmitterSpot, kEmitterSun, kEmitterQuad, kEmitterTriangle };

// The scene's enabled lights as emitters with a power CDF (empty when nothing emits).
std::vector<PhotonEmitter> make_photon_emitters(const Scene& scene);

class GpuPhotonMapper {
public:
    // Renders into `g_buffer`'s size; the caller renders the G-buffer each frame before render().
    GpuPhotonMapper(const Scene& scene, const GBuffer& g_buffer);

    // Restart: BVH, emitters and materials from the scene as it is now; photons dropped.
    void reset();
    // Drops the photons but keeps the BVH, emitters and materials (benchmarks: every frame's
    // photons new, as in the thesis).
    void clear_photons();
    // Traces this frame's photon paths (settings.gpu_pm.paths) unless `frames` are accumulated.
    void trace();
    // Bins the photons into the G-buffer's tiles and estimates the indirect term.
    void render();

    GLuint texture() const { return result_.get(); }  // E/π, RGBA32F; a = 1 where refined
    // The viewer's picture of the last render's binning, at the G-buffer's size: rgb a log-scale
    // colour of the pixel's tile's photon count (tile edges darker), a the count.
    GLuint render_tile_view();
    int frames_accumulated() const { return frames_; }
    bool settled() const;
    uint64_t paths_traced() const { return paths_total_; }  // since reset
    uint64_t revision() const { return revision_; }

    // Diagnostics (read back; tests and benchmarks only, never per frame).
    uint32_t stored_photons() const;  // appended since reset (may exceed capacity)
    size_t photon_capacity() const { return capacity_; }
    struct Photon {
        glm::vec4 position;  // w: octahedral direction x
        glm::vec4 power;     // w: octahedral direction y
    };
    std::vector<Photon> read_photons() const;
    // Per tile (row-major, GL orientation: tile row 0 at the bottom), the photon indices of the
    // last render, each list sorted.
    std::vector<std::vector<uint32_t>> read_tile_lists() const;
    int refined_pixels() const;  // pixels estimated again at full resolution in the last render
    int tiles_x() const { return tiles_x_; }
    int tiles_y() const { return tiles_y_; }
    float radius() const { return radius_; }  // world units
    bool index_overflow() const;              // the last render's tile lists did not fit

private:
    void bin(const GBuffer::View& view);
    void bind_tile_buffers() const;
    void set_view_uniforms(const Program& p, const GBuffer::View& view) const;
    uint32_t photon_bound() const;  // what the counter can hold now, known without reading it

    const Scene& scene_;
    const GBuffer& g_buffer_;
    int width_, height_, tiles_x_, tiles_y_, low_w_, low_h_;
    GpuBvh bvh_;
    SurfaceAlbedo albedo_;  // textures where photons bounce
    PrefixSum prefix_sum_;
    Program trace_, tile_bounds_, count_scatter_, insert_scatter_, count_brute_, insert_brute_,
        estimate_low_, composite_, tile_view_program_;
    Buffer emitters_, materials_, photons_, counter_, tile_bounds_buffer_, tile_counts_,
        tile_offsets_, tile_cursor_, indices_;
    Texture low_radiance_, result_, tile_view_;
    size_t capacity_ = 0, index_capacity_ = 0;
    uint32_t emitter_count_ = 0;
    float radius_ = 1.0f, total_power_ = 0.0f;
    float max_photon_power_ = 0.0f;  // × paths: the largest photon's power (fixed-point scale)
    int frames_ = 0;
    uint64_t paths_total_ = 0, revision_ = 1;
};

}  // namespace ag::gpu
