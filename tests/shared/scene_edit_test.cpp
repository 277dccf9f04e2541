#include "shared/scene_edit.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>
#include <numbers>
#include <string>

#include "shared/input_error.h"

namespace ag {

namespace {
using ::testing::HasSubstr;

Scene two_objects_two_lights() {
    Scene s;
    s.path = "test.json";
    s.objects.resize(2);
    s.objects[0].name = "cube";
    s.objects[0].transform.translation = {1, 2, 3};
    s.objects[1].name = "floor";
    s.lights.resize(2);
    s.lights[0].name = "lamp";
    s.lights[0].position = {0, 5, 0};
    s.lights[0].intensity = glm::vec3(10.0f);
    s.lights[1].name = "panel";
    s.lights[1].type = LightType::quad;
    s.lights[1].corners = {glm::vec3(0, 4, 0), glm::vec3(2, 4, 0), glm::vec3(2, 4, 2),
                           glm::vec3(0, 4, 2)};
    s.lights[1].radiance = glm::vec3(1.0f);
    init_versions(s);
    return s;
}
}  // namespace

TEST(SceneEdit, EveryEditBumpsVersionsAndIsRecorded) {
    Scene s = two_objects_two_lights();
    EXPECT_EQ(s.version, 0u);
    translate_object(s, 0, {1, 0, 0});
    set_albedo(s, 1, {0.5f, 0.5f, 0.5f});
    set_light_color(s, 0, {1, 2, 3});
    set_light_enabled(s, 1, false);
    set_light_position(s, 0, {0, 6, 0});
    EXPECT_EQ(s.version, 5u);
    EXPECT_EQ(s.object_versions[0], 1u);
    EXPECT_EQ(s.object_versions[1], 2u);
    EXPECT_EQ(s.light_versions[0], 5u);
    EXPECT_EQ(s.light_versions[1], 4u);

    const auto all = changes_since(s, 0);
    ASSERT_EQ(all.size(), 5u);
    EXPECT_EQ(all[0].kind, ChangeKind::object_transform);
    EXPECT_EQ(all[1].kind, ChangeKind::object_material);
    EXPECT_EQ(all[2].kind, ChangeKind::light_power);
    EXPECT_EQ(all[3].kind, ChangeKind::light_enabled);
    EXPECT_EQ(all[4].kind, ChangeKind::light_position);
    const auto recent = changes_since(s, 3);
    ASSERT_EQ(recent.size(), 2u);
    EXPECT_EQ(recent[0].index, 1);
    EXPECT_TRUE(changes_since(s, 5).empty());
}

// The log keeps only what some consumer has not seen; versions and later reads are unaffected.
TEST(SceneEdit, TrimmingDropsOnlyChangesEveryConsumerHasSeen) {
    Scene s = two_objects_two_lights();
    for (int i = 0; i < 4; ++i) translate_object(s, 0, {1, 0, 0});
    trim_changes(s, 2);
    ASSERT_EQ(s.changes.size(), 2u);
    EXPECT_EQ(s.changes[0].sequence, 3u);
    EXPECT_EQ(changes_since(s, 2).size(), 2u);
    EXPECT_EQ(changes_since(s, 3).size(), 1u);
    trim_changes(s, s.version);
    EXPECT_TRUE(s.changes.empty());
    set_light_enabled(s, 1, false);
    ASSERT_EQ(changes_since(s, 4).size(), 1u);
    EXPECT_EQ(changes_since(s, 4)[0].sequence, 5u);
    EXPECT_EQ(s.object_versions[0], 4u);
}

TEST(SceneEdit, UntouchedItemsKeepTheirVersion) {
    Scene s = two_objects_two_lights();
    translate_object(s, 0, {0, 1, 0});
    EXPECT_EQ(s.object_versions[1], 0u);
    EXPECT_EQ(s.light_versions[0], 0u);
    EXPECT_EQ(s.camera_version, 0u);
}

TEST(SceneEdit, TransformsComposeRigidly) {
    Scene s = two_objects_two_lights();
    rotate_object(s, 0, {0, 1, 0}, 90.0f);
    const Transform& t = s.objects[0].transform;
    EXPECT_NEAR(glm::length(t.translation - glm::vec3(1, 2, 3)), 0.0f,
                1e-6f);  // about its own origin
    const glm::vec3 x = t.apply_vector({1, 0, 0});
    EXPECT_NEAR(x.z, -1.0f, 1e-6f);  // +90° about +Y takes +X to -Z
    translate_object(s, 0, {0, 0, 1});
    EXPECT_NEAR(s.objects[0].transform.translation.z, 4.0f, 1e-6f);
    const glm::mat4 m = s.objects[0].transform.matrix();
    const glm::vec3 p = glm::vec3(m * glm::vec4(1, 0, 0, 1));
    EXPECT_NEAR(glm::length(p - s.objects[0].transform.apply_point({1, 0, 0})), 0.0f, 1e-5f);
}

TEST(SceneEdit, QuadLightMovesAsAWholeAndColourGoesToRadiance) {
    Scene s = two_objects_two_lights();
    set_light_position(s, 1, {5, 5, 5});
    EXPECT_NEAR(glm::length(s.lights[1].center() - glm::vec3(5, 5, 5)), 0.0f, 1e-6f);
    EXPECT_NEAR(s.lights[1].quad_area(), 4.0f, 1e-6f);
    set_light_color(s, 1, {2, 2, 2});
    EXPECT_EQ(s.lights[1].radiance, glm::vec3(2.0f));
    EXPECT_NEAR(s.lights[1].power().x, std::numbers::pi_v<float> * 4.0f * 2.0f, 1e-4f);
    EXPECT_NEAR(s.lights[0].power().x, 4.0f * std::numbers::pi_v<float> * 10.0f, 1e-3f);
}

TEST(SceneEdit, BadEditsAreInputErrorsAndChangeNothing) {
    Scene s = two_objects_two_lights();
    EXPECT_THROW(translate_object(s, 2, {1, 0, 0}), InputError);
    EXPECT_THROW(set_light_enabled(s, -1, true), InputError);
    EXPECT_THROW(set_albedo(s, 0, {1.5f, 0, 0}), InputError);
    EXPECT_THROW(translate_object(s, 0, {std::nanf(""), 0, 0}), InputError);
    EXPECT_THROW(rotate_object(s, 0, {0, 0, 0}, 10.0f), InputError);
    EXPECT_THROW(set_light_color(s, 0, {-1, 0, 0}), InputError);
    Camera c = s.camera;
    c.target = c.eye;
    EXPECT_THROW(set_camera(s, c), InputError);
    EXPECT_EQ(s.version, 0u);
    EXPECT_TRUE(s.changes.empty());
    EXPECT_EQ(s.objects[0].transform.translation, glm::vec3(1, 2, 3));
}

// Finite but huge values used to reach Embree (abort) or the frame (NaN/Inf pixels, black
// images); each edit outside the documented limits is an InputError that changes nothing.
TEST(SceneEdit, EditsBeyondTheWorldAndLightLimitsAreInputErrors) {
    Scene s = two_objects_two_lights();
    s.objects[0].dynamic = true;
    s.objects[0].mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    s.objects[0].mesh.triangles = {{0, 1, 2}};
    auto message = [](const std::function<void()>& edit) {
        try {
            edit();
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    const float two63 = 9.223372e18f;
    EXPECT_THAT(message([&] {
                    set_light_position(s, 0, {two63, 500, 200});
                }),
                HasSubstr("set_light_position: expected coordinates within ±10000000 (the "
                          "world-size limit), got [9.223372e+18, 500, 200]"));
    EXPECT_THAT(message([&] {
                    set_light_position(s, 1, {0, two63, 0});
                }),
                HasSubstr("set_light_position: corner: expected coordinates within"));
    Transform far;
    far.translation = {1e20f, 82.5f, 169};
    EXPECT_THAT(message([&] { set_object_transform(s, 0, far); }),
                HasSubstr("set_object_transform: object 'cube': expected the placed object "
                          "within ±10000000"));
    EXPECT_THROW(translate_object(s, 0, {1e7f, 0, 0}), InputError);
    EXPECT_THAT(message([&] {
                    set_light_color(s, 0, {3e38f, 1, 1});
                }),
                HasSubstr("set_light_color: expected components in [0, 1e+15], got [3e+38, 1, 1]"));
    Camera c = s.camera;
    c.eye = {0, 0, 3e38f};
    EXPECT_THAT(message([&] { set_camera(s, c); }),
                HasSubstr("set_camera: eye: expected coordinates within"));
    c = s.camera;
    c.fov_y = 179.9999f;
    EXPECT_THAT(message([&] { set_camera(s, c); }),
                HasSubstr("set_camera: fov_y: expected a number in [0.1, 179]"));
    c.fov_y = 1e-30f;
    EXPECT_THROW(set_camera(s, c), InputError);
    EXPECT_EQ(s.version, 0u);
    EXPECT_TRUE(s.changes.empty());
    EXPECT_EQ(s.objects[0].transform.translation, glm::vec3(1, 2, 3));
    EXPECT_EQ(s.lights[0].position, glm::vec3(0, 5, 0));
    EXPECT_EQ(s.lights[1].corners[0], glm::vec3(0, 4, 0));
}

// Directions are normalised after scaling, so a huge axis or up vector still has a direction.
TEST(SceneEdit, HugeAxesAndUpVectorsKeepTheirDirection) {
    Scene s = two_objects_two_lights();
    rotate_object(s, 0, {0, 1e20f, 0}, 90.0f);
    const glm::vec3 x = s.objects[0].transform.apply_vector({1, 0, 0});
    EXPECT_NEAR(x.z, -1.0f, 1e-5f);
    Camera c = s.camera;
    c.up = {0, 1e-25f, 0};
    EXPECT_NO_THROW(set_camera(s, c));
    c.up = {0, 3e38f, 0};
    EXPECT_NO_THROW(set_camera(s, c));
}

TEST(SceneEdit, StaticObjectsAreNotMovable) {
    Scene s = two_objects_two_lights();
    s.objects[0].dynamic = true;
    EXPECT_NO_THROW(check_movable(s, 0, "set_position"));
    try {
        check_movable(s, 1, "set_position");
        ADD_FAILURE() << "a static object passed";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr("set_position: object 'floor' is static; mark it "
                                        "\"dynamic\": true in the scene to move it"));
    }
}

TEST(SceneEdit, FindByName) {
    const Scene s = two_objects_two_lights();
    EXPECT_EQ(s.find_object("floor"), 1);
    EXPECT_EQ(s.find_object("nope"), -1);
    EXPECT_EQ(s.find_light("panel"), 1);
}

}  // namespace ag
