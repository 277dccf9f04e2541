#include "shared/media.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "shared/qmc.h"

namespace ag {

namespace {

// Perlin 2002: the 12 edge gradients of a cube (16 slots, four repeated), picked by a hash of
// the lattice point (a hash instead of the permutation table, so any seed costs nothing).
float gradient(uint32_t h, float x, float y, float z) {
    const uint32_t g = h & 15u;
    const float u = g < 8u ? x : y;
    const float v = g < 4u ? y : (g == 12u || g == 14u ? x : z);
    return ((g & 1u) ? -u : u) + ((g & 2u) ? -v : v);
}

float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

uint32_t lattice_hash(int64_t x, int64_t y, int64_t z, uint32_t seed) {
    return hash_u32(uint32_t(x) * 73856093u ^
                    hash_u32(uint32_t(y) * 19349663u ^ hash_u32(uint32_t(z) * 83492791u ^ seed)));
}

}  // namespace

float perlin_noise(const glm::vec3& p, uint32_t seed) {
    const glm::vec3 f = glm::floor(p);
    // 64-bit: frequency × position may pass 2^31 (|p| ≤ 10^7, frequency ≤ 10^6).
    const int64_t x = int64_t(f.x), y = int64_t(f.y), z = int64_t(f.z);
    const glm::vec3 r = p - f;
    const float u = fade(r.x), v = fade(r.y), w = fade(r.z);
    float corner[8];
    for (int i = 0; i < 8; ++i) {
        const int64_t dx = i & 1, dy = (i >> 1) & 1, dz = (i >> 2) & 1;
        corner[i] = gradient(lattice_hash(x + dx, y + dy, z + dz, seed), r.x - float(dx),
                             r.y - float(dy), r.z - float(dz));
    }
    const auto lerp = [](float a, float b, float t) { return a + t * (b - a); };
    const float x00 = lerp(corner[0], corner[1], u), x10 = lerp(corner[2], corner[3], u);
    const float x01 = lerp(corner[4], corner[5], u), x11 = lerp(corner[6], corner[7], u);
    // The 3D improved noise stays within about ±1.04; clamp so density stays ≥ 0 exactly.
    return std::clamp(lerp(lerp(x00, x10, v), lerp(x01, x11, v), w), -1.0f, 1.0f);
}

float Medium::density(const glm::vec3& p) const {
    if (!noise.active()) return 1.0f;
    return 1.0f + noise.amplitude * perlin_noise(noise.frequency * p, noise.seed);
}

float schlick_phase(float cos_theta, float k) {
    const float d = 1.0f - k * cos_theta;
    return (1.0f - k * k) / (4.0f * std::numbers::pi_v<float> * d * d);
}

glm::vec3 sample_schlick(const glm::vec3& forward, float k, float u1, float u2) {
    // Inverse of the CDF over cosθ: F(c) = (1 − k²)/(2k) · (1/(1 − kc) − 1/(1 + k)).
    float c = std::abs(k) < 1e-4f ? 2.0f * u1 - 1.0f
                                  : (2.0f * u1 + k - 1.0f) / (2.0f * k * u1 + 1.0f - k);
    c = std::clamp(c, -1.0f, 1.0f);
    const float s = std::sqrt(std::max(0.0f, 1.0f - c * c));
    const float phi = 2.0f * std::numbers::pi_v<float> * u2;
    // Orthonormal basis (Duff et al. 2017) around `forward`.
    const float sign = std::copysign(1.0f, forward.z);
    const float a = -1.0f / (sign + forward.z), b = forward.x * forward.y * a;
    const glm::vec3 t(1.0f + sign * forward.x * forward.x * a, sign * b, -sign * forward.x);
    const glm::vec3 bt(b, sign + forward.y * forward.y * a, -forward.y);
    return glm::normalize(s * std::cos(phi) * t + s * std::sin(phi) * bt + c * forward);
}

double schlick_mean_cosine(double k) {
    if (std::abs(k) < 1e-3) return 2.0 * k / 3.0;
    return (2.0 * k + (1.0 - k * k) * std::log((1.0 - k) / (1.0 + k))) / (2.0 * k * k);
}

double schlick_k_for_mean_cosine(double g) {
    // g(k) rises monotonically from −1 to 1 over k ∈ (−1, 1).
    double lo = -1.0 + 1e-15, hi = 1.0 - 1e-15;
    for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (schlick_mean_cosine(mid) < g ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

std::vector<float> schlick_spread_table(float k, int entries) {
    std::vector<float> table(size_t(std::max(entries, 2)));
    const double g = schlick_mean_cosine(k);
    for (size_t i = 0; i < table.size(); ++i) {
        const double s = double(i) / double(table.size() - 1);
        table[i] = i == 0 ? k : float(schlick_k_for_mean_cosine((1.0 - s * s) * g));
    }
    return table;
}

bool ray_box(const Bounds& b, const glm::vec3& o, const glm::vec3& d, float t0, float t1,
             float& enter, float& exit) {
    for (int a = 0; a < 3; ++a) {
        const float inv = 1.0f / d[a];
        float near = (b.min[a] - o[a]) * inv, far = (b.max[a] - o[a]) * inv;
        if (near > far) std::swap(near, far);
        if (std::isnan(near) || std::isnan(far)) {  // parallel, exactly on a slab face
            if (o[a] < b.min[a] || o[a] > b.max[a]) return false;
            continue;
        }
        t0 = std::max(t0, near);
        t1 = std::min(t1, far);
        if (t0 > t1) return false;
    }
    enter = t0;
    exit = t1;
    return t1 > t0;
}

float mean_media_transmittance(const std::vector<Medium>& media, const glm::vec3& o,
                               const glm::vec3& d, float t_max) {
    float depth = 0.0f;
    for (const Medium& m : media) {
        float enter = 0.0f, exit = 0.0f;
        if (ray_box(m.bounds, o, d, 0.0f, t_max, enter, exit))
            depth += m.sigma_t() * std::max(exit - enter, 0.0f);
    }
    return std::exp(-depth);
}

}  // namespace ag
