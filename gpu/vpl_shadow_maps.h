// Hemispherical shadow maps for virtual point lights (Barczak 2006 §4.2): one layer of a 2D
// texture array per VPL holding the distance to the nearest surface in each direction of its
// hemisphere. `octahedral`: the upper four faces of an octahedron packed into the square, each
// face a perspective projection onto its plane, so triangles stay straight and nothing leaks;
// drawn as layered, instanced passes (one instance per VPL and face, a geometry shader picks the
// layer, clip distances cut each face's octant; the thesis's ≤ 4 clipped passes). `paraboloid`:
// the dual-paraboloid front map with its per-vertex projection, which bends straight edges and so
// leaks unless the geometry is finely tessellated (thesis Fig. 4-3); kept for the leak test.
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
// position, normal, power; binding 0), the tangent frame about a VPL's normal (Duff et al.
// 2017, as cpu::orthonormal_basis) and the map coordinates of a local direction.
extern const char* const kVplMapGlsl;

class VplShadowMaps {
public:
    // `size`²-texel maps; `near_distance` clips what lies closer to a VPL than this (world units).
    VplShadowMaps(const Scene& scene, const SceneMeshes& meshes, int size, VplMapKind kind,
                  float near_distance);

    // Uploads the VPLs (binding 0 while drawing and reading); grows the arrays as needed. Maps of
    // VPLs whose index existed before keep their contents until rendered again.
    void set_vpls(const std::vector<Vpl>& vpls);
    // Renders the maps of VPLs [first, first + count) in the scene as it is now.
    void render(int first, int count);
    void render_all() { render(0, count_); }

    GLuint texture() const { return distance_.get(); }  // R32F 2D array, one layer per VPL
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
    // Object vertices transformed by map passes since construction (the thesis's cost measure:
    // each vertex once per face and VPL).
    uint64_t vertices_transformed() const { return vertices_; }
    // Reads one layer back (size² distances, rows bottom-first) for tests and views.
    std::vector<float> read_layer(int layer) const;

private:
    const Scene& scene_;
    const SceneMeshes& meshes_;
    int size_;
    VplMapKind kind_;
    float near_, far_;
    int count_ = 0, capacity_ = 0;
    Program program_;
    Buffer vpl_buffer_;
    Texture distance_, depth_;
    Framebuffer layered_, single_;
    uint64_t vertices_ = 0;
};

}  // namespace ag::gpu
