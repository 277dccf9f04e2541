// Albedo textures end to end: the progressive frame of a Cornell box with a checker-textured floor,
// back wall and cube agrees with the path tracer, per pixel on the direct term (the frame reads the
// texel per pixel) and in mean on the indirect term (photons take the albedo where they land, and
// the AIM the texel's mean albedo).
#include <gtest/gtest.h>

#include "../gpu/gl_fixture.h"
#include "cpu/reference/reference.h"
#include "shared/metrics.h"
#include "shared/pipeline/pipeline.h"
#include "shared/scene_file.h"

namespace ag {
namespace {

glm::dvec3 mean(const Image& image) {
    glm::dvec3 sum(0.0);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) sum += glm::dvec3(image.rgb(x, y));
    return sum / double(image.width * image.height);
}

class TextureTest : public test::GlTest {};

TEST_F(TextureTest, TexturedFrameAgreesWithPathTracing) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell_textured.json");
    std::erase_if(scene.objects, [](const Object& o) { return o.name == "sphere"; });
    ASSERT_TRUE(scene.objects[size_t(scene.find_object("floor"))].material.albedo_map);
    scene.settings.gather.backend = GatherBackend::cpu;
    scene.camera.width = scene.camera.height = 48;
    make_surfaces_and_atlas(scene);

    Pipeline pipeline(scene, PipelineOptions{48, 48});
    pipeline.prime();
    pipeline.frame();
    const gpu::FrameImages frame = pipeline.images();

    cpu::ReferenceSettings settings;
    settings.spp = 1024;
    ThreadPool pool(2);
    const cpu::ReferenceResult pt = cpu::render_reference(scene, settings, pool);

    // Direct: per pixel, where a flat-albedo frame would miss every checker square.
    const Image& direct = frame.aov[size_t(FrameTerm::direct)];
    const double direct_rel_mse =
        compare_images(direct, pt.components[size_t(FrameTerm::direct)]).rel_mse;
    // Indirect: the mean (pt is noisy per pixel at this budget).
    const glm::dvec3 frame_indirect = mean(frame.aov[size_t(FrameTerm::indirect)]);
    const glm::dvec3 pt_indirect = mean(pt.components[size_t(FrameTerm::indirect)]);
    std::printf(
        "textured Cornell 48x48: direct relMSE %.4f; indirect mean frame/pt %.3f %.3f %.3f\n",
        direct_rel_mse, frame_indirect.x / pt_indirect.x, frame_indirect.y / pt_indirect.y,
        frame_indirect.z / pt_indirect.z);
    EXPECT_LT(direct_rel_mse, 0.02);
    // The untextured box (each texture replaced by its mean) reads 0.971 0.970 0.977 at this size
    // (the lightmaps' coarseness, issue #12); a frame or photons ignoring the texture are off by
    // far more (white albedo where the checker is red).
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(frame_indirect[c] / pt_indirect[c], 1.0, 0.05) << c;
}

}  // namespace
}  // namespace ag
