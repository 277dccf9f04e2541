// The viewing pass of Pfeuti 2009 (ch. 3.1.6): one invocation per pixel marches the camera ray
// through the grids, bending it by the smoothed index (eqs. 2.10/2.11), and sums single
// scattering: T · σ_s · p_Schlick(mean photon direction, towards the camera) · fluence.
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

private:
    Program program_;
};

}  // namespace ag::gpu
