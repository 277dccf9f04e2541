// A virtual point light (Keller 1997; Barczak 2006 §4.1): the plain record the CPU sources
// (cpu/vpl_source.h) make, the CPU shading reads and the GL shadow maps and gather upload.
#pragma once

#include <glm/glm.hpp>

namespace ag {

// Radiant intensity I(ω) = power/π · cos θ towards ω in front of `normal`, so the irradiance at a
// point x with normal n is E = power/π · cos θ_l cos θ_x / d² (Barczak §4.3, times V).
struct Vpl {
    glm::vec3 position{0.0f};  // world space
    glm::vec3 normal{0.0f};    // unit, world space: the side it emits to
    glm::vec3 power{0.0f};     // reflected flux Φ_in · ρ, W
    int light = -1, group = -1;
    int bounce = 0;  // 0: its flux came straight from the light
    bool operator==(const Vpl&) const = default;
};

}  // namespace ag
