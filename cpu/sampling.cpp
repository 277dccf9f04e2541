#include "cpu/sampling.h"

#include <algorithm>
#include <cmath>

namespace ag::cpu {

namespace {
constexpr float kPi = 3.14159265358979f;
}  // namespace

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
    const float phi = 2.0f * kPi * u1, r = std::sqrt(u2);
    const float z = std::sqrt(std::max(0.0f, 1.0f - u2));
    return glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + z * n);
}

glm::vec3 sphere_direction(float u1, float u2) {
    const float z = 1.0f - 2.0f * u1, phi = 2.0f * kPi * u2;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

glm::vec3 cone_direction(const glm::vec3& axis, float cos_max, float u1, float u2) {
    glm::vec3 t, b;
    orthonormal_basis(axis, t, b);
    const float z = 1.0f - u1 * (1.0f - cos_max), phi = 2.0f * kPi * u2;
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

Ray specular_bounce(const Material& material, const RayHit& hit, const glm::vec3& direction,
                    float u, float epsilon) {
    const glm::vec3 d = glm::normalize(direction);
    const bool front = glm::dot(d, hit.normal) < 0.0f;
    const glm::vec3 facing = front ? hit.normal : -hit.normal;  // towards the incoming side
    Ray out;
    if (material.type == MaterialType::glass) {
        const float eta = front ? 1.0f / material.ior : material.ior;
        const float cos_i = -glm::dot(d, facing);
        float cos_t = 0.0f;
        if (u >= fresnel_dielectric(cos_i, eta, cos_t)) {
            out.origin = hit.position - epsilon * facing;
            out.direction = glm::normalize(eta * d + (eta * cos_i - cos_t) * facing);
            return out;
        }
    }
    out.origin = hit.position + epsilon * facing;
    out.direction = glm::reflect(d, facing);
    return out;
}

}  // namespace ag::cpu
