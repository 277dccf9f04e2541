// The shared G-buffer: every target agrees with the scene it was drawn from, and caustics read
// from a shared G-buffer equal caustics drawing their own.
#include "gpu/g_buffer.h"

#include <gtest/gtest.h>

#include <random>

#include "gl_fixture.h"
#include "gpu/caustics_renderer.h"
#include "shared/scene_file.h"

namespace ag::gpu {

class GBufferTest : public test::GlTest {};

TEST_F(GBufferTest, TargetsAgreeWithTheScene) {
    const Scene scene = load_scene(AG_SOURCE_DIR "/scenes/cornell.json");
    SceneMeshes meshes(scene);
    GBuffer g(scene, meshes, 48, 40);
    g.render();
    const auto position = g.read(GBufferTarget::position), surface = g.read(GBufferTarget::surface),
               normal = g.read(GBufferTarget::normal), ids = g.read(GBufferTarget::ids);
    const std::vector<int> materials = material_ids(scene);
    const glm::vec3 eye = scene.camera.eye;
    const glm::vec3 axis = glm::normalize(scene.camera.target - eye);
    size_t covered = 0;
    std::vector<char> seen(scene.objects.size(), 0);
    for (size_t i = 0; i < position.size(); ++i) {
        if (position[i].w == 0.0f) {
            EXPECT_EQ(ids[i].w, 0.0f);
            continue;
        }
        ++covered;
        const int object = int(ids[i].r + 0.5f);
        ASSERT_GE(object, 0);
        ASSERT_LT(object, int(scene.objects.size()));
        seen[size_t(object)] = 1;
        const Material& m = scene.objects[size_t(object)].material;
        EXPECT_EQ(int(ids[i].g + 0.5f), materials[size_t(object)]);
        EXPECT_EQ(int(ids[i].b + 0.5f), int(m.type));
        if (m.type == MaterialType::diffuse) {
            EXPECT_NEAR(surface[i].r, m.albedo.r, 1e-6f);
            EXPECT_GT(surface[i].a, 0.0f);
        }
        const glm::vec3 n(normal[i]), p(position[i]);
        EXPECT_NEAR(glm::length(n), 1.0f, 1e-4f);
        EXPECT_GT(glm::dot(n, eye - p), 0.0f);  // faces the eye
        EXPECT_NEAR(normal[i].w, glm::dot(p - eye, axis), 1e-4f * glm::length(p - eye));
    }
    EXPECT_GT(covered, position.size() / 2);
    EXPECT_GE(std::count(seen.begin(), seen.end(), 1), 5);  // walls, floor, ceiling, blocks
}

TEST_F(GBufferTest, MaterialIdsJoinEqualMaterials) {
    Scene scene;
    for (int i = 0; i < 3; ++i) scene.objects.emplace_back();
    scene.objects[1].material.albedo = glm::vec3(0.1f);
    EXPECT_EQ(material_ids(scene), (std::vector<int>{0, 1, 0}));
}

TEST_F(GBufferTest, CausticsFromASharedGBufferEqualTheirOwn) {
    const Scene scene = load_scene(AG_SOURCE_DIR "/scenes/cornell.json");
    SceneMeshes meshes(scene);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const Bounds b = scene.world_bounds();
    std::vector<glm::vec3> positions, powers;
    for (int i = 0; i < 500; ++i) {  // on the floor
        positions.push_back({b.min.x + u(rng) * (b.max.x - b.min.x), b.min.y + 1e-3f,
                             b.min.z + u(rng) * (b.max.z - b.min.z)});
        powers.push_back(glm::vec3(1e-3f));
    }
    CausticsRenderer own(scene, meshes, 64, 64);
    own.render(positions, powers);
    GBuffer g(scene, meshes, 64, 64);
    CausticsRenderer shared(scene, meshes, 64, 64, &g);
    g.render();
    shared.render(positions, powers);
    const auto a = own.read_radiance(), c = shared.read_radiance();
    double sum = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i], c[i]) << "pixel " << i;
        sum += a[i].r;
    }
    EXPECT_GT(sum, 0.0);
}

}  // namespace ag::gpu
