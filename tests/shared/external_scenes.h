// Scene files that wrap meshes from ../shared/external-scenes (beside the repository, never copied
// into it: /work/shared/external-scenes/README.md) load only where that folder exists. Tests that
// need such a scene for everything but the mesh (names, placements, lights, settings) load it with
// a stand-in for each external mesh, so they neither skip nor pay for a 331k-triangle load.
#pragma once

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "shared/scene_file.h"

namespace ag::test {

// Whether a scene file's "mesh" value points into an external-scenes folder.
inline bool is_external_mesh(const std::string& mesh) {
    return mesh.find("external-scenes/") != std::string::npos;
}

inline nlohmann::json read_scene_json(const std::filesystem::path& scene_file) {
    std::ifstream in(scene_file, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    return nlohmann::json::parse(text.str(), nullptr, true, /*ignore_comments=*/true);
}

// The external meshes a scene file names (resolved against its folder, as the loader does) that
// do not exist here.
inline std::vector<std::string> missing_external_meshes(const std::filesystem::path& scene_file) {
    std::vector<std::string> missing;
    const nlohmann::json j = read_scene_json(scene_file);
    for (const nlohmann::json& o : j.at("objects")) {
        if (!o.contains("mesh") || !is_external_mesh(o["mesh"].get<std::string>())) continue;
        const std::filesystem::path p = scene_file.parent_path() / o["mesh"].get<std::string>();
        if (!std::filesystem::is_regular_file(p)) missing.push_back(p.string());
    }
    return missing;
}

// The scene with every external mesh replaced by a unit box (same name, material, dynamic flag,
// offset and transform; the mesh's scale and decimation dropped; a grey "stand_in" material where
// the mesh brought its own). Everything else is read as load_scene reads it.
inline Scene load_scene_with_stand_ins(const std::filesystem::path& scene_file) {
    nlohmann::json j = read_scene_json(scene_file);
    for (nlohmann::json& o : j.at("objects")) {
        if (!o.contains("mesh") || !is_external_mesh(o["mesh"].get<std::string>())) continue;
        o.erase("mesh");
        o.erase("scale");
        o.erase("materials");
        o.erase("decimate");            // applies to meshes only
        if (!o.contains("material")) {  // a mesh bringing its own materials
            j["materials"]["stand_in"] = {{"albedo", 0.5}};
            o["material"] = "stand_in";
        }
        o["shape"] = {{"type", "box"}, {"size", {1, 1, 1}}};
    }
    return parse_scene(j.dump(), scene_file.string());
}

}  // namespace ag::test
