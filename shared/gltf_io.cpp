// glTF 2.0 through tinygltf (the only file that includes it): the default scene's nodes
// flattened into world-space parts, materials mapped, KHR_lights_punctual and cameras read, and
// one warning per feature that is not rendered.
#include "shared/gltf_io.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <map>
#include <set>
#include <sstream>

#include "shared/input_error.h"

namespace ag {
namespace {

// tinygltf does not decode images: a baseColorTexture whose image is a file beside the glTF is
// read through OpenImageIO (shared/texture.h); embedded images get a warning, and a missing image
// must not stop the load.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                const unsigned char*, int, void*) {
    return true;
}

// tinygltf's own file reader takes a directory for a file of 2^63 - 1 bytes (std::bad_alloc
// escaped the load: an image `uri` of "/tmp") and reads devices; this one reads regular files
// only, as many bytes as the file system says they hold. The glTF file, its buffers and images.
bool read_regular_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                       void*) {
    std::error_code ec;
    const bool regular = std::filesystem::is_regular_file(path, ec);
    const std::uintmax_t size = regular && !ec ? std::filesystem::file_size(path, ec) : 0;
    const auto fail = [&](const std::string& why) {
        if (err) *err += path + ": " + why + "\n";
        return false;
    };
    if (!regular || ec)
        return fail(std::filesystem::exists(path, ec) ? "expected a regular file" : "no such file");
    if (size == 0) return fail("the file is empty");
    std::ifstream file(path, std::ios::binary);
    out->resize(size_t(size));
    if (!file.read(reinterpret_cast<char*>(out->data()), std::streamsize(size)))
        return fail("cannot read the file");
    return true;
}

const std::set<std::string> kSupportedExtensions = {
    "KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior",
    "KHR_materials_emissive_strength"};

// The node tree's depth bound: visit() recurses once per level.
constexpr int kMaxNodeDepth = 256;

class GltfReader {
public:
    GltfReader(const std::string& path, const tinygltf::Model& gltf, int64_t max_triangles)
        : path_(path), g_(gltf), max_triangles_(max_triangles) {}

    Model read() {
        for (const std::string& e : g_.extensionsUsed)
            if (!kSupportedExtensions.count(e)) unsupported("extension " + e);
        if (!g_.animations.empty()) unsupported("animations");
        if (!g_.skins.empty()) unsupported("skins");
        std::vector<int> roots;
        if (!g_.scenes.empty()) {
            const int s = g_.defaultScene >= 0 && size_t(g_.defaultScene) < g_.scenes.size()
                              ? g_.defaultScene
                              : 0;
            if (g_.scenes.size() > 1) unsupported("scenes other than the default one");
            roots = g_.scenes[size_t(s)].nodes;
        } else {
            // No scene: every node that is nobody's child is a root.
            std::vector<char> child(g_.nodes.size(), 0);
            for (const tinygltf::Node& n : g_.nodes)
                for (int c : n.children)
                    if (c >= 0 && size_t(c) < child.size()) child[size_t(c)] = 1;
            for (size_t i = 0; i < g_.nodes.size(); ++i)
                if (!child[i]) roots.push_back(int(i));
        }
        reached_.assign(g_.nodes.size(), 0);
        for (int r : roots) visit(r, glm::dmat4(1.0), 0);
        if (model_.parts.empty())
            throw_input_error(path_, "", "expected at least one triangle mesh, got none");
        return std::move(model_);
    }

private:
    void unsupported(const std::string& what) {
        if (warned_.insert(what).second)
            warn(path_ + ": glTF " + what + " is not supported; ignored");
    }

    [[noreturn]] void fail(const std::string& place, const std::string& message) const {
        throw_input_error(path_, place, message);
    }

    static glm::dmat4 local_matrix(const tinygltf::Node& n) {
        if (n.matrix.size() == 16) {
            glm::dmat4 m;
            for (int i = 0; i < 16; ++i) m[i / 4][i % 4] = n.matrix[size_t(i)];  // column-major
            return m;
        }
        glm::dmat4 t(1.0), r(1.0), s(1.0);
        if (n.translation.size() == 3)
            t[3] = glm::dvec4(n.translation[0], n.translation[1], n.translation[2], 1.0);
        if (n.rotation.size() == 4)  // glTF: (x, y, z, w)
            r = glm::mat4_cast(
                glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]));
        if (n.scale.size() == 3)
            s = glm::scale(glm::dmat4(1.0), glm::dvec3(n.scale[0], n.scale[1], n.scale[2]));
        return t * r * s;
    }

    void visit(int index, const glm::dmat4& parent, int depth) {
        if (index < 0 || size_t(index) >= g_.nodes.size())
            fail("node " + std::to_string(index),
                 "expected a node index below " + std::to_string(g_.nodes.size()));
        // glTF 2.0 (3.5.3): the nodes form disjoint strict trees, no node has two parents. A
        // node reached again is a cycle or a shared child; the latter would place its subtree once
        // per path, 2^40 times for forty nodes each naming the next twice.
        if (reached_[size_t(index)])
            fail("node " + std::to_string(index),
                 "expected a node tree, got a node reached a second time (a cycle, a node with two "
                 "parents, or a child or root listed twice)");
        reached_[size_t(index)] = 1;
        if (depth > kMaxNodeDepth)
            fail("node " + std::to_string(index),
                 "expected a node tree at most " + std::to_string(kMaxNodeDepth) + " deep");
        const tinygltf::Node& n = g_.nodes[size_t(index)];
        const glm::dmat4 m = parent * local_matrix(n);
        const std::string name = n.name.empty() ? "node" + std::to_string(index) : n.name;
        if (n.skin >= 0) unsupported("skins");
        if (!n.weights.empty()) unsupported("morph targets");
        if (n.mesh >= 0) add_mesh(n.mesh, m, name);
        if (n.camera >= 0) add_camera(n.camera, m, name);
        if (const auto it = n.extensions.find("KHR_lights_punctual"); it != n.extensions.end()) {
            if (it->second.Has("light") && it->second.Get("light").IsNumber())
                add_light(it->second.Get("light").GetNumberAsInt(), m);
        }
        for (int c : n.children) visit(c, m, depth + 1);
    }

    // Calls f(i, components) for every element of accessor `index`.
    template <class F>
    void read_accessor(int index, const std::string& what, F&& f) const {
        const std::string place = what + " accessor " + std::to_string(index);
        if (index < 0 || size_t(index) >= g_.accessors.size())
            fail(place, "expected an accessor index below " + std::to_string(g_.accessors.size()));
        const tinygltf::Accessor& a = g_.accessors[size_t(index)];
        if (a.sparse.isSparse) fail(place, "expected a dense accessor, got a sparse one");
        if (a.bufferView < 0 || size_t(a.bufferView) >= g_.bufferViews.size())
            fail(place, "expected a buffer view");
        const tinygltf::BufferView& view = g_.bufferViews[size_t(a.bufferView)];
        if (view.buffer < 0 || size_t(view.buffer) >= g_.buffers.size())
            fail(place, "expected a buffer");
        const std::vector<unsigned char>& data = g_.buffers[size_t(view.buffer)].data;
        const int components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        const int size = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        const int stride = a.ByteStride(view);
        if (components <= 0 || size <= 0 || stride <= 0)
            fail(place, "expected a known type and component type");
        const size_t start = view.byteOffset + a.byteOffset;
        if (a.count > 0 && (start + size_t(stride) * (a.count - 1) + size_t(components * size) >
                            std::min(data.size(), view.byteOffset + view.byteLength)))
            fail(place, "expected " + std::to_string(a.count) +
                            " elements inside its buffer view, which is too short");
        double c[16];
        for (size_t i = 0; i < a.count; ++i) {
            const unsigned char* p = &data[start + i * size_t(stride)];
            for (int k = 0; k < components; ++k) {
                const unsigned char* q = p + k * size;
                switch (a.componentType) {
                    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
                        float v;
                        std::memcpy(&v, q, 4);
                        c[k] = v;
                        break;
                    }
                    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
                        uint32_t v;
                        std::memcpy(&v, q, 4);
                        c[k] = v;
                        break;
                    }
                    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                        uint16_t v;
                        std::memcpy(&v, q, 2);
                        c[k] = v;
                        break;
                    }
                    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                        c[k] = *q;
                        break;
                    default:
                        fail(place, "expected float or unsigned integer components");
                }
            }
            f(i, c, components);
        }
    }

    Material material(int index) {
        Material mat;
        if (index < 0) {
            mat.name = "default";
            return mat;
        }
        if (size_t(index) >= g_.materials.size())
            fail("material " + std::to_string(index),
                 "expected a material index below " + std::to_string(g_.materials.size()));
        const tinygltf::Material& m = g_.materials[size_t(index)];
        mat.name = m.name.empty() ? "material" + std::to_string(index) : m.name;
        const tinygltf::PbrMetallicRoughness& pbr = m.pbrMetallicRoughness;
        glm::vec3 base(1.0f);
        if (pbr.baseColorFactor.size() >= 3)
            base = glm::vec3(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                             float(pbr.baseColorFactor[2]));
        base = glm::clamp(base, 0.0f, 1.0f);
        if (pbr.baseColorTexture.index >= 0) {
            mat.albedo_map = base_color_texture(pbr.baseColorTexture.index, mat.name);
            texcoord_set_[index] = pbr.baseColorTexture.texCoord;
        }
        if (pbr.metallicRoughnessTexture.index >= 0) unsupported("metallicRoughnessTexture");
        if (m.normalTexture.index >= 0) unsupported("normalTexture");
        if (m.occlusionTexture.index >= 0) unsupported("occlusionTexture");
        if (m.emissiveTexture.index >= 0) unsupported("emissiveTexture");
        if (!m.alphaMode.empty() && m.alphaMode != "OPAQUE")
            unsupported("alphaMode " + m.alphaMode + " (rendered opaque)");
        float strength = 1.0f, transmission = 0.0f, ior = 1.5f;
        for (const auto& [name, value] : m.extensions) {
            if (name == "KHR_materials_emissive_strength" && value.Has("emissiveStrength"))
                strength = float(value.Get("emissiveStrength").GetNumberAsDouble());
            else if (name == "KHR_materials_transmission") {
                if (value.Has("transmissionFactor"))
                    transmission = float(value.Get("transmissionFactor").GetNumberAsDouble());
                if (value.Has("transmissionTexture")) unsupported("transmissionTexture");
            } else if (name == "KHR_materials_ior" && value.Has("ior"))
                ior = float(value.Get("ior").GetNumberAsDouble());
            else if (!kSupportedExtensions.count(name))
                unsupported("material extension " + name);
        }
        if (m.emissiveFactor.size() == 3)
            mat.emission =
                glm::max(glm::vec3(float(m.emissiveFactor[0]), float(m.emissiveFactor[1]),
                                   float(m.emissiveFactor[2])) *
                             std::max(strength, 0.0f),
                         0.0f);
        if (mat.albedo_map &&
            (transmission >= 0.5f || (pbr.metallicFactor >= 0.99 && pbr.roughnessFactor <= 0.1))) {
            unsupported("baseColorTexture on glass or mirrors (the baseColorFactor is used)");
            mat.albedo_map = nullptr;
        }
        if (transmission >= 0.5f) {
            mat.type = MaterialType::glass;
            mat.albedo = base;
            mat.ior = std::clamp(ior, 1.0f, 4.0f);
        } else if (pbr.metallicFactor >= 0.99 && pbr.roughnessFactor <= 0.1) {
            mat.type = MaterialType::mirror;
            mat.albedo = base;
        } else {
            mat.albedo = base;  // multiplies the texture, as glTF says
            if (transmission > 0.0f) unsupported("partial transmission (below 0.5: diffuse)");
            if (pbr.metallicFactor > 0.0)
                unsupported("metallic surfaces that are not mirrors (rendered diffuse)");
        }
        return mat;
    }

    // The albedo texture of texture `index`: its image must be a file (a URI relative to the glTF)
    // OpenImageIO reads; otherwise a warning and none.
    std::shared_ptr<const Texture> base_color_texture(int index, const std::string& material) {
        if (size_t(index) >= g_.textures.size())
            fail("material \"" + material + "\"",
                 "expected a texture index below " + std::to_string(g_.textures.size()));
        const int source = g_.textures[size_t(index)].source;
        if (source < 0 || size_t(source) >= g_.images.size()) {
            unsupported("textures without an image source (the baseColorFactor is used)");
            return nullptr;
        }
        const tinygltf::Image& image = g_.images[size_t(source)];
        if (image.uri.empty() || image.uri.rfind("data:", 0) == 0) {
            unsupported("embedded texture images (the baseColorFactor is used)");
            return nullptr;
        }
        const std::string file = (std::filesystem::path(path_).parent_path() / image.uri).string();
        try {
            return textures_.get(file);
        } catch (const InputError& e) {
            warn(path_ + ": material \"" + material + "\": baseColorTexture " + image.uri +
                 " cannot be used (" + e.what() + "); the baseColorFactor is used");
            return nullptr;
        }
    }

    void add_mesh(int index, const glm::dmat4& m, const std::string& node_name) {
        if (size_t(index) >= g_.meshes.size())
            fail("node " + node_name,
                 "expected a mesh index below " + std::to_string(g_.meshes.size()));
        const tinygltf::Mesh& mesh = g_.meshes[size_t(index)];
        const bool flip = glm::determinant(glm::dmat3(m)) < 0.0;  // mirrored: keep fronts out
        for (size_t k = 0; k < mesh.primitives.size(); ++k) {
            const tinygltf::Primitive& prim = mesh.primitives[k];
            const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
            if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
                mode != TINYGLTF_MODE_TRIANGLE_FAN) {
                unsupported("point and line primitives");
                continue;
            }
            if (!prim.targets.empty()) unsupported("morph targets");
            ModelPart part;
            part.material = material(prim.material);
            const auto set = texcoord_set_.find(prim.material);
            const std::string texcoord_name = part.material.albedo_map && set != texcoord_set_.end()
                                                  ? "TEXCOORD_" + std::to_string(set->second)
                                                  : "";
            for (const auto& [attribute, unused] : prim.attributes)
                if (attribute == "NORMAL")
                    unsupported("NORMAL attribute (faces are shaded flat)");
                else if (attribute.rfind("TEXCOORD", 0) == 0) {
                    if (attribute != texcoord_name)
                        unsupported(attribute + " without a texture that uses it");
                } else if (attribute != "POSITION")
                    unsupported(attribute + " attribute");
            const auto pos = prim.attributes.find("POSITION");
            if (pos == prim.attributes.end())
                fail("mesh " + std::to_string(index), "expected a POSITION attribute");
            part.name =
                mesh.primitives.size() > 1 ? node_name + "/" + std::to_string(k) : node_name;
            // Texture coordinates per vertex, v flipped (glTF's origin is the image's top left).
            std::vector<glm::vec2> vertex_uv;
            if (!texcoord_name.empty()) {
                const auto tc = prim.attributes.find(texcoord_name);
                if (tc == prim.attributes.end()) {
                    warn(path_ + ": " + part.name + ": material \"" + part.material.name +
                         "\" has a baseColorTexture but the primitive has no " + texcoord_name +
                         "; the texture's mean is used");
                } else {
                    const tinygltf::Accessor& a = g_.accessors[size_t(tc->second)];
                    const double scale =
                        !a.normalized                                               ? 1.0
                        : a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE  ? 1.0 / 255.0
                        : a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 1.0 / 65535.0
                                                                                    : 1.0;
                    read_accessor(tc->second, texcoord_name, [&](size_t, const double* c, int n) {
                        if (n != 2)
                            fail("mesh " + std::to_string(index), "expected VEC2 " + texcoord_name);
                        vertex_uv.push_back(
                            glm::vec2(float(c[0] * scale), float(1.0 - c[1] * scale)));
                    });
                }
            }
            // Bounded before the accessors are read: each placement copies the mesh.
            const auto count = [&](int accessor) {
                return accessor >= 0 && size_t(accessor) < g_.accessors.size()
                           ? int64_t(g_.accessors[size_t(accessor)].count)
                           : int64_t(0);
            };
            placed_vertices_ += count(pos->second);
            const int64_t corners = prim.indices >= 0 ? count(prim.indices) : count(pos->second);
            placed_triangles_ +=
                mode == TINYGLTF_MODE_TRIANGLES ? corners / 3 : std::max<int64_t>(corners - 2, 0);
            if (placed_triangles_ > max_triangles_ || placed_vertices_ > 3 * max_triangles_)
                fail("node " + node_name,
                     "expected at most " + std::to_string(max_triangles_) +
                         " triangles and three times as many vertices placed by the node tree "
                         "(kMaxSceneTriangles), got " +
                         std::to_string(placed_triangles_) + " triangles and " +
                         std::to_string(placed_vertices_) + " vertices with mesh " +
                         std::to_string(index));
            read_accessor(pos->second, "POSITION", [&](size_t, const double* c, int n) {
                if (n != 3) fail("mesh " + std::to_string(index), "expected VEC3 positions");
                const glm::dvec4 w = m * glm::dvec4(c[0], c[1], c[2], 1.0);
                part.mesh.positions.push_back(glm::vec3(w));
            });
            std::vector<uint32_t> indices;
            if (prim.indices >= 0) {
                read_accessor(prim.indices, "indices", [&](size_t, const double* c, int n) {
                    if (n != 1) fail("mesh " + std::to_string(index), "expected scalar indices");
                    indices.push_back(uint32_t(c[0]));
                });
            } else {
                for (size_t i = 0; i < part.mesh.positions.size(); ++i)
                    indices.push_back(uint32_t(i));
            }
            for (uint32_t i : indices)
                if (i >= part.mesh.positions.size())
                    fail("mesh " + std::to_string(index),
                         "expected indices below " + std::to_string(part.mesh.positions.size()) +
                             ", got " + std::to_string(i));
            if (!vertex_uv.empty() && vertex_uv.size() != part.mesh.positions.size())
                fail("mesh " + std::to_string(index),
                     "expected as many " + texcoord_name + " as positions (" +
                         std::to_string(part.mesh.positions.size()) + "), got " +
                         std::to_string(vertex_uv.size()));
            auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
                const glm::uvec3 t = flip ? glm::uvec3(a, c, b) : glm::uvec3(a, b, c);
                part.mesh.triangles.push_back(t);
                if (!vertex_uv.empty())
                    for (int corner = 0; corner < 3; ++corner)
                        part.mesh.texcoords.push_back(vertex_uv[t[corner]]);
            };
            if (mode == TINYGLTF_MODE_TRIANGLES)
                for (size_t i = 0; i + 2 < indices.size(); i += 3)
                    add(indices[i], indices[i + 1], indices[i + 2]);
            else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP)
                for (size_t i = 0; i + 2 < indices.size(); ++i)
                    i % 2 == 0 ? add(indices[i], indices[i + 1], indices[i + 2])
                               : add(indices[i + 1], indices[i], indices[i + 2]);
            else
                for (size_t i = 1; i + 1 < indices.size(); ++i)
                    add(indices[0], indices[i], indices[i + 1]);
            const size_t total = part.mesh.triangles.size();
            const int dropped = remove_degenerate_triangles(part.mesh);
            if (dropped > 0)
                warn(path_ + ": " + part.name + ": dropped " + std::to_string(dropped) + " of " +
                     std::to_string(total) + " triangles as degenerate");
            if (part.mesh.triangles.empty()) continue;
            // Part names are unique within the model (a mesh instanced by several nodes).
            std::string unique = part.name;
            for (int n = 2; used_names_.count(unique); ++n)
                unique = part.name + "_" + std::to_string(n);
            used_names_.insert(unique);
            part.name = unique;
            model_.parts.push_back(std::move(part));
        }
    }

    void add_camera(int index, const glm::dmat4& m, const std::string& node_name) {
        if (size_t(index) >= g_.cameras.size())
            fail("node " + node_name,
                 "expected a camera index below " + std::to_string(g_.cameras.size()));
        const tinygltf::Camera& c = g_.cameras[size_t(index)];
        if (c.type != "perspective") {
            unsupported("orthographic cameras");
            return;
        }
        ModelCamera cam;
        cam.name = c.name.empty() ? node_name : c.name;
        cam.eye = glm::vec3(m * glm::dvec4(0, 0, 0, 1));
        cam.target = cam.eye + glm::normalize(glm::vec3(m * glm::dvec4(0, 0, -1, 0)));
        cam.up = glm::normalize(glm::vec3(m * glm::dvec4(0, 1, 0, 0)));
        cam.fov_y = float(glm::degrees(c.perspective.yfov));
        model_.cameras.push_back(cam);
    }

    void add_light(int index, const glm::dmat4& m) {
        if (index < 0 || size_t(index) >= g_.lights.size())
            fail("KHR_lights_punctual",
                 "expected a light index below " + std::to_string(g_.lights.size()));
        const tinygltf::Light& gl = g_.lights[size_t(index)];
        Light l;
        l.name = gl.name.empty() ? "light" + std::to_string(index) : gl.name;
        for (int n = 2; std::any_of(model_.lights.begin(), model_.lights.end(),
                                    [&](const Light& o) { return o.name == l.name; });
             ++n)
            l.name = (gl.name.empty() ? "light" + std::to_string(index) : gl.name) + "_" +
                     std::to_string(n);
        glm::vec3 colour(1.0f);
        if (gl.color.size() == 3)
            colour = glm::vec3(float(gl.color[0]), float(gl.color[1]), float(gl.color[2]));
        // Photometric glTF values are read as radiometric ones: cd as W/sr, lx as W/m².
        const glm::vec3 value = glm::max(colour * float(gl.intensity), 0.0f);
        l.position = glm::vec3(m * glm::dvec4(0, 0, 0, 1));
        l.direction = glm::normalize(glm::vec3(m * glm::dvec4(0, 0, -1, 0)));
        if (gl.range > 0.0) unsupported("light range (lights reach everywhere)");
        if (gl.type == "directional") {
            l.type = LightType::sun;
            l.irradiance = value;
        } else if (gl.type == "spot") {
            l.type = LightType::spot;
            l.intensity = value;
            l.cone_outer = std::clamp(float(glm::degrees(gl.spot.outerConeAngle)), 0.01f, 90.0f);
            l.cone_inner =
                std::clamp(float(glm::degrees(gl.spot.innerConeAngle)), 0.0f, l.cone_outer);
        } else if (gl.type == "point") {
            l.intensity = value;
        } else {
            unsupported("light type " + gl.type);
            return;
        }
        model_.lights.push_back(l);
    }

    std::string path_;
    const tinygltf::Model& g_;
    Model model_;
    std::set<std::string> warned_, used_names_;
    std::vector<char> reached_;  // per node: visited (a node tree visits each node once)
    int64_t max_triangles_;
    int64_t placed_triangles_ = 0, placed_vertices_ = 0;  // every instance (max_triangles_)
    TextureCache textures_;
    std::map<int, int> texcoord_set_;  // material → the TEXCOORD_n its baseColorTexture reads
};

}  // namespace

Model load_gltf(const std::string& path, int64_t max_triangles) {
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    loader.SetFsCallbacks({&tinygltf::FileExists, &tinygltf::ExpandFilePath, &read_regular_file,
                           &tinygltf::WriteWholeFile, nullptr});
    tinygltf::Model gltf;
    std::string error, warning;
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    const bool ok = ext == ".glb" ? loader.LoadBinaryFromFile(&gltf, &error, &warning, path)
                                  : loader.LoadASCIIFromFile(&gltf, &error, &warning, path);
    std::istringstream lines(warning);
    for (std::string line; std::getline(lines, line);)
        if (!line.empty()) warn(path + ": " + line);
    if (!ok) {
        while (!error.empty() && (error.back() == '\n' || error.back() == '\r')) error.pop_back();
        throw_input_error(path, "", "cannot read glTF: " + (error.empty() ? "parse error" : error));
    }
    return GltfReader(path, gltf, max_triangles).read();
}

}  // namespace ag
