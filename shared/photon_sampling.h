// The sampling of GPU photon mapping (Jimenez Kwast 2016 §5.3): TEA random numbers (Listings
// 5.3/5.4/5.7), Hammersley points (Listing 5.6, without its 20-bit mask), uniform sphere points
// (eq. 5.1/5.2), cosine directions (eq. 5.3/5.4), octahedral directions (Listing 5.9) and the cone
// filter (eq. 5.5/5.6). Written once, valid as C++ and as GLSL (like host_device_shared.h): C++
// compiles AG_PHOTON_SAMPLING(inline) in namespace ag::photon; kPhotonSamplingGlsl is the same
// text for compute shaders to prepend.
#pragma once

#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>

// FN: `inline` for C++, nothing for GLSL. Only syntax both languages share: no references, no
// `inout`, functional casts, unsigned literals with `u`.
#define AG_PHOTON_SAMPLING(FN)                                                                          \
    const float kPhotonPi = 3.14159265358979f;                                                          \
    /* Kwast's TEA key (Zafar et al.): with 32 rounds this is TEA encryption of v under it. */          \
    FN uvec2 tea_key(uvec2 v, uvec4 key, int rounds) {                                                  \
        uint sum = 0u;                                                                                  \
        for (int i = 0; i < rounds; ++i) {                                                              \
            sum += 0x9E3779B9u;                                                                         \
            v.x += ((v.y << 4u) + key.x) ^ (v.y + sum) ^ ((v.y >> 5u) + key.y);                         \
            v.y += ((v.x << 4u) + key.z) ^ (v.x + sum) ^ ((v.x >> 5u) + key.w);                         \
        }                                                                                               \
        return v;                                                                                       \
    }                                                                                                   \
    FN uvec2 tea(uvec2 v, int rounds) {                                                                 \
        return tea_key(v, uvec4(0xA341316Cu, 0xC8013EA4u, 0xAD90777Du, 0x7E95761Eu), rounds);           \
    }                                                                                                   \
    /* Listing 5.7: a path's seed from its index, 16 rounds. */                                         \
    FN uvec2 tea_seed(uint index, uint stream) {                                                        \
        return tea(uvec2(index, index * 1664525u + stream), 16);                                        \
    }                                                                                                   \
    /* Listing 5.4: the next seed (8 rounds); its two words as 24-bit numbers in [0, 1). */             \
    FN uvec2 tea_next(uvec2 seed) { return tea(seed, 8); }                                              \
    FN vec2 tea_unit(uvec2 seed) {                                                                      \
        return vec2(float(seed.x & 0xFFFFFFu), float(seed.y & 0xFFFFFFu)) / 16777216.0f;                \
    }                                                                                                   \
    /* Φ_2(i), the base-2 radical inverse, to 24 bits (every float of it is exact). */                 \
    FN float radical_inverse_2(uint i) {                                                                \
        i = (i << 16u) | (i >> 16u);                                                                    \
        i = ((i & 0x00FF00FFu) << 8u) | ((i & 0xFF00FF00u) >> 8u);                                      \
        i = ((i & 0x0F0F0F0Fu) << 4u) | ((i & 0xF0F0F0F0u) >> 4u);                                      \
        i = ((i & 0x33333333u) << 2u) | ((i & 0xCCCCCCCCu) >> 2u);                                      \
        i = ((i & 0x55555555u) << 1u) | ((i & 0xAAAAAAAAu) >> 1u);                                      \
        return float(i >> 8u) / 16777216.0f;                                                            \
    }                                                                                                   \
    FN vec2 hammersley(uint i, uint n) { return vec2(float(i) / float(n), radical_inverse_2(i)); }      \
    /* Eq. 5.1/5.2: θ = 2πξ1, φ = arccos(2ξ2 − 1), a uniform point on the unit sphere. */        \
    FN vec3 uniform_sphere(vec2 u) {                                                                    \
        float z = 2.0f * u.y - 1.0f, s = sqrt(max(0.0f, 1.0f - z * z)),                                 \
              a = 2.0f * kPhotonPi * u.x;                                                               \
        return vec3(s * cos(a), s * sin(a), z);                                                         \
    }                                                                                                   \
    /* A point on the unit disc, area-uniform (Shirley–Chiu concentric map). */                       \
    FN vec2 concentric_disc(vec2 u) {                                                                   \
        vec2 p = 2.0f * u - 1.0f;                                                                       \
        if (p.x == 0.0f && p.y == 0.0f) return vec2(0.0f);                                              \
        float r = p.y, a = 0.5f * kPhotonPi - 0.25f * kPhotonPi * p.x / p.y;                            \
        if (abs(p.x) > abs(p.y)) {                                                                      \
            r = p.x;                                                                                    \
            a = 0.25f * kPhotonPi * p.y / p.x;                                                          \
        }                                                                                               \
        return r * vec2(cos(a), sin(a));                                                                \
    }                                                                                                   \
    /* A right-handed frame around unit n (Duff et al. 2017); columns t, b, n. */                       \
    FN mat3 frame_around(vec3 n) {                                                                      \
        float s = n.z >= 0.0f ? 1.0f : -1.0f, a = -1.0f / (s + n.z), b = n.x * n.y * a;                 \
        return mat3(vec3(1.0f + s * n.x * n.x * a, s * b, -s * n.x),                                    \
                    vec3(b, s + n.y * n.y * a, -n.y), n);                                               \
    }                                                                                                   \
    /* Eq. 5.3/5.4 (Malley): r = √ξ1, θ = 2πξ2, z = √(1 − ξ1), about n; pdf cos θ / π. */  \
    FN vec3 cosine_direction(vec2 u, vec3 n) {                                                          \
        float r = sqrt(u.x), a = 2.0f * kPhotonPi * u.y;                                                \
        return frame_around(n) * vec3(r * cos(a), r * sin(a), sqrt(max(0.0f, 1.0f - u.x)));             \
    }                                                                                                   \
    /* Listing 5.9: octahedral encoding of a unit vector into [−1, 1]² and back. */                  \
    FN vec2 sign_not_zero(vec2 v) {                                                                     \
        return vec2(v.x >= 0.0f ? 1.0f : -1.0f, v.y >= 0.0f ? 1.0f : -1.0f);                            \
    }                                                                                                   \
    FN vec2 octahedral_encode(vec3 v) {                                                                 \
        vec2 p = vec2(v.x, v.y) / (abs(v.x) + abs(v.y) + abs(v.z));                                     \
        if (v.z <= 0.0f) p = (vec2(1.0f) - abs(vec2(p.y, p.x))) * sign_not_zero(p);                     \
        return p;                                                                                       \
    }                                                                                                   \
    FN vec3 octahedral_decode(vec2 e) {                                                                 \
        vec3 v = vec3(e.x, e.y, 1.0f - abs(e.x) - abs(e.y));                                            \
        if (v.z < 0.0f) {                                                                               \
            vec2 p = (vec2(1.0f) - abs(vec2(v.y, v.x))) * sign_not_zero(vec2(v.x, v.y));                \
            v.x = p.x;                                                                                  \
            v.y = p.y;                                                                                  \
        }                                                                                               \
        return normalize(v);                                                                            \
    }                                                                                                   \
    /* Eq. 5.5: w = 1 − d/(kr) inside r; eq. 5.6's normalisation ∫ w dA = (1 − 2/(3k)) π r². */ \
    FN float cone_weight(float d, float r, float k) { return d < r ? 1.0f - d / (k * r) : 0.0f; }       \
    FN float cone_normalisation(float r, float k) {                                                     \
        return (1.0f - 2.0f / (3.0f * k)) * kPhotonPi * r * r;                                          \
    }

namespace ag::photon {

using uint = uint32_t;
using glm::mat3;
using glm::uvec2;
using glm::uvec4;
using glm::vec2;
using glm::vec3;
using std::abs, std::cos, std::max, std::sin, std::sqrt, glm::abs, glm::normalize;

AG_PHOTON_SAMPLING(inline)

}  // namespace ag::photon

namespace ag {

#define AG_PHOTON_SAMPLING_STRINGIFY_(...) #__VA_ARGS__
#define AG_PHOTON_SAMPLING_STRINGIFY(...) AG_PHOTON_SAMPLING_STRINGIFY_(__VA_ARGS__)

// The same functions as GLSL source, for compute shaders to prepend.
inline constexpr const char* kPhotonSamplingGlsl =
    AG_PHOTON_SAMPLING_STRINGIFY(AG_PHOTON_SAMPLING());

}  // namespace ag
