// Hemispherical shadow maps for virtual point lights (Barczak 2006 §4.2): one layer of a 2D
// texture array per VPL holding the distance to the nearest surface in each direction of its
// hemisphere. `octahedral`: the upper four faces of an octahedron packed into the square, each
// face a perspective projection onto its plane, so triangles stay straight and nothing leaks;
// drawn as layered, instanced passes (one instance per VPL and face, a geometry shader picks the
// layer, clip distances cut each face's octant; the thesis's ≤ 4 clipped passes). `paraboloid`:
// the dual-paraboloid front map with its per-vertex projection, which bends straight edges and so
// leaks unless the geometry is finely tessellated (thesis Fig. 4-3); kept for the leak test.
// More maps than the implementation's array layers (GL_MAX_ARRAY_TEXTURE_LAYERS: 2048 on
// llvmpipe, where the conference room's ~3000 photon VPLs need more) share layers as an atlas of
// tiles × tiles maps (vpl_map_layout); readers find a VPL's place from its record.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "gpu/gl_objects.h"
#include "gpu/scene_meshes.h"
#include "shared/scene.h"
#include "shared/settings.h"
#include "shared/vpl.h"

namespace ag::gpu {

using ag::VplMapKind;  // shared/settings.h

// GLSL shared by the map passes and their readers: the VPL buffer layout (three vec4 per VPL:
// position and the atlas's tiles a side in w, normal, power; binding 0), the tangent frame about
// a VPL's normal (Duff et al. 2017, as cpu::orthonormal_basis) and the map coordinates of a
// local direction.
extern const char* const kVplMapGlsl;

// The GL limits a map array must fit (queried once a context is current: gl_limits()).
struct VplMapLimits {
    int max_layers = 0;        // GL_MAX_ARRAY_TEXTURE_LAYERS
    int max_texture_size = 0;  // GL_MAX_TEXTURE_SIZE (a layer's side)
    static VplMapLimits gl_limits();
};

// Where `count` maps of size² texels go: `layers` array layers of (tiles · size)² texels, map i
// in layer i / tiles², tile i mod tiles² (row-major). One map a layer while the count fits the
// layers (tiles = 1), else the fewest tiles a side that fit. Throws std::runtime_error naming
// vpl.map_size and the limits when no layout fits.
struct VplMapLayout {
    int tiles = 1;
    int layers = 0;
    int side(int size) const { return tiles * size; }
};
VplMapLayout vpl_map_layout(int count, int size, const VplMapLimits& limits);

class VplShadowMaps {
public:
    // `size`²-texel maps; `near_distance` clips what lies closer to a VPL than this (world units).
    // `limits`: the GL's own (default) or smaller ones (tests of the atlas layout). Throws if
    // `size` exceeds the maximum texture size.
    VplShadowMaps(const Scene& scene, const SceneMeshes& meshes, int size, VplMapKind kind,
                  float near_distance, const VplMapLimits& limits = VplMapLimits::gl_limits());

    // Uploads the VPLs (binding 0 while drawing and reading); grows the arrays as needed. Maps of
    // VPLs whose index existed before keep their contents until rendered again.
    void set_vpls(const std::vector<Vpl>& vpls);
    // Renders the maps of VPLs [first, first + count) in the scene as it is now.
    void render(int first, int count);
    void render_all() { render(0, count_); }

    // R32F 2D array: layout().layers layers of layout().tiles² maps each.
    GLuint texture() const { return distance_.get(); }
    const VplMapLayout& layout() const { return layout_; }
    const VplMapLimits& limits() const { return limits_; }
    GLuint buffer() const { return vpl_buffer_.get(); }
    void bind_buffer() const;
    int size() const { return size_; }
    int count() const { return count_; }
    VplMapKind kind() const { return kind_; }
    float far_distance() const { return far_; }
    // What a reader passes to `vpl_map_visible` (kVplMapGlsl): half a texel's angle (a map spans
    // about π over `size` texels) at unit distance, and the relative depth bias.
    float offset_scale() const { return 2.0f / float(size_); }
    static constexpr float kRelativeBias = 0.01f;
    // Culling before the vertex stage (default on): each object is cut into runs of
    // kChunkTriangles triangles in mesh order, and a run is drawn only for the (VPL, face)
    // pairs whose octant (the hemisphere for paraboloid maps) its bounding box reaches. The
    // geometry shader would drop the same triangles after transforming them, so the maps are
    // identical; off: every object for every VPL and face (the naive pass).
    void set_culling(bool on) { culling_ = on; }
    bool culling() const { return culling_; }
    static constexpr int kChunkTriangles = 512;
    // Object vertices transformed by map passes since construction (the thesis's cost measure:
    // each vertex once per face and VPL; with culling, each run's share of its object's
    // vertices, by triangles, once per (VPL, face) it is drawn for).
    uint64_t vertices_transformed() const { return vertices_; }
    // Reads VPL i's map back (size² distances, rows bottom-first) for tests and views.
    std::vector<float> read_layer(int i) const;

private:
    // Draws the runs for maps [first, first + count) over their (VPL, face) lists.
    void draw_culled(int first, int count, int faces);

    const Scene& scene_;
    const SceneMeshes& meshes_;
    int size_;
    VplMapKind kind_;
    float near_, far_;
    VplMapLimits limits_;
    int count_ = 0, capacity_ = 0;
    VplMapLayout layout_;
    Program program_;
    Buffer vpl_buffer_;
    Texture distance_, depth_;
    Framebuffer layered_, single_;
    struct Chunk {
        size_t object = 0;
        int first = 0, count = 0;        // triangles
        glm::vec3 min{0.0f}, max{0.0f};  // object-space bounds
        uint64_t vertices = 0;           // its share of the object's vertices
    };
    std::vector<Chunk> chunks_;
    std::vector<Vpl> vpls_;  // as uploaded
    bool culling_ = true;
    Buffer instances_;  // culled: the (VPL, face) instances each run is drawn for (binding 4)
    uint64_t vertices_ = 0;
};

}  // namespace ag::gpu
