// Screen coverage of lightmap texels (gpu::TexelCoverage), against the G-buffer drawn at the same
// size: the coverage adds up to the pixels that show lightmapped surfaces, each pixel's texel lies
// on the surface the pixel shows, and texels facing away from the eye cover nothing.
#include "gpu/texel_coverage.h"

#include <gtest/gtest.h>

#include <numeric>

#include "gl_fixture.h"
#include "gpu/g_buffer.h"
#include "shared/scene_file.h"

namespace ag::gpu {

class TexelCoverageTest : public test::GlTest {};

TEST_F(TexelCoverageTest, AgreesWithTheGBuffer) {
    const Scene scene = load_scene(AG_SOURCE_DIR "/scenes/cornell.json");
    SceneMeshes meshes(scene);
    TexelCoverage coverage(scene, meshes, 96, 80, 48);  // counted at 48 × 40
    ASSERT_EQ(coverage.width(), 48);
    ASSERT_EQ(coverage.height(), 40);
    const std::vector<float>& c = coverage.update();
    ASSERT_EQ(c.size(), scene.atlas.texels.size());

    GBuffer g(scene, meshes, 48, 40);
    g.render();
    const auto ids = g.read(GBufferTarget::ids);
    const float pixels = float(ids.size());
    float lightmapped = 0.0f;
    for (const glm::vec4& id : ids)
        if (id.w > 0.0f && int(id.b + 0.5f) == int(MaterialType::diffuse)) lightmapped += 1.0f;
    const float total = std::accumulate(c.begin(), c.end(), 0.0f);
    EXPECT_NEAR(total, lightmapped / pixels, 0.5f / pixels);
    EXPECT_GT(total, 0.5f);

    const glm::vec3 eye = scene.camera.eye;
    int seen = 0;
    for (size_t r = 0; r < c.size(); ++r) {
        const TexelRecord& t = scene.atlas.texels[r];
        const Transform& transform = scene.objects[size_t(t.object)].transform;
        const glm::vec3 p = transform.apply_point(t.position);
        const glm::vec3 n = glm::normalize(transform.apply_vector(t.normal));
        if (glm::dot(n, eye - p) < 0.0f) {
            EXPECT_EQ(c[r], 0.0f) << "texel " << r << " faces away";
        }
        seen += c[r] > 0.0f ? 1 : 0;
    }
    // The cornell view shows the walls, floor, ceiling and the cube: a good share of the texels.
    EXPECT_GT(seen, int(c.size()) / 4);
    EXPECT_LT(seen, int(c.size()));  // the cube's bottom and back faces are hidden
}

// The frame reads the lightmap bilinearly, so a pixel depends on up to four texels: each is
// credited by its weight. Counted at 12 × 10, the walls are minified (several texels a pixel):
// more texels are seen than pixels show them, and the coverage still adds up to those pixels.
// Crediting only the texel under each lookup sees at most one texel a pixel.
TEST_F(TexelCoverageTest, CreditsTheFourTexelsABilinearLookupReads) {
    const Scene scene = load_scene(AG_SOURCE_DIR "/scenes/cornell.json");
    SceneMeshes meshes(scene);
    TexelCoverage coverage(scene, meshes, 12, 10);
    const std::vector<float>& c = coverage.update();
    GBuffer g(scene, meshes, 12, 10);
    g.render();
    int lightmapped = 0;
    for (const glm::vec4& id : g.read(GBufferTarget::ids))
        if (id.w > 0.0f && int(id.b + 0.5f) == int(MaterialType::diffuse)) ++lightmapped;
    int seen = 0;
    for (float v : c) seen += v > 0.0f ? 1 : 0;
    EXPECT_GT(seen, 2 * lightmapped);
    EXPECT_NEAR(std::accumulate(c.begin(), c.end(), 0.0f), float(lightmapped) / 120.0f, 1e-4f);
}

TEST_F(TexelCoverageTest, FollowsTheCamera) {
    Scene scene = load_scene(AG_SOURCE_DIR "/scenes/cornell.json");
    SceneMeshes meshes(scene);
    TexelCoverage coverage(scene, meshes, 48, 48);
    const std::vector<float> front = coverage.update();
    // Turned round, the eye looks out of the open box: no texel is seen.
    scene.camera.target = 2.0f * scene.camera.eye - scene.camera.target;
    const std::vector<float>& away = coverage.update();
    EXPECT_EQ(std::accumulate(away.begin(), away.end(), 0.0f), 0.0f);
    EXPECT_GT(std::accumulate(front.begin(), front.end(), 0.0f), 0.5f);
}

}  // namespace ag::gpu
