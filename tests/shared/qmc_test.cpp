#include "shared/qmc.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <vector>

namespace ag {

TEST(Qmc, RadicalInverseThesisExamples) {
    // Larsen ch. 6.1: Φ10(1234) = 0.4321, Φ10(524) = 0.425, Φ10(2) = 0.2, Φ10(23) = 0.32.
    EXPECT_NEAR(radical_inverse(10, 1234), 0.4321, 1e-15);
    EXPECT_NEAR(radical_inverse(10, 524), 0.425, 1e-15);
    EXPECT_NEAR(radical_inverse(10, 2), 0.2, 1e-15);
    EXPECT_NEAR(radical_inverse(10, 23), 0.32, 1e-15);
}

TEST(Qmc, Base2SequenceEq62) {
    // Eq. 6.2 lists the base-2 sequence level by level: {0}, {1/2}, {1/4, 3/4}, {1/8 .. 7/8}, ...
    // Each level b^(k-1) .. b^k - 1 subdivides every interval of the previous one.
    EXPECT_DOUBLE_EQ(radical_inverse(2, 0), 0.0);
    EXPECT_DOUBLE_EQ(radical_inverse(2, 1), 0.5);
    EXPECT_DOUBLE_EQ(radical_inverse(2, 2), 0.25);
    EXPECT_DOUBLE_EQ(radical_inverse(2, 3), 0.75);
    for (int level = 3; level <= 5; ++level) {
        const int first = 1 << (level - 1), count = 1 << (level - 1);
        std::vector<double> got;
        for (int i = first; i < first + count; ++i) got.push_back(radical_inverse(2, uint64_t(i)));
        std::sort(got.begin(), got.end());
        for (int j = 0; j < count; ++j)
            EXPECT_DOUBLE_EQ(got[size_t(j)], (2.0 * j + 1.0) / (2.0 * count)) << level;
    }
    EXPECT_DOUBLE_EQ(radical_inverse(2, 4), 1.0 / 8);
    EXPECT_DOUBLE_EQ(radical_inverse(2, 8), 1.0 / 16);
}

TEST(Qmc, FirstLevelIsIOverB) {
    for (uint32_t b : {3u, 5u, 7u, 11u})
        for (uint32_t i = 0; i < b; ++i) EXPECT_DOUBLE_EQ(radical_inverse(b, i), double(i) / b);
}

TEST(Qmc, Primes) {
    EXPECT_EQ(nth_prime(0), 2u);
    EXPECT_EQ(nth_prime(1), 3u);
    EXPECT_EQ(nth_prime(2), 5u);
    EXPECT_EQ(nth_prime(9), 29u);
    EXPECT_EQ(nth_prime(999), 7919u);
}

TEST(Qmc, HaltonUnscrambledMatchesRadicalInverse) {
    const Halton h(4);
    for (uint64_t i = 0; i < 100; ++i)
        for (int d = 0; d < 4; ++d)
            EXPECT_DOUBLE_EQ(h.sample(i, d), radical_inverse(nth_prime(d), i));
}

// Every full level of a (scrambled or not) radical inverse hits each of the b^k elementary
// intervals exactly once: the stratification that photon groups rely on (Larsen fig. 6.3).
TEST(Qmc, ScrambledHaltonStaysStratified) {
    for (uint32_t seed : {0u, 1u, 77u}) {
        const Halton h(3, seed);
        for (int d = 0; d < 3; ++d) {
            const uint32_t b = nth_prime(d);
            const uint32_t n = b * b * b;
            std::vector<int> count(n, 0);
            for (uint32_t i = 0; i < n; ++i) {
                const double x = h.sample(i, d);
                ASSERT_GE(x, 0.0);
                ASSERT_LT(x, 1.0);
                ++count[std::min<uint32_t>(n - 1, uint32_t(x * n + 1e-9))];
            }
            EXPECT_TRUE(std::all_of(count.begin(), count.end(), [](int c) { return c == 1; }))
                << "seed " << seed << " dim " << d;
        }
    }
}

TEST(Qmc, ScramblingDependsOnSeedAndIsDeterministic) {
    const Halton a(2, 5), b(2, 5), c(2, 6);
    int differ = 0;
    for (uint64_t i = 1; i < 64; ++i) {
        EXPECT_EQ(a.sample(i, 1), b.sample(i, 1));
        differ += a.sample(i, 1) != c.sample(i, 1) ? 1 : 0;
    }
    EXPECT_GT(differ, 32);
}

TEST(Qmc, TwoDimensionalPointsAreEvenlySpread) {
    // 2D Halton (2, 3): every block of 36 consecutive points puts exactly one point in each of
    // the 4 × 9 elementary boxes [i/2^2, (i+1)/2^2) × [j/3^2, (j+1)/3^2) (Larsen fig. 6.1, 6.3).
    const Halton h(2);
    std::vector<int> cells(36, 0);
    for (uint64_t i = 0; i < 36 * 5; ++i) {
        const int x = int(h.sample(i, 0) * 4 + 1e-9), y = int(h.sample(i, 1) * 9 + 1e-9);
        ++cells[size_t(y * 4 + x)];
    }
    for (int c : cells) EXPECT_EQ(c, 5);
}

}  // namespace ag
