// Surfaces by crease angle (Larsen ch. 8) and lightmap charts packed into one atlas, with a record
// per texel. Connectivity comes from OpenMesh; the result is plain arrays in scene.h/lightmap.h.
#pragma once

#include <optional>
#include <vector>

#include "shared/mesh.h"
#include "shared/scene.h"

namespace ag {

// Groups triangles into surfaces: edge-adjacent faces whose normals differ by less than
// `crease_angle_deg` share a surface. Returns a surface id (0..n-1) per triangle.
std::vector<int> segment_surfaces(const Mesh& mesh, float crease_angle_deg, int* surface_count);

// Fills scene.surfaces, scene.triangle_surface and scene.atlas from the objects' meshes and
// scene.settings.lightmap (crease angle, chart cone, texel size, gutter). Every object gets
// surfaces; only diffuse objects get charts and texels (specular ones have no lightmap).
// Deterministic. A texel size too small for the scene is an InputError naming
// settings.lightmap.texel_size and the limit, raised before the atlas is allocated.
void make_surfaces_and_atlas(Scene& scene);

// A point of a texel's footprint, in its object's space.
struct FootprintPoint {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};  // unit face normal of the chart triangle it lies on
};

// Points of texel record `record`'s footprint other than its centre, nearest to the centre first:
// the atlas positions (x + ½ + dx, y + ½ + dy), dx, dy ∈ {−0.4, 0, 0.4}, that lie on one of its
// chart's triangles. Where a gather from the centre starts inside geometry (the floor under a
// box), one of these usually does not, and gathers the light right beside the contact.
std::vector<FootprintPoint> texel_footprint_points(const Scene& scene, int record);
// The point of record `record`'s chart at atlas position (x + ½, y + ½) + offset, if it lies on
// one of the chart's triangles (offsets in [−½, ½]² cover the texel's footprint).
std::optional<FootprintPoint> texel_point_at(const Scene& scene, int record, glm::vec2 offset);
// Which parts of every atlas texel lie on its chart: per atlas texel (width × height, row-major),
// bit 4·j + i is set when the sub-texel point (x + (i + ½)/4, y + (j + ½)/4) lies on one of the
// chart's triangles (0 for gutters and unused texels). Chart edges at a quarter texel, for the
// AIM's boundary-corrected density estimate (cpu/aim.h).
inline constexpr int kCoverageSubdivision = 4;
std::vector<uint16_t> texel_coverage_masks(const Scene& scene);
// Whether atlas position `p` (texel units) lies on chart `chart`, by texel_coverage_masks.
bool on_chart(const LightmapAtlas& atlas, const std::vector<uint16_t>& masks, int chart,
              glm::vec2 p);
// The atlas position (texel units) of object-space point `p` projected onto chart `chart`.
glm::vec2 chart_atlas_position(const Chart& chart, const glm::vec3& p);

// Atlas bounds. Texels (gutters included): each one costs a texel record, AIM and IIM values and
// GL texels, about 100 bytes in all, so 2^24 is some 1.6 GiB. Side: the GL_MAX_TEXTURE_SIZE every
// OpenGL 4.5 implementation must reach, for the AIM and IIM textures.
inline constexpr int64_t kMaxAtlasTexels = int64_t(1) << 24;
inline constexpr int kMaxAtlasSide = 16384;

}  // namespace ag
