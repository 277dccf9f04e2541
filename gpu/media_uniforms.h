// The uniforms kMediaTransmittanceGlsl reads (gpu/media_glsl.h), set from the scene's media
// boxes: one function for every program that dims light by the media (the frame's direct
// light, the GL gather, gpu_pm's photon trace).
#pragma once

#include "gpu/gl_objects.h"
#include "shared/scene.h"

namespace ag::gpu {

// Sets media_count, media_min, media_max and media_sigma_t on `program` (in use) from the
// first kMaxMediaBoxes of scene.media (the FrameRenderer refuses scenes with more).
void set_media_uniforms(const Program& program, const Scene& scene);

}  // namespace ag::gpu
