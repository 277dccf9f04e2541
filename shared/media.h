// Participating media (Pfeuti 2009, ch. 2.2–2.3): grey homogeneous or Perlin-perturbed media in
// world boxes or inside glass objects, the Schlick phase function, and the Perlin noise that
// perturbs a medium's density and a glass object's refractive index. Plain data shared by the
// CPU references and the GPU method.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "shared/mesh.h"

namespace ag {

// Perlin perturbation: value(p) = amplitude · perlin(frequency · p), perlin ∈ [-1, 1]
// (Perlin 2002, a gradient noise with its permutation drawn from `seed`). amplitude 0 = none.
struct MediumNoise {
    float amplitude = 0.0f;
    float frequency = 1.0f;  // lattice cells per scene unit
    uint32_t seed = 1;
    bool active() const { return amplitude > 0.0f; }
};

// Improved Perlin noise (Perlin 2002) in [-1, 1] at `p`, its permutation table drawn from `seed`.
float perlin_noise(const glm::vec3& p, uint32_t seed);

// A grey medium: scattering σ_s and absorption σ_a per scene unit, scaled at each point by the
// density 1 + noise(p) (≥ 0 because amplitude ≤ 1); Schlick phase with parameter k. `bounds` is
// the world box of a scene medium (unused for a glass object's interior, which its mesh bounds).
struct Medium {
    Bounds bounds;
    float sigma_s = 0.0f;
    float sigma_a = 0.0f;
    float phase_k = 0.0f;  // Schlick k ∈ (-1, 1): > 0 forward, < 0 backward, 0 isotropic
    MediumNoise noise;

    float sigma_t() const { return sigma_s + sigma_a; }
    float albedo() const { return sigma_t() > 0.0f ? sigma_s / sigma_t() : 0.0f; }
    bool homogeneous() const { return !noise.active(); }
    float density(const glm::vec3& p) const;
    // A bound on σ_t over the medium: the majorant of delta tracking.
    float majorant() const { return sigma_t() * (1.0f + noise.amplitude); }
};

// Schlick's phase function (Blasi et al. 1993): p(θ) = (1 − k²) / (4π (1 − k cosθ)²), θ between the
// directions of travel before and after scattering (cosθ = 1: straight on). Integrates to 1.
float schlick_phase(float cos_theta, float k);
// A direction distributed by schlick_phase about the direction of travel `forward` (unit), from
// uniform (u1, u2); its pdf is schlick_phase of the returned direction.
glm::vec3 sample_schlick(const glm::vec3& forward, float k, float u1, float u2);
// The mean cosine g of schlick_phase: (2k + (1 − k²) ln((1 − k)/(1 + k))) / (2k²), odd in k,
// 2k/3 for small k, 0.9934 at k = 0.999.
double schlick_mean_cosine(double k);
// The k whose schlick_phase has mean cosine g (|g| < 1), by bisection.
double schlick_k_for_mean_cosine(double g);
// The phase seen by light whose directions spread about their mean with mean resultant length
// R ∈ [0, 1] (R = |Σ power × direction| / Σ power; 1: one direction, 0: light from all sides
// alike): Schlick with the k whose mean cosine is R × that of `k`. For Henyey–Greenstein lobes this
// is exact (zonal convolution multiplies the Legendre coefficients g^l, so HG(g₁) ⊛ HG(g₂) =
// HG(g₁g₂)); for Schlick it keeps the mean cosine and both limits exact. Tabulated at
// R = 1 − s², s = i / (entries − 1): entry 0 is `k` itself, the last 0 (isotropic); the steps in s
// resolve R near 1, where a forward k changes fastest.
std::vector<float> schlick_spread_table(float k, int entries);

// The entry and exit distances of ray o + t·d (t ∈ [t0, t1]) in box b; false if it misses.
bool ray_box(const Bounds& b, const glm::vec3& o, const glm::vec3& d, float t0, float t1,
             float& enter, float& exit);

// Beer–Lambert along o + t·d (unit d), t ∈ [0, t_max], through the media boxes at their mean
// density (the noise left out): exp(−Σ σ_t · chord), as the frame's lighting shader and the GL
// gather compute it. 1 without media.
float mean_media_transmittance(const std::vector<Medium>& media, const glm::vec3& o,
                               const glm::vec3& d, float t_max);

}  // namespace ag
