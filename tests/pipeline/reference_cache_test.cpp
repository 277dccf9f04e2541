// The reference cache (convergence.h): a cached reference's name covers everything its image
// depends on, and this build's renderer, so no stale image is read back.
#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>

#include "shared/scene_file.h"
#include "shared/texture.h"
#include "tools/afterglow/convergence.h"

namespace ag::cli {
namespace {

class ReferenceCacheTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = std::filesystem::temp_directory_path() /
               ("ag_reference_cache_" +
                std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        std::filesystem::remove_all(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    // Cornell at `size` × `size` pixels, and a cheap pm reference of it.
    static Scene tiny(int size = 6) {
        Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell.json");
        scene.camera.width = scene.camera.height = size;
        return scene;
    }
    ReferenceRequest request(int threads) const {
        ReferenceRequest r;
        r.name = "cornell";
        r.cache = dir_.string();
        r.spp = 1;
        r.photons = 3000;
        r.threads = threads;
        r.log_prefix = "reference_cache_test";
        return r;
    }
    std::filesystem::path dir_;
};

TEST_F(ReferenceCacheTest, TheSameStateFindsItsReferenceOnAnyThreadCount) {
    const Scene scene = tiny();
    const std::string first = cached_reference(scene, "", 1, request(1));
    ASSERT_TRUE(std::filesystem::exists(first));
    // The renderer's probe and the state hash do not depend on the threads: the same file.
    EXPECT_EQ(cached_reference(scene, "", 1, request(3)), first);
    EXPECT_EQ(cached_reference(scene, "", 1, request(1)), first);
}

// At 40 × 40 the renderer's probe (the central 8 × 8 pixels: the back wall) does not see the
// floor: the state's own hash tells the textured floor apart.
TEST_F(ReferenceCacheTest, WhatTheImageDependsOnNamesANewReference) {
    const Scene scene = tiny(40);
    const std::string base = cached_reference(scene, "", 1, request(2));

    // An albedo texture on the floor (the same mean as its plain albedo would not matter).
    Scene textured = scene;
    Object& floor = textured.objects[size_t(textured.find_object("floor"))];
    auto texture = std::make_shared<Texture>();
    texture->width = 2;
    texture->height = 1;
    texture->texels = {glm::vec3(0.8f, 0.1f, 0.1f), glm::vec3(0.1f, 0.8f, 0.1f)};
    texture->mean = glm::vec3(0.45f, 0.45f, 0.1f);
    floor.material.albedo_map = texture;
    floor.mesh.texcoords.assign(3 * floor.mesh.triangles.size(), glm::vec2(0.25f, 0.5f));
    const std::string with_texture = cached_reference(textured, "", 1, request(2));
    EXPECT_NE(with_texture, base);
    // Another texel of the same texture: another image, another name.
    Scene other_texel = textured;
    Object& floor2 = other_texel.objects[size_t(other_texel.find_object("floor"))];
    floor2.mesh.texcoords.assign(3 * floor2.mesh.triangles.size(), glm::vec2(0.75f, 0.5f));
    EXPECT_NE(cached_reference(other_texel, "", 1, request(2)), with_texture);

    // A participating medium filling part of the room.
    Scene foggy = scene;
    Medium fog;
    fog.bounds.add(glm::vec3(100.0f, 0.0f, 100.0f));
    fog.bounds.add(glm::vec3(400.0f, 300.0f, 400.0f));
    fog.sigma_s = 0.002f;
    foggy.media.push_back(fog);
    EXPECT_NE(cached_reference(foggy, "", 1, request(2)), base);
}

}  // namespace
}  // namespace ag::cli
