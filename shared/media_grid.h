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

// The grids the viewer's `media` view slices (docs/viewer.md): the smoothed index, σ_s, the
// fluence, the adaptive pipeline's mipmap level.
enum class MediaField { n, sigma_s, fluence, level };
inline constexpr const char* kMediaFieldNames[] = {"n", "sigma_s", "fluence", "level"};

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

// The photons of a point light as a map from the unit square: his photon plane (ch. 3.1.4) for a
// light outside the grid, the sphere of directions (z and φ, equal-area) for one inside it. A
// point (u, v) drawn with density p over the square (p = 1: uniform) gives one of `count` photons
// carrying total / (count · p) times the flux density there, so any p > 0 keeps the sum unbiased
// (the weighting of his importance-distributed photons, ch. 3.2.3).
struct PhotonSource {
    enum class Kind { plane, sphere } kind = Kind::plane;
    glm::vec3 light{0.0f};
    float intensity = 0.0f;  // W/sr
    Bounds grid;
    glm::vec3 axis{0.0f}, u{0.0f}, v{0.0f};  // the plane at distance 1 along `axis`
    float half = 0.0f;                       // its half-size
};
// Whether a point light gets the sphere source: inside the grid or on its boundary. A light on a
// face, edge or corner has grid corners level with it, which no photon plane in front of it
// covers; from the sphere, the photons heading out leave the grid at their first step.
bool light_in_grid(const glm::vec3& light, const Bounds& grid);
// The source for a point light and grid: the plane when the light lies outside the grid (every
// corner in front of it), else the sphere.
PhotonSource photon_source(const glm::vec3& light, float intensity, const Bounds& grid);
// The photon at (u, v) drawn with density `pdf` among `count`; false where it misses the grid.
bool source_photon(const PhotonSource& source, glm::vec2 uv, double pdf, int count,
                   MediaPhoton& photon);

// A density over the unit square from a `side` × `side` grid of cells, sampled by Pharr and
// Humphreys' two-stage inversion (his ch. 3.2.3: the marginal along y, then the row's
// conditional along x, by binary search on the cumulative sums). Piecewise constant (his), or
// `bilinear` (ours, docs/media.md "Session 15"): the cells' values at their centres, interpolated
// bilinearly and held constant over the outer half cells, which has the same integral as the
// cells (each centre's tent covers one cell's area) and no jump at the cell edges, so the
// weights 1/(N p) of photons drawn through it change continuously.
class PhotonDensity {
public:
    PhotonDensity() = default;
    // `cells` (side², row-major, y rows) ≥ 0 with a positive sum; normalised here.
    PhotonDensity(int side, const std::vector<float>& cells, bool bilinear = false);
    int side() const { return side_; }
    bool bilinear() const { return bilinear_; }
    // The density (mean 1 over the square) at `uv`: its cell's, or bilinear between centres.
    double pdf(glm::vec2 uv) const;
    // Maps a uniform point to one distributed by the density.
    glm::vec2 sample(glm::vec2 uniform) const;
    const std::vector<double>& cells() const { return pdf_; }

private:
    int side_ = 0;
    bool bilinear_ = false;
    std::vector<double> pdf_;  // per cell, mean 1
    // Piecewise constant: side + 1 cumulative sums over rows; side × (side + 1) within each row.
    // Bilinear: over the side + 1 segments between the knots 0, ½/side, 1½/side, …, 1 (side + 2
    // cumulative masses), of the rows' means along y; of each row's values along x.
    std::vector<double> marginal_;
    std::vector<double> rows_;
};

// 2D Hammersley point i of `count`, shifted by `shift` modulo 1 (a Cranley–Patterson rotation;
// shift 0 is the plain set): ((i + ½)/N, Φ₂(i)).
glm::vec2 hammersley(int i, int count, glm::vec2 shift);

// The orders of his Table 4.1 for the uniform photons on the plane: random, a square grid in
// row-first or column-first order, the same jittered, Halton (bases 2, 3) and Hammersley (his
// choice, and ours by default). The grids use ⌊√N⌋² points (the rest of N are dropped).
enum class PlaneSampling {
    random,
    grid_rows,
    grid_columns,
    jitter_rows,
    jitter_columns,
    halton,
    hammersley
};
inline constexpr const char* kPlaneSamplingNames[] = {
    "random", "grid_rows", "grid_columns", "jitter_rows", "jitter_columns", "halton", "hammersley"};
// Point i of `count` in `order` over the unit square; false for a grid's dropped points.
bool plane_sample(PlaneSampling order, int i, int count, glm::vec2& uv);

// Pfeuti's reconstruction (ch. 3.2.4, Listing B.3) of an adaptively sampled fluence grid: mipmap
// pyramids of fluence and flow (each level half the last, a 4-tap [1 3 3 1]/8 filter per axis), of
// the photon count (box) and of the mean photon weight (box over voxels with photons, Listing
// B.2); each voxel then reads the pyramid, trilinearly at its centre, at level
// min(centre-surround level, ⌊weight / Δweight⌋) — or, `fractional` (not his), at
// min(centre-surround level, weight / Δweight), a fractional level l + t read as (1 − t) of level
// l and t of level l + 1.
struct MediaReconstruction {
    std::vector<float> fluence;
    std::vector<glm::vec3> flow;
    std::vector<uint8_t> level;  // per voxel, the level read
    int max_level = 0;
};
// `count` per voxel: photon crossings; `weight`: their mean weight (0 where none).
// `significance` > 0 (not his): a voxel climbs from a level to the next only while the step
// between their values is within `significance` standard errors (each level's relative error
// 1/√(its crossings)). `level` holds the level read, rounded.
MediaReconstruction reconstruct_adaptive(const glm::ivec3& size, const std::vector<float>& fluence,
                                         const std::vector<glm::vec3>& flow,
                                         const std::vector<float>& count,
                                         const std::vector<float>& weight, float delta_weight,
                                         int max_level, float significance = 0.0f,
                                         bool fractional = false);

// Solid angle (sr) of box `b` seen from a point outside it: the sum over its faces turned to the
// point of the rectangle formula.
double box_solid_angle(const Bounds& b, const glm::vec3& from);

}  // namespace ag
