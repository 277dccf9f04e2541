// The viewing pass of Pfeuti 2009 (ch. 3.1.6): one invocation per pixel marches the camera ray
// through the grids, bending it by the smoothed index (eqs. 2.10/2.11), and sums single
// scattering: T · σ_s · p_Schlick(mean photon direction, towards the camera) · fluence, the phase
// broadened by the spread of the photons' directions (ours).
#pragma once

#include <vector>

#include "gpu/gl_objects.h"
#include "shared/camera.h"
#include "shared/image.h"
#include "shared/media_grid.h"

namespace ag::gpu {

struct MediaViewSettings {
    float step = 0.5f;     // in voxels (the smallest edge)
    float phase_k = 0.0f;  // Schlick k of the medium
    // Ours, not his: the phase is broadened by the spread of the photons' directions in the
    // voxel (schlick_spread_table, with R = |flow| / fluence), so that light arriving from many
    // directions (bounced from surfaces, crossing in a caustic, around a light inside the grid)
    // is not all taken to come along its mean direction. False: his p(mean direction).
    bool phase_spread = true;
};

// One ray of the view march. The radiance scattered towards `origin` counts from `split` (world
// distance along the ray) on; the march ends at `max_distance`, where the ray leaves the grid, or,
// with `n_leave` > 0, where the ray, having reached that index (the glass), is back in air.
struct MediaViewRay {
    glm::vec3 origin{0.0f};
    glm::vec3 direction{0.0f, 0.0f, 1.0f};  // unit
    float max_distance = 1e30f;
    float split = 0.0f;
    float n_leave = 0.0f;
};

// Where a ray's march ended and what it gathered on the way.
struct MediaViewEnd {
    glm::vec3 radiance{0.0f};    // single scattering from `split` on, attenuated to the origin
    float transmittance = 1.0f;  // from the origin to the end
    glm::vec3 position{0.0f};
    glm::vec3 direction{0.0f};  // unit: the bent ray's direction of travel there
    bool ended = false;         // left the glass or the grid (false: max_distance, or never in)
};

class MediaView {
public:
    MediaView();
    // Radiance scattered towards the camera by the media of `grid` lit by the deposits
    // (`fluence`, `flow`: a MediaMarcher's result), per pixel of `camera`, up to `max_distance`
    // along each pixel's centre ray (the first surface; empty = none).
    Image render(const MediaGrid& grid, const std::vector<float>& fluence,
                 const std::vector<glm::vec3>& flow, const Camera& camera,
                 const MediaViewSettings& settings,
                 const std::vector<float>& max_distance = {}) const;
    // The same march for any rays.
    std::vector<MediaViewEnd> march(const MediaGrid& grid, const std::vector<float>& fluence,
                                    const std::vector<glm::vec3>& flow,
                                    const std::vector<MediaViewRay>& rays,
                                    const MediaViewSettings& settings) const;

private:
    Program program_;
};

}  // namespace ag::gpu
