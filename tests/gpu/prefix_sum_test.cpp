// The GPU exclusive prefix sum against std::exclusive_scan, across block and level boundaries.
#include "gpu/prefix_sum.h"

#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "gl_fixture.h"

namespace ag::gpu {

class PrefixSumTest : public test::GlTest {};

TEST_F(PrefixSumTest, EqualsTheSequentialScan) {
    PrefixSum sum;
    std::mt19937 rng(11);
    for (const uint32_t n :
         {0u, 1u, 2u, 511u, 512u, 513u, 1023u, 70000u, 262143u, 262144u, 300001u}) {
        std::vector<uint32_t> in(n);
        // Mostly small counts with a few large ones, like photons per tile.
        for (uint32_t& v : in) v = rng() % 16 == 0 ? rng() % 5000 : rng() % 8;
        std::vector<uint32_t> expected(n + 1, 0);
        std::exclusive_scan(in.begin(), in.end(), expected.begin(), 0u);
        if (n > 0) expected[n] = expected[n - 1] + in[n - 1];
        in.push_back(0);  // room for the total when scanning in place
        Buffer input = make_storage_buffer(in.size() * sizeof(uint32_t), in.data());
        Buffer output = make_storage_buffer((n + 1) * sizeof(uint32_t));
        sum.exclusive(input.get(), output.get(), n);
        EXPECT_EQ(read_buffer_as<uint32_t>(output.get(), n + 1), expected) << "n = " << n;
        // In place.
        sum.exclusive(input.get(), input.get(), n);
        EXPECT_EQ(read_buffer_as<uint32_t>(input.get(), n + 1), expected) << "in place, n = " << n;
    }
}

}  // namespace ag::gpu
