// GPU photon mapping (Jimenez Kwast 2016) as an indirect method: photon energy against Embree,
// tile lists against the thesis's brute-force binning, no CPU rays and no per-frame read-back.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../gpu/gl_fixture.h"
#include "cpu/ray_tracer.h"
#include "gpu/g_buffer.h"
#include "gpu/gpu_photon_mapper.h"
#include "shared/photon_sampling.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"

namespace ag {

class GpuPmTest : public test::GlTest {};

TEST_F(GpuPmTest, Debug) {
    Scene scene = load_scene(AG_SOURCE_DIR "/scenes/cornell.json");
    scene.settings.gpu_pm.paths = 2000;
    scene.settings.gpu_pm.frames = 2;
    gpu::SceneMeshes meshes(scene);
    gpu::GBuffer g(scene, meshes, 64, 64);
    gpu::GpuPhotonMapper m(scene, g);
    m.trace();
    m.trace();
    g.render();
    m.render();
    const auto photons = m.read_photons();
    std::printf("stored %u of %llu paths, capacity %zu\n", m.stored_photons(),
                (unsigned long long)m.paths_traced(), m.photon_capacity());
    for (size_t i = 0; i < std::min<size_t>(photons.size(), 10); ++i)
        std::printf("  %g %g %g  power %g %g %g\n", photons[i].position.x, photons[i].position.y,
                    photons[i].position.z, photons[i].power.x, photons[i].power.y,
                    photons[i].power.z);
    const auto lists = m.read_tile_lists();
    size_t total = 0;
    for (const auto& l : lists) total += l.size();
    {
        std::vector<float> px(64 * 64 * 4);
        gpu::gl::BindTexture(GL_TEXTURE_2D, m.texture());
        gpu::gl::GetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, px.data());
        int nonzero = 0;
        double sum = 0;
        for (size_t i = 0; i < px.size(); i += 4) {
            nonzero += px[i] > 0;
            sum += px[i];
        }
        std::printf("result nonzero %d mean %g; row 32:", nonzero, sum / 4096);
        for (int x = 0; x < 64; x += 4)
            std::printf(" %.3g/%g", px[(32 * 64 + x) * 4], px[(32 * 64 + x) * 4 + 3]);
        std::printf("\n");
    }
    std::printf("tile entries %zu over %zu tiles, refined %d, radius %g\n", total, lists.size(),
                m.refined_pixels(), m.radius());
}

}  // namespace ag
