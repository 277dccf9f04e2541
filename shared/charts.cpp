// Surfaces by crease angle (Larsen ch. 8), lightmap charts cut from them, one packed atlas and a
// record per texel (the layout the AIMs of ch. 10 and the IIM gathers of ch. 11 write into).
#include "shared/charts.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "shared/chart_cells.h"
#include "shared/input_error.h"
#include "shared/texel_density.h"

namespace ag {
namespace {

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;
using Tri2 = std::array<glm::dvec2, 3>;

constexpr double kDegree = std::numbers::pi / 180.0;
// A texel belongs to a chart if its square overlaps chart triangles by more than this (texel²);
// anything smaller is a rounding sliver along a texel line.
constexpr double kMinCoverage = 1e-9;
// The same for the parts of a tiled chart (cut_contact_tiles): their seam lies on a texel edge up
// to the rounding of the split vertices (~1e-6 texel), which must not make a texel of its own.
constexpr double kMinTileCoverage = 1e-4;
// Snapped texel centres move this fraction of the way to the triangle's centroid, so they sit
// strictly inside a chart triangle rather than on an edge shared with a crease (ch. 8, 11).
constexpr double kSnapNudge = 1e-3;

// Equal positions get one id, so meshes that repeat corners per face (boxes exported with
// per-face normals) are still connected across their edges.
std::vector<int> weld_positions(const Mesh& mesh, int* welded_count) {
    const std::vector<glm::vec3>& p = mesh.positions;
    std::vector<int> ids(p.size(), -1);
    std::vector<int> order;
    order.reserve(p.size());
    int next = 0;
    for (int i = 0; i < int(p.size()); ++i) {
        const glm::vec3& q = p[size_t(i)];
        // NaN would break the sort's ordering; such a vertex simply stays on its own.
        if (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z))
            order.push_back(i);
        else
            ids[size_t(i)] = next++;
    }
    auto less = [&](int a, int b) {
        const glm::vec3 &pa = p[size_t(a)], &pb = p[size_t(b)];
        if (pa.x != pb.x) return pa.x < pb.x;
        if (pa.y != pb.y) return pa.y < pb.y;
        if (pa.z != pb.z) return pa.z < pb.z;
        return a < b;
    };
    std::sort(order.begin(), order.end(), less);
    for (size_t i = 0; i < order.size(); ++i) {
        if (i == 0 || p[size_t(order[i])] != p[size_t(order[i - 1])]) ++next;
        ids[size_t(order[i])] = next - 1;
    }
    *welded_count = next;
    return ids;
}

uint64_t edge_key(int a, int b) { return uint64_t(uint32_t(a)) << 32 | uint32_t(b); }

// Edge adjacency between triangles, compressed rows sorted by neighbour index.
struct Adjacency {
    std::vector<int> offsets;  // triangle count + 1
    std::vector<int> neighbours;

    int begin(int t) const { return offsets[size_t(t)]; }
    int end(int t) const { return offsets[size_t(t) + 1]; }
};

// OpenMesh's half-edge structure gives the adjacency of the manifold part. It refuses faces on
// an edge that already has two faces or the same direction, and some non-manifold fans; those
// triangles are matched instead through a map keyed by their sorted (welded) edge vertices, so
// any triangle soup gets an adjacency and nothing is dropped.
Adjacency triangle_adjacency(const Mesh& mesh) {
    const int n = int(mesh.triangles.size());
    int welded_count = 0;
    const std::vector<int> weld = weld_positions(mesh, &welded_count);
    std::vector<std::array<int, 3>> corners(static_cast<size_t>(n));
    for (int t = 0; t < n; ++t)
        for (int k = 0; k < 3; ++k)
            corners[size_t(t)][size_t(k)] = weld[mesh.triangles[size_t(t)][k]];

    // Directed edges used twice and undirected edges used more than twice make OpenMesh fail
    // (loudly); send their triangles to the edge map up front.
    std::vector<uint8_t> fallback(size_t(n), 0);
    std::vector<uint64_t> directed, undirected;
    directed.reserve(3 * size_t(n));
    undirected.reserve(3 * size_t(n));
    for (int t = 0; t < n; ++t) {
        const auto& c = corners[size_t(t)];
        if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) {
            fallback[size_t(t)] = 1;
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            const int a = c[size_t(k)], b = c[size_t((k + 1) % 3)];
            directed.push_back(edge_key(a, b));
            undirected.push_back(edge_key(std::min(a, b), std::max(a, b)));
        }
    }
    std::sort(directed.begin(), directed.end());
    std::sort(undirected.begin(), undirected.end());
    std::vector<uint64_t> bad;
    for (size_t i = 1; i < directed.size(); ++i)
        if (directed[i] == directed[i - 1]) bad.push_back(directed[i]);
    for (size_t i = 2; i < undirected.size(); ++i)
        if (undirected[i] == undirected[i - 2]) bad.push_back(undirected[i]);
    std::sort(bad.begin(), bad.end());
    auto is_bad = [&](uint64_t key) { return std::binary_search(bad.begin(), bad.end(), key); };
    for (int t = 0; t < n && !bad.empty(); ++t) {
        const auto& c = corners[size_t(t)];
        for (int k = 0; k < 3 && !fallback[size_t(t)]; ++k) {
            const int a = c[size_t(k)], b = c[size_t((k + 1) % 3)];
            if (is_bad(edge_key(a, b)) || is_bad(edge_key(std::min(a, b), std::max(a, b))))
                fallback[size_t(t)] = 1;
        }
    }

    OmMesh om;
    om.reserve(size_t(welded_count), 3 * size_t(n), size_t(n));
    std::vector<glm::vec3> welded_positions(static_cast<size_t>(welded_count));
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        welded_positions[size_t(weld[i])] = mesh.positions[i];
    for (const glm::vec3& p : welded_positions) om.add_vertex(OmMesh::Point(p.x, p.y, p.z));
    std::vector<int> face_triangle;
    face_triangle.reserve(size_t(n));
    // A face OpenMesh cannot link (a non-manifold patch) is handled below as a fallback triangle;
    // its notes on the error stream, one a face, would only bury the real messages.
    struct QuietOpenMesh {
        bool was = omerr().is_enabled();
        QuietOpenMesh() { omerr().disable(); }
        ~QuietOpenMesh() {
            if (was) omerr().enable();
        }
    } quiet;
    for (int t = 0; t < n; ++t) {
        if (fallback[size_t(t)]) continue;
        const auto& c = corners[size_t(t)];
        const OmMesh::FaceHandle fh = om.add_face(
            OmMesh::VertexHandle(c[0]), OmMesh::VertexHandle(c[1]), OmMesh::VertexHandle(c[2]));
        if (fh.is_valid())
            face_triangle.push_back(t);
        else
            fallback[size_t(t)] = 1;
    }

    std::vector<std::pair<int, int>> pairs;
    pairs.reserve(3 * size_t(n));
    for (const OmMesh::FaceHandle fh : om.faces()) {
        const int t = face_triangle[size_t(fh.idx())];
        for (const OmMesh::HalfedgeHandle heh : om.fh_range(fh)) {
            const OmMesh::FaceHandle other = om.opposite_face_handle(heh);
            if (other.is_valid()) pairs.emplace_back(t, face_triangle[size_t(other.idx())]);
        }
    }
    std::vector<std::pair<uint64_t, int>> loose_edges;
    for (int t = 0; t < n; ++t) {
        if (!fallback[size_t(t)]) continue;
        const auto& c = corners[size_t(t)];
        for (int k = 0; k < 3; ++k) {
            const int a = c[size_t(k)], b = c[size_t((k + 1) % 3)];
            if (a != b) loose_edges.emplace_back(edge_key(std::min(a, b), std::max(a, b)), t);
        }
    }
    std::sort(loose_edges.begin(), loose_edges.end());
    if (!loose_edges.empty()) {
        for (int t = 0; t < n; ++t) {
            const auto& c = corners[size_t(t)];
            for (int k = 0; k < 3; ++k) {
                const int a = c[size_t(k)], b = c[size_t((k + 1) % 3)];
                if (a == b) continue;
                const uint64_t key = edge_key(std::min(a, b), std::max(a, b));
                auto it = std::lower_bound(loose_edges.begin(), loose_edges.end(),
                                           std::pair<uint64_t, int>(key, -1));
                for (; it != loose_edges.end() && it->first == key; ++it) {
                    if (it->second == t) continue;
                    pairs.emplace_back(t, it->second);
                    pairs.emplace_back(it->second, t);
                }
            }
        }
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());

    Adjacency adjacency;
    adjacency.offsets.assign(size_t(n) + 1, 0);
    adjacency.neighbours.reserve(pairs.size());
    for (const auto& [t, other] : pairs) {
        ++adjacency.offsets[size_t(t) + 1];
        adjacency.neighbours.push_back(other);
    }
    for (int t = 0; t < n; ++t) adjacency.offsets[size_t(t) + 1] += adjacency.offsets[size_t(t)];
    return adjacency;
}

int find_root(std::vector<int>& parent, int i) {
    while (parent[size_t(i)] != i) {
        parent[size_t(i)] = parent[size_t(parent[size_t(i)])];
        i = parent[size_t(i)];
    }
    return i;
}

void unite(std::vector<int>& parent, int a, int b) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a != b) parent[size_t(std::max(a, b))] = std::min(a, b);
}

// Larsen's rule (ch. 8.1): an edge is connected when the normals on both sides differ by less
// than α, and polygons joined by connected edges share one photon map.
std::vector<int> segment(const Mesh& mesh, const Adjacency& adjacency, float crease_angle_deg,
                         int* surface_count) {
    const int n = int(mesh.triangles.size());
    const float cos_crease = float(std::cos(double(crease_angle_deg) * kDegree));
    std::vector<glm::vec3> normals(static_cast<size_t>(n));
    std::vector<uint8_t> degenerate(static_cast<size_t>(n));
    for (int t = 0; t < n; ++t) {
        degenerate[size_t(t)] = is_degenerate_triangle(mesh, t);
        normals[size_t(t)] = triangle_normal(mesh, t);
    }
    std::vector<int> parent(static_cast<size_t>(n));
    std::iota(parent.begin(), parent.end(), 0);
    for (int t = 0; t < n; ++t) {
        if (degenerate[size_t(t)]) continue;
        for (int i = adjacency.begin(t); i < adjacency.end(t); ++i) {
            const int o = adjacency.neighbours[size_t(i)];
            if (o > t && !degenerate[size_t(o)] &&
                glm::dot(normals[size_t(t)], normals[size_t(o)]) > cos_crease)
                unite(parent, t, o);
        }
    }
    // A degenerate triangle has no trustworthy normal: it joins the surface of a neighbour
    // (through chains of degenerate ones) but never bridges two surfaces.
    std::vector<uint8_t> anchored(static_cast<size_t>(n));
    for (int t = 0; t < n; ++t) anchored[size_t(t)] = !degenerate[size_t(t)];
    for (bool changed = true; changed;) {
        changed = false;
        for (int t = 0; t < n; ++t) {
            if (anchored[size_t(t)]) continue;
            for (int i = adjacency.begin(t); i < adjacency.end(t); ++i) {
                const int o = adjacency.neighbours[size_t(i)];
                if (!anchored[size_t(o)]) continue;
                unite(parent, t, o);
                anchored[size_t(t)] = 1;
                changed = true;
                break;
            }
        }
    }
    std::vector<int> root_id(size_t(n), -1), ids(static_cast<size_t>(n));
    int count = 0;
    for (int t = 0; t < n; ++t) {
        int& id = root_id[size_t(find_root(parent, t))];
        if (id < 0) id = count++;
        ids[size_t(t)] = id;
    }
    *surface_count = count;
    return ids;
}

// Projection frame of a chart: u × v = axis, so counter-clockwise fronts stay counter-clockwise
// in the atlas. The world axis least aligned with `axis` fixes u, deterministically.
struct Frame {
    glm::dvec3 axis, u, v;

    explicit Frame(const glm::dvec3& n) : axis(n) {
        const glm::dvec3 a = glm::abs(n);
        const glm::dvec3 least = a.x <= a.y && a.x <= a.z ? glm::dvec3(1, 0, 0)
                                 : a.y <= a.z             ? glm::dvec3(0, 1, 0)
                                                          : glm::dvec3(0, 0, 1);
        u = glm::normalize(glm::cross(n, least));
        v = glm::cross(n, u);
    }
    glm::dvec2 project(const glm::vec3& p) const {
        const glm::dvec3 q(p);
        return {glm::dot(q, u), glm::dot(q, v)};
    }
};

Tri2 project_triangle(const Mesh& mesh, const Frame& frame, int t) {
    const glm::uvec3 tri = mesh.triangles[size_t(t)];
    return {frame.project(mesh.positions[tri.x]), frame.project(mesh.positions[tri.y]),
            frame.project(mesh.positions[tri.z])};
}

double cross2(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

// Separating axes: two triangles overlap unless one of their six edge normals separates them,
// allowing `eps` of interpenetration so that neighbours sharing an edge or a corner (equal up to
// rounding) do not count as overlapping.
bool triangles_overlap(const Tri2& a, const Tri2& b, double eps) {
    for (const Tri2* t : {&a, &b})
        for (int k = 0; k < 3; ++k) {
            const glm::dvec2 e = (*t)[size_t((k + 1) % 3)] - (*t)[size_t(k)];
            const glm::dvec2 axis(-e.y, e.x);
            const double tolerance = eps * glm::length(axis);
            double min_a = 1e300, max_a = -1e300, min_b = 1e300, max_b = -1e300;
            for (int i = 0; i < 3; ++i) {
                const double pa = glm::dot(a[size_t(i)], axis), pb = glm::dot(b[size_t(i)], axis);
                min_a = std::min(min_a, pa), max_a = std::max(max_a, pa);
                min_b = std::min(min_b, pb), max_b = std::max(max_b, pb);
            }
            if (max_a - min_b <= tolerance || max_b - min_a <= tolerance) return false;
        }
    return true;
}

// The projected triangles of one chart in a uniform hash grid, to refuse a triangle whose flat
// image would land on top of the chart (a spiral ramp, a fold: normals inside the cone do not
// make a surface a height field).
class OverlapGrid {
public:
    void reset(double cell, double eps) {
        cell_ = cell;
        eps_ = eps;
        // clear() keeps (and wipes) every bucket of the largest chart so far; many small charts
        // after one big one would pay for that each time.
        if (cells_.bucket_count() > 4096)
            cells_ = {};
        else
            cells_.clear();
        triangles_.clear();
        big_.clear();
        seen_.clear();
    }

    bool overlaps(const Tri2& t) {
        ++query_;
        const CellRange r = range(t);
        auto test = [&](int id) {
            if (seen_[size_t(id)] == query_) return false;
            seen_[size_t(id)] = query_;
            return triangles_overlap(t, triangles_[size_t(id)], eps_);
        };
        if (r.count() > kMaxCells) {
            for (int id = 0; id < int(triangles_.size()); ++id)
                if (test(id)) return true;
            return false;
        }
        for (int id : big_)
            if (test(id)) return true;
        for (int64_t y = r.y0; y <= r.y1; ++y)
            for (int64_t x = r.x0; x <= r.x1; ++x) {
                const auto it = cells_.find(key(x, y));
                if (it == cells_.end()) continue;
                for (int id : it->second)
                    if (test(id)) return true;
            }
        return false;
    }

    void insert(const Tri2& t) {
        const int id = int(triangles_.size());
        triangles_.push_back(t);
        seen_.push_back(0);
        const CellRange r = range(t);
        if (r.count() > kMaxCells) {
            big_.push_back(id);
            return;
        }
        for (int64_t y = r.y0; y <= r.y1; ++y)
            for (int64_t x = r.x0; x <= r.x1; ++x) cells_[key(x, y)].push_back(id);
    }

private:
    // Triangles far larger than the cell are tested against everything instead of being
    // spread over thousands of cells.
    static constexpr double kMaxCells = 256;

    struct CellRange {
        int64_t x0, y0, x1, y1;
        double count() const { return double(x1 - x0 + 1) * double(y1 - y0 + 1); }
    };
    CellRange range(const Tri2& t) const {
        const glm::dvec2 lo = glm::min(glm::min(t[0], t[1]), t[2]);
        const glm::dvec2 hi = glm::max(glm::max(t[0], t[1]), t[2]);
        auto cell = [&](double c) {
            return int64_t(std::floor(std::clamp(c / cell_, -1e15, 1e15)));
        };
        return {cell(lo.x), cell(lo.y), cell(hi.x), cell(hi.y)};
    }
    // Wrapping coordinates only merge cells, which costs tests, never correctness.
    static uint64_t key(int64_t x, int64_t y) { return uint64_t(x) << 32 ^ uint64_t(uint32_t(y)); }

    double cell_ = 1.0, eps_ = 0.0;
    std::unordered_map<uint64_t, std::vector<int>> cells_;
    std::vector<Tri2> triangles_;
    std::vector<int> big_;
    std::vector<uint32_t> seen_;
    uint32_t query_ = 0;
};

// Per-triangle quantities that chart growth reads over and over.
struct TriangleInfo {
    std::vector<glm::dvec3> normal;  // unit, zero for degenerate triangles
    std::vector<glm::dvec3> cross;   // 2 × area along the normal
    std::vector<double> area;
    std::vector<uint8_t> degenerate;
};

TriangleInfo triangle_info(const Mesh& mesh) {
    const size_t n = mesh.triangles.size();
    TriangleInfo info;
    info.normal.resize(n);
    info.cross.resize(n);
    info.area.resize(n);
    info.degenerate.resize(n);
    for (size_t t = 0; t < n; ++t) {
        const glm::uvec3 tri = mesh.triangles[t];
        const glm::dvec3 a(mesh.positions[tri.x]), b(mesh.positions[tri.y]),
            c(mesh.positions[tri.z]);
        info.cross[t] = glm::cross(b - a, c - a);
        info.area[t] = 0.5 * glm::length(info.cross[t]);
        info.degenerate[t] = is_degenerate_triangle(mesh, int(t));
        info.normal[t] = info.degenerate[t] ? glm::dvec3(0.0) : glm::normalize(info.cross[t]);
    }
    return info;
}

struct ChartCut {
    std::vector<int> triangles;
    glm::dvec3 axis;
};

// Cuts one surface into charts by greedy region growing (breadth first over edge neighbours).
// Growth keeps the seed's normal as the projection axis, so every member is within the cone of
// it; afterwards the area-weighted mean normal replaces it if every member is within the cone
// of the mean too and the flat image does not fold in its plane. A member at angle θ from the
// axis is stretched by 1/cos θ in area: the cone bounds the lightmap's distortion.
std::vector<ChartCut> cut_charts(const Mesh& mesh, const Adjacency& adjacency,
                                 const TriangleInfo& info, const std::vector<int>& surface_of,
                                 int surface, const std::vector<int>& members, double cos_cone,
                                 std::vector<int>& chart_of, std::vector<int>& tried, int& stamp,
                                 OverlapGrid& grid) {
    glm::dvec3 mean(0.0);
    double edge_sum = 0.0;
    int edge_count = 0;
    for (int t : members) {
        mean += info.cross[size_t(t)];
        if (info.degenerate[size_t(t)]) continue;
        const glm::uvec3 tri = mesh.triangles[size_t(t)];
        const glm::vec3 a = mesh.positions[tri.x], b = mesh.positions[tri.y],
                        c = mesh.positions[tri.z];
        edge_sum += double(std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)}));
        ++edge_count;
    }
    const double cell = edge_count > 0 && edge_sum > 0.0 ? edge_sum / edge_count : 1.0;
    const double eps = 1e-6 * cell;
    const glm::dvec3 surface_normal =
        glm::length(mean) > 0.0 ? glm::normalize(mean) : glm::dvec3(0.0, 0.0, 1.0);

    // Seeds: the triangles most aligned with the surface's mean normal first (on a bumpy floor
    // that grows one big chart from the flat parts instead of starting at the steepest bump),
    // then the largest, then the lowest index.
    std::vector<int> seeds = members;
    std::vector<double> alignment(seeds.size());
    for (size_t i = 0; i < seeds.size(); ++i)
        alignment[i] = glm::dot(info.normal[size_t(seeds[i])], surface_normal);
    std::vector<size_t> order(seeds.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        const int ta = seeds[a], tb = seeds[b];
        if (info.degenerate[size_t(ta)] != info.degenerate[size_t(tb)])
            return info.degenerate[size_t(tb)] > info.degenerate[size_t(ta)];
        if (alignment[a] != alignment[b]) return alignment[a] > alignment[b];
        if (info.area[size_t(ta)] != info.area[size_t(tb)])
            return info.area[size_t(ta)] > info.area[size_t(tb)];
        return ta < tb;
    });

    std::vector<ChartCut> charts;
    for (size_t oi : order) {
        const int seed = seeds[oi];
        if (chart_of[size_t(seed)] >= 0) continue;
        const int id = int(charts.size());
        ++stamp;
        ChartCut chart;
        chart.axis = info.degenerate[size_t(seed)] ? surface_normal : info.normal[size_t(seed)];
        const Frame frame(chart.axis);
        grid.reset(cell, eps);
        chart.triangles.push_back(seed);
        chart_of[size_t(seed)] = id;
        tried[size_t(seed)] = stamp;
        if (!info.degenerate[size_t(seed)]) grid.insert(project_triangle(mesh, frame, seed));
        for (size_t head = 0; head < chart.triangles.size(); ++head) {
            const int t = chart.triangles[head];
            for (int i = adjacency.begin(t); i < adjacency.end(t); ++i) {
                const int o = adjacency.neighbours[size_t(i)];
                // Each test depends only on the chart so far, which only grows: a refused
                // triangle stays refused, so try each once.
                if (tried[size_t(o)] == stamp) continue;
                tried[size_t(o)] = stamp;
                if (chart_of[size_t(o)] >= 0 || surface_of[size_t(o)] != surface) continue;
                if (!info.degenerate[size_t(o)]) {
                    if (glm::dot(info.normal[size_t(o)], chart.axis) < cos_cone) continue;
                    const Tri2 projected = project_triangle(mesh, frame, o);
                    if (grid.overlaps(projected)) continue;
                    grid.insert(projected);
                }
                chart_of[size_t(o)] = id;
                chart.triangles.push_back(o);
            }
        }

        glm::dvec3 chart_mean(0.0);
        for (int t : chart.triangles) chart_mean += info.cross[size_t(t)];
        if (chart.triangles.size() > 1 && glm::length(chart_mean) > 0.0) {
            const glm::dvec3 m = glm::normalize(chart_mean);
            bool ok = glm::dot(m, chart.axis) < 1.0;
            for (size_t i = 0; ok && i < chart.triangles.size(); ++i) {
                const int t = chart.triangles[i];
                ok = info.degenerate[size_t(t)] || glm::dot(info.normal[size_t(t)], m) >= cos_cone;
            }
            if (ok) {
                const Frame mean_frame(m);
                grid.reset(cell, eps);
                for (size_t i = 0; ok && i < chart.triangles.size(); ++i) {
                    const int t = chart.triangles[i];
                    if (info.degenerate[size_t(t)]) continue;
                    const Tri2 projected = project_triangle(mesh, mean_frame, t);
                    ok = !grid.overlaps(projected);
                    grid.insert(projected);
                }
            }
            if (ok) chart.axis = m;
        }
        std::sort(chart.triangles.begin(), chart.triangles.end());
        charts.push_back(std::move(chart));
    }
    return charts;
}

// Area of the unit square [0,1]² (texel-local coordinates) inside a counter-clockwise triangle,
// by Sutherland–Hodgman clipping of the square against the triangle's three edges.
double clipped_square_area(const Tri2& tri) {
    std::array<glm::dvec2, 8> poly{glm::dvec2(0, 0), glm::dvec2(1, 0), glm::dvec2(1, 1),
                                   glm::dvec2(0, 1)};
    std::array<glm::dvec2, 8> next;
    int count = 4;
    for (int k = 0; k < 3 && count > 0; ++k) {
        const glm::dvec2 a = tri[size_t(k)], e = tri[size_t((k + 1) % 3)] - a;
        int out = 0;
        for (int i = 0; i < count; ++i) {
            const glm::dvec2 p = poly[size_t(i)], q = poly[size_t((i + 1) % count)];
            const double dp = cross2(e, p - a), dq = cross2(e, q - a);
            if (dp >= 0.0) next[size_t(out++)] = p;
            if ((dp >= 0.0) != (dq >= 0.0)) next[size_t(out++)] = p + (q - p) * (dp / (dp - dq));
        }
        poly = next;
        count = out;
    }
    double area = 0.0;
    for (int i = 0; i < count; ++i) area += cross2(poly[size_t(i)], poly[size_t((i + 1) % count)]);
    return 0.5 * area;
}

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5), as
// barycentric weights of (a, b, c); also the squared distance.
glm::dvec3 closest_barycentric(const glm::dvec2& p, const Tri2& t, double* distance2) {
    const glm::dvec2 a = t[0], b = t[1], c = t[2];
    const glm::dvec2 ab = b - a, ac = c - a, ap = p - a;
    glm::dvec3 w;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    const glm::dvec2 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    const glm::dvec2 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d1 <= 0.0 && d2 <= 0.0) {
        w = {1, 0, 0};
    } else if (d3 >= 0.0 && d4 <= d3) {
        w = {0, 1, 0};
    } else if (d6 >= 0.0 && d5 <= d6) {
        w = {0, 0, 1};
    } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double s = d1 / (d1 - d3);
        w = {1 - s, s, 0};
    } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double s = d2 / (d2 - d6);
        w = {1 - s, 0, s};
    } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        const double s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        w = {0, 1 - s, s};
    } else {
        const double denom = 1.0 / (va + vb + vc);
        w = {va * denom, vb * denom, vc * denom};
    }
    const glm::dvec2 q = w.x * a + w.y * b + w.z * c;
    *distance2 = glm::dot(p - q, p - q);
    return w;
}

// Barycentric weights of p in triangle t, or nothing if p lies outside it.
bool inside_barycentric(const glm::dvec2& p, const Tri2& t, glm::dvec3* w) {
    const double area = cross2(t[1] - t[0], t[2] - t[0]);
    const double w0 = cross2(t[1] - p, t[2] - p) / area, w1 = cross2(t[2] - p, t[0] - p) / area;
    const double w2 = 1.0 - w0 - w1;
    if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) return false;
    *w = {w0, w1, w2};
    return true;
}

// A chart triangle in the chart's texel space: (0,0) is the corner of the chart's first texel.
Tri2 chart_texel_triangle(const Mesh& mesh, const Chart& chart, int t, double texel_size) {
    const glm::uvec3 tri = mesh.triangles[size_t(t)];
    Tri2 out;
    for (int k = 0; k < 3; ++k) {
        const glm::dvec3 p(mesh.positions[tri[k]]);
        out[size_t(k)] = {
            (glm::dot(p, glm::dvec3(chart.u_axis)) - double(chart.origin.x)) / texel_size,
            (glm::dot(p, glm::dvec3(chart.v_axis)) - double(chart.origin.y)) / texel_size};
    }
    return out;
}

// Texel records of one chart (ch. 10, 11): every texel whose square overlaps a chart triangle,
// with the world area it covers and its centre on the surface, snapped inside the chart where
// the centre falls outside, so gathers never start below a neighbouring crease.
void make_chart_texels(const Mesh& mesh, const TriangleInfo& info, const Chart& chart, int chart_id,
                       double texel_size, LightmapAtlas& atlas) {
    const int w = chart.width, h = chart.height;
    const size_t count = size_t(w) * size_t(h);
    std::vector<double> area(count, 0.0), coverage(count, 0.0);
    std::vector<double> best_distance(count, std::numeric_limits<double>::infinity());
    std::vector<int> best_triangle(count, -1);
    std::vector<glm::dvec3> best_weights(count);

    for (int t : chart.triangles) {
        if (info.degenerate[size_t(t)]) continue;
        const Tri2 q = chart_texel_triangle(mesh, chart, t, texel_size);
        const double texel_area = 0.5 * cross2(q[1] - q[0], q[2] - q[0]);
        if (!(texel_area > 0.0)) continue;
        const double world_per_texel = info.area[size_t(t)] / texel_area;
        const glm::dvec2 lo = glm::min(glm::min(q[0], q[1]), q[2]);
        const glm::dvec2 hi = glm::max(glm::max(q[0], q[1]), q[2]);
        // Texels the triangle overlaps, and (wider) texels whose centre may be nearest to it:
        // a covered texel's centre is within √½ of some chart triangle.
        const int cx0 = std::max(0, int(std::floor(lo.x))),
                  cx1 = std::min(w - 1, int(std::ceil(hi.x)) - 1);
        const int cy0 = std::max(0, int(std::floor(lo.y))),
                  cy1 = std::min(h - 1, int(std::ceil(hi.y)) - 1);
        const int sx0 = std::max(0, int(std::floor(lo.x - 1.21))),
                  sx1 = std::min(w - 1, int(std::floor(hi.x + 0.21)));
        const int sy0 = std::max(0, int(std::floor(lo.y - 1.21))),
                  sy1 = std::min(h - 1, int(std::floor(hi.y + 0.21)));
        for (int y = sy0; y <= sy1; ++y)
            for (int x = sx0; x <= sx1; ++x) {
                const size_t i = size_t(y) * size_t(w) + size_t(x);
                const glm::dvec2 centre(x + 0.5, y + 0.5);
                glm::dvec3 weights;
                double distance2 = 0.0;
                if (!inside_barycentric(centre, q, &weights))
                    weights = closest_barycentric(centre, q, &distance2);
                if (distance2 < best_distance[i]) {
                    best_distance[i] = distance2;
                    best_triangle[i] = t;
                    best_weights[i] = weights;
                }
                if (x < cx0 || x > cx1 || y < cy0 || y > cy1) continue;
                const glm::dvec2 corner(x, y);
                const Tri2 local{q[0] - corner, q[1] - corner, q[2] - corner};
                const double covered = lo.x >= x && hi.x <= x + 1 && lo.y >= y && hi.y <= y + 1
                                           ? texel_area
                                           : clipped_square_area(local);
                coverage[i] += covered;
                area[i] += covered * world_per_texel;
            }
    }

    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            if (!(coverage[i] > (chart.tile_group >= 0 ? kMinTileCoverage : kMinCoverage)))
                continue;
            const int t = best_triangle[i];
            glm::dvec3 weights = best_weights[i];
            // Centres outside the chart, or exactly on an edge (a half-covered texel along a
            // chart border), move inside: a gather from the junction of two walls would see the
            // other wall edge-on (GL) or at zero distance (rays).
            const double smallest = std::min({weights.x, weights.y, weights.z});
            if (best_distance[i] > 0.0 || smallest < kSnapNudge / 3.0)
                weights = (1.0 - kSnapNudge) * weights + kSnapNudge / 3.0;
            const glm::uvec3 tri = mesh.triangles[size_t(t)];
            const glm::dvec3 p = weights.x * glm::dvec3(mesh.positions[tri.x]) +
                                 weights.y * glm::dvec3(mesh.positions[tri.y]) +
                                 weights.z * glm::dvec3(mesh.positions[tri.z]);
            TexelRecord record;
            record.object = chart.object;
            record.surface = chart.surface;
            record.chart = chart_id;
            record.triangle = t;
            record.x = chart.x + x;
            record.y = chart.y + y;
            record.position = glm::vec3(p);
            record.normal = glm::vec3(info.normal[size_t(t)]);
            record.area = float(area[i]);
            int& slot =
                atlas.texel_index[size_t(record.y) * size_t(atlas.width) + size_t(record.x)];
            slot = int(atlas.texels.size());
            atlas.texels.push_back(record);
        }
}

// Shelf packing of the gutter-padded rectangles, tallest first; returns the used height.
int pack_shelves(const std::vector<glm::ivec2>& sizes, const std::vector<int>& order, int width,
                 std::vector<glm::ivec2>* positions) {
    positions->assign(sizes.size(), glm::ivec2(0));
    int x = 0, y = 0, shelf = 0;
    for (int id : order) {
        const glm::ivec2 s = sizes[size_t(id)];
        if (x + s.x > width) {
            y += shelf;
            x = 0;
            shelf = 0;
        }
        (*positions)[size_t(id)] = {x, y};
        x += s.x;
        shelf = std::max(shelf, s.y);
    }
    return y + shelf;
}

int round_up(int value, int multiple) { return (value + multiple - 1) / multiple * multiple; }

// ---- Density within a chart (lightmap.refine_tile) ----

// What a vertex of a triangle piece lies on: an edge of the original mesh (its two vertex
// indices, ascending) or a cut line (axis 0 = u, 1 = v, and its index along the axis).
struct Carrier {
    enum Kind : int { kEdge, kLine } kind = kEdge;
    int a = -1, b = -1;
    bool operator==(const Carrier&) const = default;
};

struct PieceVertex {
    uint32_t index = 0;       // into the mesh's positions
    glm::dvec2 uv{0.0};       // chart-plane coordinates, object units
    glm::dvec3 weights{0.0};  // barycentric weights in the original triangle (texcoords)
    std::array<Carrier, 2> on{};
    int on_count = 0;

    bool lies_on(const Carrier& c) const {
        for (int i = 0; i < on_count; ++i)
            if (on[size_t(i)] == c) return true;
        return false;
    }
};

// Splits one object's chart triangles along cut lines, sharing every new vertex between the
// pieces on both sides of a cut (the point where a line crosses a mesh edge is made once, from
// the edge's end points in a fixed order), so the split mesh is as watertight as the original.
class TriangleSplitter {
public:
    TriangleSplitter(Mesh& mesh, const Frame& frame, glm::dvec2 origin, double cell)
        : mesh_(mesh), frame_(frame), origin_(origin), cell_(cell) {}

    // The convex pieces of triangle `t` cut by the lines u = origin.x + k·cell and v =
    // origin.y + k·cell that cross it.
    std::vector<std::vector<PieceVertex>> split(int t) {
        const glm::uvec3 f = mesh_.triangles[size_t(t)];
        std::vector<PieceVertex> corners(3);
        glm::dvec2 lo(1e300), hi(-1e300);
        for (int k = 0; k < 3; ++k) {
            PieceVertex& v = corners[size_t(k)];
            v.index = f[k];
            v.uv = uv_of(f[k]);
            v.weights[k] = 1.0;
            v.on = {edge(f[k], f[(k + 1) % 3]), edge(f[(k + 2) % 3], f[k])};
            v.on_count = 2;
            lo = glm::min(lo, v.uv);
            hi = glm::max(hi, v.uv);
        }
        std::vector<std::vector<PieceVertex>> pieces{corners}, next;
        for (int axis = 0; axis < 2; ++axis) {
            const int k0 = int(std::floor((lo[axis] - origin_[axis]) / cell_)) + 1;
            const int k1 = int(std::ceil((hi[axis] - origin_[axis]) / cell_)) - 1;
            for (int k = k0; k <= k1; ++k) {
                next.clear();
                for (const std::vector<PieceVertex>& piece : pieces) cut(t, piece, axis, k, next);
                pieces.swap(next);
            }
        }
        return pieces;
    }

    // Every vertex made on an edge of the original mesh, by the edge's end points (ascending).
    void add_edge_vertices(
        std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>>& out) const {
        for (const auto& [key, index] : made_)
            if (key[0] == 0) out[{uint32_t(key[1]), uint32_t(key[2])}].push_back(index);
    }

private:
    static Carrier edge(uint32_t a, uint32_t b) {
        return {Carrier::kEdge, int(std::min(a, b)), int(std::max(a, b))};
    }
    glm::dvec2 uv_of(uint32_t index) const { return frame_.project(mesh_.positions[index]); }
    double line_value(int axis, int k) const { return origin_[axis] + double(k) * cell_; }

    // Adds the parts of `piece` on either side of line (axis, k) to `out`.
    void cut(int t, const std::vector<PieceVertex>& piece, int axis, int k,
             std::vector<std::vector<PieceVertex>>& out) {
        const Carrier line{Carrier::kLine, axis, k};
        const double c = line_value(axis, k);
        const size_t n = piece.size();
        std::vector<double> side(n);
        bool below = false, above = false;
        for (size_t i = 0; i < n; ++i) {
            side[i] = piece[i].lies_on(line) ? 0.0 : piece[i].uv[axis] - c;
            below = below || side[i] < 0.0;
            above = above || side[i] > 0.0;
        }
        if (!(below && above)) {
            out.push_back(piece);
            return;
        }
        std::vector<PieceVertex> left, right;
        for (size_t i = 0; i < n; ++i) {
            const PieceVertex &p = piece[i], &q = piece[(i + 1) % n];
            const double sp = side[i], sq = side[(i + 1) % n];
            if (sp <= 0.0) left.push_back(p);
            if (sp >= 0.0) right.push_back(p);
            if ((sp < 0.0 && sq > 0.0) || (sp > 0.0 && sq < 0.0)) {
                const PieceVertex x = crossing(t, p, q, line);
                left.push_back(x);
                right.push_back(x);
            }
        }
        for (std::vector<PieceVertex>* part : {&left, &right})
            if (part->size() >= 3) out.push_back(std::move(*part));
    }

    // Where segment p–q of a piece crosses `line`. The segment lies on a mesh edge or on an
    // earlier cut line; either names the new vertex, so both sides of the cut get the same one.
    PieceVertex crossing(int t, const PieceVertex& p, const PieceVertex& q, const Carrier& line) {
        const int axis = line.a;
        const double c = line_value(axis, line.b);
        std::optional<Carrier> common;
        for (int i = 0; i < p.on_count && !common; ++i)
            if (q.lies_on(p.on[size_t(i)])) common = p.on[size_t(i)];
        PieceVertex x;
        x.on[0] = line;
        x.on_count = 1;
        const glm::uvec3 f = mesh_.triangles[size_t(t)];
        const auto weights_of = [&](uint32_t index) {
            glm::dvec3 w(0.0);
            for (int k = 0; k < 3; ++k)
                if (f[k] == index) w[k] = 1.0;
            return w;
        };
        if (common && common->kind == Carrier::kEdge) {
            const std::array<int64_t, 5> key{0, common->a, common->b, axis, line.b};
            // The edge's end points in a fixed order (by position, then index), so a triangle
            // on the other side of the edge computes the same point bit for bit.
            uint32_t a = uint32_t(common->a), b = uint32_t(common->b);
            const glm::vec3 pa = mesh_.positions[a], pb = mesh_.positions[b];
            if (std::tie(pb.x, pb.y, pb.z) < std::tie(pa.x, pa.y, pa.z)) std::swap(a, b);
            const double ua = uv_of(a)[axis], ub = uv_of(b)[axis];
            const double s = std::clamp((c - ua) / (ub - ua), 0.0, 1.0);
            const glm::dvec3 pos =
                glm::mix(glm::dvec3(mesh_.positions[a]), glm::dvec3(mesh_.positions[b]), s);
            x.index = vertex(key, pos);
            x.uv = frame_.project(mesh_.positions[x.index]);
            x.weights = glm::mix(weights_of(a), weights_of(b), s);
            x.on[1] = *common;
            x.on_count = 2;
            return x;
        }
        // Inside the triangle: the corner of two cut lines (or, failing a common carrier, the
        // point on p–q), made from the original triangle so its pieces share it.
        const double s = std::clamp((c - p.uv[axis]) / (q.uv[axis] - p.uv[axis]), 0.0, 1.0);
        glm::dvec3 w = glm::mix(p.weights, q.weights, s);
        std::array<int64_t, 5> key{2, t, int64_t(p.index), int64_t(q.index), line.b};
        if (common && common->kind == Carrier::kLine && common->a != axis) {
            const glm::dvec2 target = axis == 0 ? glm::dvec2(c, line_value(1, common->b))
                                                : glm::dvec2(line_value(0, common->b), c);
            const glm::dvec2 a = uv_of(f.x), b = uv_of(f.y), d = uv_of(f.z);
            const double det = cross2(b - a, d - a);
            if (std::abs(det) > 0.0) {
                const double wb = cross2(target - a, d - a) / det;
                const double wd = cross2(b - a, target - a) / det;
                w = {1.0 - wb - wd, wb, wd};
            }
            key = {1, t, axis == 0 ? line.b : common->b, axis == 0 ? common->b : line.b, 0};
            x.on[1] = *common;
            x.on_count = 2;
        }
        const glm::dvec3 pos = w.x * glm::dvec3(mesh_.positions[f.x]) +
                               w.y * glm::dvec3(mesh_.positions[f.y]) +
                               w.z * glm::dvec3(mesh_.positions[f.z]);
        x.index = vertex(key, pos);
        x.uv = frame_.project(mesh_.positions[x.index]);
        x.weights = w;
        return x;
    }

    uint32_t vertex(const std::array<int64_t, 5>& key, const glm::dvec3& pos) {
        const auto [it, inserted] = made_.try_emplace(key, uint32_t(mesh_.positions.size()));
        if (inserted) mesh_.positions.push_back(glm::vec3(pos));
        return it->second;
    }

    Mesh& mesh_;
    const Frame& frame_;
    glm::dvec2 origin_;
    double cell_;
    std::map<std::array<int64_t, 5>, uint32_t> made_;
};

// A cut puts vertices on the edges of the original mesh where its lines cross them. A triangle on
// the other side of such an edge that the cut did not split (one of another chart: a box's side
// beside its cut face), or one split by another chart's lines, would then meet them in a
// T-junction, a crack in the mesh. Every triangle of the object with a made vertex strictly
// inside one of its edges is split: its corners and those vertices in order, fanned around their
// centroid; the new triangles join the triangle's chart and surface (texcoords interpolated).
void close_t_junctions(Scene& scene, int oi,
                       const std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>>& made) {
    Object& object = scene.objects[size_t(oi)];
    Mesh& mesh = object.mesh;
    // Per vertex: the original edges it lies on, with its parameter along the edge.
    struct OnEdge {
        std::pair<uint32_t, uint32_t> edge;
        double t;
    };
    std::unordered_map<uint32_t, std::vector<OnEdge>> on;
    const auto parameter = [&](const std::pair<uint32_t, uint32_t>& e, uint32_t v) {
        const glm::dvec3 a(mesh.positions[e.first]), b(mesh.positions[e.second]);
        const glm::dvec3 x(mesh.positions[v]);
        return glm::dot(x - a, b - a) / glm::dot(b - a, b - a);
    };
    for (const auto& [e, vertices] : made) {
        on[e.first].push_back({e, 0.0});
        on[e.second].push_back({e, 1.0});
        for (uint32_t v : vertices) on[v].push_back({e, parameter(e, v)});
    }
    std::vector<int> chart_of(mesh.triangles.size(), -1);
    for (size_t c = 0; c < scene.atlas.charts.size(); ++c)
        if (scene.atlas.charts[c].object == oi)
            for (int t : scene.atlas.charts[c].triangles) chart_of[size_t(t)] = int(c);
    const size_t count = mesh.triangles.size();
    for (size_t t = 0; t < count; ++t) {
        const glm::uvec3 f = mesh.triangles[t];
        // The triangle's outline: each corner, then the made vertices strictly inside the edge
        // to the next corner, in order along it.
        std::vector<uint32_t> ring;
        std::vector<glm::dvec3> weights;
        bool split = false;
        for (int k = 0; k < 3; ++k) {
            const uint32_t p = f[k], q = f[(k + 1) % 3];
            ring.push_back(p);
            weights.push_back(glm::dvec3(k == 0, k == 1, k == 2));
            const auto ip = on.find(p), iq = on.find(q);
            if (ip == on.end() || iq == on.end()) continue;
            for (const OnEdge& ep : ip->second)
                for (const OnEdge& eq : iq->second) {
                    if (ep.edge != eq.edge) continue;
                    std::vector<std::pair<double, uint32_t>> inside;
                    const double lo = std::min(ep.t, eq.t), hi = std::max(ep.t, eq.t);
                    for (uint32_t v : made.at(ep.edge)) {
                        const double tv = parameter(ep.edge, v);
                        if (v == p || v == q || !(tv > lo && tv < hi)) continue;
                        // Ordered from p to q.
                        inside.emplace_back((tv - ep.t) / (eq.t - ep.t), v);
                    }
                    std::sort(inside.begin(), inside.end());
                    for (const auto& [s, v] : inside) {
                        ring.push_back(v);
                        weights.push_back(glm::mix(
                            glm::dvec3(k == 0, k == 1, k == 2),
                            glm::dvec3((k + 1) % 3 == 0, (k + 1) % 3 == 1, (k + 1) % 3 == 2), s));
                        split = true;
                    }
                }
        }
        if (!split) continue;
        std::vector<glm::vec2> original_uv;
        if (mesh.has_texcoords())
            original_uv.assign(mesh.texcoords.begin() + std::ptrdiff_t(3 * t),
                               mesh.texcoords.begin() + std::ptrdiff_t(3 * t + 3));
        glm::dvec3 centre(0.0), centre_weights(0.0);
        for (size_t i = 0; i < ring.size(); ++i) {
            centre += glm::dvec3(mesh.positions[ring[i]]);
            centre_weights += weights[i];
        }
        const uint32_t centre_index = uint32_t(mesh.positions.size());
        mesh.positions.push_back(glm::vec3(centre / double(ring.size())));
        centre_weights /= double(ring.size());
        const int surface = scene.triangle_surface[size_t(oi)][t];
        for (size_t i = 0; i < ring.size(); ++i) {
            const size_t j = (i + 1) % ring.size();
            size_t index = t;
            if (i == 0) {
                mesh.triangles[t] = {centre_index, ring[i], ring[j]};
            } else {
                index = mesh.triangles.size();
                mesh.triangles.push_back({centre_index, ring[i], ring[j]});
                if (mesh.has_texcoords()) mesh.texcoords.resize(mesh.texcoords.size() + 3);
                scene.surfaces[size_t(surface)].triangles.push_back(int(index));
                scene.triangle_surface[size_t(oi)].push_back(surface);
                if (chart_of[t] >= 0)
                    scene.atlas.charts[size_t(chart_of[t])].triangles.push_back(int(index));
            }
            if (mesh.has_texcoords()) {
                const glm::dvec3 w[3] = {centre_weights, weights[i], weights[j]};
                for (int k = 0; k < 3; ++k)
                    mesh.texcoords[3 * index + size_t(k)] = glm::vec2(
                        w[k].x * glm::dvec2(original_uv[0]) + w[k].y * glm::dvec2(original_uv[1]) +
                        w[k].z * glm::dvec2(original_uv[2]));
            }
        }
    }
    for (Chart& chart : scene.atlas.charts)
        if (chart.object == oi) std::sort(chart.triangles.begin(), chart.triangles.end());
}

// Cuts every chart that touches a partner (texel_density.h) along its base texel grid into
// tiles of `refine_tile` base texels, where at most half of its tiles are near the partner and it
// is at least 4 tiles across; the
// tiles with a sample point near the partner (and not under it: the floor beneath a box needs no
// finer texels), grouped
// into 4-connected patches, become charts of their own laid out exactly on that grid (so the
// subdivision can refine them), the rest stays the original chart at the base size. The
// chart's triangles are split along the patches' tile edges (new triangles are appended to the
// object's mesh; the first piece keeps the original's index). Objects whose material emits are
// left whole (their mesh lights were made from their triangles).
void cut_contact_tiles(Scene& scene, std::vector<TriangleInfo>& infos,
                       std::vector<ChartLayout>& layouts, double texel_size) {
    const LightmapSettings& ls = scene.settings.lightmap;
    LightmapAtlas& atlas = scene.atlas;
    const int tile = ls.refine_tile;
    const double cell = double(tile) * texel_size;
    // Tiles within reach of a partner (lightmap.refine_reach) are refined with the contact's.
    const double reach = double(ls.refine_reach);
    std::vector<uint8_t> touched(scene.objects.size(), 0);
    // Per object: the vertices every cut made on the original mesh's edges.
    std::vector<std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>>> made(
        scene.objects.size());
    const int original_count = int(atlas.charts.size());
    ContactCache cache;  // objects cut below are taken again: their meshes grow
    for (int c = 0; c < original_count; ++c) {
        const int oi = atlas.charts[size_t(c)].object;
        Object& object = scene.objects[size_t(oi)];
        const glm::vec3& e = object.material.emission;
        if (std::max({e.x, e.y, e.z}) > 0.0f) continue;
        const glm::dvec2 origin = chart_layout_origin(layouts[size_t(c)], texel_size);
        // A chart over 65536 texels wide is refused after this, naming the texel size; cutting
        // it first would allocate its tile grid (a 10^7 m triangle at 0.2 m: bad_alloc).
        const glm::dvec2 extent = layouts[size_t(c)].extent / texel_size;
        if (!(extent.x < 65536.0 && extent.y < 65536.0)) continue;
        const glm::ivec2 texels = chart_layout_texels(layouts[size_t(c)], texel_size);
        const int nx = (texels.x + tile - 1) / tile, ny = (texels.y + tile - 1) / tile;
        // The chart's own (float) axes, as its layout was measured with.
        Frame frame{glm::dvec3(atlas.charts[size_t(c)].axis)};
        frame.u = glm::dvec3(atlas.charts[size_t(c)].u_axis);
        frame.v = glm::dvec3(atlas.charts[size_t(c)].v_axis);
        const auto cell_of = [&](glm::dvec2 uv) {
            const glm::ivec2 i(glm::floor((uv - origin) / cell));
            return glm::clamp(i, glm::ivec2(0), glm::ivec2(nx - 1, ny - 1));
        };
        // 0 = no chart here, 1 = chart, 2 = within reach of a partner, 3 = near one. Both 2 and
        // 3 get finer texels; whether the chart is cut at all follows the contact (3) alone.
        constexpr uint8_t kBand = 2, kNear = 3;
        std::vector<uint8_t> state(size_t(nx) * size_t(ny), 0);
        bool covered_only = true;
        for_each_contact_sample(
            scene, atlas.charts[size_t(c)], double(ls.refine_distance) * texel_size,
            0.25 * texel_size, reach,
            [&](const glm::dvec3& p, double, const ContactSample& sample) {
                covered_only = covered_only && sample.covered;
                const glm::ivec2 i = cell_of(frame.project(glm::vec3(p)));
                uint8_t& s = state[size_t(i.y) * size_t(nx) + size_t(i.x)];
                const uint8_t level = sample.covered        ? 1
                                      : sample.near         ? kNear
                                      : sample.within_reach ? kBand
                                                            : 1;
                s = std::max(s, level);
            },
            &cache);
        const auto near_cells = std::count(state.begin(), state.end(), kNear);
        if (near_cells == 0 && covered_only) {
            layouts[size_t(c)].keep_base = true;  // wholly under a partner (a box's bottom)
            continue;
        }
        // No contact, most of the chart near it, or a chart under 4 tiles across: the whole-chart
        // rule decides. (Cutting a small chart, a box's side, would save a few texels for a
        // seam across a face in plain view.)
        const auto occupied =
            std::count_if(state.begin(), state.end(), [](uint8_t s) { return s > 0; });
        if (near_cells == 0 || 2 * near_cells > occupied || std::max(nx, ny) < 4) continue;

        // Patches: 4-connected cells near or within reach, numbered in scan order.
        std::vector<int> patch(state.size(), -1);
        std::vector<glm::ivec4> bounds;  // per patch: x0, y0, x1, y1 in cells
        for (int start = 0; start < int(state.size()); ++start) {
            if (state[size_t(start)] < kBand || patch[size_t(start)] >= 0) continue;
            const int id = int(bounds.size());
            bounds.emplace_back(nx, ny, -1, -1);
            std::vector<int> stack{start};
            patch[size_t(start)] = id;
            while (!stack.empty()) {
                const int i = stack.back();
                stack.pop_back();
                const int x = i % nx, y = i / nx;
                bounds[size_t(id)] = {
                    std::min(bounds[size_t(id)].x, x), std::min(bounds[size_t(id)].y, y),
                    std::max(bounds[size_t(id)].z, x), std::max(bounds[size_t(id)].w, y)};
                const int around[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
                for (const auto& d : around) {
                    const int ax = x + d[0], ay = y + d[1];
                    if (ax < 0 || ay < 0 || ax >= nx || ay >= ny) continue;
                    const int j = ay * nx + ax;
                    if (state[size_t(j)] < kBand || patch[size_t(j)] >= 0) continue;
                    patch[size_t(j)] = id;
                    stack.push_back(j);
                }
            }
        }

        // Split the chart's triangles and sort the pieces into the rest and the patches.
        if (scene.unsplit_meshes[size_t(oi)].triangles.empty())
            scene.unsplit_meshes[size_t(oi)] = object.mesh;
        touched[size_t(oi)] = 1;
        Mesh& mesh = object.mesh;
        const int surface_id = atlas.charts[size_t(c)].surface;
        TriangleSplitter splitter(mesh, frame, origin, cell);
        std::vector<int> rest;
        std::vector<std::vector<int>> parts(bounds.size());
        const std::vector<int> members = atlas.charts[size_t(c)].triangles;
        for (int t : members) {
            const std::vector<std::vector<PieceVertex>> pieces = splitter.split(t);
            std::vector<glm::vec2> original_uv;
            if (mesh.has_texcoords())
                original_uv.assign(mesh.texcoords.begin() + std::ptrdiff_t(3 * size_t(t)),
                                   mesh.texcoords.begin() + std::ptrdiff_t(3 * size_t(t) + 3));
            bool first = true;
            for (const std::vector<PieceVertex>& piece : pieces) {
                // Pieces with more than three corners are fanned around their centroid (a
                // corner fan would make slivers where corners lie on one cut line).
                std::vector<PieceVertex> ring = piece;
                glm::dvec2 centre_uv(0.0);
                for (const PieceVertex& v : ring) centre_uv += v.uv;
                centre_uv /= double(ring.size());
                std::vector<std::array<PieceVertex, 3>> triangles;
                if (ring.size() == 3) {
                    triangles.push_back({ring[0], ring[1], ring[2]});
                } else {
                    PieceVertex centre;
                    glm::dvec3 pos(0.0);
                    for (const PieceVertex& v : ring) {
                        pos += glm::dvec3(mesh.positions[v.index]);
                        centre.weights += v.weights;
                    }
                    centre.index = uint32_t(mesh.positions.size());
                    mesh.positions.push_back(glm::vec3(pos / double(ring.size())));
                    centre.weights /= double(ring.size());
                    for (size_t i = 0; i < ring.size(); ++i)
                        triangles.push_back({centre, ring[i], ring[(i + 1) % ring.size()]});
                }
                const glm::ivec2 at = cell_of(centre_uv);
                const int p = patch[size_t(at.y) * size_t(nx) + size_t(at.x)];
                for (const auto& tri : triangles) {
                    int index = t;
                    if (first) {
                        mesh.triangles[size_t(t)] = {tri[0].index, tri[1].index, tri[2].index};
                        first = false;
                    } else {
                        index = int(mesh.triangles.size());
                        mesh.triangles.push_back({tri[0].index, tri[1].index, tri[2].index});
                        if (mesh.has_texcoords()) mesh.texcoords.resize(mesh.texcoords.size() + 3);
                        scene.surfaces[size_t(surface_id)].triangles.push_back(index);
                        scene.triangle_surface[size_t(oi)].push_back(surface_id);
                    }
                    if (mesh.has_texcoords())
                        for (int k = 0; k < 3; ++k) {
                            const glm::dvec3 w = tri[size_t(k)].weights;
                            mesh.texcoords[3 * size_t(index) + size_t(k)] =
                                glm::vec2(w.x * glm::dvec2(original_uv[0]) +
                                          w.y * glm::dvec2(original_uv[1]) +
                                          w.z * glm::dvec2(original_uv[2]));
                        }
                    (p < 0 ? rest : parts[size_t(p)]).push_back(index);
                }
            }
        }

        splitter.add_edge_vertices(made[size_t(oi)]);

        // The rest keeps the chart's grid at the base size; each patch is laid out on the same
        // grid over its cells' bounds.
        Chart& chart = atlas.charts[size_t(c)];
        std::sort(rest.begin(), rest.end());
        chart.triangles = rest;
        chart.tile_group = c;
        layouts[size_t(c)] = {origin, glm::dvec2(texels) * texel_size, true, true};
        for (size_t p = 0; p < parts.size(); ++p) {
            if (parts[p].empty()) continue;
            Chart part;
            part.object = oi;
            part.surface = surface_id;
            part.axis = atlas.charts[size_t(c)].axis;
            part.u_axis = atlas.charts[size_t(c)].u_axis;
            part.v_axis = atlas.charts[size_t(c)].v_axis;
            part.tile_group = c;
            std::sort(parts[p].begin(), parts[p].end());
            part.triangles = std::move(parts[p]);
            // One fine texel of margin each side keeps every corner strictly inside the
            // rectangle (as kChartMargin does for other charts) and the grid where it was.
            const glm::ivec4 b = bounds[p];
            const double margin = texel_size / double(ls.refine_factor);
            const glm::dvec2 lo = origin + glm::dvec2(b.x, b.y) * cell - margin;
            const glm::dvec2 hi = glm::min(origin + glm::dvec2(b.z + 1, b.w + 1) * cell,
                                           origin + glm::dvec2(texels) * texel_size) +
                                  margin;
            scene.surfaces[size_t(surface_id)].charts.push_back(int(atlas.charts.size()));
            atlas.charts.push_back(std::move(part));
            layouts.push_back({lo, hi - lo, true, false});
        }
    }
    for (size_t oi = 0; oi < scene.objects.size(); ++oi)
        if (touched[oi]) {
            close_t_junctions(scene, int(oi), made[oi]);
            infos[oi] = triangle_info(scene.objects[oi].mesh);
        }
}

}  // namespace

std::vector<int> segment_surfaces(const Mesh& mesh, float crease_angle_deg, int* surface_count) {
    return segment(mesh, triangle_adjacency(mesh), crease_angle_deg, surface_count);
}

void make_surfaces_and_atlas(Scene& scene) {
    using Clock = std::chrono::steady_clock;
    Clock::time_point phase = Clock::now();
    const auto lap = [&] {
        const Clock::time_point now = Clock::now();
        const double s = std::chrono::duration<double>(now - phase).count();
        phase = now;
        return s;
    };
    const LightmapSettings& ls = scene.settings.lightmap;
    const std::string where = scene.path.empty() ? "scene" : scene.path;
    // A layout starts from the meshes as loaded: undo an earlier tile cut (cut_contact_tiles).
    for (size_t oi = 0; oi < scene.unsplit_meshes.size() && oi < scene.objects.size(); ++oi)
        if (!scene.unsplit_meshes[oi].triangles.empty())
            scene.objects[oi].mesh = std::move(scene.unsplit_meshes[oi]);
    scene.unsplit_meshes.assign(scene.objects.size(), Mesh{});
    scene.surfaces.clear();
    scene.triangle_surface.assign(scene.objects.size(), {});
    LightmapAtlas& atlas = scene.atlas;
    atlas = LightmapAtlas{};
    atlas.gutter = std::max(0, ls.gutter);
    atlas.corner_uvs.assign(scene.objects.size(), {});

    Bounds bounds;
    for (const Object& object : scene.objects)
        for (const glm::vec3& p : object.mesh.positions)
            bounds.add(object.transform.apply_point(p));
    const float longest = bounds.empty() ? 0.0f
                                         : glm::max(glm::max(bounds.extent().x, bounds.extent().y),
                                                    bounds.extent().z);
    const float texel_size_f = effective_texel_size(scene.settings, longest);
    if (!(texel_size_f > 0.0f) || !std::isfinite(texel_size_f))
        throw_input_error(where, "settings.lightmap.texel_size",
                          "expected a positive texel size, got " + std::to_string(texel_size_f));
    atlas.texel_size = texel_size_f;
    const double texel_size = texel_size_f;
    const double cos_cone = std::cos(double(ls.chart_cone) * kDegree);

    std::vector<TriangleInfo> infos(scene.objects.size());
    std::vector<ChartLayout> layouts;  // per chart, object units
    OverlapGrid grid;
    for (int oi = 0; oi < int(scene.objects.size()); ++oi) {
        const Mesh& mesh = scene.objects[size_t(oi)].mesh;
        const int n = int(mesh.triangles.size());
        const Adjacency adjacency = triangle_adjacency(mesh);
        int local_count = 0;
        const std::vector<int> local = segment(mesh, adjacency, ls.crease_angle, &local_count);
        TriangleInfo& info = infos[size_t(oi)];
        info = triangle_info(mesh);

        const int first_surface = int(scene.surfaces.size());
        scene.surfaces.resize(size_t(first_surface + local_count));
        std::vector<int>& global = scene.triangle_surface[size_t(oi)];
        global.resize(size_t(n));
        std::vector<glm::dvec3> normal_sums(size_t(local_count), glm::dvec3(0.0));
        std::vector<double> area_sums(size_t(local_count), 0.0);
        for (int t = 0; t < n; ++t) {
            const int s = local[size_t(t)];
            global[size_t(t)] = first_surface + s;
            Surface& surface = scene.surfaces[size_t(first_surface + s)];
            surface.object = oi;
            surface.triangles.push_back(t);
            normal_sums[size_t(s)] += info.cross[size_t(t)];
            area_sums[size_t(s)] += info.area[size_t(t)];
        }

        std::vector<int> chart_of(size_t(n), -1), tried(size_t(n), -1);
        int stamp = -1;
        for (int s = 0; s < local_count; ++s) {
            Surface& surface = scene.surfaces[size_t(first_surface + s)];
            surface.area = float(area_sums[size_t(s)]);
            const double length = glm::length(normal_sums[size_t(s)]);
            surface.normal =
                length > 0.0 ? glm::vec3(normal_sums[size_t(s)] / length) : glm::vec3(0.0f);
            // Mirrors and glass reflect no diffuse light: they keep their surfaces (photon paths
            // name them) but get no lightmap texels.
            if (scene.objects[size_t(oi)].material.type != MaterialType::diffuse) continue;
            std::vector<ChartCut> cuts =
                cut_charts(mesh, adjacency, info, local, s, surface.triangles, cos_cone, chart_of,
                           tried, stamp, grid);
            for (ChartCut& cut : cuts) {
                Chart chart;
                chart.object = oi;
                chart.surface = first_surface + s;
                chart.triangles = std::move(cut.triangles);
                const Frame frame(cut.axis);
                chart.axis = glm::vec3(frame.axis);
                chart.u_axis = glm::vec3(frame.u);
                chart.v_axis = glm::vec3(frame.v);
                // Projected bounds; the rectangle follows once each chart's density is chosen.
                glm::dvec2 lo(1e300), hi(-1e300);
                for (int t : chart.triangles)
                    for (int k = 0; k < 3; ++k) {
                        const glm::dvec3 p(mesh.positions[mesh.triangles[size_t(t)][k]]);
                        const glm::dvec2 uv(glm::dot(p, glm::dvec3(chart.u_axis)),
                                            glm::dot(p, glm::dvec3(chart.v_axis)));
                        lo = glm::min(lo, uv);
                        hi = glm::max(hi, uv);
                    }
                layouts.push_back({lo, hi - lo, false, false});
                surface.charts.push_back(int(atlas.charts.size()));
                atlas.charts.push_back(std::move(chart));
            }
        }
    }

    // An atlas over the limit at the base texel size is refused below, naming the texel size,
    // whatever finer texels would add: no tiles or subdivision are worked out for it first (a
    // 10 µm texel on the Cornell box: a tile grid of 3·10⁹ cells, and another error message).
    double base_total = 0.0;
    for (const ChartLayout& layout : layouts) {
        const glm::dvec2 wide = layout.extent / texel_size;
        if (!(wide.x < 65536.0 && wide.y < 65536.0)) {  // refused below as it is
            base_total = std::numeric_limits<double>::infinity();
            break;
        }
        const glm::dvec2 e =
            glm::dvec2(chart_layout_texels(layout, texel_size)) + 2.0 * double(atlas.gutter);
        base_total += e.x * e.y;
    }
    const bool refine = base_total <= double(kMaxAtlasTexels);
    if (refine && ls.refine_tile > 0 && ls.refine_factor > 1)
        cut_contact_tiles(scene, infos, layouts, texel_size);

    // Rectangles: the projected bounds plus a margin, centred, in whole texels of the chart's
    // own size (texel_density.h: finer where the chart touches a dynamic object); the parts of
    // a tiled chart exactly on its grid.
    const std::vector<int> subdivision =
        refine ? choose_chart_subdivision(scene, atlas.charts, layouts, texel_size, atlas.gutter)
               : std::vector<int>(atlas.charts.size(), 1);
    for (size_t c = 0; c < atlas.charts.size(); ++c) {
        Chart& chart = atlas.charts[c];
        const double size = texel_size / double(subdivision[c]);
        chart.texel_size = float(size);
        const glm::dvec2 texels = layouts[c].extent / size + 2.0 * kChartMargin;
        if (!(texels.x < 65536.0 && texels.y < 65536.0))
            throw_input_error(where, "settings.lightmap.texel_size",
                              "a chart of object '" + scene.objects[size_t(chart.object)].name +
                                  "' would be over 65536 texels wide; expected a texel "
                                  "size closer to the scene's scale");
        const glm::ivec2 e = chart_layout_texels(layouts[c], size);
        chart.width = e.x;
        chart.height = e.y;
        chart.origin = glm::vec2(chart_layout_origin(layouts[c], size));
    }

    scene.load_timing.surfaces = lap();
    // Pack every chart with `gutter` free texels on each side, so bilinear lookups near a
    // chart's edge never read a neighbouring chart.
    const int count = int(atlas.charts.size());
    const int pad = 2 * atlas.gutter;
    std::vector<glm::ivec2> sizes(static_cast<size_t>(count));
    double total = 0.0;
    int widest = 1;
    for (int c = 0; c < count; ++c) {
        const Chart& chart = atlas.charts[size_t(c)];
        sizes[size_t(c)] = {chart.width + pad, chart.height + pad};
        total += double(sizes[size_t(c)].x) * double(sizes[size_t(c)].y);
        widest = std::max(widest, sizes[size_t(c)].x);
    }
    char texel_size_text[32];
    std::snprintf(texel_size_text, sizeof texel_size_text, "%g", double(texel_size_f));
    if (total > double(kMaxAtlasTexels))
        throw_input_error(where, "settings.lightmap.texel_size",
                          "a texel size of " + std::string(texel_size_text) +
                              " makes a lightmap atlas of " + std::to_string(int64_t(total)) +
                              " texels; expected at most " + std::to_string(kMaxAtlasTexels) +
                              " (a larger texel size)");
    std::vector<int> order(static_cast<size_t>(count));
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
        if (sizes[size_t(a)].y != sizes[size_t(b)].y)
            return sizes[size_t(a)].y > sizes[size_t(b)].y;
        if (sizes[size_t(a)].x != sizes[size_t(b)].x)
            return sizes[size_t(a)].x > sizes[size_t(b)].x;
        return a < b;
    });
    std::vector<glm::ivec2> positions;
    if (count > 0) {
        int width = 1;
        while (width < widest || double(width) * double(width) < total) width *= 2;
        // Shelves waste the space above shorter charts; a twice-wider atlas sometimes wastes less.
        const int height = round_up(pack_shelves(sizes, order, width, &positions), 4);
        std::vector<glm::ivec2> wide_positions;
        const int wide_height = round_up(pack_shelves(sizes, order, 2 * width, &wide_positions), 4);
        if (2.0 * double(width) * double(wide_height) < double(width) * double(height)) {
            atlas.width = 2 * width;
            atlas.height = wide_height;
            positions = std::move(wide_positions);
        } else {
            atlas.width = width;
            atlas.height = height;
        }
    }
    for (int c = 0; c < count; ++c) {
        atlas.charts[size_t(c)].x = positions[size_t(c)].x + atlas.gutter;
        atlas.charts[size_t(c)].y = positions[size_t(c)].y + atlas.gutter;
    }

    if (atlas.width > kMaxAtlasSide || atlas.height > kMaxAtlasSide)
        throw_input_error(where, "settings.lightmap.texel_size",
                          "a texel size of " + std::string(texel_size_text) +
                              " makes a lightmap atlas of " + std::to_string(atlas.width) + "×" +
                              std::to_string(atlas.height) + " texels; expected at most " +
                              std::to_string(kMaxAtlasSide) + " on a side (a larger texel size)");
    scene.load_timing.packing = lap();
    atlas.texel_index.assign(size_t(atlas.width) * size_t(atlas.height), -1);
    for (int oi = 0; oi < int(scene.objects.size()); ++oi)
        atlas.corner_uvs[size_t(oi)].assign(3 * scene.objects[size_t(oi)].mesh.triangles.size(),
                                            glm::vec2(0.0f));
    for (int c = 0; c < count; ++c) {
        const Chart& chart = atlas.charts[size_t(c)];
        const Mesh& mesh = scene.objects[size_t(chart.object)].mesh;
        std::vector<glm::vec2>& uvs = atlas.corner_uvs[size_t(chart.object)];
        for (int t : chart.triangles) {
            const Tri2 q = chart_texel_triangle(mesh, chart, t, chart.texel_size);
            for (int k = 0; k < 3; ++k)
                uvs[3 * size_t(t) + size_t(k)] =
                    glm::vec2(q[size_t(k)] + glm::dvec2(chart.x, chart.y));
        }
        make_chart_texels(mesh, infos[size_t(chart.object)], chart, c, chart.texel_size, atlas);
    }
    scene.load_timing.texels = lap();
}

std::optional<FootprintPoint> texel_point_at(const Scene& scene, int record, glm::vec2 offset) {
    const LightmapAtlas& atlas = scene.atlas;
    const TexelRecord& t = atlas.texels[size_t(record)];
    const Chart& chart = atlas.charts[size_t(t.chart)];
    const Mesh& mesh = scene.objects[size_t(t.object)].mesh;
    const std::vector<glm::vec2>& uvs = atlas.corner_uvs[size_t(t.object)];
    const glm::vec2 q = glm::vec2(float(t.x) + 0.5f, float(t.y) + 0.5f) + offset;
    for (int tri : chart.triangles) {
        const glm::vec2 a = uvs[3 * size_t(tri)], b = uvs[3 * size_t(tri) + 1],
                        c = uvs[3 * size_t(tri) + 2];
        const float det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        if (std::abs(det) < 1e-12f) continue;
        const float u = ((q.x - a.x) * (c.y - a.y) - (c.x - a.x) * (q.y - a.y)) / det;
        const float v = ((b.x - a.x) * (q.y - a.y) - (q.x - a.x) * (b.y - a.y)) / det;
        if (u < 0.0f || v < 0.0f || u + v > 1.0f) continue;
        const glm::uvec3 f = mesh.triangles[size_t(tri)];
        const glm::vec3 p0 = mesh.positions[f.x], p1 = mesh.positions[f.y],
                        p2 = mesh.positions[f.z];
        const glm::vec3 n = glm::cross(p1 - p0, p2 - p0);
        if (glm::dot(n, n) <= 0.0f) continue;
        return FootprintPoint{(1.0f - u - v) * p0 + u * p1 + v * p2, glm::normalize(n)};
    }
    return std::nullopt;
}

std::vector<FootprintPoint> texel_footprint_points(const Scene& scene, int record) {
    constexpr float kStep = 0.4f;
    // Edge neighbours (distance 0.4) before corners (0.57).
    constexpr int kOffsets[8][2] = {{-1, 0},  {1, 0},  {0, -1}, {0, 1},
                                    {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
    std::vector<FootprintPoint> out;
    for (const auto& o : kOffsets)
        if (const std::optional<FootprintPoint> p =
                texel_point_at(scene, record, kStep * glm::vec2(float(o[0]), float(o[1]))))
            out.push_back(*p);
    return out;
}

std::vector<uint16_t> texel_coverage_masks(const Scene& scene) {
    const LightmapAtlas& atlas = scene.atlas;
    constexpr int n = kCoverageSubdivision;
    std::vector<uint16_t> masks(size_t(atlas.width) * size_t(atlas.height), 0);
    for (const Chart& chart : atlas.charts) {
        const std::vector<glm::vec2>& uvs = atlas.corner_uvs[size_t(chart.object)];
        for (int tri : chart.triangles)
            visit_triangle_cells(chart, uvs, tri, [&](int x, int y, int i, int j, double, double) {
                uint16_t& m = masks[size_t(y) * size_t(atlas.width) + size_t(x)];
                m = uint16_t(m | (1u << (n * j + i)));
            });
    }
    return masks;
}

bool on_chart(const LightmapAtlas& atlas, const std::vector<uint16_t>& masks, int chart,
              glm::vec2 p) {
    const glm::vec2 f = glm::floor(p);
    const int x = int(f.x), y = int(f.y);
    if (x < 0 || y < 0 || x >= atlas.width || y >= atlas.height) return false;
    const int record = atlas.texel_at(x, y);
    if (record < 0 || atlas.texels[size_t(record)].chart != chart) return false;
    constexpr int n = kCoverageSubdivision;
    const int i = std::min(n - 1, int((p.x - f.x) * float(n))),
              j = std::min(n - 1, int((p.y - f.y) * float(n)));
    return (masks[size_t(y) * size_t(atlas.width) + size_t(x)] >> (n * j + i)) & 1u;
}

glm::vec2 chart_atlas_position(const Chart& chart, const glm::vec3& p) {
    return {float(chart.x) + (glm::dot(p, chart.u_axis) - chart.origin.x) / chart.texel_size,
            float(chart.y) + (glm::dot(p, chart.v_axis) - chart.origin.y) / chart.texel_size};
}

}  // namespace ag
