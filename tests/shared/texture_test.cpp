// Albedo textures (shared/texture.h) and where they come from: orientation, bilinear sampling and
// wrapping, sRGB decoding; map_Kd with per-corner texture coordinates from OBJ; "albedo_map" in
// scene files; and the warnings and errors for textures that cannot be used.
#include "shared/texture.h"

#include <gtest/gtest.h>

#include "shared/image.h"
#include "shared/input_error.h"
#include "shared/model_io.h"
#include "shared/scene.h"
#include "shared/scene_file.h"
#include "shared/shapes.h"
#include "tests/shared/temp_dir.h"

namespace ag {
namespace {

class TextureTest : public test::TempDirTest {
protected:
    // A 2 × 2 EXR (linear): top row red, green; bottom row blue, white.
    std::string write_2x2(const std::string& name) {
        Image image(2, 2);
        image.set_rgb(0, 0, {1, 0, 0});
        image.set_rgb(1, 0, {0, 1, 0});
        image.set_rgb(0, 1, {0, 0, 1});
        image.set_rgb(1, 1, {1, 1, 1});
        write_image(image, path(name));
        return path(name);
    }
};

TEST_F(TextureTest, BottomLeftIsTheOriginAndSamplingIsBilinearWithWrapping) {
    const auto t = load_texture(write_2x2("t.exr"));
    ASSERT_EQ(t->width, 2);
    // Texel centres at u, v = ¼ and ¾; v = ¼ is the image's bottom row.
    EXPECT_EQ(t->sample({0.25f, 0.25f}), glm::vec3(0, 0, 1));
    EXPECT_EQ(t->sample({0.75f, 0.25f}), glm::vec3(1, 1, 1));
    EXPECT_EQ(t->sample({0.25f, 0.75f}), glm::vec3(1, 0, 0));
    EXPECT_EQ(t->sample({0.75f, 0.75f}), glm::vec3(0, 1, 0));
    // Halfway between the bottom texels; the centre mixes all four.
    const glm::vec3 mid = t->sample({0.5f, 0.25f});
    EXPECT_NEAR(mid.x, 0.5f, 1e-6f);
    EXPECT_NEAR(mid.z, 1.0f, 1e-6f);
    const glm::vec3 centre = t->sample({0.5f, 0.5f});
    EXPECT_NEAR(centre.x, 0.5f, 1e-6f);
    EXPECT_NEAR(centre.y, 0.5f, 1e-6f);
    EXPECT_NEAR(centre.z, 0.5f, 1e-6f);
    // Repeat wrapping: one period on, and across the u = 0 edge (between both columns).
    EXPECT_EQ(t->sample({3.25f, -1.75f}), glm::vec3(0, 0, 1));
    const glm::vec3 edge = t->sample({0.0f, 0.25f});
    EXPECT_NEAR(edge.x, 0.5f, 1e-6f);
    EXPECT_EQ(t->mean, glm::vec3(0.5f, 0.5f, 0.5f));
    EXPECT_NEAR(t->box_mean({0, 0}, {1, 1}, 8).x, 0.5f, 1e-6f);
}

TEST_F(TextureTest, EightBitFilesAreDecodedFromSrgbAndGreyIsReplicated) {
    Image grey(1, 1, 1);
    grey.pixels[0] = 0.5f;  // written as sRGB 8-bit
    write_image(grey, path("g.png"));
    const auto t = load_texture(path("g.png"));
    const glm::vec3 c = t->sample({0.3f, 0.3f});
    EXPECT_NEAR(c.x, 0.5f, 0.003f);  // linear again, within 8-bit steps
    EXPECT_EQ(c.x, c.y);
    EXPECT_EQ(c.x, c.z);
}

TEST_F(TextureTest, UnreadableImageIsAnErrorNamingTheFile) {
    write("bad.png", "not a png");
    try {
        load_texture(path("bad.png"));
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.png"), std::string::npos) << e.what();
    }
}

TEST_F(TextureTest, ObjMapKdGivesTheTextureAndPerCornerCoordinates) {
    write_2x2("tex.exr");
    write("m.mtl", "newmtl tiles\nKd 0.5 0.5 0.5\nmap_Kd tex.exr\nnewmtl plain\nKd 0.2 0.3 0.4\n");
    // A quad with a UV seam: vertex 1 has two texture coordinates.
    const Model model = load_model(write("m.obj", R"(mtllib m.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vt 0.5 0.5
usemtl tiles
f 1/1 2/2 3/3
f 1/5 3/3 4/4
usemtl plain
f 1 3 4
)"));
    ASSERT_EQ(model.parts.size(), 2u);
    const ModelPart& tiles = model.parts[0];
    ASSERT_TRUE(tiles.material.albedo_map);
    EXPECT_EQ(tiles.material.albedo, glm::vec3(1.0f));  // the texture replaces Kd
    ASSERT_EQ(tiles.mesh.texcoords.size(), 6u);
    EXPECT_EQ(tiles.mesh.texcoords[1], glm::vec2(1, 0));
    EXPECT_EQ(tiles.mesh.texcoords[3], glm::vec2(0.5f, 0.5f));
    EXPECT_EQ(tiles.mesh.positions.size(), 4u);  // the seam does not split vertex 1
    EXPECT_FALSE(model.parts[1].material.albedo_map);
    EXPECT_FALSE(model.parts[1].mesh.has_texcoords());

    // albedo_at reads the texture at the hit's barycentrics (u, v): triangle 0 maps them to
    // (u + v, v), so (0, ¼) is the bottom-left texel's centre and (½, ¼) the bottom-right one's.
    Object o;
    o.mesh = tiles.mesh;
    o.material = tiles.material;
    EXPECT_EQ(albedo_at(o, 0, {0.0f, 0.25f}), glm::vec3(0, 0, 1));
    const glm::vec3 a = albedo_at(o, 0, {0.5f, 0.25f});  // (0.75, 0.25)
    EXPECT_NEAR(a.x, 1.0f, 1e-5f);
    EXPECT_NEAR(a.y, 1.0f, 1e-5f);
}

TEST_F(TextureTest, MissingMapKdWarnsAndKeepsKd) {
    write("m.mtl", "newmtl tiles\nKd 0.5 0.25 0.125\nmap_Kd nowhere.png\n");
    ::testing::internal::CaptureStderr();
    const Model model = load_model(write("m.obj",
                                         "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\n"
                                         "vt 0 1\nusemtl tiles\nf 1/1 2/2 3/3\n"));
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("nowhere.png"), std::string::npos) << err;
    EXPECT_NE(err.find("tiles"), std::string::npos) << err;
    EXPECT_FALSE(model.parts[0].material.albedo_map);
    EXPECT_EQ(model.parts[0].material.albedo, glm::vec3(0.5f, 0.25f, 0.125f));
}

TEST_F(TextureTest, TexturedFacesWithoutCoordinatesWarnAndUseTheMean) {
    write_2x2("tex.exr");
    write("m.mtl", "newmtl tiles\nmap_Kd tex.exr\n");
    ::testing::internal::CaptureStderr();
    const Model model = load_model(
        write("m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl tiles\nf 1 2 3\n"));
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("no texture coordinates"), std::string::npos) << err;
    Object o;
    o.mesh = model.parts[0].mesh;
    o.material = model.parts[0].material;
    EXPECT_EQ(albedo_at(o, 0, {0.2f, 0.2f}), glm::vec3(0.5f));
    EXPECT_EQ(base_albedo(o), glm::vec3(0.5f));
}

TEST_F(TextureTest, SceneFileAlbedoMapIsRelativeToTheSceneAndChecked) {
    write_2x2("tex.exr");
    const std::string scene = R"({"camera": {"eye": [0, 1, 5], "target": [0, 0, 0]},
        "materials": {"tiles": {"albedo_map": "tex.exr"},
                      "tinted": {"albedo": [0.5, 0.5, 0.5], "albedo_map": "tex.exr"}},
        "lights": [{"name": "lamp", "type": "point", "position": [0, 3, 0], "intensity": [1, 1, 1]}],
        "objects": [{"name": "floor", "material": "tiles", "shape": {"type": "quad", "size": [2, 2]}},
                    {"name": "box", "material": "tinted", "shape": {"type": "box", "size": [1, 1, 1]},
                     "transform": {"translate": [0, 0.5, 0]}}]})";
    const Scene s = load_scene(write("s.json", scene));
    const Object& floor = s.objects[size_t(s.find_object("floor"))];
    ASSERT_TRUE(floor.material.albedo_map);
    EXPECT_EQ(floor.material.albedo, glm::vec3(1.0f));
    ASSERT_EQ(floor.mesh.texcoords.size(), 6u);  // built-in shapes carry coordinates
    const Object& box = s.objects[size_t(s.find_object("box"))];
    EXPECT_EQ(box.material.albedo, glm::vec3(0.5f));
    EXPECT_EQ(box.material.albedo_map, floor.material.albedo_map);  // read once

    for (const std::string& bad :
         {std::string(R"("albedo_map": "missing.png")"), std::string(R"("albedo_map": 3)"),
          std::string(R"("type": "mirror", "albedo_map": "tex.exr")")}) {
        std::string text = scene;
        text.replace(text.find(R"("albedo_map": "tex.exr"})"), 24, bad + "}");
        try {
            load_scene(write("bad.json", text));
            FAIL() << "expected an InputError for " << bad;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("/materials/tiles"), std::string::npos)
                << e.what();
        }
    }
}

TEST_F(TextureTest, ShapesCarryCoordinatesThatSurviveDroppedTriangles) {
    Mesh box = make_box(glm::vec3(1.0f));
    ASSERT_EQ(box.texcoords.size(), 36u);
    for (const glm::vec2& uv : box.texcoords) {
        EXPECT_GE(uv.x, 0.0f);
        EXPECT_LE(uv.x, 1.0f);
        EXPECT_GE(uv.y, 0.0f);
        EXPECT_LE(uv.y, 1.0f);
    }
    const glm::vec2 kept = box.texcoords[3];
    filter_triangles(box, [](int t) { return t != 0; });
    ASSERT_EQ(box.texcoords.size(), 33u);
    EXPECT_EQ(box.texcoords[0], kept);
}

}  // namespace
}  // namespace ag
