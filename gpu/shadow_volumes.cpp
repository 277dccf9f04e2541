#include "gpu/shadow_volumes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <tuple>
#include <unordered_map>
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

namespace {

// Two corners weld when they lie within kWeldSteps float steps of the largest coordinate their
// transforms worked with (the translation, the mesh's extent): a quarter turn in a float
// quaternion puts the corner two walls share a step or two apart in each.
constexpr double kWeldSteps = 64.0;

struct WeldCell {
    int level;  // cells of side 2^level
    int64_t x, y, z;
    bool operator==(const WeldCell&) const = default;
};

struct WeldCellHash {
    size_t operator()(const WeldCell& c) const {
        uint64_t h = uint64_t(int64_t(c.level)) * 0x9E3779B97F4A7C15ull;
        for (const int64_t v : {c.x, c.y, c.z}) h = (h ^ uint64_t(v)) * 0xBF58476D1CE4E5B9ull;
        return size_t(h ^ (h >> 31));
    }
};

int64_t cell_index(float v, int level) {
    const double c = std::floor(std::ldexp(double(v), -level));
    return int64_t(std::clamp(c, -0x1p62, 0x1p62));
}

glm::vec3 world_point(const glm::mat4& model, const glm::vec3& p) {
    return glm::vec3(model * glm::vec4(p, 1.0f));
}

// The closed form: the light-facing triangles as the near cap, the others as the far cap, the
// silhouette edges' sides.
void append_closed(const ShadowCaster& caster, const std::vector<glm::vec3>& p,
                   const glm::vec4& light_h, std::vector<glm::vec4>& out) {
    const glm::vec3 light(light_h);
    const float w = light_h.w;  // 1: a point; 0: a direction towards the light
    auto far = [&](unsigned v) { return glm::vec4(w * p[v] - light, 0.0f); };
    auto near = [&](unsigned v) { return glm::vec4(p[v], 1.0f); };
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

// A side face of a soup prism, along edge a→b of its triangle turned to face the light.
struct SideFace {
    uint64_t edge;  // the welded corners' ids, the lower one first
    int sign;       // +1 where a→b runs from the lower id to the higher
    glm::vec3 a, b;
};

void append_side(const glm::vec3& a, const glm::vec3& b, const glm::vec4& light_h,
                 std::vector<glm::vec4>& out) {
    const glm::vec3 light(light_h);
    const float w = light_h.w;
    const glm::vec4 na(a, 1.0f), nb(b, 1.0f), fa(w * a - light, 0.0f), fb(w * b - light, 0.0f);
    out.insert(out.end(), {nb, na, fa, nb, fa, fb});
}

}  // namespace

namespace {

struct Corner {
    glm::vec3 p;
    double tolerance;
};

// SoupWeld::inner: for each outline edge of each soup caster, the welded corners of other meshes
// strictly inside it (within the smaller of the two weld tolerances of the segment). Corners are
// binned in a uniform grid over their bounds; an edge visits the cells its box overlaps.
void find_corners_on_edges(const std::vector<ShadowCaster>& casters,
                           const std::vector<glm::mat4>& models, const std::vector<Corner>& corners,
                           SoupWeld& weld) {
    weld.inner.assign(casters.size(), {});
    if (corners.size() < 3) return;
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const Corner& c : corners) {
        lo = glm::min(lo, glm::dvec3(c.p));
        hi = glm::max(hi, glm::dvec3(c.p));
    }
    const int n = std::clamp(int(std::cbrt(double(corners.size()))), 1, 64);
    const glm::dvec3 size = glm::max(hi - lo, glm::dvec3(1e-30));
    const auto cell_of = [&](const glm::dvec3& p) {
        const glm::dvec3 f = glm::clamp((p - lo) / size * double(n), 0.0, double(n - 1));
        return glm::ivec3(f);
    };
    std::vector<std::vector<uint32_t>> grid(size_t(n) * size_t(n) * size_t(n));
    const auto at = [&](const glm::ivec3& i) -> std::vector<uint32_t>& {
        return grid[(size_t(i.z) * size_t(n) + size_t(i.y)) * size_t(n) + size_t(i.x)];
    };
    for (size_t k = 0; k < corners.size(); ++k)
        at(cell_of(glm::dvec3(corners[k].p))).push_back(uint32_t(k));
    for (size_t o = 0; o < casters.size(); ++o) {
        const ShadowCaster& c = casters[o];
        if (!c.soup) continue;
        const std::vector<uint32_t>& ids = weld.ids[o];
        // The outline: edges (by id) one triangle alone has; with a local corner for each end.
        std::unordered_map<uint64_t, std::pair<int, glm::uvec2>> edges;
        for (const glm::uvec3& t : c.triangles)
            for (int k = 0; k < 3; ++k) {
                const unsigned a = t[k], b = t[(k + 1) % 3];
                const uint32_t ia = ids[a], ib = ids[b];
                if (ia == ib) continue;
                const uint64_t key = (uint64_t(std::min(ia, ib)) << 32) | std::max(ia, ib);
                auto& [count, ends] = edges[key];
                ++count;
                ends = ia < ib ? glm::uvec2(a, b) : glm::uvec2(b, a);
            }
        for (const auto& [key, edge] : edges) {
            if (edge.first != 1) continue;
            const glm::dvec3 a(world_point(models[o], c.positions[edge.second.x]));
            const glm::dvec3 b(world_point(models[o], c.positions[edge.second.y]));
            const uint32_t ia = uint32_t(key >> 32), ib = uint32_t(key & 0xffffffffu);
            const double tolerance = std::min(corners[ia].tolerance, corners[ib].tolerance);
            const glm::dvec3 d = b - a;
            const double length2 = glm::dot(d, d);
            if (!(length2 > 0.0) || !std::isfinite(length2)) continue;
            const glm::ivec3 c0 = cell_of(glm::min(a, b) - tolerance);
            const glm::ivec3 c1 = cell_of(glm::max(a, b) + tolerance);
            std::vector<std::pair<double, uint32_t>> on;
            for (int z = c0.z; z <= c1.z; ++z)
                for (int y = c0.y; y <= c1.y; ++y)
                    for (int x = c0.x; x <= c1.x; ++x)
                        for (const uint32_t k : at({x, y, z})) {
                            if (k == ia || k == ib) continue;
                            const glm::dvec3 p(corners[k].p);
                            const double t = glm::dot(p - a, d) / length2;
                            if (!(t > 0.0 && t < 1.0)) continue;
                            const double within = std::min(tolerance, corners[k].tolerance);
                            const glm::dvec3 off = glm::abs(a + t * d - p);
                            if (std::max({off.x, off.y, off.z}) > within) continue;
                            // Not one of the ends (those would have welded to it).
                            if (glm::length(p - a) <= within || glm::length(p - b) <= within)
                                continue;
                            on.emplace_back(t, k);
                        }
            if (on.empty()) continue;
            std::sort(on.begin(), on.end());
            std::vector<uint32_t>& list = weld.inner[o][key];
            for (const auto& [t, k] : on) list.push_back(k);
        }
    }
}

}  // namespace

SoupWeld weld_soup_corners(const std::vector<ShadowCaster>& casters,
                           const std::vector<glm::mat4>& models) {
    SoupWeld weld;
    weld.ids.resize(casters.size());
    std::vector<Corner> corners;  // one per id: the first corner that took it
    std::unordered_map<WeldCell, std::vector<uint32_t>, WeldCellHash> grid;
    std::vector<int> levels;  // those grid holds, in the order first used
    for (size_t o = 0; o < casters.size(); ++o) {
        const ShadowCaster& c = casters[o];
        if (!c.soup) continue;
        const glm::mat4& m = models[o];
        float extent = std::max({std::abs(m[3].x), std::abs(m[3].y), std::abs(m[3].z)});
        for (const glm::vec3& v : c.positions)
            extent = std::max({extent, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
        const double tolerance =
            std::max(kWeldSteps * double(std::numeric_limits<float>::epsilon()) * double(extent),
                     double(std::numeric_limits<float>::min()));
        int level = 0;
        std::frexp(tolerance, &level);  // tolerance < 2^level: a corner's cell and its neighbours
                                        // hold every corner within it
        if (std::find(levels.begin(), levels.end(), level) == levels.end()) levels.push_back(level);
        weld.ids[o].resize(c.positions.size());
        for (size_t i = 0; i < c.positions.size(); ++i) {
            const glm::vec3 p = world_point(m, c.positions[i]);
            // The lowest id within the smaller of the two tolerances. Looked for at every level:
            // a corner of level L lies within 2^L of what it welds with, so the 27 cells of side
            // 2^L around p hold it.
            uint32_t id = std::numeric_limits<uint32_t>::max();
            for (const int l : levels)
                for (int dz = -1; dz <= 1; ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            const WeldCell cell{l, cell_index(p.x, l) + dx, cell_index(p.y, l) + dy,
                                                cell_index(p.z, l) + dz};
                            const auto it = grid.find(cell);
                            if (it == grid.end()) continue;
                            for (const uint32_t k : it->second) {
                                const glm::vec3 d = glm::abs(corners[k].p - p);
                                const double within = std::min(tolerance, corners[k].tolerance);
                                if (double(std::max({d.x, d.y, d.z})) <= within)
                                    id = std::min(id, k);
                            }
                        }
            if (id == std::numeric_limits<uint32_t>::max()) {
                id = uint32_t(corners.size());
                corners.push_back({p, tolerance});
                grid[{level, cell_index(p.x, level), cell_index(p.y, level),
                      cell_index(p.z, level)}]
                    .push_back(id);
            }
            weld.ids[o][i] = id;
        }
    }
    weld.corners.reserve(corners.size());
    for (const Corner& c : corners) weld.corners.push_back(c.p);
    weld.planes.assign(casters.size(), {});
    for (size_t o = 0; o < casters.size(); ++o) {
        const ShadowCaster& c = casters[o];
        if (!c.soup || c.positions.empty()) continue;
        // The plane of the largest triangle; planar if every corner lies within the weld
        // tolerance of it.
        std::vector<glm::dvec3> p(c.positions.size());
        for (size_t i = 0; i < p.size(); ++i)
            p[i] = glm::dvec3(world_point(models[o], c.positions[i]));
        glm::dvec3 normal(0.0);
        double largest = 0.0;
        for (const glm::uvec3& t : c.triangles) {
            const glm::dvec3 n = glm::cross(p[t.y] - p[t.x], p[t.z] - p[t.x]);
            const double l = glm::length(n);
            if (l > largest && std::isfinite(l)) {
                largest = l;
                normal = n / l;
            }
        }
        if (!(largest > 0.0)) continue;
        const double offset = -glm::dot(normal, p[c.triangles.front().x]);
        double tolerance = 0.0;
        for (const uint32_t id : weld.ids[o])
            tolerance = std::max(tolerance, corners[id].tolerance);
        bool planar = true;
        for (const glm::dvec3& q : p)
            planar = planar && std::abs(glm::dot(normal, q) + offset) <= tolerance;
        if (planar) weld.planes[o] = {normal, offset, tolerance};
    }
    find_corners_on_edges(casters, models, corners, weld);
    return weld;
}

namespace {

// The receiver test of append_shadow_volumes: whether every receiver but the caster itself lies
// on the light's side of the planar soup's plane or in it (its volume then holds none).
bool shadows_nothing(const SoupWeld::Plane& plane, size_t self,
                     const std::vector<Bounds>& receivers, const glm::vec4& light_h) {
    if (!(plane.tolerance > 0.0)) return false;
    const double towards =
        glm::dot(plane.normal, glm::dvec3(light_h)) + double(light_h.w) * plane.offset;
    if (towards == 0.0 || !std::isfinite(towards)) return false;
    const double side = towards > 0.0 ? 1.0 : -1.0;
    for (size_t r = 0; r < receivers.size(); ++r) {
        const Bounds& b = receivers[r];
        if (r == self || b.empty()) continue;
        // The corner of the box farthest behind the plane.
        const glm::dvec3 n = side * plane.normal;
        const glm::dvec3 corner(n.x >= 0.0 ? b.min.x : b.max.x, n.y >= 0.0 ? b.min.y : b.max.y,
                                n.z >= 0.0 ? b.min.z : b.max.z);
        if (!(glm::dot(n, corner) + side * plane.offset >= -plane.tolerance)) return false;
    }
    return true;
}

}  // namespace

void append_shadow_volumes(const std::vector<ShadowCaster>& casters,
                           const std::vector<glm::mat4>& models, const SoupWeld& weld,
                           const glm::vec4& light_h, std::vector<glm::vec4>& out,
                           const std::vector<Bounds>* receivers) {
    const glm::vec3 light(light_h);
    const float w = light_h.w;  // 1: a point; 0: a direction towards the light
    std::vector<SideFace> sides;
    std::unordered_map<uint64_t, int> net;  // per welded edge: sides drawn lower→higher − back
    std::vector<glm::vec3> p;
    std::vector<uint32_t> chain;  // an edge's ids from one end to the other
    for (size_t o = 0; o < casters.size(); ++o) {
        const ShadowCaster& caster = casters[o];
        if (!caster.closed && !caster.soup) continue;
        p.resize(caster.positions.size());
        for (size_t i = 0; i < p.size(); ++i) p[i] = world_point(models[o], caster.positions[i]);
        if (caster.closed) {
            append_closed(caster, p, light_h, out);
            continue;
        }
        if (receivers && o < weld.planes.size() &&
            shadows_nothing(weld.planes[o], o, *receivers, light_h))
            continue;
        // Each triangle, turned to face the light (an opaque sheet blocks from either side), as
        // its own closed prism: near cap, far cap here, three sides below.
        const std::vector<uint32_t>& ids = weld.ids[o];
        for (const glm::uvec3& t : caster.triangles) {
            glm::uvec3 tri = t;
            const glm::vec3 n = glm::cross(p[tri.y] - p[tri.x], p[tri.z] - p[tri.x]);
            const float facing = glm::dot(n, light - w * p[tri.x]);
            if (facing == 0.0f || !std::isfinite(facing)) continue;  // edge-on: no volume
            if (facing < 0.0f) std::swap(tri.y, tri.z);
            out.insert(out.end(), {glm::vec4(p[tri.x], 1.0f), glm::vec4(p[tri.y], 1.0f),
                                   glm::vec4(p[tri.z], 1.0f)});
            out.insert(out.end(), {glm::vec4(w * p[tri.x] - light, 0.0f),
                                   glm::vec4(w * p[tri.z] - light, 0.0f),
                                   glm::vec4(w * p[tri.y] - light, 0.0f)});
            for (int k = 0; k < 3; ++k) {
                const unsigned a = tri[k], b = tri[(k + 1) % 3];
                const uint32_t ia = ids[a], ib = ids[b];
                if (ia == ib) {  // shorter than the weld: nothing shares it
                    append_side(p[a], p[b], light_h, out);
                    continue;
                }
                const uint64_t edge = (uint64_t(std::min(ia, ib)) << 32) | std::max(ia, ib);
                // Other meshes' corners on the edge split it into pieces, each of which may be
                // shared.
                chain.assign(1, ia);
                if (!weld.inner.empty()) {
                    const auto it = weld.inner[o].find(edge);
                    if (it != weld.inner[o].end()) {
                        if (ia < ib)
                            chain.insert(chain.end(), it->second.begin(), it->second.end());
                        else
                            chain.insert(chain.end(), it->second.rbegin(), it->second.rend());
                    }
                }
                chain.push_back(ib);
                for (size_t i = 0; i + 1 < chain.size(); ++i) {
                    const uint32_t u = chain[i], v = chain[i + 1];
                    const glm::vec3 pu = i == 0 ? p[a] : weld.corners[u];
                    const glm::vec3 pv = i + 2 == chain.size() ? p[b] : weld.corners[v];
                    const uint64_t piece = (uint64_t(std::min(u, v)) << 32) | std::max(u, v);
                    const int sign = u < v ? 1 : -1;
                    net[piece] += sign;
                    sides.push_back({piece, sign, pu, pv});
                }
            }
        }
    }
    // A side face two prisms share, drawn once each way, cancels in the stencil count; drawn from
    // two meshes' corners (a few float steps apart) and split along other diagonals, the pair
    // rasterized at slightly different depths where it meets the receivers along the seam and
    // left cracks of light there. Only the sides of each edge's net count are drawn.
    for (const SideFace& s : sides) {
        int& left = net[s.edge];
        if (left == 0 || (left > 0) != (s.sign > 0)) continue;
        append_side(s.a, s.b, light_h, out);
        left -= s.sign;
    }
}

void append_shadow_volume(const ShadowCaster& caster, const glm::mat4& model,
                          const glm::vec3& light, std::vector<glm::vec4>& out) {
    append_shadow_volume(caster, model, glm::vec4(light, 1.0f), out);
}

void append_shadow_volume(const ShadowCaster& caster, const glm::mat4& model,
                          const glm::vec4& light_h, std::vector<glm::vec4>& out) {
    const std::vector<ShadowCaster> one{caster};
    const std::vector<glm::mat4> models{model};
    append_shadow_volumes(one, models, weld_soup_corners(one, models), light_h, out);
}

}  // namespace ag::gpu
