// Curved photon marching through the smoothed index grid on the GPU (Pfeuti 2009, ch. 3.1.5):
// the ray equation d/ds(n dx/ds) = ∇n stepped by eqs. 2.10/2.11, Beer–Lambert attenuation per
// step, and the photon's power deposited into a fluence grid either by his voxel walk (one deposit
// per voxel crossed along the major axis) or by a track-length estimator (power × chord length in
// each voxel the segment crosses, by a 3D DDA). Deposits are 64-bit fixed-point sums built from
// 32-bit atomic adds (llvmpipe has no 64-bit atomics), so the grid is the same on every run.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "gpu/gl_objects.h"
#include "shared/media_grid.h"

namespace ag::gpu {

enum class MediaDeposit { track_length, voxel_walk };

struct MediaMarchSettings {
    float step = 0.25f;  // Δs in voxels (the smallest voxel edge)
    MediaDeposit deposit = MediaDeposit::track_length;
    // His octree (ch. 3.1.3): whole runs of steps at once through cubes where n and σ_t are
    // constant (media_octree); the same deposits up to float rounding. Track length only.
    bool octree = true;
    int max_steps = 0;  // per photon; 0 = enough to cross the grid 8 times
};

struct MediaMarchResult {
    std::vector<float> fluence;            // per voxel: Σ power × chord length / voxel volume
    std::vector<glm::vec3> flow;           // per voxel: the same sums × each photon's direction
    std::vector<MediaPhoton> photons;      // where each photon left the grid (or stopped)
    double entered = 0.0;                  // Σ power of the photons marched
    double absorbed = 0.0, escaped = 0.0;  // extinguished in the grid; left it
    double seconds = 0.0;                  // the dispatch, to glFinish
    double octree_seconds = 0.0;           // building media_octree (CPU), or finding it cached
    // With statistics: `stat_count` per voxel (voxel-major): Σ crossings (chord lengths in voxel
    // edges; 1 per voxel credited by the walk), then Σ crossing × attribute k of each photon.
    std::vector<float> stats;
};

// His octree (Pfeuti ch. 3.1.3) as an array the size of the grid: per voxel, the edge (2, 4, 8,
// … voxels) of the largest aligned cube containing it in which n and σ_t are constant, within
// 2 voxels around it too (the reach of the march's reads); 0 where there is none. Exact
// equality where he groups n within a threshold ε: the long steps must not change the result.
std::vector<int32_t> media_octree(const MediaGrid& grid);

class MediaMarcher {
public:
    MediaMarcher();
    // Marches `photons` (each on or in the grid's box) through `grid` (n already smoothed).
    // With `stat_count` > 0 (at most 5) it also sums per voxel the crossings and the crossings
    // times the first stat_count − 1 components of each photon's `attributes` entry (his photon
    // counts, weights and origins, ch. 3.2).
    MediaMarchResult march(const MediaGrid& grid, const std::vector<MediaPhoton>& photons,
                           const MediaMarchSettings& settings,
                           const std::vector<glm::vec4>& attributes = {}, int stat_count = 0) const;

    // How many times this marcher built the octree: once per distinct n and σ_t grids (the
    // pilots, the photons and each surface bounce of one grid share one).
    int octree_builds() const { return octree_builds_; }

private:
    const std::vector<int32_t>& cached_octree(const MediaGrid& grid) const;

    Program program_;
    struct OctreeKey {
        glm::ivec3 size{0};
        std::vector<float> n, sigma_t;
    };
    mutable std::optional<OctreeKey> octree_key_;
    mutable std::vector<int32_t> octree_;
    mutable int octree_builds_ = 0;
};

}  // namespace ag::gpu
