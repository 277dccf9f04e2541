#include "gpu/shadow_volumes.h"

#include <map>
#include <tuple>

namespace ag::gpu {

ShadowCaster make_shadow_caster(const Mesh& mesh) {
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
    // Small holes (a quad's outline, a box without its bottom) are closed by fans for the shadow
    // volume only, so thin panels and open boxes still cast shadows. Large boundaries (a floor's
    // rim) stay open: such a mesh casts no volume.
    std::map<unsigned, unsigned> boundary_next;
    for (const auto& [edge, owner] : edges)
        if (!edges.count({edge.second, edge.first})) {
            if (!boundary_next.emplace(edge.first, edge.second).second) return ShadowCaster{};
        }
    constexpr size_t kMaxHole = 16;
    while (!boundary_next.empty()) {
        std::vector<unsigned> loop{boundary_next.begin()->first};
        for (unsigned v = boundary_next.begin()->second; v != loop.front();
             v = boundary_next.at(v)) {
            if (!boundary_next.count(v) || loop.size() > kMaxHole) return ShadowCaster{};
            loop.push_back(v);
        }
        for (unsigned v : loop) boundary_next.erase(v);
        // The fill runs each boundary edge backwards: fan (v0, v[i+1], v[i]).
        for (size_t i = 1; i + 1 < loop.size(); ++i) {
            const int t = int(c.triangles.size());
            c.triangles.push_back({loop[0], loop[i + 1], loop[i]});
            for (int k = 0; k < 3; ++k) {
                const unsigned a = c.triangles.back()[k], b = c.triangles.back()[(k + 1) % 3];
                if (!edges.emplace(std::make_pair(a, b), std::make_pair(t, k)).second)
                    return ShadowCaster{};
            }
        }
    }
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
    if (!caster.closed) return;
    std::vector<glm::vec3> p(caster.positions.size());
    for (size_t i = 0; i < p.size(); ++i)
        p[i] = glm::vec3(model * glm::vec4(caster.positions[i], 1.0f));
    std::vector<char> lit(caster.triangles.size());
    for (size_t t = 0; t < caster.triangles.size(); ++t) {
        const glm::uvec3 tri = caster.triangles[t];
        const glm::vec3 n = glm::cross(p[tri.y] - p[tri.x], p[tri.z] - p[tri.x]);
        lit[t] = glm::dot(n, light - p[tri.x]) > 0.0f;
    }
    auto far = [&](unsigned v) { return glm::vec4(p[v] - light, 0.0f); };
    auto near = [&](unsigned v) { return glm::vec4(p[v], 1.0f); };
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
