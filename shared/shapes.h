// Built-in shapes for scene files, in object space, counter-clockwise outward-facing triangles.
#pragma once

#include <cstdint>

#include "shared/mesh.h"

namespace ag {

// Axis-aligned box centred at the origin with the given edge lengths (12 triangles); texture
// coordinates show an albedo map once per face, upright from outside.
Mesh make_box(const glm::vec3& size);
// Sphere of `radius` at the origin: an icosahedron subdivided `subdivisions` times (20·4^s tris).
Mesh make_sphere(float radius, int subdivisions);
// Quad in the XZ plane centred at the origin, normal +Y, width along X, depth along Z; texture
// coordinates span it once (u along +X, v along −Z).
Mesh make_quad(float width, float depth);
// Height field over the XZ plane (normal +Y), `resolution` × `resolution` cells (2 triangles
// each), heights a smooth deterministic bump function of amplitude `amplitude`.
Mesh make_bumpy_plane(float width, float depth, int resolution, float amplitude, uint32_t seed);

}  // namespace ag
