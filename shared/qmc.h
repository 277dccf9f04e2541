// Quasi-Monte-Carlo sequences: radical inverse and Halton points in prime bases (Larsen ch. 6),
// with optional deterministic digit scrambling (Owen-style random permutations per digit, seeded).
#pragma once

#include <cstdint>
#include <vector>

namespace ag {

// Φ_b(i) of eq. 6.1: the digits of i in base b mirrored about the radix point. b ≥ 2.
double radical_inverse(uint32_t base, uint64_t index);

// The n-th prime (0 → 2, 1 → 3, ...), for n < 1000.
uint32_t nth_prime(int n);

// A Halton sequence over `dimensions` prime bases 2, 3, 5, ... Scrambling permutes the digits of
// each base with permutations drawn from `seed` (seed 0 = unscrambled, the plain sequence).
class Halton {
public:
    explicit Halton(int dimensions, uint32_t seed = 0);
    // Coordinate `dimension` of point `index`, in [0, 1).
    double sample(uint64_t index, int dimension) const;
    int dimensions() const { return dimensions_; }

private:
    int dimensions_;
    uint32_t seed_;
    // permutations_[d] holds base(d) digit permutations, one per digit position (up to 64/log2 b).
    std::vector<std::vector<uint16_t>> permutations_;
    // tails_[d][j]: value of the permuted zero digits from position j on, so a sample loops only
    // over the index's own digits.
    std::vector<std::vector<double>> tails_;
};

// Stateless 32-bit hash (for decorrelating sequences; not a QMC point set).
uint32_t hash_u32(uint32_t x);

}  // namespace ag
