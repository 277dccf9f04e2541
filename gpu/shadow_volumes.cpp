#include "gpu/shadow_volumes.h"

#include <cmath>
#include <map>
#include <tuple>
#include <utility>

namespace ag::gpu {

namespace {

// Meshes that cannot be closed cast one prism per triangle: correct for any triangle soup, at
// eight triangles each, so only up to this size (a 331k-triangle room casts nothing instead).
constexpr size_t kMaxSoupTriangles = 65536;

ShadowCaster soup_caster(const Mesh& mesh) {
    ShadowCaster c;
    if (mesh.triangles.empty() || mesh.triangles.size() > kMaxSoupTriangles) return c;
    c.soup = true;
    c.positions = mesh.positions;
    c.triangles = mesh.triangles;
    return c;
}

}  // namespace

ShadowCaster make_shadow_caster(const Mesh& mesh) {
    ShadowCaster closed = make_closed_caster(mesh);
    return closed.closed ? closed : soup_caster(mesh);
}

ShadowCaster make_closed_caster(const Mesh& mesh) {
    ShadowCaster c;
    std::map<std::tuple<float, float, float>, unsigned> weld;
    std::vector<unsigned> remap(mesh.positions.size());
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec3 p = mesh.positions[i];
        auto [it, added] = weld.try_emplace({p.x, p.y, p.z}, unsigned(c.positions.size()));
        if (added) c.positions.push_back(p);
        remap[i] = it->second;
    }
    for (const glm::uvec3& t : mesh.triangles)
        c.triangles.push_back({remap[t.x], remap[t.y], remap[t.z]});
    // Directed edge (a, b) -> (triangle, edge slot). A closed, consistently wound mesh has every
    // directed edge once and its reverse once.
    std::map<std::pair<unsigned, unsigned>, std::pair<int, int>> edges;
    for (int t = 0; t < int(c.triangles.size()); ++t)
        for (int k = 0; k < 3; ++k) {
            const unsigned a = c.triangles[size_t(t)][k], b = c.triangles[size_t(t)][(k + 1) % 3];
            if (!edges.emplace(std::make_pair(a, b), std::make_pair(t, k)).second)
                return ShadowCaster{};
        }
    // An open mesh (a quad panel, a box without its bottom, an atrium open to the sky) is not
    // closed here: filling its holes would invent geometry (a lid over the atrium), so it casts
    // per-triangle prisms instead (make_shadow_caster).
    c.neighbours.assign(c.triangles.size(), glm::ivec3(-1));
    for (const auto& [edge, owner] : edges) {
        auto it = edges.find({edge.second, edge.first});
        if (it == edges.end()) return ShadowCaster{};  // open mesh
        c.neighbours[size_t(owner.first)][owner.second] = it->second.first;
    }
    c.closed = !c.triangles.empty();
    return c;
}

void append_shadow_volume(const ShadowCaster& caster, const glm::mat4& model,
                          const glm::vec3& light, std::vector<glm::vec4>& out) {
    append_shadow_volume(caster, model, glm::vec4(light, 1.0f), out);
}

void append_shadow_volume(const ShadowCaster& caster, const glm::mat4& model,
                          const glm::vec4& light_h, std::vector<glm::vec4>& out) {
    if (!caster.closed && !caster.soup) return;
    const glm::vec3 light(light_h);
    const float w = light_h.w;  // 1: a point; 0: a direction towards the light
    std::vector<glm::vec3> p(caster.positions.size());
    for (size_t i = 0; i < p.size(); ++i)
        p[i] = glm::vec3(model * glm::vec4(caster.positions[i], 1.0f));
    auto far = [&](unsigned v) { return glm::vec4(w * p[v] - light, 0.0f); };
    auto near = [&](unsigned v) { return glm::vec4(p[v], 1.0f); };
    if (caster.soup) {
        // Each triangle, turned to face the light (an opaque sheet blocks from either side), as
        // its own closed prism: near cap, three sides, far cap.
        for (const glm::uvec3& t : caster.triangles) {
            glm::uvec3 tri = t;
            const glm::vec3 n = glm::cross(p[tri.y] - p[tri.x], p[tri.z] - p[tri.x]);
            const float facing = glm::dot(n, light - w * p[tri.x]);
            if (facing == 0.0f || !std::isfinite(facing)) continue;  // edge-on: no volume
            if (facing < 0.0f) std::swap(tri.y, tri.z);
            out.insert(out.end(), {near(tri.x), near(tri.y), near(tri.z)});
            out.insert(out.end(), {far(tri.x), far(tri.z), far(tri.y)});
            for (int k = 0; k < 3; ++k) {
                const unsigned a = tri[k], b = tri[(k + 1) % 3];
                out.insert(out.end(), {near(b), near(a), far(a), near(b), far(a), far(b)});
            }
        }
        return;
    }
    std::vector<char> lit(caster.triangles.size());
    for (size_t t = 0; t < caster.triangles.size(); ++t) {
        const glm::uvec3 tri = caster.triangles[t];
        const glm::vec3 n = glm::cross(p[tri.y] - p[tri.x], p[tri.z] - p[tri.x]);
        lit[t] = glm::dot(n, light - w * p[tri.x]) > 0.0f;
    }
    for (size_t t = 0; t < caster.triangles.size(); ++t) {
        const glm::uvec3 tri = caster.triangles[t];
        if (lit[t]) {
            out.insert(out.end(), {near(tri.x), near(tri.y), near(tri.z)});  // near cap
            for (int k = 0; k < 3; ++k) {
                const int other = caster.neighbours[t][k];
                if (other >= 0 && lit[size_t(other)]) continue;
                // Silhouette edge a→b of a lit face: the side quad runs b→a so the closed
                // volume is consistently oriented (each edge traversed once each way).
                const unsigned a = tri[k], b = tri[(k + 1) % 3];
                out.insert(out.end(), {near(b), near(a), far(a), near(b), far(a), far(b)});
            }
        } else {
            out.insert(out.end(), {far(tri.x), far(tri.y), far(tri.z)});  // far cap at infinity
        }
    }
}

}  // namespace ag::gpu
