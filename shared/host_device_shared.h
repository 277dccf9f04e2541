// Constants valid both as C++ and as GLSL (Falcor's HostDeviceShared idea, STYLE.md): the list is
// written once, in AG_HOST_DEVICE_SHARED; C++ compiles it inside namespace ag and gpu::Program
// prepends the same text (kHostDeviceSharedGlsl) to every shader, so the sides cannot drift.
#pragma once

// Every entry must read the same in both languages: `const int kName = value;` only (comments
// are stripped by the preprocessor before the list is turned into shader text).
#define AG_HOST_DEVICE_SHARED                                                              \
    /* Point-light samples the GPU frame shades; a quad light counts as its n x n grid. */ \
    /* Scenes needing more are rejected on load (check_light_samples, shared/scene.h). */  \
    const int kMaxLightSamples = 64;                                                       \
    /* MaterialType values: the frame shaders' `material` uniform. */                      \
    const int kMaterialDiffuse = 0;                                                        \
    const int kMaterialMirror = 1;                                                         \
    const int kMaterialGlass = 2;                                                          \
    /* FrameTerm values (Larsen eq. 13.2): each term's image index and fragment output. */ \
    const int kFrameTermDirect = 0;                                                        \
    const int kFrameTermIndirect = 1;                                                      \
    const int kFrameTermCaustics = 2;                                                      \
    const int kFrameTermSpecular = 3;                                                      \
    const int kFrameTermVolume = 4;                                                        \
    const int kFrameTermCount = 5;                                                         \
    /* Width of the viewer's surface-id texture (one texel per triangle, row by row). */   \
    const int kIdTextureWidth = 4096;

namespace ag {

AG_HOST_DEVICE_SHARED

#define AG_HOST_DEVICE_STRINGIFY_(...) #__VA_ARGS__
#define AG_HOST_DEVICE_STRINGIFY(...) AG_HOST_DEVICE_STRINGIFY_(__VA_ARGS__)

// The same constants as GLSL source, for gpu::Program to put after `#version`.
inline constexpr const char* kHostDeviceSharedGlsl =
    AG_HOST_DEVICE_STRINGIFY(AG_HOST_DEVICE_SHARED);

}  // namespace ag
