// Voxelisation of the scene's media and glass for Pfeuti's method (2009, ch. 3.1.2) through our
// ray tracer: inside/outside of each glass object by ray parity along rows of sub-voxel rays
// (instead of his XOR-blended slice map), coverage-weighted index and coefficients at borders.
#pragma once

#include "cpu/ray_tracer.h"
#include "shared/media_grid.h"
#include "shared/scene.h"

namespace ag::cpu {

// The grid of `size` voxels over `bounds`: sub² rows of rays per voxel row along each of x, y
// and z, each giving the exact length inside each glass object (between odd and even crossings:
// ray parity); each voxel's coverage weighs the three axes' estimates by the squared normal
// components (the axis along the normal is exact, the others come in steps of 1/sub). A voxel
// mixes by that coverage the object (index ior + ior_noise, interior medium) and the outside
// (n = 1, the world medium whose box holds the centre). Glass meshes must be closed.
MediaGrid voxelize_media(const Scene& scene, const RayTracer& rays, const Bounds& bounds,
                         const glm::ivec3& size, int sub = 8);

}  // namespace ag::cpu
