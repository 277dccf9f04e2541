// Sampling and scattering pieces shared by every CPU tracer (photons, caustic photons, the CPU
// gather, the reference renderers): QMC samplers and hashed numbers, directions from uniform
// numbers (Larsen ch. 6.3) and the specular bounce.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>

#include "cpu/ray_tracer.h"
#include "shared/qmc.h"
#include "shared/scene.h"

namespace ag::cpu {

// Number `dim` of sample `index` of a sequence: a scrambled Halton point with a Cranley–Patterson
// rotation drawn from `key` (one key per pixel or light), hashed numbers past the Halton's
// dimensions. A pure function of (halton, key, index, dim).
class Sampler {
public:
    Sampler(const Halton& halton, uint64_t key, uint64_t index)
        : halton_(halton), key_(key), index_(index) {}
    float get(int dim) const;
    uint64_t key() const { return key_; }
    uint64_t index() const { return index_; }

private:
    const Halton& halton_;
    uint64_t key_, index_;
};

uint64_t mix64(uint64_t x);                       // SplitMix64 finaliser
float hashed_uniform(uint64_t a, uint64_t b);     // [0, 1) from two words
uint64_t pixel_key(uint32_t seed, int x, int y);  // a pixel's Sampler key

// A hash to [0, 1): its top 24 bits, so every float is exact and 1 is never reached.
inline float to_unit_float(uint32_t h) { return float(h >> 8) * (1.0f / 16777216.0f); }
inline float to_unit_float(uint64_t h) { return float(h >> 40) * (1.0f / 16777216.0f); }

// Shirley–Chiu concentric map between the unit square and the cosine-weighted hemisphere about
// +z (area-preserving, so uniform squares give cosine-weighted directions, and compact regions of
// the hemisphere stay compact in the square: QMC strata stay strata, and a histogram over the
// square can guide final-gather rays).
glm::vec3 square_to_cosine_hemisphere(const glm::vec2& u);
glm::vec2 cosine_hemisphere_to_square(const glm::vec3& d);  // d.z ≥ 0; inverse of the above

// Orthonormal basis (t, b) around unit n (Duff et al. 2017).
void orthonormal_basis(const glm::vec3& n, glm::vec3& t, glm::vec3& b);
// Cosine-weighted direction about unit n (Larsen ch. 6.3: φ = 2π u1, cos θ = √(1 − u2)).
glm::vec3 cosine_direction(const glm::vec3& n, float u1, float u2);
// Uniform direction on the unit sphere.
glm::vec3 sphere_direction(float u1, float u2);
// Uniform in the cone of directions within angle acos(cos_max) of the unit `axis`.
glm::vec3 cone_direction(const glm::vec3& axis, float cos_max, float u1, float u2);
// A photon's emission from `light` (Larsen ch. 6.3): `u` picks the direction (point: the sphere;
// spot: uniform in its outer cone; quad, mesh: cosine around the normal; sun: its direction),
// `v` the origin (quad, mesh: a point by area; sun: a point of its disc). `weight` scales the
// light's mean photon flux Φ/N for this photon (a spot's falloff over its cone); 1 otherwise.
struct EmissionRay {
    Ray ray;
    float weight = 1.0f;
};
EmissionRay emission_ray(const Scene& scene, const Light& light, const glm::vec2& u,
                         const glm::vec2& v, float epsilon);
// Unpolarised Fresnel reflectance of a dielectric; cos_i > 0, eta = n_i / n_t; sets cos_t.
float fresnel_dielectric(float cos_i, float eta, float& cos_t);
// Both continuations of a specular bounce, for estimators that follow each with its weight
// rather than choosing one: `reflected` carries `reflectance` (F; 1 for mirrors and total
// internal reflection), `refracted` carries 1 − F (glass only). Rays offset by `epsilon`.
struct SpecularSplit {
    Ray reflected, refracted;
    float reflectance = 1.0f;
};
SpecularSplit specular_split(const Material& material, const RayHit& hit,
                             const glm::vec3& direction, float epsilon);
// A mirror reflects; glass reflects with the Fresnel probability (u < F) and refracts otherwise.
// Neither absorbs (albedo is unused). Returns the continuing ray, offset by `epsilon`.
Ray specular_bounce(const Material& material, const RayHit& hit, const glm::vec3& direction,
                    float u, float epsilon);

}  // namespace ag::cpu
