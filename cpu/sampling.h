// Sampling and scattering pieces shared by every CPU tracer (photons, caustic photons, the CPU
// gather, the reference renderers): directions from uniform numbers and the specular bounce.
#pragma once

#include <glm/glm.hpp>

#include "cpu/ray_tracer.h"
#include "shared/scene.h"

namespace ag::cpu {

// Orthonormal basis (t, b) around unit n (Duff et al. 2017).
void orthonormal_basis(const glm::vec3& n, glm::vec3& t, glm::vec3& b);
// Cosine-weighted direction about unit n (Larsen ch. 6.3: φ = 2π u1, cos θ = √(1 − u2)).
glm::vec3 cosine_direction(const glm::vec3& n, float u1, float u2);
// Uniform direction on the unit sphere.
glm::vec3 sphere_direction(float u1, float u2);
// Uniform in the cone of directions within angle acos(cos_max) of the unit `axis`.
glm::vec3 cone_direction(const glm::vec3& axis, float cos_max, float u1, float u2);
// Unpolarised Fresnel reflectance of a dielectric; cos_i > 0, eta = n_i / n_t; sets cos_t.
float fresnel_dielectric(float cos_i, float eta, float& cos_t);
// A mirror reflects; glass reflects with the Fresnel probability (u < F) and refracts otherwise.
// Neither absorbs (albedo is unused). Returns the continuing ray, offset by `epsilon`.
Ray specular_bounce(const Material& material, const RayHit& hit, const glm::vec3& direction,
                    float u, float epsilon);

}  // namespace ag::cpu
