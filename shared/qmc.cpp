#include "shared/qmc.h"

#include <cassert>
#include <cmath>
#include <numeric>

namespace ag {

double radical_inverse(uint32_t base, uint64_t index) {
    assert(base >= 2);
    // Accumulate digits as an integer and the matching power of the base, then divide once, so
    // Φ_10(1234) is 4321 / 10^4 exactly as in the thesis.
    const double inv_base = 1.0 / double(base);
    uint64_t reversed = 0;
    double inv_base_n = 1.0;
    while (index > 0) {
        const uint64_t next = index / base;
        reversed = reversed * base + (index - next * base);
        inv_base_n *= inv_base;
        index = next;
    }
    const double v = double(reversed) * inv_base_n;
    return v < 1.0 ? v : std::nextafter(1.0, 0.0);
}

uint32_t nth_prime(int n) {
    static const std::vector<uint32_t> primes = [] {
        std::vector<uint32_t> p;
        for (uint32_t c = 2; p.size() < 1000; ++c) {
            bool prime = true;
            for (uint32_t q : p) {
                if (q * q > c) break;
                if (c % q == 0) {
                    prime = false;
                    break;
                }
            }
            if (prime) p.push_back(c);
        }
        return p;
    }();
    assert(n >= 0 && n < int(primes.size()));
    return primes[size_t(n)];
}

uint32_t hash_u32(uint32_t x) {
    // lowbias32 (Chris Wellons): good avalanche, cheap.
    x ^= x >> 16;
    x *= 0x7feb352dU;
    x ^= x >> 15;
    x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

namespace {
int digits_for_base(uint32_t base) {
    // Enough digits to exhaust 64-bit indices.
    return int(std::ceil(64.0 / std::log2(double(base))));
}
}  // namespace

Halton::Halton(int dimensions, uint32_t seed) : dimensions_(dimensions), seed_(seed) {
    assert(dimensions > 0 && dimensions <= 1000);
    if (seed_ == 0) return;
    permutations_.resize(size_t(dimensions));
    tails_.resize(size_t(dimensions));
    for (int d = 0; d < dimensions; ++d) {
        const uint32_t base = nth_prime(d);
        const int digits = digits_for_base(base);
        std::vector<uint16_t>& perm = permutations_[size_t(d)];
        perm.resize(size_t(digits) * base);
        for (int j = 0; j < digits; ++j) {
            uint16_t* p = perm.data() + size_t(j) * base;
            std::iota(p, p + base, uint16_t(0));
            // Fisher–Yates with a hashed stream: deterministic in (seed, dimension, digit).
            uint32_t state = hash_u32(seed_ ^ hash_u32(uint32_t(d) * 7919u + uint32_t(j)));
            for (uint32_t k = base - 1; k > 0; --k) {
                state = hash_u32(state + k);
                std::swap(p[k], p[state % (k + 1)]);
            }
        }
        std::vector<double>& tail = tails_[size_t(d)];
        tail.assign(size_t(digits) + 1, 0.0);
        for (int j = digits - 1; j >= 0; --j)
            tail[size_t(j)] = tail[size_t(j) + 1] + double(perm[size_t(j) * base]) *
                                                        std::pow(double(base), -double(j + 1));
    }
}

double Halton::sample(uint64_t index, int dimension) const {
    assert(dimension >= 0 && dimension < dimensions_);
    const uint32_t base = nth_prime(dimension);
    if (permutations_.empty()) return radical_inverse(base, index);
    // Scrambled radical inverse: permute every digit, including the infinite tail of zeros up to
    // the digit budget, so the point set stays stratified in every elementary interval.
    const uint16_t* perm = permutations_[size_t(dimension)].data();
    const double inv_base = 1.0 / double(base);
    double factor = inv_base, value = 0.0;
    int j = 0;
    for (; index > 0; ++j) {
        const uint64_t next = index / base;
        value += double(perm[size_t(j) * base + (index - next * base)]) * factor;
        index = next;
        factor *= inv_base;
    }
    value += tails_[size_t(dimension)][size_t(j)];  // the permuted zeros beyond the index's digits
    return value < 1.0 ? value : std::nextafter(1.0, 0.0);
}

}  // namespace ag
