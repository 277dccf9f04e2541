// Pfeuti's reference pipeline (2009, ch. 3.1) end to end: voxelisation through the ray tracer,
// the smoothed index grid, the photon plane of the scene's point light, curved photon marching
// and the view march on the GPU. Joins cpu/ (voxeliser) and gpu/ (marchers), so it lives here.
#pragma once

#include <string>

#include "gpu/media_marcher.h"
#include "shared/image.h"
#include "shared/scene.h"

namespace ag {

struct MediaMethodSettings {
    int grid = 64;             // voxels along the longest side of the grid's box
    int photons = 122000;      // on the photon plane (his Table 4.1 count)
    float march_step = 0.25f;  // photon step, voxels
    float view_step = 0.5f;    // view-ray step, voxels
    gpu::MediaDeposit deposit = gpu::MediaDeposit::track_length;
};

// Seconds per pass, as his Tables 4.2–4.4 list them (no octree, no copy: the grids are SSBOs).
struct MediaMethodTiming {
    double voxelisation = 0.0, smoothing = 0.0, photon_generation = 0.0, photon_marching = 0.0,
           viewing = 0.0;
    double total() const {
        return voxelisation + smoothing + photon_generation + photon_marching + viewing;
    }
};

struct MediaMethodResult {
    Image volume;  // the `volume` frame term: single scattering before the first surface
    MediaMethodTiming timing;
    glm::ivec3 grid{0};
    size_t photons_marched = 0;  // photons of the plane that meet the grid
    MediaGrid grids;             // n (smoothed), σ_s, σ_t, for slice views
    std::vector<float> fluence;  // per voxel, as deposited
};

// The grid covers the scene's media boxes and glass objects; light comes from the first enabled
// point or spot light (spot cones ignored), else the first quad light. Needs a current GL
// context. Throws std::invalid_argument naming scene.path where the scene has no media or glass,
// or no such light.
MediaMethodResult render_media(const Scene& scene, const MediaMethodSettings& settings);

}  // namespace ag
