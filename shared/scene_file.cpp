// JSON scene files (docs/scene-format.md): parse with duplicate-key detection, validate every
// value with its JSON path, build objects, lights and camera, then derive surfaces and the atlas.
#include "shared/scene_file.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/gtc/quaternion.hpp>
#include <map>
#include <set>
#include <sstream>

#include "shared/charts.h"
#include "shared/input_error.h"
#include "shared/json_read.h"
#include "shared/mesh_decimate.h"
#include "shared/mesh_io.h"
#include "shared/model_io.h"
#include "shared/scene_edit.h"
#include "shared/settings_json.h"
#include "shared/shapes.h"

namespace ag {
namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

constexpr double kMaxSigma = 1e6;     // per scene unit
constexpr double kMaxPhaseK = 0.999;  // Schlick k; |k| → 1 is a delta peak
constexpr std::array kShapeNames = {"box",         "sphere",       "quad",
                                    "bumpy_plane", "lumpy_sphere", "torus"};
enum class ShapeType { box, sphere, quad, bumpy_plane, lumpy_sphere, torus };

std::string format_vec(const glm::vec3& v) {
    return "[" + JsonInput::format_number(v.x) + ", " + JsonInput::format_number(v.y) + ", " +
           JsonInput::format_number(v.z) + "]";
}

// 1-based line and column of the character at 0-based `index` (clamped to the end of `text`).
std::string line_column(const std::string& text, size_t index) {
    index = std::min(index, text.size());
    size_t line = 1, line_start = 0;
    for (size_t i = 0; i < index; ++i)
        if (text[i] == '\n') {
            ++line;
            line_start = i + 1;
        }
    return "line " + std::to_string(line) + ", column " + std::to_string(index - line_start + 1);
}

// nlohmann keeps the last of repeated keys silently; a repeated key in a scene file is almost
// always a copy-paste slip, so the parser callback tracks the JSON path and rejects it.
Json parse_json(const std::string& text, const std::string& file) {
    struct Frame {
        bool is_array = false;
        long index = -1;
        std::string key;
        std::set<std::string> keys;
    };
    std::vector<Frame> stack;
    auto element_starts = [&] {
        if (!stack.empty() && stack.back().is_array) ++stack.back().index;
    };
    auto callback = [&](int, Json::parse_event_t event, Json& parsed) {
        switch (event) {
            case Json::parse_event_t::object_start:
                element_starts();
                stack.push_back({false});
                break;
            case Json::parse_event_t::array_start:
                element_starts();
                stack.push_back({true});
                break;
            case Json::parse_event_t::object_end:
            case Json::parse_event_t::array_end:
                stack.pop_back();
                break;
            case Json::parse_event_t::key: {
                Frame& frame = stack.back();
                frame.key = parsed.get<std::string>();
                if (!frame.keys.insert(frame.key).second) {
                    std::string path;
                    for (const Frame& f : stack)
                        path = f.is_array ? JsonInput::child(path, size_t(f.index))
                                          : JsonInput::child(path, f.key);
                    throw_input_error(file, path, "duplicate key; expected each key once");
                }
                break;
            }
            case Json::parse_event_t::value:
                element_starts();
                break;
        }
        return true;
    };
    try {
        return Json::parse(text, callback, /*allow_exceptions=*/true, /*ignore_comments=*/true);
    } catch (const Json::parse_error& e) {
        // e.byte is the 1-based offset of the last character read.
        std::string message = e.what();
        const size_t column = message.find("column ");
        const size_t colon = message.find(": ", column == std::string::npos ? 0 : column);
        if (colon != std::string::npos) message = message.substr(colon + 2);
        throw_input_error(file, line_column(text, e.byte > 0 ? e.byte - 1 : 0),
                          "invalid JSON: " + message);
    } catch (const Json::out_of_range& e) {
        // Number overflow ("1e999"): nlohmann names the literal but not where it is.
        std::string message = e.what();
        const size_t open = message.find('\''), close = message.rfind('\'');
        std::string place;
        if (open != std::string::npos && close > open) {
            const size_t at = text.find(message.substr(open + 1, close - open - 1));
            if (at != std::string::npos) place = line_column(text, at);
            message = "number " + message.substr(open, close - open + 1) +
                      " is out of range; expected a finite number";
        }
        throw_input_error(file, place, message);
    }
}

class SceneParser {
public:
    SceneParser(const std::string& path, int64_t max_triangles)
        : in_(path), base_(fs::path(path).parent_path()), max_triangles_(max_triangles) {}

    Scene parse(const Json& root) {
        const auto start = std::chrono::steady_clock::now();
        in_.object(root, "");
        in_.check_keys(root, "",
                       {"name", "units", "camera", "materials", "lights", "objects", "media",
                        "settings", "script"});
        scene_.path = in_.file();
        scene_.name = fs::path(in_.file()).stem().string();
        if (const Json* v = JsonInput::find(root, "name")) scene_.name = in_.string(*v, "/name");
        if (const Json* v = JsonInput::find(root, "units"))
            scene_.length_unit = in_.string(*v, "/units");
        if (const Json* v = JsonInput::find(root, "settings"))
            read_settings(*v, scene_.settings, in_.file(), "/settings");
        read_materials(in_.require(root, "", "materials", "an object of named materials"));
        read_lights(in_.require(root, "", "lights", "an array of lights (may be empty)"));
        read_objects(in_.require(root, "", "objects", "an array of objects"));
        if (const Json* v = JsonInput::find(root, "media")) read_media(*v);
        // Without "camera" the first camera of a glTF object is used.
        if (JsonInput::find(root, "camera") || model_cameras_.empty()) {
            read_camera(in_.require(root, "", "camera", "a camera {eye, target, ...}"));
        } else {
            const ModelCamera& c = model_cameras_.front();
            scene_.camera.eye = c.eye;
            scene_.camera.target = c.target;
            scene_.camera.up = c.up;
            scene_.camera.fov_y = std::clamp(c.fov_y, float(kMinFovY), float(kMaxFovY));
            std::string key;
            if (const std::string problem = camera_problem(scene_.camera, key); !problem.empty())
                in_.fail("/objects", "the glTF camera \"" + c.name + "\": " + problem);
        }
        add_mesh_lights(scene_);
        update_sun_discs(scene_);
        check_light_samples(scene_);
        check_photon_budget(scene_);
        if (const Json* v = JsonInput::find(root, "script"))
            scene_.script = existing_file(*v, "/script", "Lua script");
        init_versions(scene_);
        const double files =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        make_surfaces_and_atlas(scene_);
        warn_about_scale(scene_);
        scene_.load_timing.files = files;
        return std::move(scene_);
    }

private:
    // A path relative to the scene file, which must name an existing regular file.
    std::string existing_file(const Json& value, const std::string& path, const char* what) {
        const std::string name = in_.string(value, path);
        const fs::path resolved = fs::path(name).is_absolute() ? fs::path(name) : base_ / name;
        std::error_code ec;
        if (!fs::is_regular_file(resolved, ec))
            in_.fail(path, std::string("expected an existing ") + what + " file, got \"" + name +
                               "\" (looked for " + resolved.string() + ")");
        return resolved.string();
    }

    void read_camera(const Json& json) {
        const std::string path = "/camera";
        in_.object(json, path);
        in_.check_keys(json, path, {"eye", "target", "up", "fov_y", "resolution"});
        Camera& c = scene_.camera;
        c.eye =
            in_.vec3(in_.require(json, path, "eye", "[x, y, z]"), path + "/eye", kMaxCoordinate);
        c.target = in_.vec3(in_.require(json, path, "target", "[x, y, z]"), path + "/target",
                            kMaxCoordinate);
        if (const Json* v = JsonInput::find(json, "up")) c.up = in_.vec3(*v, path + "/up");
        if (const Json* v = JsonInput::find(json, "fov_y"))
            c.fov_y = float(in_.number(*v, path + "/fov_y", kMinFovY, kMaxFovY));
        if (const Json* v = JsonInput::find(json, "resolution")) {
            const std::string rpath = path + "/resolution";
            if (!v->is_array() || v->size() != 2)
                in_.fail(rpath, "expected [width, height], got " + JsonInput::describe(*v));
            c.width = int(in_.integer((*v)[0], rpath + "/0", 1, 16384));
            c.height = int(in_.integer((*v)[1], rpath + "/1", 1, 16384));
        }
        std::string key;
        if (const std::string problem = camera_problem(c, key); !problem.empty())
            in_.fail(path + "/" + key, problem);
    }

    void read_materials(const Json& json) {
        const std::string path = "/materials";
        in_.object(json, path);
        for (const auto& item : json.items()) {
            const std::string mpath = JsonInput::child(path, item.key());
            const Json& m = in_.object(item.value(), mpath);
            if (item.key().empty()) in_.fail(mpath, "expected a non-empty material name");
            in_.check_keys(m, mpath,
                           {"type", "albedo", "albedo_map", "ior", "emission", "light", "interior",
                            "ior_noise"});
            Material mat;
            mat.name = item.key();
            if (const Json* v = JsonInput::find(m, "type"))
                mat.type = MaterialType(in_.choice(*v, mpath + "/type", kMaterialTypeNames));
            // Specular albedo tints the reflected/refracted light; untinted unless given.
            if (mat.type != MaterialType::diffuse) mat.albedo = glm::vec3(1.0f);
            if (const Json* v = JsonInput::find(m, "albedo"))
                mat.albedo = in_.color(*v, mpath + "/albedo", 0, 1);
            if (const Json* v = JsonInput::find(m, "ior")) {
                if (mat.type != MaterialType::glass)
                    in_.fail(mpath + "/ior", "ior applies to glass only; expected no ior for a " +
                                                 std::string(kMaterialTypeNames[size_t(mat.type)]) +
                                                 " material");
                mat.ior = float(in_.number(*v, mpath + "/ior", 1, 4));
            }
            if (const Json* v = JsonInput::find(m, "emission"))
                mat.emission = in_.color(*v, mpath + "/emission", 0, kMaxLightValue);
            if (const Json* v = JsonInput::find(m, "light"))
                mat.emits_light = in_.boolean(*v, mpath + "/light");
            if (const Json* v = JsonInput::find(m, "albedo_map")) {
                if (mat.type != MaterialType::diffuse)
                    in_.fail(mpath + "/albedo_map",
                             "an albedo map applies to diffuse materials only");
                const std::string file = existing_file(*v, mpath + "/albedo_map", "image");
                try {
                    mat.albedo_map = textures_.get(file);
                } catch (const InputError& e) {
                    in_.fail(mpath + "/albedo_map",
                             std::string("expected a readable image: ") + e.what());
                }
                // Without "albedo" the texture alone is the albedo.
                if (!JsonInput::find(m, "albedo")) mat.albedo = glm::vec3(1.0f);
            }
            for (const char* key : {"interior", "ior_noise"})
                if (JsonInput::find(m, key) && mat.type != MaterialType::glass)
                    in_.fail(mpath + "/" + key,
                             std::string(key) + " applies to glass only; expected no " + key +
                                 " for a " + kMaterialTypeNames[size_t(mat.type)] + " material");
            if (const Json* v = JsonInput::find(m, "interior")) {
                mat.has_interior = true;
                mat.interior = read_medium(*v, mpath + "/interior", false);
            }
            if (const Json* v = JsonInput::find(m, "ior_noise")) {
                // n(p) = ior + noise(p) must stay ≥ 1 everywhere.
                mat.ior_noise = read_noise(*v, mpath + "/ior_noise", mat.ior - 1.0);
            }
            materials_[mat.name] = mat;
        }
    }

    void read_lights(const Json& json) {
        const std::string path = "/lights";
        in_.array(json, path);
        for (size_t i = 0; i < json.size(); ++i) {
            const std::string lpath = JsonInput::child(path, i);
            const Json& l = in_.object(json[i], lpath);
            Light light;
            light.type =
                LightType(in_.choice(in_.require(l, lpath, "type", "point, quad, sun or spot"),
                                     lpath + "/type", kLightTypeNames));
            if (light.type == LightType::mesh)
                in_.fail(
                    lpath + "/type",
                    "expected point, quad, sun or spot, got \"mesh\" (mesh lights are the objects "
                    "whose material has an emission)");
            if (light.type == LightType::point)
                in_.check_keys(l, lpath, {"name", "type", "position", "intensity", "enabled"});
            else if (light.type == LightType::sun)
                in_.check_keys(l, lpath, {"name", "type", "direction", "irradiance", "enabled"});
            else if (light.type == LightType::spot)
                in_.check_keys(l, lpath,
                               {"name", "type", "position", "direction", "intensity", "cone_outer",
                                "cone_inner", "enabled"});
            else
                in_.check_keys(l, lpath, {"name", "type", "corners", "radiance", "enabled"});
            light.name =
                in_.string(in_.require(l, lpath, "name", "a unique light name"), lpath + "/name");
            if (scene_.find_light(light.name) >= 0)
                in_.fail(lpath + "/name",
                         "expected a unique light name, got \"" + light.name + "\" a second time");
            if (const Json* v = JsonInput::find(l, "enabled"))
                light.enabled = in_.boolean(*v, lpath + "/enabled");
            if (light.type == LightType::sun || light.type == LightType::spot) {
                const std::string dpath = lpath + "/direction";
                const glm::vec3 d =
                    in_.vec3(in_.require(l, lpath, "direction", "[x, y, z] light travels"), dpath);
                if (!safe_normalize(d, light.direction))
                    in_.fail(dpath, "expected a non-zero direction, got " + format_vec(d));
            }
            if (light.type == LightType::sun) {
                light.irradiance =
                    in_.color(in_.require(l, lpath, "irradiance", "[r, g, b] in W/unit²"),
                              lpath + "/irradiance", 0, kMaxLightValue);
            } else if (light.type == LightType::spot) {
                light.position = in_.vec3(in_.require(l, lpath, "position", "[x, y, z]"),
                                          lpath + "/position", kMaxCoordinate);
                light.intensity = in_.color(in_.require(l, lpath, "intensity", "[r, g, b] in W/sr"),
                                            lpath + "/intensity", 0, kMaxLightValue);
                light.cone_outer =
                    float(in_.number(in_.require(l, lpath, "cone_outer", "a half-angle in (0, 90]"),
                                     lpath + "/cone_outer", 0, 90, true));
                light.cone_inner = light.cone_outer;
                if (const Json* v = JsonInput::find(l, "cone_inner"))
                    light.cone_inner =
                        float(in_.number(*v, lpath + "/cone_inner", 0, light.cone_outer));
            } else if (light.type == LightType::point) {
                light.position = in_.vec3(in_.require(l, lpath, "position", "[x, y, z]"),
                                          lpath + "/position", kMaxCoordinate);
                light.intensity = in_.color(in_.require(l, lpath, "intensity", "[r, g, b] in W/sr"),
                                            lpath + "/intensity", 0, kMaxLightValue);
            } else {
                read_quad_corners(in_.require(l, lpath, "corners", "4 corners [[x, y, z], ...]"),
                                  lpath + "/corners", light);
                light.radiance =
                    in_.color(in_.require(l, lpath, "radiance", "[r, g, b] in W/(sr·unit²)"),
                              lpath + "/radiance", 0, kMaxLightValue);
            }
            scene_.lights.push_back(light);
        }
    }

    // A medium {bounds, sigma_s, sigma_a, phase_k, noise}; `bounds` only for a scene medium.
    Medium read_medium(const Json& json, const std::string& path, bool with_bounds) {
        in_.object(json, path);
        if (with_bounds)
            in_.check_keys(json, path, {"bounds", "sigma_s", "sigma_a", "phase_k", "noise"});
        else
            in_.check_keys(json, path, {"sigma_s", "sigma_a", "phase_k", "noise"});
        Medium m;
        if (with_bounds) {
            const std::string bpath = path + "/bounds";
            const Json& b = in_.object(
                in_.require(json, path, "bounds", "{\"min\": [x, y, z], \"max\": [x, y, z]}"),
                bpath);
            in_.check_keys(b, bpath, {"min", "max"});
            m.bounds.min =
                in_.vec3(in_.require(b, bpath, "min", "[x, y, z]"), bpath + "/min", kMaxCoordinate);
            m.bounds.max =
                in_.vec3(in_.require(b, bpath, "max", "[x, y, z]"), bpath + "/max", kMaxCoordinate);
            for (int a = 0; a < 3; ++a)
                if (!(m.bounds.min[a] < m.bounds.max[a]))
                    in_.fail(bpath + "/max", "expected max > min on every axis, got min " +
                                                 format_vec(m.bounds.min) + " and max " +
                                                 format_vec(m.bounds.max));
        }
        m.sigma_s = float(in_.number(in_.require(json, path, "sigma_s", "a number >= 0 per unit"),
                                     path + "/sigma_s", 0, kMaxSigma));
        m.sigma_a = float(in_.number(in_.require(json, path, "sigma_a", "a number >= 0 per unit"),
                                     path + "/sigma_a", 0, kMaxSigma));
        if (const Json* v = JsonInput::find(json, "phase_k"))
            m.phase_k = float(in_.number(*v, path + "/phase_k", -kMaxPhaseK, kMaxPhaseK));
        if (const Json* v = JsonInput::find(json, "noise"))
            m.noise = read_noise(*v, path + "/noise", 1.0);
        return m;
    }

    // {amplitude, frequency, seed}: amplitude in [0, max_amplitude].
    MediumNoise read_noise(const Json& json, const std::string& path, double max_amplitude) {
        in_.object(json, path);
        in_.check_keys(json, path, {"amplitude", "frequency", "seed"});
        MediumNoise n;
        n.amplitude = float(in_.number(in_.require(json, path, "amplitude", "a number >= 0"),
                                       path + "/amplitude", 0, max_amplitude));
        n.frequency = float(in_.number(in_.require(json, path, "frequency", "a number > 0"),
                                       path + "/frequency", 0, 1e6, true));
        if (const Json* v = JsonInput::find(json, "seed"))
            n.seed = uint32_t(in_.integer(*v, path + "/seed", 0, 4294967295ll));
        return n;
    }

    void read_media(const Json& json) {
        const std::string path = "/media";
        in_.array(json, path);
        for (size_t i = 0; i < json.size(); ++i) {
            const std::string mpath = JsonInput::child(path, i);
            const Medium m = read_medium(json[i], mpath, true);
            // Disjoint boxes: every point lies in at most one medium (docs/media.md).
            for (size_t j = 0; j < scene_.media.size(); ++j) {
                const Bounds& o = scene_.media[j].bounds;
                if (glm::all(glm::lessThan(m.bounds.min, o.max)) &&
                    glm::all(glm::lessThan(o.min, m.bounds.max)))
                    in_.fail(mpath + "/bounds",
                             "expected media boxes that do not overlap; this "
                             "one overlaps /media/" +
                                 std::to_string(j));
            }
            scene_.media.push_back(m);
        }
    }

    void read_quad_corners(const Json& json, const std::string& path, Light& light) {
        if (!json.is_array() || json.size() != 4)
            in_.fail(path, "expected 4 corners [[x, y, z], ...], got " + JsonInput::describe(json));
        for (size_t k = 0; k < 4; ++k)
            light.corners[k] = in_.vec3(json[k], JsonInput::child(path, k), kMaxCoordinate);
        const std::array<glm::vec3, 4>& c = light.corners;
        const glm::vec3 e1 = c[1] - c[0], e3 = c[3] - c[0];
        const float scale = std::max(glm::length(e1), glm::length(e3));
        if (!(glm::length(glm::cross(e1, e3)) > 1e-6f * scale * scale))
            in_.fail(path,
                     "expected a parallelogram of non-zero area, got corners 0, 1 and 3 "
                     "on one line");
        const glm::vec3 expected = c[1] + c[3] - c[0];
        if (glm::length(c[2] - expected) > 1e-4f * scale)
            in_.fail(path + "/2",
                     "expected a parallelogram: corner 2 = corner 1 + corner 3 - "
                     "corner 0 = " +
                         format_vec(expected) + ", got " + format_vec(c[2]));
    }

    void read_objects(const Json& json) {
        const std::string path = "/objects";
        in_.array(json, path);
        if (json.empty()) in_.fail(path, "expected at least one object, got an empty array");
        for (size_t i = 0; i < json.size(); ++i) {
            const std::string opath = JsonInput::child(path, i);
            const Json& o = in_.object(json[i], opath);
            in_.check_keys(o, opath,
                           {"name", "material", "materials", "dynamic", "mesh", "scale", "decimate",
                            "shape", "offset", "transform"});
            Object object;
            object.name =
                in_.string(in_.require(o, opath, "name", "a unique object name"), opath + "/name");
            if (scene_.find_object(object.name) >= 0)
                in_.fail(opath + "/name", "expected a unique object name, got \"" + object.name +
                                              "\" a second time");
            if (const Json* v = JsonInput::find(o, "dynamic"))
                object.dynamic = in_.boolean(*v, opath + "/dynamic");
            Transform transform;
            if (const Json* v = JsonInput::find(o, "transform"))
                transform = read_transform(*v, opath + "/transform");

            // An OBJ without "material" brings its own: one object per file material.
            const Json* mesh = JsonInput::find(o, "mesh");
            const Json* material = JsonInput::find(o, "material");
            std::vector<Object> parts;
            if (mesh && !material && JsonInput::find(o, "shape") == nullptr) {
                if (JsonInput::find(o, "decimate"))
                    in_.fail(opath + "/decimate",
                             "decimate applies to a mesh read as one object; expected a "
                             "\"material\" beside it");
                parts = read_model(o, opath, object, transform);
            } else {
                if (JsonInput::find(o, "materials"))
                    in_.fail(opath + "/materials",
                             "material overrides apply to OBJ meshes read with their own "
                             "materials; expected no \"materials\" next to \"material\" or "
                             "\"shape\"");
                object.material = find_material(
                    in_.string(in_.require(o, opath, "material", "the name of a material"),
                               opath + "/material"),
                    opath + "/material");
                read_geometry(o, opath, object);
                parts.push_back(std::move(object));
            }
            for (Object& part : parts) {
                part.transform = transform;
                if (const std::string problem = placement_problem(part.mesh, part.transform);
                    !problem.empty())
                    in_.fail(opath + "/transform", problem);
                if (scene_.find_object(part.name) >= 0)
                    in_.fail(opath + "/name", "expected a unique object name, got \"" + part.name +
                                                  "\" a second time");
                triangles_ += int64_t(part.mesh.triangles.size());
                if (triangles_ > max_triangles_)
                    in_.fail(opath, "expected at most " + std::to_string(max_triangles_) +
                                        " triangles in the scene (kMaxSceneTriangles), got " +
                                        std::to_string(triangles_) + " with this object");
                scene_.objects.push_back(std::move(part));
            }
        }
    }

    const Material& find_material(const std::string& material, const std::string& path) {
        const auto it = materials_.find(material);
        if (it == materials_.end()) {
            std::string list;
            for (const auto& [name, unused] : materials_) list += (list.empty() ? "" : ", ") + name;
            in_.fail(path, "unknown material \"" + material + "\"; expected one of " +
                               (list.empty() ? "(none defined)" : list));
        }
        return it->second;
    }

    // An OBJ with its MTL materials: one object per material ("NAME/MATERIAL" when there are
    // several), each material mapped from the file unless "materials" names a scene material for
    // it. Other formats carry no materials, so they need "material".
    std::vector<Object> read_model(const Json& o, const std::string& opath, const Object& base,
                                   const Transform& transform) {
        const Json& mesh = *JsonInput::find(o, "mesh");
        const std::string file = existing_file(mesh, opath + "/mesh", "mesh");
        std::string ext = fs::path(file).extension().string();
        for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
        if (ext != ".obj" && ext != ".gltf" && ext != ".glb")  // only these bring materials
            in_.require(o, opath, "material", "the name of a material");
        Model model;
        try {
            model = load_model(file, max_triangles_ - triangles_);
        } catch (const InputError& e) {
            in_.fail(opath + "/mesh", std::string("expected a usable mesh; ") + e.what());
        }
        std::map<std::string, std::string> overrides;
        if (const Json* v = JsonInput::find(o, "materials")) {
            const std::string mpath = opath + "/materials";
            in_.object(*v, mpath);
            for (const auto& item : v->items()) {
                const std::string ipath = JsonInput::child(mpath, item.key());
                const bool known =
                    std::any_of(model.parts.begin(), model.parts.end(),
                                [&](const ModelPart& p) { return p.material.name == item.key(); });
                if (!known) {
                    std::string list;
                    std::set<std::string> listed;
                    for (const ModelPart& p : model.parts)
                        if (listed.insert(p.material.name).second)
                            list += (list.empty() ? "" : ", ") + p.material.name;
                    in_.fail(ipath, "unknown material \"" + item.key() + "\" in " + file +
                                        "; expected one of " + list);
                }
                const std::string name = in_.string(item.value(), ipath);
                find_material(name, ipath);
                overrides[item.key()] = name;
            }
        }
        std::vector<Object> parts;
        for (ModelPart& part : model.parts) {
            Object object = base;
            object.name = model.parts.size() == 1 ? base.name : base.name + "/" + part.name;
            const auto it = overrides.find(part.material.name);
            object.material = it != overrides.end() ? materials_[it->second] : part.material;
            object.mesh = std::move(part.mesh);
            object.source = mesh.get<std::string>();
            finish_mesh(o, opath, object);
            parts.push_back(std::move(object));
        }
        // The file's lights and cameras are placed as its meshes: scale, offset, transform.
        glm::vec3 scale(1.0f), offset(0.0f);
        if (const Json* v = JsonInput::find(o, "scale"))
            scale = v->is_number() ? glm::vec3(float(v->get<double>())) : in_.vec3(*v, opath);
        if (const Json* v = JsonInput::find(o, "offset")) offset = in_.vec3(*v, opath + "/offset");
        const auto place = [&](const glm::vec3& p) {
            return transform.apply_point(scale * p + offset);
        };
        const auto turn = [&](const glm::vec3& d) {
            glm::vec3 unit(0.0f, -1.0f, 0.0f);
            safe_normalize(transform.apply_vector(d / scale), unit);
            return unit;
        };
        for (Light l : model.lights) {
            l.name = base.name + "/" + l.name;
            l.position = place(l.position);
            l.direction = turn(l.direction);
            if (scene_.find_light(l.name) >= 0)
                in_.fail(opath + "/name", "expected light names of " + file +
                                              " unique in the scene, got \"" + l.name +
                                              "\" a second time");
            scene_.lights.push_back(l);
        }
        for (ModelCamera c : model.cameras) {
            c.eye = place(c.eye);
            c.target = place(c.target);
            c.up = turn(c.up);
            model_cameras_.push_back(c);
        }
        return parts;
    }

    void read_geometry(const Json& o, const std::string& opath, Object& object) {
        const Json* mesh = JsonInput::find(o, "mesh");
        const Json* shape = JsonInput::find(o, "shape");
        if (mesh && shape) in_.fail(opath, "expected either \"mesh\" or \"shape\", got both");
        if (!mesh && !shape)
            in_.fail(opath, "missing key \"mesh\" or \"shape\"; expected one of them");
        if (mesh) {
            const std::string file = existing_file(*mesh, opath + "/mesh", "mesh");
            try {
                object.mesh = load_mesh(file);
            } catch (const InputError& e) {
                in_.fail(opath + "/mesh", std::string("expected a usable mesh; ") + e.what());
            }
            object.source = mesh->get<std::string>();
            if (const Json* v = JsonInput::find(o, "decimate")) {
                // Quadric-error decimation to at most this many vertices (Barczak's ~3000-vertex
                // bunny from the 35k-vertex scan).
                const long long target = in_.integer(*v, opath + "/decimate", 4, 1000000000ll);
                if (size_t(target) < object.mesh.positions.size()) {
                    try {
                        object.mesh = decimate_mesh(object.mesh, size_t(target));
                    } catch (const std::invalid_argument& e) {
                        in_.fail(opath + "/decimate",
                                 std::string("expected a manifold mesh to decimate; ") + e.what());
                    }
                }
            }
            finish_mesh(o, opath, object);
            return;
        }
        if (JsonInput::find(o, "decimate"))
            in_.fail(opath + "/decimate", "decimate applies to meshes only; expected a \"mesh\"");
        if (JsonInput::find(o, "scale"))
            in_.fail(opath + "/scale",
                     "scale applies to meshes only; expected the size in "
                     "the shape itself");
        object.mesh = read_shape(*shape, opath + "/shape");
        object.source = (*shape)["type"].get<std::string>();
        apply_offset(o, opath, object);
    }

    // Scale (meshes only) and offset, then the world-size check of every vertex.
    void finish_mesh(const Json& o, const std::string& opath, Object& object) {
        {
            if (const Json* v = JsonInput::find(o, "scale")) {
                const std::string spath = opath + "/scale";
                const glm::vec3 s =
                    v->is_number() ? glm::vec3(float(in_.number(*v, spath))) : in_.vec3(*v, spath);
                if (s.x == 0.0f || s.y == 0.0f || s.z == 0.0f)
                    in_.fail(spath, "expected non-zero scale factors, got " + format_vec(s));
                scale_mesh(object.mesh, s);
                const size_t total = object.mesh.triangles.size();
                const int dropped = remove_degenerate_triangles(object.mesh);
                if (object.mesh.triangles.empty())
                    in_.fail(spath,
                             "expected a scale that leaves triangles of non-zero area, got " +
                                 format_vec(s) + ", which makes all " + std::to_string(total) +
                                 " triangles degenerate");
                if (dropped > 0)
                    warn(in_.file() + ": " + spath + ": dropped " + std::to_string(dropped) +
                         " triangles made degenerate by the scale");
            }
        }
        apply_offset(o, opath, object);
    }

    void apply_offset(const Json& o, const std::string& opath, Object& object) {
        if (const Json* v = JsonInput::find(o, "offset")) {
            const glm::vec3 offset = in_.vec3(*v, opath + "/offset", kMaxCoordinate);
            for (glm::vec3& p : object.mesh.positions) p += offset;
        }
        for (const glm::vec3& p : object.mesh.positions)
            if (const std::string problem = position_problem(p); !problem.empty())
                in_.fail(opath, "vertex positions after scale and offset: " + problem);
    }

    // Positive finite extents: [x, y, z] for a box, [width, depth] for planes.
    glm::vec3 positive_size(const Json& json, const std::string& path, int n) {
        const char* form = n == 3 ? "[x, y, z]" : "[width, depth]";
        if (!json.is_array() || int(json.size()) != n)
            in_.fail(path, std::string("expected ") + form + " of positive numbers, got " +
                               JsonInput::describe(json));
        glm::vec3 size(0.0f);
        for (int k = 0; k < n; ++k)
            size[k] = float(in_.number(json[size_t(k)], JsonInput::child(path, size_t(k)), 0,
                                       2.0 * kMaxCoordinate, true));
        return size;
    }

    Mesh read_shape(const Json& json, const std::string& path) {
        in_.object(json, path);
        const auto type = ShapeType(
            in_.choice(in_.require(json, path, "type",
                                   "box, sphere, quad, bumpy_plane, lumpy_sphere or torus"),
                       path + "/type", kShapeNames));
        Mesh mesh;
        switch (type) {
            case ShapeType::box: {
                in_.check_keys(json, path, {"type", "size", "open_bottom"});
                mesh = make_box(
                    positive_size(in_.require(json, path, "size", "[x, y, z]"), path + "/size", 3));
                if (const Json* v = JsonInput::find(json, "open_bottom");
                    v && in_.boolean(*v, path + "/open_bottom"))
                    remove_bottom(mesh);
                break;
            }
            case ShapeType::sphere: {
                in_.check_keys(json, path, {"type", "radius", "subdivisions"});
                const double radius = in_.number(in_.require(json, path, "radius", "a number > 0"),
                                                 path + "/radius", 0, kMaxCoordinate, true);
                long long subdivisions = 3;
                if (const Json* v = JsonInput::find(json, "subdivisions"))
                    subdivisions = in_.integer(*v, path + "/subdivisions", 0, 7);
                mesh = make_sphere(float(radius), int(subdivisions));
                break;
            }
            case ShapeType::quad: {
                in_.check_keys(json, path, {"type", "size"});
                const glm::vec3 size = positive_size(
                    in_.require(json, path, "size", "[width, depth]"), path + "/size", 2);
                mesh = make_quad(size.x, size.y);
                break;
            }
            case ShapeType::bumpy_plane: {
                in_.check_keys(json, path, {"type", "size", "resolution", "amplitude", "seed"});
                const glm::vec3 size = positive_size(
                    in_.require(json, path, "size", "[width, depth]"), path + "/size", 2);
                const long long resolution =
                    in_.integer(in_.require(json, path, "resolution", "an integer in [1, 2048]"),
                                path + "/resolution", 1, 2048);
                const double amplitude =
                    in_.number(in_.require(json, path, "amplitude", "a number >= 0"),
                               path + "/amplitude", 0, kMaxCoordinate);
                long long seed = 1;
                if (const Json* v = JsonInput::find(json, "seed"))
                    seed = in_.integer(*v, path + "/seed", 0, 4294967295ll);
                mesh = make_bumpy_plane(size.x, size.y, int(resolution), float(amplitude),
                                        uint32_t(seed));
                break;
            }
            case ShapeType::lumpy_sphere: {
                in_.check_keys(json, path, {"type", "radius", "triangles", "amplitude", "seed"});
                const double radius = in_.number(in_.require(json, path, "radius", "a number > 0"),
                                                 path + "/radius", 0, kMaxCoordinate, true);
                const long long triangles = in_.integer(
                    in_.require(json, path, "triangles", "an integer in [12, 20000000]"),
                    path + "/triangles", 12, 20000000);
                double amplitude = 0.0;
                if (const Json* v = JsonInput::find(json, "amplitude"))
                    amplitude = in_.number(*v, path + "/amplitude", 0, 0.5 * radius);
                long long seed = 1;
                if (const Json* v = JsonInput::find(json, "seed"))
                    seed = in_.integer(*v, path + "/seed", 0, 4294967295ll);
                mesh = make_lumpy_sphere(float(radius), lumpy_sphere_cells(triangles),
                                         float(amplitude), uint32_t(seed));
                break;
            }
            case ShapeType::torus: {
                in_.check_keys(json, path, {"type", "radius", "tube_radius", "rings", "sides"});
                const double radius = in_.number(in_.require(json, path, "radius", "a number > 0"),
                                                 path + "/radius", 0, kMaxCoordinate, true);
                // A tube as thick as the ring's radius would meet itself at the axis.
                const double tube =
                    in_.number(in_.require(json, path, "tube_radius", "a number > 0 and < radius"),
                               path + "/tube_radius", 0, radius, true, true);
                long long rings = 41, sides = 20;  // Barczak's torus: 820 vertices
                if (const Json* v = JsonInput::find(json, "rings"))
                    rings = in_.integer(*v, path + "/rings", 3, 4096);
                if (const Json* v = JsonInput::find(json, "sides"))
                    sides = in_.integer(*v, path + "/sides", 3, 4096);
                mesh = make_torus(float(radius), float(tube), int(rings), int(sides));
                break;
            }
        }
        const size_t total = mesh.triangles.size();
        const int dropped = remove_degenerate_triangles(mesh);
        if (mesh.triangles.empty())
            in_.fail(path, "expected a shape with non-zero area, got " + std::to_string(total) +
                               " degenerate triangles (is it too small?)");
        if (dropped > 0)
            warn(in_.file() + ": " + path + ": dropped " + std::to_string(dropped) +
                 " degenerate triangles");
        return mesh;
    }

    // An open box (five faces) stands on a floor without a hidden bottom surface, as the blocks
    // of the Cornell box do.
    static void remove_bottom(Mesh& mesh) {
        std::vector<char> keep(mesh.triangles.size());
        for (int t = 0; t < int(mesh.triangles.size()); ++t)
            keep[size_t(t)] = triangle_normal(mesh, t).y > -0.5f;
        filter_triangles(mesh, [&](int t) { return keep[size_t(t)] != 0; });
    }

    glm::quat read_rotation(const Json& json, const std::string& path) {
        in_.object(json, path);
        in_.check_keys(json, path, {"axis", "degrees"});
        const glm::vec3 axis =
            in_.vec3(in_.require(json, path, "axis", "[x, y, z]"), path + "/axis");
        glm::vec3 unit;
        if (!safe_normalize(axis, unit))
            in_.fail(path + "/axis", "expected a non-zero axis, got " + format_vec(axis));
        const double degrees =
            in_.number(in_.require(json, path, "degrees", "a number"), path + "/degrees");
        return glm::angleAxis(glm::radians(float(degrees)), unit);
    }

    Transform read_transform(const Json& json, const std::string& path) {
        in_.object(json, path);
        in_.check_keys(json, path, {"translate", "rotate", "rotate_euler"});
        Transform t;
        if (const Json* v = JsonInput::find(json, "translate"))
            t.translation = in_.vec3(*v, path + "/translate", kMaxCoordinate);
        const Json* rotate = JsonInput::find(json, "rotate");
        const Json* euler = JsonInput::find(json, "rotate_euler");
        if (rotate && euler)
            in_.fail(path, "expected either \"rotate\" or \"rotate_euler\", got both");
        if (rotate && rotate->is_array()) {
            // Applied in the order listed: the first rotation acts on the object first.
            for (size_t k = 0; k < rotate->size(); ++k)
                t.rotation =
                    read_rotation((*rotate)[k], JsonInput::child(path + "/rotate", k)) * t.rotation;
        } else if (rotate) {
            if (!rotate->is_object())
                in_.fail(path + "/rotate",
                         "expected {\"axis\": [x, y, z], \"degrees\": d} or a "
                         "list of them, got " +
                             JsonInput::describe(*rotate));
            t.rotation = read_rotation(*rotate, path + "/rotate");
        } else if (euler) {
            const glm::vec3 d = in_.vec3(*euler, path + "/rotate_euler");
            // About the world X, then Y, then Z axes.
            t.rotation = glm::angleAxis(glm::radians(d.z), glm::vec3(0, 0, 1)) *
                         glm::angleAxis(glm::radians(d.y), glm::vec3(0, 1, 0)) *
                         glm::angleAxis(glm::radians(d.x), glm::vec3(1, 0, 0));
        }
        return t;
    }

    JsonInput in_;
    fs::path base_;
    Scene scene_;
    std::map<std::string, Material> materials_;
    int64_t max_triangles_;                   // kMaxSceneTriangles unless a caller asks for fewer
    int64_t triangles_ = 0;                   // placed so far, every object together
    TextureCache textures_;                   // albedo maps, each file read once
    std::vector<ModelCamera> model_cameras_;  // cameras of glTF files, placed
};

}  // namespace

Scene parse_scene(const std::string& json_text, const std::string& path, int64_t max_triangles) {
    return SceneParser(path, max_triangles).parse(parse_json(json_text, path));
}

void settings_changed(Scene& scene, const LightmapSettings& before) {
    check_light_samples(scene);
    check_photon_budget(scene);
    const LightmapSettings& after = scene.settings.lightmap;
    if (after.texel_size != before.texel_size || after.crease_angle != before.crease_angle ||
        after.chart_cone != before.chart_cone || after.gutter != before.gutter ||
        after.refine_factor != before.refine_factor ||
        after.refine_distance != before.refine_distance ||
        after.refine_budget != before.refine_budget || after.refine_tile != before.refine_tile ||
        after.refine_reach != before.refine_reach)
        make_surfaces_and_atlas(scene);
}

void apply_settings_json(Scene& scene, const std::string& json_text, const std::string& source) {
    Settings settings = scene.settings;
    read_settings(parse_json(json_text, source), settings, source, "");
    const Settings before = scene.settings;
    scene.settings = settings;
    try {
        settings_changed(scene, before.lightmap);
    } catch (...) {
        scene.settings = before;
        throw;
    }
}

Scene load_scene(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw_input_error(path, "", "cannot open scene file: no such file");
    if (!fs::is_regular_file(path, ec))
        throw_input_error(path, "", "cannot open scene file: not a regular file");
    std::ifstream file(path, std::ios::binary);
    if (!file) throw_input_error(path, "", "cannot open scene file: permission denied");
    std::ostringstream text;
    text << file.rdbuf();
    if (file.bad()) throw_input_error(path, "", "cannot read scene file");
    return parse_scene(text.str(), path);
}

}  // namespace ag
