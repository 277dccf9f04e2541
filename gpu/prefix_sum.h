// Exclusive prefix sum of 32-bit counts on the GPU (compute shaders, work-efficient scan per
// block of 512 after Blelloch, block sums scanned recursively): the offsets of variable-length
// lists built by count → scan → insert. Jimenez Kwast (2016, §5.3.3.1) summed his tile counts on
// the CPU; here nothing is read back.
#pragma once

#include <cstdint>
#include <vector>

#include "gpu/gl_objects.h"

namespace ag::gpu {

class PrefixSum {
public:
    PrefixSum();

    // out[i] = Σ_{j<i} in[j] for i ≤ count, so out[count] holds the total. `in` holds at least
    // `count` uints, `out` at least count + 1; they may be the same buffer. Ends with a barrier.
    void exclusive(GLuint in, GLuint out, uint32_t count);

    static constexpr uint32_t kBlock = 512;  // elements per work group

private:
    void scan(GLuint in, GLuint out, uint32_t read, uint32_t write, size_t level);
    Program scan_, add_;
    std::vector<Buffer> sums_;  // block sums per recursion level
    std::vector<uint32_t> sums_size_;
};

// The index of the current work group when it was dispatched by dispatch_compute (groups spill
// from x into y); for compute shaders.
inline constexpr const char* kComputeGroupIndex = R"(
uint group_index() { return gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x; }
)";

}  // namespace ag::gpu
