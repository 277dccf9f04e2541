// OBJ + MTL through tinyobjloader (the only file that includes it); other formats through
// load_mesh. Faces are grouped by material into parts.
#include "shared/model_io.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <sstream>
#include <unordered_map>

#include "shared/gltf_io.h"
#include "shared/input_error.h"
#include "shared/mesh_io.h"

namespace ag {
namespace {

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

glm::vec3 clamp_colour(const float* c) {
    return glm::clamp(glm::vec3(c[0], c[1], c[2]), glm::vec3(0.0f), glm::vec3(1.0f));
}

// MTL illumination models (Wavefront): 3 and 5 reflect by ray tracing, 4, 6, 7 and 9 also
// refract. Everything else is diffuse with Kd; a specular Ks on it is dropped with a warning.
Material obj_material(const tinyobj::material_t& m, const std::string& file) {
    Material mat;
    mat.name = m.name;
    mat.emission = glm::max(glm::vec3(m.emission[0], m.emission[1], m.emission[2]), 0.0f);
    const glm::vec3 ks = clamp_colour(m.specular);
    const float ks_max = std::max({ks.x, ks.y, ks.z});
    const bool refracts = m.illum == 4 || m.illum == 6 || m.illum == 7 || m.illum == 9;
    const bool reflects = m.illum == 5 || (m.illum == 3 && ks_max > 0.0f);
    if (refracts) {
        mat.type = MaterialType::glass;
        mat.albedo = glm::vec3(1.0f);
        mat.ior = std::clamp(float(m.ior), 1.0f, 4.0f);
        if (!(m.ior >= 1.0f)) mat.ior = 1.5f;  // Ni absent or below 1: window glass
    } else if (reflects) {
        mat.type = MaterialType::mirror;
        mat.albedo = ks_max > 0.0f ? ks : glm::vec3(1.0f);
    } else {
        mat.albedo = clamp_colour(m.diffuse);
        if (ks_max > 0.0f)
            warn(file + ": material \"" + m.name + "\": specular Ks (illum " +
                 std::to_string(m.illum) +
                 ") is not supported on diffuse surfaces; rendered as diffuse Kd");
    }
    return mat;
}

// tinyobjloader reports warnings as lines of text; each becomes one warning naming the file.
void forward_warnings(const std::string& text, const std::string& file) {
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line))
        if (!line.empty()) warn(file + ": " + line);
}

Model load_obj(const std::string& path) {
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    tinyobj::ObjReader reader;
    const bool ok = reader.ParseFromFile(path, config);
    std::string warnings = reader.Warning();
    // A missing MTL library is a warning: the faces get the default material.
    if (!ok || !reader.Error().empty()) {
        std::string error = reader.Error();
        while (!error.empty() && (error.back() == '\n' || error.back() == '\r')) error.pop_back();
        if (ok && error.find("not found") != std::string::npos) {
            warnings += error + " (the faces get the default material)\n";
        } else {
            throw_input_error(path, "",
                              "cannot read OBJ: " + (error.empty() ? "parse error" : error));
        }
    }
    forward_warnings(warnings, path);

    const tinyobj::attrib_t& attrib = reader.GetAttrib();
    const std::vector<tinyobj::material_t>& materials = reader.GetMaterials();
    const size_t vertex_count = attrib.vertices.size() / 3;

    // Parts in the order their materials first appear; -1 = no material.
    std::map<int, size_t> part_of_material;
    std::vector<std::unordered_map<int, uint32_t>> remap;
    Model model;
    size_t faces = 0;
    // Per part: texture coordinates per corner ((0, 0) where a face has none) and the number of
    // faces that have them.
    std::vector<std::vector<glm::vec2>> corner_uvs;
    std::vector<size_t> uv_faces;
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        const tinyobj::mesh_t& m = shape.mesh;
        for (size_t f = 0; f < m.num_face_vertices.size(); ++f, ++faces) {
            if (m.num_face_vertices[f] != 3)
                throw_input_error(path, "shape \"" + shape.name + "\"",
                                  "expected faces of at least 3 vertices, got one of " +
                                      std::to_string(int(m.num_face_vertices[f])));
            int mat = f < m.material_ids.size() ? m.material_ids[f] : -1;
            if (mat >= int(materials.size())) mat = -1;
            auto [it, inserted] = part_of_material.emplace(mat, model.parts.size());
            if (inserted) {
                ModelPart part;
                if (mat >= 0) {
                    part.material = obj_material(materials[size_t(mat)], path);
                    part.name = part.material.name;
                } else {
                    part.name = part.material.name = "default";
                }
                model.parts.push_back(std::move(part));
                remap.emplace_back();
            }
            ModelPart& part = model.parts[it->second];
            const size_t part_index = it->second;
            glm::uvec3 tri;
            glm::vec2 uv[3];
            bool has_uv = true;
            for (int k = 0; k < 3; ++k) {
                const int v = m.indices[3 * f + size_t(k)].vertex_index;
                if (v < 0 || size_t(v) >= vertex_count)
                    throw_input_error(path, "shape \"" + shape.name + "\"",
                                      "expected vertex indices in [1, " +
                                          std::to_string(vertex_count) + "], got " +
                                          std::to_string(v + 1));
                auto [slot, fresh] =
                    remap[it->second].emplace(v, uint32_t(part.mesh.positions.size()));
                if (fresh)
                    part.mesh.positions.push_back({attrib.vertices[3 * size_t(v)],
                                                   attrib.vertices[3 * size_t(v) + 1],
                                                   attrib.vertices[3 * size_t(v) + 2]});
                tri[k] = slot->second;
                const int t = m.indices[3 * f + size_t(k)].texcoord_index;
                if (t >= 0 && size_t(2 * t + 1) < attrib.texcoords.size())
                    uv[k] = {attrib.texcoords[2 * size_t(t)], attrib.texcoords[2 * size_t(t) + 1]};
                else
                    has_uv = false;
            }
            part.mesh.triangles.push_back(tri);
            corner_uvs.resize(model.parts.size());
            uv_faces.resize(model.parts.size());
            for (int k = 0; k < 3; ++k)
                corner_uvs[part_index].push_back(has_uv ? uv[k] : glm::vec2(0.0f));
            if (has_uv) ++uv_faces[part_index];
        }
    }
    if (faces == 0) throw_input_error(path, "", "expected at least one face, got none");
    // Albedo textures: map_Kd on a diffuse material replaces Kd (relative to the OBJ's folder). A
    // texture that cannot be read is a warning, and the Kd colour is used. What MTL says that is
    // not rendered gets named: other maps, partly transparent dissolve.
    TextureCache textures;
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    for (size_t i = 0; i < model.parts.size(); ++i) {
        ModelPart& part = model.parts[i];
        if (uv_faces[i] > 0) part.mesh.texcoords = std::move(corner_uvs[i]);
        const auto found = std::find_if(
            materials.begin(), materials.end(),
            [&](const tinyobj::material_t& m) { return m.name == part.material.name; });
        if (found == materials.end() || found->diffuse_texname.empty() ||
            part.material.type != MaterialType::diffuse)
            continue;
        std::string file = found->diffuse_texname;
        std::replace(file.begin(), file.end(), '\\', '/');
        const std::string texture_path = (folder / file).string();
        try {
            part.material.albedo_map = textures.get(texture_path);
            part.material.albedo = glm::vec3(1.0f);
        } catch (const InputError& e) {
            warn(path + ": material \"" + part.material.name + "\": map_Kd " +
                 found->diffuse_texname + " cannot be used (" + e.what() +
                 "); its Kd colour is used");
            continue;
        }
        const size_t faces_here = part.mesh.triangles.size();
        if (uv_faces[i] < faces_here)
            warn(path + ": material \"" + part.material.name + "\": " +
                 std::to_string(faces_here - uv_faces[i]) + " of " + std::to_string(faces_here) +
                 " faces have no texture coordinates (vt); they read the texture at (0, 0)" +
                 (uv_faces[i] == 0 ? " — the texture's mean is used" : ""));
    }
    std::string textured, transparent;
    for (const tinyobj::material_t& m : materials) {
        if (!m.bump_texname.empty() || !m.alpha_texname.empty() || !m.specular_texname.empty() ||
            !m.normal_texname.empty() || !m.displacement_texname.empty())
            textured += (textured.empty() ? "" : ", ") + m.name;
        if (m.dissolve < 1.0) transparent += (transparent.empty() ? "" : ", ") + m.name;
    }
    if (!textured.empty())
        warn(path +
             ": texture maps other than map_Kd (bump, map_d, map_Ks, ...) are not "
             "supported; materials " +
             textured + " ignore them");
    if (!transparent.empty())
        warn(path + ": dissolve d < 1 is not supported; materials " + transparent +
             " are rendered opaque");
    for (const ModelPart& part : model.parts)
        for (const glm::vec3& p : part.mesh.positions)
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw_input_error(path, "", "expected finite vertex coordinates");

    // Degenerate triangles are dropped as load_mesh drops them; a part left empty goes.
    size_t dropped = 0;
    std::vector<ModelPart> kept;
    for (ModelPart& part : model.parts) {
        dropped += size_t(remove_degenerate_triangles(part.mesh));
        if (!part.mesh.triangles.empty()) kept.push_back(std::move(part));
    }
    if (kept.empty())
        throw_input_error(path, "",
                          "all " + std::to_string(faces) +
                              " faces are degenerate (zero area or repeated vertices)");
    if (dropped > 0)
        warn(path + ": dropped " + std::to_string(dropped) + " of " + std::to_string(faces) +
             " faces as degenerate (zero area or repeated vertices)");
    model.parts = std::move(kept);
    for (const ModelPart& part : model.parts)
        if (part.name == "default" && !materials.empty())
            warn(path + ": " + std::to_string(part.mesh.triangles.size()) +
                 " faces have no material (or an unknown one); they get the default material");
    return model;
}

}  // namespace

Model load_model(const std::string& path, int64_t max_triangles) {
    const std::string ext = lower_extension(path);
    Model model;
    if (ext == ".obj") {
        model = load_obj(path);
    } else if (ext == ".gltf" || ext == ".glb") {
        model = load_gltf(path, max_triangles);
    } else {
        ModelPart part;
        part.name = part.material.name = "default";
        part.mesh = load_mesh(path);
        model.parts.push_back(std::move(part));
    }
    // A face given twice (McGuire's Cornell boxes give each block's front face again as its
    // "bottom") would be lit twice by the GPU frame's additive light passes.
    for (ModelPart& part : model.parts) {
        const size_t faces = part.mesh.triangles.size();
        const int dropped = remove_duplicate_triangles(part.mesh);
        if (dropped > 0)
            warn(path + ": part \"" + part.name + "\": dropped " + std::to_string(dropped) +
                 " of " + std::to_string(faces) +
                 " triangles that repeat another one (the same corners, the same side)");
    }
    return model;
}

}  // namespace ag
