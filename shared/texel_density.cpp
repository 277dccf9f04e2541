#include "shared/texel_density.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <numeric>
#include <unordered_map>

namespace ag {
namespace {

// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection §5.1.5).
glm::dvec3 closest_on_triangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b,
                               const glm::dvec3& c) {
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return a;
    const glm::dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3));
    const glm::dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

struct WorldTriangle {
    glm::dvec3 a, b, c, lo, hi;  // bounds without margin
};

// Scalar compares: this runs for every sample against every nearby triangle, and the fuzz
// build instruments every glm call it would otherwise make.
bool outside(const glm::dvec3& p, const glm::dvec3& lo, const glm::dvec3& hi, double margin) {
    return p.x < lo.x - margin || p.y < lo.y - margin || p.z < lo.z - margin ||
           p.x > hi.x + margin || p.y > hi.y + margin || p.z > hi.z + margin;
}
bool outside(const glm::dvec3& p, const WorldTriangle& t, double margin) {
    return outside(p, t.lo, t.hi, margin);
}

// Spreads the low 21 bits of v to every third bit (for a 63-bit Morton code).
uint64_t spread_bits(uint64_t v) {
    v &= 0x1fffffull;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

// Sorts triangles along a Morton curve of their centroids within (lo, hi), so runs of consecutive
// triangles are spatially compact. The contact tests ask "is any triangle near", so the order
// changes no answer.
void sort_along_morton_curve(std::vector<WorldTriangle>& triangles, const glm::dvec3& lo,
                             const glm::dvec3& hi) {
    const glm::dvec3 size = glm::max(hi - lo, glm::dvec3(1e-300));
    std::vector<std::pair<uint64_t, size_t>> keyed;
    keyed.reserve(triangles.size());
    for (size_t i = 0; i < triangles.size(); ++i) {
        const WorldTriangle& t = triangles[i];
        const glm::dvec3 u = ((t.lo + t.hi) * 0.5 - lo) / size;
        // 21 bits an axis; NaN (a degenerate mesh) and anything outside [0, 1] clamped, before
        // the cast to an integer.
        const auto bits = [](double x) {
            constexpr double kTop = double((1 << 21) - 1);
            return x > 0.0 ? uint64_t(std::min(x, 1.0) * kTop) : uint64_t(0);
        };
        keyed.emplace_back(
            spread_bits(bits(u.x)) | spread_bits(bits(u.y)) << 1 | spread_bits(bits(u.z)) << 2, i);
    }
    std::stable_sort(keyed.begin(), keyed.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<WorldTriangle> sorted;
    sorted.reserve(keyed.size());
    for (const auto& [code, i] : keyed) sorted.push_back(triangles[i]);
    triangles = std::move(sorted);
}

// Triangles per run: runs of kCluster consecutive triangles (in Morton order, so compact) carry
// their bounds, and a box test on a run stands for its triangles'.
constexpr size_t kCluster = 16;

// The bounds (lo, hi) of each run of kCluster of the `count` triangles triangles[index(i)].
template <class Index>
std::vector<WorldTriangle> run_bounds(const std::vector<WorldTriangle>& triangles, size_t count,
                                      Index index) {
    std::vector<WorldTriangle> runs;
    for (size_t i = 0; i < count; i += kCluster) {
        WorldTriangle run;
        run.lo = glm::dvec3(1e300);
        run.hi = glm::dvec3(-1e300);
        for (size_t j = i; j < std::min(i + kCluster, count); ++j) {
            run.lo = glm::min(run.lo, triangles[index(j)].lo);
            run.hi = glm::max(run.hi, triangles[index(j)].hi);
        }
        runs.push_back(run);
    }
    return runs;
}

// Each chart triangle is sampled at the centroids of an n×n split: n for its world corners (NaN
// and anything below one step: 1).
int sample_subdivisions(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                        double spacing) {
    const double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    const double steps = longest / spacing;
    return steps > 1.0 ? int(std::min(std::ceil(steps), 64.0)) : 1;
}

// Partner triangles by the cells of a uniform grid their bounds (grown by `margin`) overlap, so a
// sample tests the few that can lie within `margin` of it, not every triangle of a large mesh (a
// dynamic box's charts against a 133k-triangle room: minutes before).
class TriangleGrid {
public:
    // Over `triangles[i]` for each i in `indices` (the near candidates among a chart's partners).
    TriangleGrid(const std::vector<WorldTriangle>& triangles, const std::vector<int>& indices,
                 double margin) {
        glm::dvec3 lo(1e300), hi(-1e300);
        double extent = 0.0;
        for (int i : indices) {
            const WorldTriangle& t = triangles[size_t(i)];
            lo = glm::min(lo, t.lo);
            hi = glm::max(hi, t.hi);
            extent += glm::length(t.hi - t.lo);
        }
        // Cells about the size of a triangle plus the margin: a few triangles per cell.
        cell_ = std::max(2.0 * margin + extent / double(std::max<size_t>(1, indices.size())),
                         1e-9 * std::max(1.0, glm::length(hi - lo)));
        origin_ = lo - margin;
        // A triangle far larger than the cells (a floor among a statue's triangles) is tested by
        // every sample instead of filling a million cells.
        constexpr int64_t kMaxCells = 4096;
        for (int i : indices) {
            const WorldTriangle& t = triangles[size_t(i)];
            const glm::ivec3 a = cell_of(t.lo - margin), b = cell_of(t.hi + margin);
            const int64_t cells =
                (int64_t(b.x) - a.x + 1) * (int64_t(b.y) - a.y + 1) * (int64_t(b.z) - a.z + 1);
            if (cells > kMaxCells) {
                large_.push_back(i);
                continue;
            }
            for (int z = a.z; z <= b.z; ++z)
                for (int y = a.y; y <= b.y; ++y)
                    for (int x = a.x; x <= b.x; ++x) cells_[key(glm::ivec3(x, y, z))].push_back(i);
        }
    }
    // The triangles whose grown bounds may hold p, but for large().
    const std::vector<int>& near(const glm::dvec3& p) const {
        static const std::vector<int> none;
        const auto it = cells_.find(key(cell_of(p)));
        return it == cells_.end() ? none : it->second;
    }
    // The triangles every point may be near.
    const std::vector<int>& large() const { return large_; }

private:
    glm::ivec3 cell_of(const glm::dvec3& p) const {
        const glm::dvec3 c = glm::floor((p - origin_) / cell_);
        return glm::ivec3(glm::clamp(c, glm::dvec3(-1e6), glm::dvec3(1e6)));
    }
    static uint64_t key(const glm::ivec3& c) {
        const auto u = [](int v) { return uint64_t(uint32_t(v + (1 << 20))) & 0x1fffffull; };
        return u(c.x) | (u(c.y) << 21) | (u(c.z) << 42);
    }
    double cell_ = 1.0;
    glm::dvec3 origin_{0.0};
    std::unordered_map<uint64_t, std::vector<int>> cells_;
    std::vector<int> large_;  // the triangles too large for the cells: every point tests them
};

}  // namespace

glm::ivec2 chart_texel_extent(glm::dvec2 extent, double texel_size) {
    const glm::dvec2 texels = extent / texel_size + 2.0 * kChartMargin;
    return {std::max(1, int(std::ceil(texels.x))), std::max(1, int(std::ceil(texels.y)))};
}

glm::ivec2 chart_layout_texels(const ChartLayout& layout, double texel_size) {
    if (!layout.exact) return chart_texel_extent(layout.extent, texel_size);
    const glm::dvec2 texels = glm::round(layout.extent / texel_size);
    return {std::max(1, int(texels.x)), std::max(1, int(texels.y))};
}

// Per object: its triangles in world space as placed now, along a Morton curve of their centres,
// with the runs' bounds, built once per pass and not once per chart (66 spheres: 2,911 charts
// each transformed and sorted every other sphere's 1,280 triangles before).
struct ContactCache::Impl {
    struct Entry {
        size_t triangle_count = std::numeric_limits<size_t>::max();
        size_t position_count = std::numeric_limits<size_t>::max();
        std::vector<glm::dvec3> vertices;
        glm::dvec3 lo{1e300}, hi{-1e300};
        std::vector<WorldTriangle> triangles;  // Morton order
        std::vector<WorldTriangle> runs;       // bounds of triangles [kCluster i, kCluster (i+1))
    };
    std::vector<Entry> objects;

    // The object's entry, rebuilt when its mesh has grown (cut into tiles) since.
    const Entry& get(const Scene& scene, int oi) {
        if (objects.size() != scene.objects.size()) objects.assign(scene.objects.size(), Entry{});
        Entry& e = objects[size_t(oi)];
        const Object& o = scene.objects[size_t(oi)];
        if (e.triangle_count == o.mesh.triangles.size() &&
            e.position_count == o.mesh.positions.size())
            return e;
        e = Entry{};
        e.triangle_count = o.mesh.triangles.size();
        e.position_count = o.mesh.positions.size();
        for (const glm::vec3& p : o.mesh.positions) {
            e.vertices.emplace_back(o.transform.apply_point(p));
            e.lo = glm::min(e.lo, e.vertices.back());
            e.hi = glm::max(e.hi, e.vertices.back());
        }
        for (const glm::uvec3& f : o.mesh.triangles) {
            WorldTriangle t;
            t.a = e.vertices[f.x];
            t.b = e.vertices[f.y];
            t.c = e.vertices[f.z];
            t.lo = glm::min(glm::min(t.a, t.b), t.c);
            t.hi = glm::max(glm::max(t.a, t.b), t.c);
            e.triangles.push_back(t);
        }
        sort_along_morton_curve(e.triangles, e.lo, e.hi);
        e.runs = run_bounds(e.triangles, e.triangles.size(), [](size_t j) { return j; });
        return e;
    }
};

ContactCache::ContactCache() : impl(std::make_unique<Impl>()) {}
ContactCache::~ContactCache() = default;

namespace {

bool apart(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dvec3& other_lo,
           const glm::dvec3& other_hi, double margin) {
    return hi.x + margin < other_lo.x || hi.y + margin < other_lo.y || hi.z + margin < other_lo.z ||
           lo.x - margin > other_hi.x || lo.y - margin > other_hi.y || lo.z - margin > other_hi.z;
}

}  // namespace

void for_each_contact_sample(const Scene& scene, const Chart& chart, double distance,
                             double spacing, double reach,
                             const std::function<void(const glm::dvec3& object_point, double area,
                                                      const ContactSample&)>& visit,
                             ContactCache* cache) {
    ContactCache local;
    ContactCache::Impl& world = *(cache ? cache : &local)->impl;
    const Object& own = scene.objects[size_t(chart.object)];
    // The chart's world bounds: a partner farther from them than both `distance` and its reach
    // can make no sample near or within reach, so it is left out (66 dynamic spheres: every
    // chart against every other sphere's vertices took minutes).
    glm::dvec3 chart_lo(1e300), chart_hi(-1e300);
    for (int tri : chart.triangles)
        for (int k = 0; k < 3; ++k) {
            const glm::dvec3 p(
                own.transform.apply_point(own.mesh.positions[own.mesh.triangles[size_t(tri)][k]]));
            chart_lo = glm::min(chart_lo, p);
            chart_hi = glm::max(chart_hi, p);
        }
    // The partners' triangles in world space, with their bounds for a quick reject.
    std::vector<WorldTriangle> partners;
    std::vector<const std::vector<glm::dvec3>*> partner_vertices;
    std::vector<int> partner_begin;  // per partner, its first triangle in `partners`; then the end
    std::vector<double> partner_grow;
    std::vector<WorldTriangle> partner_bounds;  // per partner: its world bounds (lo, hi)
    for (int oi = 0; oi < int(scene.objects.size()); ++oi) {
        const Object& o = scene.objects[size_t(oi)];
        if (oi == chart.object || !(own.dynamic || o.dynamic)) continue;
        const ContactCache::Impl::Entry& e = world.get(scene, oi);
        // A sample is within reach of a partner's triangle only within `reach` × the partner's
        // size of it (and within `reach` × the partner's height above the sample's plane).
        const double grow = std::max(
            distance, reach > 0.0 && !e.vertices.empty() ? reach * glm::length(e.hi - e.lo) : 0.0);
        if (apart(e.lo, e.hi, chart_lo, chart_hi, grow)) continue;
        partner_grow.push_back(grow);
        WorldTriangle whole;
        whole.lo = e.lo;
        whole.hi = e.hi;
        partner_bounds.push_back(whole);
        partner_begin.push_back(int(partners.size()));
        // Only the triangles that can come within `grow` of the chart (every test below is one
        // of distance or reach, and both are at most grow): a sphere among 65 others keeps the
        // few facing the chart, and the grid over them is built from those alone. A little
        // slack: a sample point may lie a rounding step outside the chart's bounds.
        const double slack = grow + 1e-9 * (1.0 + glm::length(chart_hi - chart_lo));
        for (size_t run = 0; run < e.runs.size(); ++run) {
            if (apart(e.runs[run].lo, e.runs[run].hi, chart_lo, chart_hi, slack)) continue;
            for (size_t i = run * kCluster; i < std::min((run + 1) * kCluster, e.triangles.size());
                 ++i) {
                const WorldTriangle& t = e.triangles[i];
                if (apart(t.lo, t.hi, chart_lo, chart_hi, slack)) continue;
                partners.push_back(t);
            }
        }
        partner_vertices.push_back(&e.vertices);
    }
    if (partners.empty()) return;
    partner_begin.push_back(int(partners.size()));
    // Each partner's triangles (in Morton order, so compact runs) in runs of kCluster with the
    // runs' bounds: the reach test skips a run whose bounds are out of reach, not each of its
    // triangles (a block's charts against a bumpy floor's 12,800 triangles: 20 s in the fuzz
    // build before).
    std::vector<WorldTriangle> clusters;  // bounds only
    std::vector<int> cluster_begin;       // per partner, its first run in `clusters`; then the end
    for (size_t k = 0; k + 1 < partner_begin.size(); ++k) {
        cluster_begin.push_back(int(clusters.size()));
        const size_t first = size_t(partner_begin[k]);
        const std::vector<WorldTriangle> runs =
            run_bounds(partners, size_t(partner_begin[k + 1]) - first,
                       [first](size_t j) { return first + j; });
        clusters.insert(clusters.end(), runs.begin(), runs.end());
    }
    cluster_begin.push_back(int(clusters.size()));
    // The near test (within `distance`) needs only the triangles within distance of the chart;
    // the rest were kept for the reach test. Few (a box): test them all; many (a room's mesh):
    // through a grid.
    const double near_slack = distance + 1e-9 * (1.0 + glm::length(chart_hi - chart_lo));
    std::vector<int> near_candidates;
    for (int i = 0; i < int(partners.size()); ++i) {
        const WorldTriangle& t = partners[size_t(i)];
        if (!apart(t.lo, t.hi, chart_lo, chart_hi, near_slack)) near_candidates.push_back(i);
    }
    // The candidates in runs of kCluster with their bounds (they keep the partners' Morton
    // order, so the runs are compact).
    const std::vector<WorldTriangle> near_runs = run_bounds(
        partners, near_candidates.size(), [&](size_t j) { return size_t(near_candidates[j]); });
    // Samples against the runs cost (samples × runs); a grid costs about 8 hashed cells per
    // candidate to build and a few triangles per sample: it pays for itself only for many
    // samples against many candidates (a sphere's 29-triangle chart among five others: the grid
    // was a third of a load).
    size_t samples = 0;
    for (int tri : chart.triangles) {
        const glm::uvec3 f = own.mesh.triangles[size_t(tri)];
        const glm::dvec3 a(own.transform.apply_point(own.mesh.positions[f.x])),
            b(own.transform.apply_point(own.mesh.positions[f.y])),
            c(own.transform.apply_point(own.mesh.positions[f.z]));
        const size_t n = size_t(sample_subdivisions(a, b, c, spacing));
        samples += n * n;
    }
    constexpr size_t kGridFrom = 256;
    std::unique_ptr<TriangleGrid> grid;
    if (near_candidates.size() >= kGridFrom &&
        double(samples) * double(near_runs.size()) > 64.0 * double(near_candidates.size()))
        grid = std::make_unique<TriangleGrid>(partners, near_candidates, distance);

    // Sample each chart triangle at the centroids of an n×n split into equal sub-triangles.
    const double d2 = distance * distance;
    // Per partner, per chart triangle: the top of its bounding box over the triangle's plane (a
    // cheap upper bound), and the exact top over its vertices, found only when the bound lets
    // the partner come within reach of a sample (NaN: not yet).
    std::vector<double> partner_box_top(partner_vertices.size()),
        partner_top(partner_vertices.size());
    for (int tri : chart.triangles) {
        const glm::uvec3 f = own.mesh.triangles[size_t(tri)];
        const glm::dvec3 oa(own.mesh.positions[f.x]), ob(own.mesh.positions[f.y]),
            oc(own.mesh.positions[f.z]);
        const glm::dvec3 a(own.transform.apply_point(own.mesh.positions[f.x]));
        const glm::dvec3 b(own.transform.apply_point(own.mesh.positions[f.y]));
        const glm::dvec3 c(own.transform.apply_point(own.mesh.positions[f.z]));
        const glm::dvec3 cross = glm::cross(b - a, c - a);
        const double area = 0.5 * glm::length(cross);
        if (!(area > 0.0)) continue;
        const glm::dvec3 normal = cross / (2.0 * area);
        const int n = sample_subdivisions(a, b, c, spacing);
        const double piece = area / double(n * n);
        // A partner's height above a sample's plane is max_w (w · normal) − p · normal: the
        // maximum over its vertices is the triangle's, once (not once per sample), and only for
        // the partners whose box may reach (66 spheres: each chart triangle against every other
        // sphere's vertices was most of a load before).
        if (reach > 0.0)
            for (size_t k = 0; k < partner_vertices.size(); ++k) {
                const WorldTriangle& box = partner_bounds[k];
                partner_box_top[k] = glm::dot(
                    glm::mix(box.lo, box.hi, glm::dvec3(glm::greaterThan(normal, glm::dvec3(0.0)))),
                    normal);
                partner_top[k] = std::numeric_limits<double>::quiet_NaN();
            }
        const auto exact_top = [&](size_t k) {
            if (std::isnan(partner_top[k])) {
                double top = -1e300;
                for (const glm::dvec3& w : *partner_vertices[k])
                    top = std::max(top, glm::dot(w, normal));
                partner_top[k] = top;
            }
            return partner_top[k];
        };
        const auto sample = [&](double u, double v) {
            const glm::dvec3 p = a + (b - a) * (u / n) + (c - a) * (v / n);
            const glm::dvec3 q_object = oa + (ob - oa) * (u / n) + (oc - oa) * (v / n);
            ContactSample s;
            // Near and covered are "any triangle" answers: the order of the lists is immaterial.
            // Once near, only a covering triangle can change the answer, and one lies within
            // sqrt(1e-12) × distance of the sample: the box test tightens to that (with slack).
            const auto test_one = [&](int i) {
                const WorldTriangle& t = partners[size_t(i)];
                if (outside(p, t, s.near ? 2e-6 * distance : distance)) return;
                const glm::dvec3 q = closest_on_triangle(p, t.a, t.b, t.c);
                const double e2 = glm::dot(q - p, q - p);
                s.near = s.near || e2 <= d2;
                s.covered = s.covered || e2 <= 1e-12 * d2;
            };
            const auto test = [&](const std::vector<int>& list) {
                for (size_t j = 0; !s.covered && j < list.size(); ++j) test_one(list[j]);
            };
            if (grid) {
                test(grid->near(p));
                if (!s.covered) test(grid->large());
            } else {
                for (size_t run = 0; !s.covered && run < near_runs.size(); ++run) {
                    if (outside(p, near_runs[run], s.near ? 2e-6 * distance : distance)) continue;
                    for (size_t j = run * kCluster;
                         !s.covered && j < std::min((run + 1) * kCluster, near_candidates.size());
                         ++j)
                        test_one(near_candidates[j]);
                }
            }
            // Within reach of a partner: it only counts for a sample neither covered nor near.
            for (size_t k = 0; reach > 0.0 && !s.near && k < partner_vertices.size(); ++k) {
                // The partner's height above the sample's plane: first its box's, an upper bound.
                const double plane = glm::dot(p, normal);
                const double box_height = std::max(0.0, partner_box_top[k] - plane);
                if (!(box_height > 0.0) ||
                    outside(p, partner_bounds[k], std::min(reach * box_height, partner_grow[k])))
                    continue;
                const double height = std::max(0.0, exact_top(k) - plane);
                const double reach2 = reach * reach * height * height;
                if (!(reach2 > 0.0)) continue;
                const double r = std::min(std::sqrt(reach2), partner_grow[k]);
                // Outside the partner's bounds grown by r: outside every triangle's (the same
                // answer, without the loop).
                if (outside(p, partner_bounds[k], r)) continue;
                for (int run = cluster_begin[k]; !s.within_reach && run < cluster_begin[k + 1];
                     ++run) {
                    if (outside(p, clusters[size_t(run)], r)) continue;
                    const int first = partner_begin[k] + (run - cluster_begin[k]) * int(kCluster);
                    const int last = std::min(first + int(kCluster), partner_begin[k + 1]);
                    for (int i = first; i < last; ++i) {
                        const WorldTriangle& t = partners[size_t(i)];
                        if (outside(p, t, r)) continue;
                        const glm::dvec3 q = closest_on_triangle(p, t.a, t.b, t.c);
                        if (glm::dot(q - p, q - p) <= reach2) {
                            s.within_reach = true;
                            break;
                        }
                    }
                }
                if (s.within_reach) break;
            }
            visit(q_object, piece, s);
        };
        for (int i = 0; i < n; ++i)
            for (int j = 0; i + j < n; ++j) {
                sample(i + 1.0 / 3.0, j + 1.0 / 3.0);
                if (i + j < n - 1) sample(i + 2.0 / 3.0, j + 2.0 / 3.0);
            }
    }
}

glm::dvec2 chart_layout_origin(const ChartLayout& layout, double texel_size) {
    if (layout.exact) return layout.lo;
    const glm::dvec2 slack =
        glm::dvec2(chart_layout_texels(layout, texel_size)) * texel_size - layout.extent;
    return layout.lo - 0.5 * slack;
}

double chart_contact_fraction(const Scene& scene, const Chart& chart, double distance,
                              double spacing, ContactCache* cache) {
    double near_area = 0.0, total_area = 0.0;
    for_each_contact_sample(
        scene, chart, distance, spacing, 0.0,
        [&](const glm::dvec3&, double area, const ContactSample& s) {
            total_area += area;
            if (s.near) near_area += area;
        },
        cache);
    return total_area > 0.0 ? near_area / total_area : 0.0;
}

std::vector<int> choose_chart_subdivision(const Scene& scene, const std::vector<Chart>& charts,
                                          const std::vector<ChartLayout>& layouts,
                                          double base_texel_size, int gutter) {
    const LightmapSettings& ls = scene.settings.lightmap;
    const int count = int(charts.size());
    std::vector<int> subdivision(static_cast<size_t>(count), 1);
    if (ls.refine_factor <= 1 || count == 0) return subdivision;
    // In doubles: an atlas too large for ints is refused after this, naming the texel size.
    const auto texels = [&](int c, int factor) {
        const glm::dvec2 e(chart_layout_texels(layouts[size_t(c)], base_texel_size / factor));
        return (e.x + 2.0 * gutter) * (e.y + 2.0 * gutter);
    };
    std::vector<double> fraction(static_cast<size_t>(count));
    double total = 0.0;
    ContactCache cache;
    for (int c = 0; c < count; ++c) {
        fraction[size_t(c)] =
            layouts[size_t(c)].keep_base
                ? 0.0
                : chart_contact_fraction(scene, charts[size_t(c)],
                                         double(ls.refine_distance) * base_texel_size,
                                         0.25 * base_texel_size, &cache);
        total += texels(c, 1);
    }
    const double budget = double(ls.refine_budget) * total;
    std::vector<int> order(static_cast<size_t>(count));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return fraction[size_t(a)] > fraction[size_t(b)]; });
    for (int c : order) {
        if (!(fraction[size_t(c)] > 0.0)) break;
        const double finer = total - texels(c, 1) + texels(c, ls.refine_factor);
        if (finer > budget) continue;
        total = finer;
        subdivision[size_t(c)] = ls.refine_factor;
    }
    return subdivision;
}

}  // namespace ag
