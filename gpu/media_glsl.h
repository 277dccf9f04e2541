// The world's media boxes in GLSL, shared by the frame's direct light and the GL gather: their
// bounds and mean σ_t as uniforms (at most kMaxMediaBoxes; the FrameRenderer refuses scenes with
// more) and Beer–Lambert along a ray through them.
#pragma once

#define AG_GLSL_MEDIA_BOXES 8
#define AG_GLSL_STRINGIFY_(x) #x
#define AG_GLSL_STRINGIFY(x) AG_GLSL_STRINGIFY_(x)

namespace ag::gpu {

inline constexpr int kMaxMediaBoxes = AG_GLSL_MEDIA_BOXES;

inline constexpr const char* kMediaTransmittanceGlsl =
    "const int kMaxMediaBoxes = " AG_GLSL_STRINGIFY(AG_GLSL_MEDIA_BOXES) R"(;
uniform int media_count;
uniform vec3 media_min[kMaxMediaBoxes];
uniform vec3 media_max[kMaxMediaBoxes];
uniform float media_sigma_t[kMaxMediaBoxes];  // σ_s + σ_a, the mean density (noise left out)
// Beer–Lambert from p along unit l up to distance t_max through the world's media boxes
// (disjoint, so the optical depths add): what pt's shadow rays see, in closed form.
float media_transmittance(vec3 p, vec3 l, float t_max) {
    float depth = 0.0;
    for (int m = 0; m < media_count; ++m) {
        vec3 inv = 1.0 / l;
        vec3 ta = (media_min[m] - p) * inv, tb = (media_max[m] - p) * inv;
        vec3 lo = min(ta, tb), hi = max(ta, tb);
        float t0 = max(max(lo.x, lo.y), max(lo.z, 0.0));
        float t1 = min(min(hi.x, hi.y), min(hi.z, t_max));
        depth += media_sigma_t[m] * max(t1 - t0, 0.0);
    }
    return exp(-depth);
}
)";

}  // namespace ag::gpu
