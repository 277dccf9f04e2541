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
// The number of cells per cube edge that make_lumpy_sphere uses for a target triangle count:
// 12·n² triangles come closest to `triangles` (n ≥ 1).
int lumpy_sphere_cells(long long triangles);
// Closed, dense stand-in for a scanned statue: a cube sphere (each face `cells` × `cells` quads
// of 2 triangles, 12·cells² in all, vertices shared along the cube's edges so it is watertight)
// of `radius` with smooth lumps of up to ±`amplitude` (< radius) along the normal; the same seed
// gives the same lumps everywhere.
Mesh make_lumpy_sphere(float radius, int cells, float amplitude, uint32_t seed);
// Torus about the Y axis: a tube of `tube_radius` round the circle of `radius` in the XZ plane
// (tube_radius < radius), `rings` steps round the circle × `sides` round the tube, one vertex
// each (rings · sides; watertight), 2 · rings · sides triangles. Barczak's mover (2006, §5.2):
// 41 × 20 = 820 vertices.
Mesh make_torus(float radius, float tube_radius, int rings, int sides);

}  // namespace ag
