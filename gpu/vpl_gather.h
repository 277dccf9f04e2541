// Per-pixel sum over virtual point lights with shadow-map visibility (Barczak 2006 §4.3):
// E(x) = Σ_i Φ_i/π · cos θ_l cos θ_x / max(d², clamp²) · V_i(x), V_i read from VPL i's
// hemispherical shadow map (gpu::VplShadowMaps) at points given per pixel (a G-buffer).
//
// Cutting the per-pixel sum (what a many-light renderer does):
// - Tile lists (set_tiles): per 8×8 tile, the CPU lists only the VPLs that can light one of the
//   tile's points (both cosines positive: exact), and with F/P/N labels (Barczak §4.3.1) leaves
//   out VPLs fully occluded at every facing point and marks a shadow-map lookup only where some
//   facing point's patch is P.
// - Interleaved sampling (Keller & Heidrich 2001): with interleave n, VPL i belongs to class
//   hash(i) mod n², a pixel sums only the class of its place in an n × n pattern, and a
//   geometry-aware filter adds, per class, the mean of that class's partial sums over the
//   (2n−1)² (or n × n) neighbours on the same surface (normals within ~25°, off the pixel's plane
//   by less than 0.1 × their distance). Not exact: the error is measured against the full sum.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "gpu/vpl_shadow_maps.h"
#include "shared/vpl.h"

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
    // Builds the tile lists over `vpls` (the maps' records, same order) for the points of the
    // last set_points(); `labels` (optional, patch-major over the last set_points() patches and
    // vpls.size()): as in set_labels(). `interleave` 1-4; `wide_filter`: the (2n−1)² window,
    // else n × n (each class once; cheaper, noisier). shade() uses them until clear_tiles().
    // Rebuild after the points or the VPLs change.
    void set_tiles(const std::vector<Vpl>& vpls, int interleave = 1,
                   const std::vector<uint32_t>* labels = nullptr, bool wide_filter = true);
    void clear_tiles();
    struct TileCounts {
        uint64_t pairs = 0;    // tiles × VPLs
        uint64_t entries = 0;  // (tile, VPL) pairs listed
        uint64_t lookups = 0;  // of those, with a shadow-map lookup
        // Work of the per-pixel loop (machine-independent): Σ over points of the VPLs it
        // evaluates, and of those with a lookup (the full sum: points × VPLs, all looked up).
        uint64_t evaluations = 0, evaluated_lookups = 0;
    };
    const TileCounts& tile_counts() const { return tile_counts_; }
    static constexpr int kTile = 8;  // tile side in pixels (a multiple of the interleave: 6 at 3)

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
    Program program_, filter_;
    Texture positions_, normals_, output_, partial_;
    Framebuffer fbo_, partial_fbo_;
    Buffer labels_, tile_offsets_, tile_entries_;
    // CPU copies of the points (rows bottom-first) for the tile lists.
    std::vector<glm::vec3> cpu_positions_, cpu_normals_;
    std::vector<int> cpu_patches_;
    bool tiled_ = false, wide_filter_ = true;
    int interleave_ = 1, tile_ = kTile, tiles_x_ = 0;
    TileCounts tile_counts_;
    VertexArray empty_vao_;
};

}  // namespace ag::gpu
