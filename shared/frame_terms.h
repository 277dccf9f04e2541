// The terms of the composed frame, Larsen ch. 13, eq. 13.2:
// L = L_indirect + L_caustics + L_specular + Σ_lights L_direct(i)·shadow(i), plus the light that
// participating media scatter towards the camera (Pfeuti 2009).
// One list for the GPU frame's term images, the reference renderers' components, the CLI and the
// viewer.
#pragma once

#include <array>
#include <optional>
#include <string_view>

#include "shared/host_device_shared.h"

namespace ag {

// direct: emission and the lights' shadowed direct light at the first diffuse point seen;
// indirect: the rest of the light arriving there (IIM × albedo on the GPU); caustics: light that
// reached it through mirrors or glass (L S+ D); specular: whole pixels whose camera ray meets a
// mirror or glass first; volume: light scattered towards the camera by a medium before its ray
// meets any surface (the other terms are seen through the medium, attenuated by its
// transmittance). They add up to the frame.
enum class FrameTerm {
    direct = kFrameTermDirect,
    indirect = kFrameTermIndirect,
    caustics = kFrameTermCaustics,
    specular = kFrameTermSpecular,
    volume = kFrameTermVolume,
};
inline constexpr std::array<FrameTerm, kFrameTermCount> kFrameTerms = {
    FrameTerm::direct, FrameTerm::indirect, FrameTerm::caustics, FrameTerm::specular,
    FrameTerm::volume};
inline constexpr std::array<const char*, kFrameTermCount> kFrameTermNames = {
    "direct", "indirect", "caustics", "specular", "volume"};

inline const char* frame_term_name(FrameTerm t) { return kFrameTermNames[size_t(t)]; }

// The term named `name` (one of kFrameTermNames), or none.
inline std::optional<FrameTerm> parse_frame_term(std::string_view name) {
    for (size_t i = 0; i < kFrameTermNames.size(); ++i)
        if (name == kFrameTermNames[i]) return FrameTerm(i);
    return std::nullopt;
}

}  // namespace ag
