// The voxel grids of Pfeuti 2009 ch. 3.1.2: refractive index n, scattering σ_s and extinction σ_t
// over a world box, the Gaussian smoothing of n that the ray equation (eq. 2.7) needs, and the
// photons of the photon plane (ch. 3.1.4). Plain data for the CPU voxeliser and the GPU marcher.
#pragma once

#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "shared/image.h"
#include "shared/mesh.h"

namespace ag {

struct MediaGrid {
    Bounds bounds;
    glm::ivec3 size{0};
    std::vector<float> n;        // refractive index, 1 in air
    std::vector<float> sigma_s;  // per scene unit
    std::vector<float> sigma_t;  // per scene unit

    size_t index(int x, int y, int z) const {
        return (size_t(z) * size_t(size.y) + size_t(y)) * size_t(size.x) + size_t(x);
    }
    size_t voxel_count() const { return size_t(size.x) * size_t(size.y) * size_t(size.z); }
    glm::vec3 voxel_size() const { return bounds.extent() / glm::vec3(size); }
    glm::vec3 voxel_centre(int x, int y, int z) const {
        return bounds.min + (glm::vec3(x, y, z) + 0.5f) * voxel_size();
    }
};

// A grid of `size` voxels over `bounds`, n = 1 and no medium.
MediaGrid make_media_grid(const Bounds& bounds, const glm::ivec3& size);

// The slice of a per-voxel field (`values`, grid.voxel_count() of them) through voxel layer
// `layer` across `axis` (0: a y–z image, 1: x–z, 2: x–y), grey, rows top down (first row = largest
// second coordinate): what `afterglow media --slices` writes.
Image grid_slice(const MediaGrid& grid, const std::vector<float>& values, int axis, int layer);

// Smooths `values` (a grid of `size`) in place with a separable Gaussian of `taps` taps per axis
// (odd) and standard deviation `sigma` voxels, clamping at the borders (Pfeuti: 9 taps, σ = 9/6).
void gaussian_smooth(std::vector<float>& values, const glm::ivec3& size, int taps, float sigma);

// One photon of the photon plane: where it enters the grid, its unit direction and its flux.
struct MediaPhoton {
    glm::vec3 position{0.0f};
    glm::vec3 direction{0.0f};
    float power = 0.0f;
};

// Pfeuti ch. 3.1.4: `count` photons of a point light (intensity I, W/sr) through a square plane
// perpendicular to the light→grid axis that covers the grid as seen from the light, at 2D
// Hammersley points; each carries I·ΔA·cosθ/r² (the solid angle of its plane cell), moved to where
// it enters the grid's box. Photons that miss the box are dropped, so the total power is
// I · Ω(box) up to the sampling error.
std::vector<MediaPhoton> plane_photons(const glm::vec3& light, float intensity, const Bounds& grid,
                                       int count);

// A point light inside the grid: `count` photons from its position in Hammersley directions over
// the sphere, each carrying 4πI/count.
std::vector<MediaPhoton> sphere_photons(const glm::vec3& light, float intensity, int count);

// A quad light (corners as Light::corners, front normal edge01 × edge03, radiance L): `count`
// photons from Hammersley points on it in cosine-distributed directions, each carrying πLA/count,
// moved to where they enter the grid's box (those that miss it are dropped).
std::vector<MediaPhoton> quad_photons(const std::array<glm::vec3, 4>& corners, float radiance,
                                      const Bounds& grid, int count);

// Solid angle (sr) of box `b` seen from a point outside it: the sum over its faces turned to the
// point of the rectangle formula.
double box_solid_angle(const Bounds& b, const glm::vec3& from);

}  // namespace ag
