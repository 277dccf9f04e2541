#include "cpu/sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ag::cpu {

namespace {
constexpr float kOneBelowOne = 0x1.fffffep-1f;
}  // namespace

glm::vec3 square_to_cosine_hemisphere(const glm::vec2& u) {
    const float a = 2.0f * u.x - 1.0f, b = 2.0f * u.y - 1.0f;
    if (a == 0.0f && b == 0.0f) return {0.0f, 0.0f, 1.0f};
    float r, phi;
    if (std::abs(a) > std::abs(b)) {
        r = a;
        phi = 0.25f * std::numbers::pi_v<float> * (b / a);
    } else {
        r = b;
        phi = 0.5f * std::numbers::pi_v<float> - 0.25f * std::numbers::pi_v<float> * (a / b);
    }
    const float x = r * std::cos(phi), y = r * std::sin(phi);
    return {x, y, std::sqrt(std::max(0.0f, 1.0f - (x * x + y * y)))};
}

glm::vec2 cosine_hemisphere_to_square(const glm::vec3& d) {
    const float r = std::sqrt(d.x * d.x + d.y * d.y);
    if (r == 0.0f) return {0.5f, 0.5f};
    float phi = std::atan2(d.y, d.x);  // (−π, π], folded to [−π/4, 7π/4)
    if (phi < -0.25f * std::numbers::pi_v<float>) phi += 2.0f * std::numbers::pi_v<float>;
    float a, b;
    if (phi < 0.25f * std::numbers::pi_v<float>) {
        a = r;
        b = phi * (4.0f / std::numbers::pi_v<float>)*a;
    } else if (phi < 0.75f * std::numbers::pi_v<float>) {
        b = r;
        a = (0.5f * std::numbers::pi_v<float> - phi) * (4.0f / std::numbers::pi_v<float>)*b;
    } else if (phi < 1.25f * std::numbers::pi_v<float>) {
        a = -r;
        b = (phi - std::numbers::pi_v<float>)*(4.0f / std::numbers::pi_v<float>)*a;
    } else {
        b = -r;
        a = (1.5f * std::numbers::pi_v<float> - phi) * (4.0f / std::numbers::pi_v<float>)*b;
    }
    return glm::clamp(0.5f * glm::vec2(a + 1.0f, b + 1.0f), glm::vec2(0.0f),
                      glm::vec2(kOneBelowOne));
}

uint64_t mix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

float hashed_uniform(uint64_t a, uint64_t b) { return to_unit_float(mix64(mix64(a) ^ b)); }

uint64_t pixel_key(uint32_t seed, int x, int y) {
    return mix64(mix64(seed) ^ ((uint64_t(uint32_t(y)) << 32) | uint64_t(uint32_t(x))));
}

float Sampler::get(int dim) const {
    const uint64_t h = mix64(key_ ^ mix64(uint64_t(dim) + 0x632be59bd9b4e019ull));
    if (dim < halton_.dimensions()) {
        // Cranley–Patterson rotation: every pixel gets its own shifted copy of the sequence.
        double u = halton_.sample(index_, dim) + double(h >> 11) * 0x1.0p-53;
        if (u >= 1.0) u -= 1.0;
        return std::min(float(u), kOneBelowOne);
    }
    return to_unit_float(mix64(h ^ mix64(index_)));
}

void orthonormal_basis(const glm::vec3& n, glm::vec3& t, glm::vec3& b) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float c = n.x * n.y * a;
    t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = glm::vec3(c, sign + n.y * n.y * a, -n.y);
}

glm::vec3 cosine_direction(const glm::vec3& n, float u1, float u2) {
    glm::vec3 t, b;
    orthonormal_basis(n, t, b);
    const float phi = 2.0f * std::numbers::pi_v<float> * u1, r = std::sqrt(u2);
    const float z = std::sqrt(std::max(0.0f, 1.0f - u2));
    return glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + z * n);
}

glm::vec3 sphere_direction(float u1, float u2) {
    const float z = 1.0f - 2.0f * u1, phi = 2.0f * std::numbers::pi_v<float> * u2;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

glm::vec3 cone_direction(const glm::vec3& axis, float cos_max, float u1, float u2) {
    glm::vec3 t, b;
    orthonormal_basis(axis, t, b);
    const float z = 1.0f - u1 * (1.0f - cos_max), phi = 2.0f * std::numbers::pi_v<float> * u2;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + z * axis);
}

float fresnel_dielectric(float cos_i, float eta, float& cos_t) {
    const float sin2_t = eta * eta * std::max(0.0f, 1.0f - cos_i * cos_i);
    if (sin2_t >= 1.0f) {
        cos_t = 0.0f;
        return 1.0f;  // total internal reflection
    }
    cos_t = std::sqrt(1.0f - sin2_t);
    const float rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    const float rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5f * (rs * rs + rp * rp);
}

SpecularSplit specular_split(const Material& material, const RayHit& hit,
                             const glm::vec3& direction, float epsilon) {
    const glm::vec3 d = glm::normalize(direction);
    const bool front = glm::dot(d, hit.normal) < 0.0f;
    const glm::vec3 facing = front ? hit.normal : -hit.normal;  // towards the incoming side
    SpecularSplit out;
    out.reflected.origin = hit.position + epsilon * facing;
    out.reflected.direction = glm::reflect(d, facing);
    if (material.type == MaterialType::glass) {
        const float eta = front ? 1.0f / material.ior : material.ior;
        const float cos_i = -glm::dot(d, facing);
        float cos_t = 0.0f;
        out.reflectance = fresnel_dielectric(cos_i, eta, cos_t);
        if (out.reflectance < 1.0f) {
            out.refracted.origin = hit.position - epsilon * facing;
            out.refracted.direction = glm::normalize(eta * d + (eta * cos_i - cos_t) * facing);
        }
    }
    return out;
}

Ray specular_bounce(const Material& material, const RayHit& hit, const glm::vec3& direction,
                    float u, float epsilon) {
    const SpecularSplit split = specular_split(material, hit, direction, epsilon);
    return u >= split.reflectance ? split.refracted : split.reflected;
}

EmissionRay emission_ray(const Scene& scene, const Light& light, const glm::vec2& u,
                         const glm::vec2& v, float epsilon) {
    EmissionRay out;
    switch (light.type) {
        case LightType::point:
            out.ray = {light.position, sphere_direction(u.x, u.y)};
            break;
        case LightType::spot: {
            // Uniform in the outer cone (solid angle 2π(1 − cos_o)); the weight turns the mean
            // flux Φ/N into I·f(θ)·Ω_o/N (Light::power).
            const float co = light.cos_outer(), ci = light.cos_inner();
            out.ray = {light.position, cone_direction(light.direction, co, u.x, u.y)};
            const float mean = (1.0f - ci) + 0.5f * (ci - co);
            out.weight = mean > 0.0f
                             ? light.spot_factor(glm::dot(out.ray.direction, light.direction)) *
                                   (1.0f - co) / mean
                             : 0.0f;
            break;
        }
        case LightType::sun: {
            // A disc of the scene's bounding sphere, facing the sun, just outside the sphere.
            glm::vec3 t, b;
            orthonormal_basis(light.direction, t, b);
            const glm::vec3 d = square_to_cosine_hemisphere(v);  // (x, y): uniform in the disc
            out.ray = {
                light.sun_center + light.sun_radius * (d.x * t + d.y * b - 1.01f * light.direction),
                light.direction};
            break;
        }
        case LightType::quad:
        case LightType::mesh: {
            const LightPoint at = sample_area_light(scene, light, v.x, v.y);
            out.ray = {at.position + epsilon * at.normal, cosine_direction(at.normal, u.x, u.y)};
            break;
        }
    }
    return out;
}

}  // namespace ag::cpu
