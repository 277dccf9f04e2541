#include "gpu/prefix_sum.h"

#include <string>

namespace ag::gpu {

namespace {

// One block of 512: up-sweep and down-sweep in shared memory (Blelloch 1990); the block's total
// goes to sums[block] for the next level.
const std::string kScan = std::string(kComputeGroupIndex) + R"(
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer In { uint data_in[]; };
layout(std430, binding = 1) buffer Out { uint data_out[]; };
layout(std430, binding = 2) writeonly buffer Sums { uint sums[]; };
uniform uint read_count;   // elements read; those beyond count as 0
uniform uint write_count;  // elements written
shared uint temp[512];
void main() {
    uint block = group_index(), t = gl_LocalInvocationID.x;
    uint a = block * 512u + 2u * t, b = a + 1u;
    temp[2u * t] = a < read_count ? data_in[a] : 0u;
    temp[2u * t + 1u] = b < read_count ? data_in[b] : 0u;
    uint offset = 1u;
    for (uint d = 256u; d > 0u; d >>= 1u) {
        barrier();
        if (t < d) temp[offset * (2u * t + 2u) - 1u] += temp[offset * (2u * t + 1u) - 1u];
        offset <<= 1u;
    }
    barrier();
    if (t == 0u) {
        sums[block] = temp[511];
        temp[511] = 0u;
    }
    for (uint d = 1u; d < 512u; d <<= 1u) {
        offset >>= 1u;
        barrier();
        if (t < d) {
            uint ai = offset * (2u * t + 1u) - 1u, bi = offset * (2u * t + 2u) - 1u;
            uint x = temp[ai];
            temp[ai] = temp[bi];
            temp[bi] += x;
        }
    }
    barrier();
    if (a < write_count) data_out[a] = temp[2u * t];
    if (b < write_count) data_out[b] = temp[2u * t + 1u];
}
)";

// Adds each block's scanned offset to its elements.
const std::string kAdd = std::string(kComputeGroupIndex) + R"(
layout(local_size_x = 256) in;
layout(std430, binding = 1) buffer Out { uint data_out[]; };
layout(std430, binding = 2) readonly buffer Offsets { uint offsets[]; };
uniform uint write_count;
void main() {
    uint block = group_index(), t = gl_LocalInvocationID.x;
    uint a = block * 512u + 2u * t, add = offsets[block];
    if (a < write_count) data_out[a] += add;
    if (a + 1u < write_count) data_out[a + 1u] += add;
}
)";

uint32_t blocks_for(uint32_t n) { return (n + PrefixSum::kBlock - 1) / PrefixSum::kBlock; }

}  // namespace

PrefixSum::PrefixSum()
    : scan_(Program::compute("prefix sum: scan", kScan)),
      add_(Program::compute("prefix sum: add", kAdd)) {}

void PrefixSum::exclusive(GLuint in, GLuint out, uint32_t count) {
    // count + 1 outputs: the element past the end reads as 0, so it receives the total.
    scan(in, out, count, count + 1, 0);
    gl::UseProgram(0);
    check_gl("PrefixSum::exclusive");
}

void PrefixSum::scan(GLuint in, GLuint out, uint32_t read, uint32_t write, size_t level) {
    const uint32_t blocks = blocks_for(write);
    if (sums_.size() <= level) {
        sums_.resize(level + 1);
        sums_size_.resize(level + 1, 0);
    }
    if (sums_size_[level] < blocks) {
        sums_[level] = make_storage_buffer(size_t(blocks) * sizeof(uint32_t));
        sums_size_[level] = blocks;
    }
    const GLuint sums = sums_[level].get();
    scan_.use();
    scan_.set("read_count", read);
    scan_.set("write_count", write);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, in);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, sums);
    dispatch_compute(blocks);
    if (blocks == 1) return;
    scan(sums, sums, blocks, blocks, level + 1);  // the blocks' offsets, in place
    add_.use();
    add_.set("write_count", write);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, sums);
    dispatch_compute(blocks);
}

}  // namespace ag::gpu
