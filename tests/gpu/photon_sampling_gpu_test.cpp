// The GLSL text of shared/photon_sampling.h computes what its C++ does: TEA and the radical
// inverse bit for bit, the float functions within rounding.
#include <gtest/gtest.h>

#include <cstring>

#include "gl_fixture.h"
#include "gpu/gl_objects.h"
#include "gpu/prefix_sum.h"
#include "shared/photon_sampling.h"

namespace ag::gpu {

class PhotonSamplingGpuTest : public test::GlTest {};

TEST_F(PhotonSamplingGpuTest, GlslEqualsCpp) {
    const uint32_t n = 4096;
    const std::string source = std::string(kPhotonSamplingGlsl) + kComputeGroupIndex + R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) writeonly buffer Out { uint words[]; };
uniform uint n;
void main() {
    uint i = group_index() * 64u + gl_LocalInvocationID.x;
    if (i >= n) return;
    uvec2 seed = tea_next(tea_seed(i, 3u));
    vec3 d = cosine_direction(tea_unit(seed), uniform_sphere(hammersley(i, n)));
    vec2 e = octahedral_encode(d);
    vec3 back = octahedral_decode(e);
    uint o = i * 10u;
    words[o] = seed.x;
    words[o + 1u] = seed.y;
    words[o + 2u] = floatBitsToUint(radical_inverse_2(i * 2654435761u));
    words[o + 3u] = floatBitsToUint(d.x);
    words[o + 4u] = floatBitsToUint(d.y);
    words[o + 5u] = floatBitsToUint(d.z);
    words[o + 6u] = floatBitsToUint(e.x);
    words[o + 7u] = floatBitsToUint(e.y);
    words[o + 8u] = floatBitsToUint(length(back - d));
    words[o + 9u] = floatBitsToUint(cone_weight(float(i) / float(n), 0.8, 1.0));
}
)";
    Program program = Program::compute("photon sampling test", source);
    Buffer out = make_storage_buffer(n * 10 * sizeof(uint32_t));
    program.use();
    program.set("n", n);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, out.get());
    dispatch_compute(n / 64);
    const std::vector<uint32_t> w = read_buffer_as<uint32_t>(out.get(), n * 10);
    const auto f = [&](size_t k) {
        float v;
        std::memcpy(&v, &w[k], 4);
        return v;
    };
    using namespace photon;
    for (uint32_t i = 0; i < n; ++i) {
        const size_t o = size_t(i) * 10;
        const uvec2 seed = tea_next(tea_seed(i, 3u));
        ASSERT_EQ(w[o], seed.x) << i;
        ASSERT_EQ(w[o + 1], seed.y) << i;
        ASSERT_EQ(f(o + 2), radical_inverse_2(i * 2654435761u)) << i;
        const vec3 d = cosine_direction(tea_unit(seed), uniform_sphere(hammersley(i, n)));
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(f(o + 3 + size_t(c)), d[c], 2e-5f) << i;
        const vec2 e = octahedral_encode(d);
        ASSERT_NEAR(f(o + 6), e.x, 2e-5f) << i;
        ASSERT_NEAR(f(o + 7), e.y, 2e-5f) << i;
        ASSERT_LT(f(o + 8), 1e-5f) << i;
        ASSERT_NEAR(f(o + 9), cone_weight(float(i) / float(n), 0.8f, 1.0f), 1e-6f) << i;
    }
}

}  // namespace ag::gpu
