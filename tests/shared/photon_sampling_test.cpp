// The sampling of GPU photon mapping (Jimenez Kwast 2016 §5.3) on the CPU: Hammersley exact to
// 24 bits, TEA against published vectors, the cone filter's normalisation by quasi-Monte Carlo,
// cosine directions, octahedral round trips.
#include "shared/photon_sampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "shared/qmc.h"

namespace ag::photon {

TEST(PhotonSampling, HammersleyIsTheRadicalInverseExactTo24Bits) {
    const auto truncated = [](uint32_t i) {
        // Bit by bit: bit j of i lands at 2^−(j+1); keep the first 24 places.
        uint32_t r = 0;
        for (int j = 0; j < 24; ++j) r |= ((i >> j) & 1u) << (23 - j);
        return double(r) / 16777216.0;
    };
    std::mt19937 rng(1);
    for (uint32_t n = 0; n < 200000; ++n) {
        const uint32_t i = n < 100000 ? n : uint32_t(rng());
        ASSERT_EQ(double(radical_inverse_2(i)), truncated(i)) << i;
        ASSERT_EQ(double(radical_inverse_2(i)),
                  std::floor(radical_inverse(2, i) * 16777216.0) / 16777216.0)
            << i;
    }
    EXPECT_EQ(radical_inverse_2(1u << 23), 1.0f / 16777216.0f);  // the 24th place is kept
    EXPECT_EQ(radical_inverse_2(1u << 24), 0.0f);                // the 25th is not
    EXPECT_EQ(hammersley(3, 4), glm::vec2(0.75f, 0.75f));
}

TEST(PhotonSampling, TeaMatchesPublishedVectors) {
    // 32 rounds of the same round function are TEA encryption (Wheeler & Needham 1994).
    EXPECT_EQ(tea_key(uvec2(0u, 0u), uvec4(0u), 32), uvec2(0x41EA3A0Au, 0x94BAA940u));
    EXPECT_EQ(tea_key(uvec2(0x01020304u, 0x05060708u),
                      uvec4(0x00112233u, 0x44556677u, 0x8899AABBu, 0xCCDDEEFFu), 32),
              uvec2(0xDEB1C0A2u, 0x7E745DB3u));
    // Kwast's key and round counts: deterministic, and the 24-bit units are uniform in [0, 1).
    EXPECT_EQ(tea_seed(7, 0), tea(uvec2(7u, 7u * 1664525u), 16));
    double sum = 0.0, sum_sq = 0.0;
    const int n = 100000;
    uvec2 seed = tea_seed(12345, 0);
    for (int i = 0; i < n; ++i) {
        seed = tea_next(seed);
        const vec2 u = tea_unit(seed);
        ASSERT_GE(u.x, 0.0f);
        ASSERT_LT(u.y, 1.0f);
        sum += u.x + u.y;
        sum_sq += u.x * u.x + u.y * u.y;
    }
    EXPECT_NEAR(sum / (2 * n), 0.5, 5 * std::sqrt(1.0 / 12.0 / (2 * n)));
    EXPECT_NEAR(sum_sq / (2 * n), 1.0 / 3.0, 0.005);
}

TEST(PhotonSampling, ConeFilterNormalisationWithinATenthOfAPercent) {
    // ∫ over the disc of radius r of (1 − d/(kr)) = (1 − 2/(3k)) π r² (eq. 5.6), by Hammersley
    // points over the square around the disc.
    const uint32_t n = 1u << 20;
    for (const float k : {1.0f, 1.5f, 3.0f})
        for (const float r : {0.25f, 2.0f}) {
            double sum = 0.0;
            for (uint32_t i = 0; i < n; ++i) {
                const vec2 p = (2.0f * hammersley(i, n) - 1.0f) * r;
                sum += cone_weight(glm::length(p), r, k);
            }
            const double integral = sum / n * double(4.0f * r * r);
            EXPECT_NEAR(integral / cone_normalisation(r, k), 1.0, 1e-3) << "k " << k << " r " << r;
        }
    EXPECT_NEAR(cone_normalisation(1.0f, 1.0f), std::numbers::pi / 3.0, 1e-6);
}

TEST(PhotonSampling, CosineDirectionsHaveMeanCosineTwoThirds) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int t = 0; t < 4; ++t) {
        const vec3 n = t == 0 ? vec3(0, 0, -1) : uniform_sphere(vec2(u(rng), u(rng)));
        double mean = 0.0, mean_x = 0.0;
        const uint32_t count = 1u << 16;
        const mat3 f = frame_around(n);
        for (uint32_t i = 0; i < count; ++i) {
            const vec3 d = cosine_direction(hammersley(i, count), n);
            ASSERT_NEAR(glm::length(d), 1.0f, 1e-5f);
            ASSERT_GE(glm::dot(d, n), -1e-6f);
            mean += glm::dot(d, n);
            mean_x += glm::dot(d, f[0]);
        }
        EXPECT_NEAR(mean / count, 2.0 / 3.0, 1e-3);
        EXPECT_NEAR(mean_x / count, 0.0, 1e-3);
        EXPECT_NEAR(glm::dot(f[0], f[1]), 0.0f, 1e-6f);
        EXPECT_NEAR(glm::dot(glm::cross(f[0], f[1]), n), 1.0f, 1e-5f);
    }
}

TEST(PhotonSampling, UniformSpherePointsAreCentred) {
    glm::dvec3 mean(0.0);
    const uint32_t n = 1u << 16;
    for (uint32_t i = 0; i < n; ++i) {
        const vec3 p = uniform_sphere(hammersley(i, n));
        ASSERT_NEAR(glm::length(p), 1.0f, 1e-5f);
        mean += glm::dvec3(p);
    }
    EXPECT_LT(glm::length(mean / double(n)), 1e-3);
}

TEST(PhotonSampling, OctahedralDirectionsRoundTrip) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<vec3> dirs = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int i = 0; i < 10000; ++i) dirs.push_back(uniform_sphere(vec2(u(rng), u(rng))));
    for (const vec3& d : dirs) {
        const vec2 e = octahedral_encode(d);
        ASSERT_LE(std::abs(e.x), 1.0f);
        ASSERT_LE(std::abs(e.y), 1.0f);
        ASSERT_NEAR(glm::length(octahedral_decode(e) - d), 0.0f, 1e-5f)
            << d.x << " " << d.y << " " << d.z;
    }
}

TEST(PhotonSampling, ConcentricDiscIsAreaUniform) {
    const uint32_t n = 1u << 16;
    int inner = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const vec2 p = concentric_disc(hammersley(i, n));
        ASSERT_LE(glm::length(p), 1.0f + 1e-6f);
        inner += glm::length(p) < std::sqrt(0.5f) ? 1 : 0;
    }
    EXPECT_NEAR(double(inner) / n, 0.5, 2e-3);
}

}  // namespace ag::photon
