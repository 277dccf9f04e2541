// Voxelisation of the scene's media and glass for Pfeuti's method (2009, ch. 3.1.2) through our
// ray tracer: inside/outside of each glass object by ray parity along rows of sub-voxel rays
// (instead of his XOR-blended slice map), coverage-weighted index and coefficients at borders.
#pragma once

#include "cpu/ray_tracer.h"
#include "shared/media_grid.h"
#include "shared/scene.h"

namespace ag::cpu {

// The grid of `size` voxels over `bounds`: each voxel split into sub³ samples; a sample inside a
// glass object (odd count of its surfaces crossed from outside) takes its index ior + ior_noise(p)
// and its interior medium, a sample elsewhere n = 1 and the world medium whose box holds it.
// Glass meshes must be closed.
MediaGrid voxelize_media(const Scene& scene, const RayTracer& rays, const Bounds& bounds,
                         const glm::ivec3& size, int sub = 2);

}  // namespace ag::cpu
