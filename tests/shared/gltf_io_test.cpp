// glTF 2.0 models (shared/gltf_io.h): files the tests write themselves cover the node hierarchy,
// each material mapping, KHR_lights_punctual, cameras, .glb, every warning and the errors; the
// Khronos box from ../shared/external-scenes loads through its scene file.
#include "shared/gltf_io.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "shared/image.h"
#include "shared/input_error.h"
#include "shared/scene.h"
#include "shared/scene_file.h"
#include "tests/shared/deadline.h"
#include "tests/shared/external_scenes.h"
#include "tests/shared/temp_dir.h"

namespace ag {
namespace {

using Json = nlohmann::json;
using test::TempDirTest;

std::string base64(const std::vector<unsigned char>& data) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < data.size(); i += 3) {
        uint32_t v = uint32_t(data[i]) << 16;
        if (i + 1 < data.size()) v |= uint32_t(data[i + 1]) << 8;
        if (i + 2 < data.size()) v |= data[i + 2];
        out += k[(v >> 18) & 63];
        out += k[(v >> 12) & 63];
        out += i + 1 < data.size() ? k[(v >> 6) & 63] : '=';
        out += i + 2 < data.size() ? k[v & 63] : '=';
    }
    return out;
}

// One unit quad in the XZ plane facing +y (4 positions, 6 uint16 indices) as buffer 0 with
// accessors 0 (POSITION) and 1 (indices); `extra` adds to the document.
struct GltfDoc {
    Json j;
    std::vector<unsigned char> bin;

    GltfDoc() {
        const float p[12] = {-0.5f, 0, -0.5f, -0.5f, 0, 0.5f, 0.5f, 0, 0.5f, 0.5f, 0, -0.5f};
        const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
        bin.resize(sizeof p + sizeof idx);
        std::memcpy(bin.data(), p, sizeof p);
        std::memcpy(bin.data() + sizeof p, idx, sizeof idx);
        j = {{"asset", {{"version", "2.0"}}},
             {"bufferViews",
              {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", sizeof p}},
               {{"buffer", 0}, {"byteOffset", sizeof p}, {"byteLength", sizeof idx}}}},
             {"accessors",
              {{{"bufferView", 0},
                {"componentType", 5126},
                {"count", 4},
                {"type", "VEC3"},
                {"min", {-0.5, 0, -0.5}},
                {"max", {0.5, 0, 0.5}}},
               {{"bufferView", 1}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}},
             {"meshes", Json::array()},
             {"materials", Json::array()},
             {"nodes", Json::array()},
             {"scenes", {{{"nodes", Json::array()}}}},
             {"scene", 0}};
    }
    // A mesh of the quad with material `material` (-1: none); returns its index.
    int mesh(int material) {
        Json prim = {{"attributes", {{"POSITION", 0}}}, {"indices", 1}};
        if (material >= 0) prim["material"] = material;
        j["meshes"].push_back({{"primitives", {prim}}});
        return int(j["meshes"].size()) - 1;
    }
    int material(const Json& m) {
        j["materials"].push_back(m);
        return int(j["materials"].size()) - 1;
    }
    int node(const Json& n, bool root = true) {
        j["nodes"].push_back(n);
        const int i = int(j["nodes"].size()) - 1;
        if (root) j["scenes"][0]["nodes"].push_back(i);
        return i;
    }
    std::string gltf() const {
        Json out = j;
        out["buffers"] = {{{"byteLength", bin.size()},
                           {"uri", "data:application/octet-stream;base64," + base64(bin)}}};
        return out.dump(1);
    }
    std::string glb() const {
        Json out = j;
        out["buffers"] = {{{"byteLength", bin.size()}}};
        std::string json = out.dump();
        while (json.size() % 4) json += ' ';
        std::vector<unsigned char> b = bin;
        while (b.size() % 4) b.push_back(0);
        std::string s;
        auto u32 = [&](uint32_t v) { s.append(reinterpret_cast<const char*>(&v), 4); };
        u32(0x46546C67);
        u32(2);
        u32(uint32_t(12 + 8 + json.size() + 8 + b.size()));
        u32(uint32_t(json.size()));
        u32(0x4E4F534A);
        s += json;
        u32(uint32_t(b.size()));
        u32(0x004E4942);
        s.append(reinterpret_cast<const char*>(b.data()), b.size());
        return s;
    }
};

class GltfTest : public TempDirTest {
protected:
    Model load(const GltfDoc& doc, std::string* warnings = nullptr, bool binary = false) {
        const std::string file = binary ? write("m.glb", doc.glb()) : write("m.gltf", doc.gltf());
        ::testing::internal::CaptureStderr();
        Model m;
        try {
            m = load_gltf(file);
        } catch (...) {
            const std::string err = ::testing::internal::GetCapturedStderr();
            if (warnings) *warnings = err;
            throw;
        }
        const std::string err = ::testing::internal::GetCapturedStderr();
        if (warnings) *warnings = err;
        return m;
    }
};

TEST_F(GltfTest, NodeHierarchyIsFlattenedIntoWorldPositions) {
    GltfDoc doc;
    const int mesh = doc.mesh(-1);
    const int child =
        doc.node({{"mesh", mesh}, {"translation", {0, 1, 0}}, {"scale", {2, 2, 2}}}, false);
    // Parent: 90° about +z (quaternion x y z w), then moved by +10 x.
    const float s = std::sqrt(0.5f);
    doc.node({{"name", "parent"},
              {"children", {child}},
              {"translation", {10, 0, 0}},
              {"rotation", {0, 0, s, s}}});
    const Model m = load(doc);
    ASSERT_EQ(m.parts.size(), 1u);
    const Bounds b = mesh_bounds(m.parts[0].mesh);
    // Child: quad scaled 2 at y = 1 → x ∈ [-1, 1], y = 1; rotated about z by 90° → x = -1,
    // y ∈ [-1, 1]; moved → x = 9.
    EXPECT_NEAR(b.min.x, 9.0f, 1e-5f);
    EXPECT_NEAR(b.max.x, 9.0f, 1e-5f);
    EXPECT_NEAR(b.min.y, -1.0f, 1e-5f);
    EXPECT_NEAR(b.max.z, 1.0f, 1e-5f);
    EXPECT_EQ(m.parts[0].material.name, "default");
    // The quad faced +y; the rotation turns that to -x.
    EXPECT_NEAR(triangle_normal(m.parts[0].mesh, 0).x, -1.0f, 1e-5f);
}

// glTF's nodes form trees (no node has two parents). Forty nodes each naming the next as its
// child twice place the quad 2^40 times along distinct paths: the reader recursed down every path
// (a hang, then memory). A node reached a second time is now an error naming it, as is a cycle and
// a chain deeper than 256; a mesh placed by two nodes (instancing) still loads as two parts.
TEST_F(GltfTest, ANodeReachedTwiceIsAnErrorNotTwoToTheFortyPlacements) {
    const auto error = [&](const GltfDoc& doc) -> std::string {
        std::string message;
        test::within_deadline(std::chrono::seconds(20), [&] {
            try {
                load(doc);
            } catch (const InputError& e) {
                message = e.what();
            }
        });
        return message;
    };
    {
        GltfDoc doc;
        const int mesh = doc.mesh(-1);
        for (int i = 0; i < 40; ++i) doc.node({{"children", {i + 1, i + 1}}}, i == 0);
        doc.node({{"mesh", mesh}}, false);
        const std::string e = error(doc);
        EXPECT_NE(e.find("m.gltf: node 40: expected a node tree, got a node reached a second time"),
                  std::string::npos)
            << e;
    }
    {
        GltfDoc doc;  // a cycle 0 → 1 → 0
        doc.node({{"mesh", doc.mesh(-1)}, {"children", {1}}});
        doc.node({{"children", {0}}}, false);
        EXPECT_NE(error(doc).find("node 0: expected a node tree, got a node reached a second"),
                  std::string::npos);
    }
    {
        GltfDoc doc;  // a root listed twice
        doc.node({{"mesh", doc.mesh(-1)}});
        doc.j["scenes"][0]["nodes"].push_back(0);
        EXPECT_NE(error(doc).find("reached a second time"), std::string::npos);
    }
    {
        GltfDoc doc;  // a chain of 300 nodes
        for (int i = 0; i < 300; ++i) doc.node({{"children", {i + 1}}}, i == 0);
        doc.node({{"mesh", doc.mesh(-1)}}, false);
        EXPECT_NE(error(doc).find("node 257: expected a node tree at most 256 deep"),
                  std::string::npos);
    }
    GltfDoc doc;  // one mesh, two nodes: two parts
    const int mesh = doc.mesh(-1);
    doc.node({{"mesh", mesh}});
    doc.node({{"mesh", mesh}, {"translation", {3, 0, 0}}});
    EXPECT_EQ(load(doc).parts.size(), 2u);
}

// Each placement of a mesh copies it, so the triangles placed, instances included, are bounded
// before any accessor is read (kMaxSceneTriangles; here a bound of 10): five placements of the
// quad (10 triangles) load, six fail naming the sixth node.
TEST_F(GltfTest, TrianglesPlacedByInstancesAreBounded) {
    GltfDoc doc;
    const int mesh = doc.mesh(-1);
    for (int i = 0; i < 5; ++i) doc.node({{"name", "n" + std::to_string(i)}, {"mesh", mesh}});
    EXPECT_EQ(load_gltf(write("five.gltf", doc.gltf()), 10).parts.size(), 5u);
    doc.node({{"name", "n5"}, {"mesh", mesh}});
    try {
        load_gltf(write("six.gltf", doc.gltf()), 10);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("six.gltf: node n5: expected at most 10 triangles"),
                  std::string::npos)
            << e.what();
    }
}

TEST_F(GltfTest, MirroringNodeKeepsFrontFacesOutward) {
    GltfDoc doc;
    doc.node({{"mesh", doc.mesh(-1)}, {"scale", {1, -1, 1}}});
    const Model m = load(doc);
    EXPECT_NEAR(triangle_normal(m.parts[0].mesh, 0).y, -1.0f, 1e-5f);
}

TEST_F(GltfTest, MaterialsMapToDiffuseEmissiveGlassAndMirror) {
    GltfDoc doc;
    const int red =
        doc.material({{"name", "red"},
                      {"pbrMetallicRoughness",
                       {{"baseColorFactor", {0.8, 0.1, 0.1, 1}}, {"metallicFactor", 0}}}});
    const int lamp = doc.material(
        {{"name", "lamp"},
         {"emissiveFactor", {1, 0.5, 0.25}},
         {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 8}}}}}});
    const int glass = doc.material({{"name", "glass"},
                                    {"extensions",
                                     {{"KHR_materials_transmission", {{"transmissionFactor", 1}}},
                                      {"KHR_materials_ior", {{"ior", 1.33}}}}}});
    const int chrome = doc.material(
        {{"name", "chrome"},
         {"pbrMetallicRoughness", {{"metallicFactor", 1}, {"roughnessFactor", 0.05}}}});
    for (int mat : {red, lamp, glass, chrome})
        doc.node({{"name", "n" + std::to_string(mat)}, {"mesh", doc.mesh(mat)}});
    const Model m = load(doc);
    ASSERT_EQ(m.parts.size(), 4u);
    EXPECT_EQ(m.parts[0].material.type, MaterialType::diffuse);
    EXPECT_NEAR(m.parts[0].material.albedo.x, 0.8f, 1e-6f);
    EXPECT_EQ(m.parts[1].material.emission, glm::vec3(8, 4, 2));
    EXPECT_EQ(m.parts[2].material.type, MaterialType::glass);
    EXPECT_NEAR(m.parts[2].material.ior, 1.33f, 1e-6f);
    EXPECT_EQ(m.parts[3].material.type, MaterialType::mirror);
    EXPECT_EQ(m.parts[3].name, "n3");
}

TEST_F(GltfTest, PunctualLightsAndCamerasAreReadInWorldSpace) {
    GltfDoc doc;
    doc.node({{"mesh", doc.mesh(-1)}});
    doc.j["extensionsUsed"] = {"KHR_lights_punctual"};
    doc.j["extensions"] = {
        {"KHR_lights_punctual",
         {{"lights",
           {{{"name", "bulb"}, {"type", "point"}, {"color", {1, 0.5, 0.5}}, {"intensity", 4}},
            {{"name", "torch"},
             {"type", "spot"},
             {"intensity", 10},
             {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.5}}}},
            {{"name", "sun"}, {"type", "directional"}, {"intensity", 3}}}}}}};
    const float s = std::sqrt(0.5f);  // -90° about x: -z (the light's axis) turns to -y
    doc.node(
        {{"translation", {0, 2, 0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    doc.node({{"translation", {1, 3, 0}},
              {"rotation", {-s, 0, 0, s}},
              {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
    doc.node(
        {{"rotation", {-s, 0, 0, s}}, {"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}});
    doc.j["cameras"] = {{{"type", "perspective"},
                         {"name", "view"},
                         {"perspective", {{"yfov", 0.7}, {"znear", 0.1}}}}};
    doc.node({{"camera", 0}, {"translation", {0, 1, 5}}});
    const Model m = load(doc);
    ASSERT_EQ(m.lights.size(), 3u);
    EXPECT_EQ(m.lights[0].type, LightType::point);
    EXPECT_EQ(m.lights[0].intensity, glm::vec3(4, 2, 2));
    EXPECT_NEAR(m.lights[0].position.y, 2.0f, 1e-6f);
    EXPECT_EQ(m.lights[1].type, LightType::spot);
    EXPECT_NEAR(m.lights[1].direction.y, -1.0f, 1e-5f);
    EXPECT_NEAR(m.lights[1].cone_outer, glm::degrees(0.5f), 1e-3f);
    EXPECT_NEAR(m.lights[1].cone_inner, glm::degrees(0.2f), 1e-3f);
    EXPECT_EQ(m.lights[2].type, LightType::sun);
    EXPECT_EQ(m.lights[2].irradiance, glm::vec3(3));
    EXPECT_NEAR(m.lights[2].direction.y, -1.0f, 1e-5f);
    ASSERT_EQ(m.cameras.size(), 1u);
    EXPECT_NEAR(m.cameras[0].eye.z, 5.0f, 1e-6f);
    EXPECT_NEAR(m.cameras[0].target.z, 4.0f, 1e-6f);
    EXPECT_NEAR(m.cameras[0].fov_y, glm::degrees(0.7f), 1e-3f);

    // In a scene: lights named OBJECT/LIGHT, placed by the object's transform; the glTF camera
    // stands in for a missing "camera".
    write("m.gltf", doc.gltf());
    const Scene scene = parse_scene(R"({"materials": {}, "lights": [],
        "objects": [{"name": "room", "mesh": "m.gltf", "transform": {"translate": [0, 10, 0]}}]})",
                                    path("s.json"));
    ASSERT_EQ(scene.lights.size(), 3u);
    EXPECT_EQ(scene.lights[0].name, "room/bulb");
    EXPECT_NEAR(scene.lights[0].position.y, 12.0f, 1e-5f);
    EXPECT_NEAR(scene.camera.eye.y, 11.0f, 1e-5f);
    EXPECT_NEAR(scene.camera.fov_y, glm::degrees(0.7f), 1e-3f);
}

TEST_F(GltfTest, BinaryGlbLoadsLikeGltf) {
    GltfDoc doc;
    doc.node({{"mesh", doc.mesh(doc.material({{"pbrMetallicRoughness",
                                               {{"baseColorFactor", {0.2, 0.4, 0.6, 1}}}}}))}});
    const Model m = load(doc, nullptr, true);
    ASSERT_EQ(m.parts.size(), 1u);
    EXPECT_EQ(m.parts[0].mesh.triangles.size(), 2u);
    EXPECT_NEAR(m.parts[0].material.albedo.z, 0.6f, 1e-6f);
}

// baseColorTexture with TEXCOORD_0: the image file beside the glTF is the albedo map (times the
// baseColorFactor), coordinates are per corner with v flipped to the bottom-left origin; an
// embedded image is named in a warning.
TEST_F(GltfTest, BaseColorTextureReadsTheImageAndTexcoords) {
    GltfDoc doc;
    const float uv[8] = {0, 0, 0, 1, 1, 1, 1, 0.25f};
    const size_t offset = doc.bin.size();
    doc.bin.resize(offset + sizeof uv);
    std::memcpy(doc.bin.data() + offset, uv, sizeof uv);
    doc.j["bufferViews"].push_back(
        {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", sizeof uv}});
    doc.j["accessors"].push_back(
        {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}});
    const int mat = doc.material(
        {{"pbrMetallicRoughness",
          {{"baseColorFactor", {0.5, 1, 1, 1}}, {"baseColorTexture", {{"index", 0}}}}}});
    doc.j["textures"] = {{{"source", 0}}};
    Image image(2, 2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 2; ++x) image.set_rgb(x, y, glm::vec3(0.2f + 0.2f * float(x + 2 * y)));
    write_image(image, path("tiles.exr"));
    doc.j["images"] = {{{"uri", "tiles.exr"}}};
    const int mesh = doc.mesh(mat);
    doc.j["meshes"][size_t(mesh)]["primitives"][0]["attributes"]["TEXCOORD_0"] = 2;
    doc.node({{"mesh", mesh}});
    std::string warnings;
    const Model m = load(doc, &warnings);
    ASSERT_EQ(m.parts.size(), 1u);
    const ModelPart& part = m.parts[0];
    ASSERT_TRUE(part.material.albedo_map) << warnings;
    EXPECT_EQ(part.material.albedo, glm::vec3(0.5f, 1.0f, 1.0f));
    ASSERT_EQ(part.mesh.texcoords.size(), 6u);
    // Triangle 0 is vertices 0, 1, 2: glTF (0, 0) is the image's top left, ours (0, 1).
    EXPECT_EQ(part.mesh.texcoords[0], glm::vec2(0, 1));
    EXPECT_EQ(part.mesh.texcoords[1], glm::vec2(0, 0));
    EXPECT_EQ(part.mesh.texcoords[5], glm::vec2(1, 0.75f));  // vertex 3 of triangle 1
    EXPECT_EQ(warnings.find("TEXCOORD"), std::string::npos) << warnings;
    // The image's top-left pixel (0.2) sits at glTF (¼, ¼).
    EXPECT_NEAR(part.material.albedo_map->sample({0.25f, 0.75f}).x, 0.2f, 1e-3f);

    doc.j["images"] = {{{"uri", "data:image/png;base64,AAAA"}}};
    std::string embedded;
    const Model e = load(doc, &embedded);
    EXPECT_FALSE(e.parts[0].material.albedo_map);
    EXPECT_NE(embedded.find("embedded texture images"), std::string::npos) << embedded;
}

TEST_F(GltfTest, EachUnsupportedFeatureIsNamedInAWarning) {
    GltfDoc doc;
    const int mat = doc.material({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}},
                                  {"normalTexture", {{"index", 0}}},
                                  {"alphaMode", "BLEND"}});
    doc.j["textures"] = {{{"source", 0}}};
    doc.j["images"] = {{{"uri", "missing.png"}}};
    const int mesh = doc.mesh(mat);
    doc.j["meshes"][size_t(mesh)]["primitives"][0]["attributes"]["NORMAL"] = 0;
    doc.j["meshes"][size_t(mesh)]["primitives"].push_back(
        {{"attributes", {{"POSITION", 0}}}, {"mode", 1}});  // lines
    doc.node({{"mesh", mesh}});
    doc.j["extensionsUsed"] = {"EXT_fancy"};
    doc.j["cameras"] = {
        {{"type", "orthographic"},
         {"orthographic", {{"xmag", 1}, {"ymag", 1}, {"znear", 0.1}, {"zfar", 9}}}}};
    doc.node({{"camera", 0}});
    doc.j["animations"] = Json::array({{{"channels", Json::array()}, {"samplers", Json::array()}}});
    std::string warnings;
    const Model m = load(doc, &warnings);
    EXPECT_EQ(m.parts.size(), 1u);
    for (const char* what :
         {"baseColorTexture", "normalTexture", "alphaMode BLEND", "NORMAL attribute",
          "point and line primitives", "extension EXT_fancy", "orthographic cameras", "animations"})
        EXPECT_NE(warnings.find(what), std::string::npos) << what << " in:\n" << warnings;
    EXPECT_NE(warnings.find("m.gltf"), std::string::npos);
}

// The rest of the warnings (the test above names the first eight): each remaining unsupported
// feature of a file that still loads is named, once, beside the file's name.
TEST_F(GltfTest, EveryOtherUnsupportedFeatureIsNamedInAWarning) {
    GltfDoc doc;
    Image image(1, 1);
    image.set_rgb(0, 0, glm::vec3(0.5f));
    write_image(image, path("grey.exr"));
    doc.j["images"] = {{{"uri", "grey.exr"}}};
    doc.j["textures"] = {{{"source", 0}}, Json::object()};  // texture 1 has no image source
    // A diffuse material with every texture but the base colour, partial transmission with a
    // texture, some metal and an unknown material extension.
    const int diffuse =
        doc.material({{"pbrMetallicRoughness",
                       {{"metallicFactor", 0.5}, {"metallicRoughnessTexture", {{"index", 0}}}}},
                      {"occlusionTexture", {{"index", 0}}},
                      {"emissiveTexture", {{"index", 0}}},
                      {"extensions",
                       {{"KHR_materials_transmission",
                         {{"transmissionFactor", 0.3}, {"transmissionTexture", {{"index", 0}}}}},
                        {"EXT_material_other", Json::object()}}}});
    const int glass = doc.material(
        {{"pbrMetallicRoughness", {{"metallicFactor", 0}, {"baseColorTexture", {{"index", 0}}}}},
         {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 1.0}}}}}});
    const int sourceless = doc.material(
        {{"pbrMetallicRoughness", {{"metallicFactor", 0}, {"baseColorTexture", {{"index", 1}}}}}});
    doc.j["extensionsUsed"] = {"KHR_materials_transmission", "KHR_lights_punctual"};
    for (const int mat : {diffuse, glass, sourceless}) doc.node({{"mesh", doc.mesh(mat)}});
    Json& prim = doc.j["meshes"][0]["primitives"][0];
    prim["attributes"]["TEXCOORD_1"] = 0;  // no texture reads it
    prim["attributes"]["COLOR_0"] = 0;
    prim["targets"] = {{{"POSITION", 0}}};
    doc.j["skins"] = {{{"joints", {0}}}};
    doc.j["scenes"].push_back({{"nodes", Json::array()}});
    doc.j["extensions"] = {{"KHR_lights_punctual",
                            {{"lights", {{{"type", "point"}, {"intensity", 1}, {"range", 5}}}}}}};
    doc.node({{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    std::string warnings;
    const Model m = load(doc, &warnings);
    EXPECT_EQ(m.parts.size(), 3u);
    EXPECT_EQ(m.parts[1].material.type, MaterialType::glass);
    EXPECT_FALSE(m.parts[1].material.albedo_map);
    EXPECT_FALSE(m.parts[2].material.albedo_map);
    for (const char* what :
         {"metallicRoughnessTexture", "occlusionTexture", "emissiveTexture", "transmissionTexture",
          "material extension EXT_material_other", "partial transmission",
          "metallic surfaces that are not mirrors", "baseColorTexture on glass or mirrors",
          "textures without an image source", "TEXCOORD_1 without a texture", "COLOR_0 attribute",
          "morph targets", "skins", "scenes other than the default", "light range"})
        EXPECT_NE(warnings.find(what), std::string::npos) << what << " in:\n" << warnings;
    // Each named once, every line naming the file.
    EXPECT_EQ(warnings.find("skins"), warnings.rfind("skins")) << warnings;
    std::istringstream lines(warnings);
    for (std::string line; std::getline(lines, line);) {
        if (line.empty()) continue;
        EXPECT_NE(line.find("m.gltf"), std::string::npos) << line;
    }
}

// The warnings left: degenerate triangles dropped (with the count), an unknown light type, and
// what tinygltf itself warns about, passed on line by line with the file's name.
TEST_F(GltfTest, DegenerateTrianglesUnknownLightsAndTinygltfWarnings) {
    GltfDoc doc;
    // A second index list over the same positions whose second triangle repeats a vertex.
    const uint16_t idx[6] = {0, 1, 2, 0, 0, 3};
    const size_t offset = doc.bin.size();
    doc.bin.resize(offset + sizeof idx);
    std::memcpy(doc.bin.data() + offset, idx, sizeof idx);
    doc.j["bufferViews"].push_back(
        {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", sizeof idx}});
    doc.j["accessors"].push_back(
        {{"bufferView", 2}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}});
    doc.j["meshes"].push_back(
        {{"name", "pinched"},
         {"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 2}}}}});
    doc.node({{"mesh", 0}});
    doc.j["extensionsUsed"] = {"KHR_lights_punctual"};
    doc.j["extensions"] = {
        {"KHR_lights_punctual", {{"lights", {{{"type", "area"}, {"intensity", 1}}}}}}};
    doc.node({{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    doc.j["images"] = {{{"uri", "missing.png"}}};  // tinygltf warns that it cannot read it
    std::string warnings;
    const Model m = load(doc, &warnings);
    ASSERT_EQ(m.parts.size(), 1u);
    EXPECT_EQ(m.parts[0].mesh.triangles.size(), 1u);
    EXPECT_NE(warnings.find("dropped 1 of 2 triangles as degenerate"), std::string::npos)
        << warnings;
    EXPECT_NE(warnings.find("light type area"), std::string::npos) << warnings;
    EXPECT_TRUE(m.lights.empty());
    std::istringstream lines(warnings);
    int count = 0;
    for (std::string line; std::getline(lines, line);) {
        if (line.empty()) continue;
        ++count;
        EXPECT_NE(line.find("m.gltf"), std::string::npos) << line;
    }
    EXPECT_NE(warnings.find("Failed to load external 'uri' for image[0]"), std::string::npos)
        << "tinygltf's own warning:\n"
        << warnings;
    EXPECT_GE(count, 3) << warnings;
}

TEST_F(GltfTest, BadInputIsAnErrorNamingTheFile) {
    {
        GltfDoc doc;
        const int mesh = doc.mesh(-1);
        doc.j["meshes"][size_t(mesh)]["primitives"][0]["indices"] = 7;
        doc.node({{"mesh", mesh}});
        try {
            load(doc);
            FAIL() << "expected an InputError";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("m.gltf"), std::string::npos) << e.what();
        }
    }
    {
        GltfDoc doc;  // an index past the positions
        doc.bin[12 * 4 + 2] = 9;
        doc.node({{"mesh", doc.mesh(-1)}});
        EXPECT_THROW(load(doc), InputError);
    }
    EXPECT_THROW(load_gltf(write("bad.gltf", "{ not json")), InputError);
    EXPECT_THROW(load_gltf(path("absent.gltf")), InputError);
    GltfDoc empty;
    EXPECT_THROW(load(empty), InputError);  // no meshes
}

// Files a glTF names are read only if they are regular files: an image `uri` naming a folder
// made tinygltf's reader allocate 2^63 - 1 bytes (std::bad_alloc escaped the load), one naming
// /dev/zero made OpenImageIO read forever; a buffer naming a device is an error naming it.
// (Before the fix the folder image gave std::bad_alloc, not a warning.)
TEST_F(GltfTest, ImagesAndBuffersThatAreNotRegularFilesAreNotRead) {
    for (const std::string& uri : {path("a_folder"), std::string("/dev/zero")}) {
        std::filesystem::create_directories(path("a_folder"));
        GltfDoc doc;
        const int mat = doc.material(
            {{"pbrMetallicRoughness",
              {{"baseColorFactor", {0.5, 1, 1, 1}}, {"baseColorTexture", {{"index", 0}}}}}});
        doc.j["textures"] = {{{"source", 0}}};
        doc.j["images"] = {{{"uri", uri}}};
        doc.node({{"mesh", doc.mesh(mat)}});
        std::string warnings;
        test::within_deadline(std::chrono::seconds(20), [&] {
            const Model m = load(doc, &warnings);
            ASSERT_EQ(m.parts.size(), 1u);
            EXPECT_FALSE(m.parts[0].material.albedo_map);
        });
        EXPECT_NE(warnings.find(uri + ": cannot read image: expected a regular file"),
                  std::string::npos)
            << warnings;
    }
    GltfDoc doc;
    doc.node({{"mesh", doc.mesh(-1)}});
    Json j = nlohmann::json::parse(doc.gltf());
    j["buffers"][0]["uri"] = "/dev/zero";
    try {
        load_gltf(write("device_buffer.gltf", j.dump()));
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("device_buffer.gltf: cannot read glTF:"),
                  std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("/dev/zero"), std::string::npos) << e.what();
    }
}

TEST(ExternalScenes, KhronosBoxLoadsThroughItsScene) {
    const std::filesystem::path file =
        std::filesystem::path(AG_SOURCE_DIR) / "scenes" / "box_gltf.json";
    if (!test::missing_external_meshes(file).empty())
        GTEST_SKIP() << "../shared/external-scenes is absent: " << file << " needs it";
    const Scene scene = load_scene(file.string());
    size_t triangles = 0;
    for (size_t i = 0; i < scene.objects.size(); ++i)
        if (const Object& o = scene.objects[i]; o.source.find("Box.gltf") != std::string::npos) {
            // The mesh as loaded (a tiled layout splits it: lightmap.refine_tile).
            const bool split =
                i < scene.unsplit_meshes.size() && !scene.unsplit_meshes[i].triangles.empty();
            triangles += (split ? scene.unsplit_meshes[i] : o.mesh).triangles.size();
            EXPECT_NEAR(o.material.albedo.x, 0.8f, 1e-6f);
            EXPECT_EQ(o.material.albedo.y, 0.0f);
        }
    EXPECT_EQ(triangles, 12u);
}

}  // namespace
}  // namespace ag
