// Stencil shadow volumes (Larsen ch. 13; Carmack's depth-fail): for every closed mesh, the
// silhouette edges seen from a point light extruded to infinity, with near and far caps, built on
// the CPU from edge adjacency each frame (objects and lights move).
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <unordered_map>
#include <vector>

#include "shared/mesh.h"

namespace ag::gpu {

// Edge adjacency of a closed mesh (positions welded exactly): it casts the volume of its
// silhouette. A mesh with boundary or non-manifold edges (`closed` false: a quad panel, an open
// box, an atrium open to the sky) casts one prism per triangle instead (`soup`), each triangle an
// opaque sheet, if it has at most 65536 triangles; larger open meshes cast nothing.
struct ShadowCaster {
    bool closed = false;
    bool soup = false;
    std::vector<glm::vec3> positions;    // welded
    std::vector<glm::uvec3> triangles;   // into positions
    std::vector<glm::ivec3> neighbours;  // per triangle edge (k, k+1): the adjacent triangle
};

ShadowCaster make_shadow_caster(const Mesh& mesh);
// Only the closed form: `closed` false (and no soup) where the mesh cannot be closed.
ShadowCaster make_closed_caster(const Mesh& mesh);

// The soup casters' corners in world space, welded across meshes: corners a few float steps apart
// (a room's two walls at the corner they share, each turned into place by its own rotation) get
// one id. It does not depend on the light: made again when the geometry changes.
struct SoupWeld {
    std::vector<std::vector<uint32_t>> ids;  // per caster, per position; empty unless soup
    // Per caster: the world plane (unit normal, offset: n·x + offset = 0) of a soup whose corners
    // all lie in one plane within its weld tolerance (`tolerance`, > 0), for the receiver test of
    // append_shadow_volumes; tolerance 0 where the caster is not a planar soup.
    struct Plane {
        glm::dvec3 normal{0.0};
        double offset = 0.0;
        double tolerance = 0.0;
    };
    std::vector<Plane> planes;
    // Per id: where its first corner lies (world space).
    std::vector<glm::vec3> corners;
    // Per caster: for each edge of its outline (an edge one of its triangles alone has, keyed by
    // its ids, the lower first) that another mesh's corners lie on, those corners' ids in order
    // from the lower id's end. A tiled wall's corners on the edge of the whole wall beside it
    // (T-junctions between meshes) split that edge, so that its pieces meet their pairs.
    std::vector<std::unordered_map<uint64_t, std::vector<uint32_t>>> inner;
};
SoupWeld weld_soup_corners(const std::vector<ShadowCaster>& casters,
                           const std::vector<glm::mat4>& models);

// Appends every caster's volume (transformed by its model) for one homogeneous light, as
// append_shadow_volume does for each, except that a side face two soup prisms share (one welded
// edge, drawn once each way: a quad's two triangles along its diagonal, two walls along their
// seam) is left out: the pair cancels in the count, and drawn it left cracks along the seams.
// With `receivers` (the world bounds of everything the frame draws, per object, in the casters'
// order): a planar soup whose plane has every other receiver on the light's side or in it (a
// room's floor, walls and ceiling under a lamp inside the room) is left out. Its volume lies
// behind its plane, where no receiver is, so it holds no visible point and changes no count;
// the other prisms stay closed without it (their sides along its seams are then drawn).
void append_shadow_volumes(const std::vector<ShadowCaster>& casters,
                           const std::vector<glm::mat4>& models, const SoupWeld& weld,
                           const glm::vec4& light, std::vector<glm::vec4>& out,
                           const std::vector<Bounds>* receivers = nullptr);

// Appends the volume of `caster` (transformed by `model`) for a point light at `light` as
// homogeneous world-space triangles (w = 0 at infinity), consistently wound outwards.
void append_shadow_volume(const ShadowCaster& caster, const glm::mat4& model,
                          const glm::vec3& light, std::vector<glm::vec4>& out);
// The same for a homogeneous light: (position, 1) for a point light, (direction towards the
// light, 0) for a directional one (a sun), whose volumes are parallel prisms.
void append_shadow_volume(const ShadowCaster& caster, const glm::mat4& model,
                          const glm::vec4& light, std::vector<glm::vec4>& out);

}  // namespace ag::gpu
