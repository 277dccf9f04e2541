// OBJ + MTL models (shared/model_io.h) and scene objects that take a whole OBJ with its materials:
// one part per material, Kd/Ke/illum/Ni mapped, overrides, emissive parts as mesh lights, and
// warnings or errors for bad input.
#include "shared/model_io.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "shared/input_error.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "tests/shared/external_scenes.h"
#include "tests/shared/temp_dir.h"

namespace ag {
namespace {

using test::TempDirTest;

constexpr const char* kMtl = R"(newmtl white
Kd 0.7 0.7 0.7
illum 2
newmtl lamp
Kd 0.78 0.78 0.78
Ke 17 12 4
newmtl chrome
Kd 0.01 0.01 0.01
Ks 0.9 0.9 0.9
illum 5
newmtl glass
Ks 0.3 0.3 0.3
Ni 1.33
illum 7
)";

// A floor (white, 2 triangles), a lamp quad facing down (lamp), a mirror and a glass triangle.
constexpr const char* kObj = R"(mtllib room.mtl
v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
v -0.5 2 -0.5
v 0.5 2 -0.5
v 0.5 2 0.5
v -0.5 2 0.5
v 0 1 0
v 1 1 0
v 0 1 1
usemtl white
f 1 4 3 2
usemtl lamp
f 5 6 7 8
usemtl chrome
f 9 10 11
usemtl glass
f 9 11 10
)";

class ModelIoTest : public TempDirTest {};

TEST_F(ModelIoTest, ObjMaterialsGivePartsWithMappedMaterials) {
    write("room.mtl", kMtl);
    const Model model = load_model(write("room.obj", kObj));
    ASSERT_EQ(model.parts.size(), 4u);
    EXPECT_EQ(model.parts[0].name, "white");
    EXPECT_EQ(model.parts[0].mesh.triangles.size(), 2u);
    EXPECT_EQ(model.parts[0].material.type, MaterialType::diffuse);
    EXPECT_FLOAT_EQ(model.parts[0].material.albedo.y, 0.7f);
    EXPECT_EQ(model.parts[1].name, "lamp");
    EXPECT_EQ(model.parts[1].material.emission, glm::vec3(17, 12, 4));
    EXPECT_EQ(model.parts[2].material.type, MaterialType::mirror);
    EXPECT_FLOAT_EQ(model.parts[2].material.albedo.x, 0.9f);
    EXPECT_EQ(model.parts[3].material.type, MaterialType::glass);
    EXPECT_FLOAT_EQ(model.parts[3].material.ior, 1.33f);
    // Each part keeps only its own vertices.
    EXPECT_EQ(model.parts[2].mesh.positions.size(), 3u);
}

TEST_F(ModelIoTest, MissingMtlWarnsAndUsesTheDefaultMaterial) {
    const std::string obj = write("room.obj", kObj);  // no room.mtl beside it
    ::testing::internal::CaptureStderr();
    const Model model = load_model(obj);
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("room.obj"), std::string::npos) << err;
    EXPECT_NE(err.find("room.mtl"), std::string::npos) << err;
    ASSERT_EQ(model.parts.size(), 1u);
    EXPECT_EQ(model.parts[0].name, "default");
    EXPECT_EQ(model.parts[0].material.albedo, Material{}.albedo);
    EXPECT_EQ(model.parts[0].mesh.triangles.size(), 6u);
}

// A face given twice (rotated corners, or other vertices at the same places) is dropped with a
// warning: the frame's additive light passes would light it twice (McGuire's Cornell boxes give
// each block's front face again as its bottom). The same face turned over is another face.
TEST_F(ModelIoTest, RepeatedFacesAreDroppedWithAWarning) {
    const std::string obj = write("twice.obj",
                                  "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                  "f 1 2 3\nf 2 3 1\nf 4 5 6\nf 1 3 2\n");
    ::testing::internal::CaptureStderr();
    const Model model = load_model(obj);
    const std::string err = ::testing::internal::GetCapturedStderr();
    ASSERT_EQ(model.parts.size(), 1u);
    ASSERT_EQ(model.parts[0].mesh.triangles.size(), 2u);
    EXPECT_EQ(model.parts[0].mesh.triangles[0], glm::uvec3(0, 1, 2));
    EXPECT_EQ(model.parts[0].mesh.triangles[1], glm::uvec3(0, 2, 1));
    EXPECT_NE(err.find("twice.obj"), std::string::npos) << err;
    EXPECT_NE(err.find("dropped 2 of 4 triangles that repeat"), std::string::npos) << err;
}

TEST_F(ModelIoTest, BadIndexIsAnErrorNamingTheFile) {
    const std::string obj = write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
    try {
        load_model(obj);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.obj"), std::string::npos) << e.what();
    }
}

TEST_F(ModelIoTest, SpecularOnDiffuseWarnsNamingTheMaterial) {
    write("p.mtl", "newmtl shiny\nKd 0.5 0.5 0.5\nKs 0.3 0.3 0.3\nillum 2\n");
    ::testing::internal::CaptureStderr();
    const Model model = load_model(
        write("p.obj", "mtllib p.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl shiny\nf 1 2 3\n"));
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("shiny"), std::string::npos) << err;
    EXPECT_EQ(model.parts[0].material.type, MaterialType::diffuse);
}

std::string scene_json(const std::string& object) {
    return R"({"camera": {"eye": [0, 1, 5], "target": [0, 1, 0]},
               "materials": {"red": {"albedo": [0.6, 0.1, 0.1]}}, "lights": [],
               "objects": [)" +
           object + "]}";
}

TEST_F(ModelIoTest, SceneObjectTakesTheObjWithItsMaterialsAndEmissivePartsLight) {
    write("room.mtl", kMtl);
    write("room.obj", kObj);
    const Scene scene = parse_scene(
        scene_json(R"({"name": "room", "mesh": "room.obj", "dynamic": true})"), path("s.json"));
    ASSERT_EQ(scene.objects.size(), 4u);
    EXPECT_EQ(scene.objects[1].name, "room/lamp");
    EXPECT_TRUE(scene.objects[1].dynamic);
    ASSERT_EQ(scene.lights.size(), 1u);
    const Light& lamp = scene.lights[0];
    EXPECT_EQ(lamp.type, LightType::mesh);
    EXPECT_EQ(lamp.name, "room/lamp");
    EXPECT_EQ(lamp.object, 1);
    EXPECT_NEAR(lamp.area(), 1.0f, 1e-5f);
    EXPECT_NEAR(lamp.power().x, std::numbers::pi_v<float> * 17.0f, 1e-3f);
    // Its points lie on the lamp and face down (the quad's winding).
    for (float u : {0.1f, 0.6f, 0.99f}) {
        const LightPoint p = sample_area_light(scene, lamp, u, 0.3f);
        EXPECT_NEAR(p.position.y, 2.0f, 1e-5f);
        EXPECT_LE(std::abs(p.position.x), 0.5f + 1e-5f);
        EXPECT_NEAR(p.normal.y, -1.0f, 1e-5f);
    }
    EXPECT_NEAR(glm::length(lamp.center() - glm::vec3(0, 2, 0)), 0.0f, 1e-5f);
}

TEST_F(ModelIoTest, MeshLightFollowsItsObjectAndRefusesALightMove) {
    write("room.mtl", kMtl);
    write("room.obj", kObj);
    Scene scene = parse_scene(
        scene_json(R"({"name": "room", "mesh": "room.obj", "dynamic": true})"), path("s.json"));
    const uint64_t before = scene.version;
    translate_object(scene, 1, glm::vec3(1, 0, 0));
    EXPECT_NEAR(glm::length(scene.lights[0].center() - glm::vec3(1, 2, 0)), 0.0f, 1e-5f);
    bool light_moved = false;
    for (const SceneChange& c : scene.changes)
        light_moved |= c.sequence > before && c.kind == ChangeKind::light_position && c.index == 0;
    EXPECT_TRUE(light_moved);
    EXPECT_THROW(set_light_position(scene, 0, glm::vec3(0)), InputError);
    set_light_color(scene, 0, glm::vec3(1, 2, 3));
    EXPECT_EQ(scene.objects[1].material.emission, glm::vec3(1, 2, 3));
}

TEST_F(ModelIoTest, SceneOverridesFileMaterialsByName) {
    write("room.mtl", kMtl);
    write("room.obj", kObj);
    const Scene scene = parse_scene(
        scene_json(R"({"name": "room", "mesh": "room.obj", "materials": {"white": "red"}})"),
        path("s.json"));
    EXPECT_EQ(scene.objects[0].material.name, "red");
    EXPECT_EQ(scene.objects[1].material.name, "lamp");
    try {
        parse_scene(
            scene_json(R"({"name": "room", "mesh": "room.obj", "materials": {"whyte": "red"}})"),
            path("s.json"));
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("/objects/0/materials/whyte"), std::string::npos) << m;
        EXPECT_NE(m.find("white, lamp, chrome, glass"), std::string::npos) << m;
    }
}

TEST_F(ModelIoTest, SingleMaterialKeepsTheWholeMeshAsOneObject) {
    write("room.mtl", kMtl);
    write("room.obj", kObj);
    const Scene scene = parse_scene(
        scene_json(R"({"name": "room", "mesh": "room.obj", "material": "red"})"), path("s.json"));
    ASSERT_EQ(scene.objects.size(), 1u);
    EXPECT_TRUE(scene.lights.empty());
}

TEST_F(ModelIoTest, LampMaterialWithLightFalseStaysALamp) {
    const std::string json = R"({"camera": {"eye": [0, 1, 5], "target": [0, 1, 0]},
        "materials": {"lamp": {"emission": 5, "light": false}, "glow": {"emission": 2}},
        "lights": [], "objects": [
          {"name": "a", "material": "lamp", "shape": {"type": "quad", "size": [1, 1]}},
          {"name": "b", "material": "glow", "shape": {"type": "quad", "size": [1, 1]}}]})";
    const Scene scene = parse_scene(json, path("s.json"));
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].name, "b");
    EXPECT_EQ(object_lights(scene), (std::vector<int>{-1, 0}));
}

TEST_F(ModelIoTest, MeshLightNameClashIsAnError) {
    const std::string json = R"({"camera": {"eye": [0, 1, 5], "target": [0, 1, 0]},
        "materials": {"glow": {"emission": 2}},
        "lights": [{"name": "b", "type": "point", "position": [0, 1, 0], "intensity": 1}],
        "objects": [{"name": "b", "material": "glow", "shape": {"type": "quad", "size": [1, 1]}}]})";
    EXPECT_THROW(parse_scene(json, path("s.json")), InputError);
}

TEST(ExternalScenes, McGuireCornellBoxBringsItsOwnLight) {
    const std::filesystem::path file =
        std::filesystem::path(AG_SOURCE_DIR) / "scenes" / "cornell_mcguire.json";
    if (!test::missing_external_meshes(file).empty())
        GTEST_SKIP() << "../shared/external-scenes is absent: " << file << " needs it";
    const Scene scene = load_scene(file.string());
    EXPECT_EQ(scene.objects.size(), 8u);  // floor, ceiling, 3 walls, 2 blocks, light
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].type, LightType::mesh);
    EXPECT_EQ(scene.lights[0].radiance, glm::vec3(17, 12, 4));
    EXPECT_NEAR(scene.lights[0].area(), 0.47f * 0.38f, 1e-4f);
}

}  // namespace
}  // namespace ag
