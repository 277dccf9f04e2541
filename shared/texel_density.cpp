#include "shared/texel_density.h"

#include <algorithm>
#include <cmath>
#include <functional>
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
    int partner = 0;             // index into the partners' vertex lists
};

bool outside(const glm::dvec3& p, const WorldTriangle& t, double margin) {
    return glm::any(glm::lessThan(p, t.lo - margin)) ||
           glm::any(glm::greaterThan(p, t.hi + margin));
}

// Partner triangles by the cells of a uniform grid their bounds (grown by `margin`) overlap, so a
// sample tests the few that can lie within `margin` of it, not every triangle of a large mesh (a
// dynamic box's charts against a 133k-triangle room: minutes before).
class TriangleGrid {
public:
    TriangleGrid(const std::vector<WorldTriangle>& triangles, double margin) {
        glm::dvec3 lo(1e300), hi(-1e300);
        double extent = 0.0;
        for (const WorldTriangle& t : triangles) {
            lo = glm::min(lo, t.lo);
            hi = glm::max(hi, t.hi);
            extent += glm::length(t.hi - t.lo);
        }
        // Cells about the size of a triangle plus the margin: a few triangles per cell.
        cell_ = std::max(2.0 * margin + extent / double(std::max<size_t>(1, triangles.size())),
                         1e-9 * std::max(1.0, glm::length(hi - lo)));
        origin_ = lo - margin;
        // A triangle far larger than the cells (a floor among a statue's triangles) is tested by
        // every sample instead of filling a million cells.
        constexpr int64_t kMaxCells = 4096;
        std::vector<std::pair<glm::ivec3, glm::ivec3>> spans(triangles.size());
        for (size_t i = 0; i < triangles.size(); ++i) {
            const glm::ivec3 a = cell_of(triangles[i].lo - margin),
                             b = cell_of(triangles[i].hi + margin);
            const int64_t cells =
                (int64_t(b.x) - a.x + 1) * (int64_t(b.y) - a.y + 1) * (int64_t(b.z) - a.z + 1);
            if (cells > kMaxCells) {
                large_.push_back(int(i));
                spans[i] = {glm::ivec3(1), glm::ivec3(0)};  // empty
            } else {
                spans[i] = {a, b};
            }
        }
        for (size_t i = 0; i < triangles.size(); ++i) {
            const auto [a, b] = spans[i];
            for (int z = a.z; z <= b.z; ++z)
                for (int y = a.y; y <= b.y; ++y)
                    for (int x = a.x; x <= b.x; ++x) {
                        std::vector<int>& cell = cells_[key(glm::ivec3(x, y, z))];
                        if (cell.empty()) cell = large_;  // in increasing index order
                        cell.insert(std::upper_bound(cell.begin(), cell.end(), int(i)), int(i));
                    }
        }
    }
    // The triangles whose grown bounds may hold p (in increasing index order).
    const std::vector<int>& near(const glm::dvec3& p) const {
        const auto it = cells_.find(key(cell_of(p)));
        return it == cells_.end() ? large_ : it->second;
    }

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
    std::vector<int> large_;  // the triangles every cell holds
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

void for_each_contact_sample(const Scene& scene, const Chart& chart, double distance,
                             double spacing, double reach,
                             const std::function<void(const glm::dvec3& object_point, double area,
                                                      const ContactSample&)>& visit) {
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
    std::vector<std::vector<glm::dvec3>> partner_vertices;
    std::vector<int> partner_begin;  // per partner, its first triangle in `partners`; then the end
    std::vector<double> partner_grow;
    std::vector<WorldTriangle> partner_bounds;  // per partner: its world bounds (lo, hi)
    for (int oi = 0; oi < int(scene.objects.size()); ++oi) {
        const Object& o = scene.objects[size_t(oi)];
        if (oi == chart.object || !(own.dynamic || o.dynamic)) continue;
        std::vector<glm::dvec3> vertices;
        glm::dvec3 lo(1e300), hi(-1e300);
        for (const glm::vec3& p : o.mesh.positions) {
            vertices.emplace_back(o.transform.apply_point(p));
            lo = glm::min(lo, vertices.back());
            hi = glm::max(hi, vertices.back());
        }
        // A sample is within reach of a partner's triangle only within `reach` × the partner's
        // size of it (and within `reach` × the partner's height above the sample's plane).
        const double grow = std::max(
            distance, reach > 0.0 && !vertices.empty() ? reach * glm::length(hi - lo) : 0.0);
        if (glm::any(glm::lessThan(hi + grow, chart_lo)) ||
            glm::any(glm::greaterThan(lo - grow, chart_hi)))
            continue;
        partner_grow.push_back(grow);
        WorldTriangle whole;
        whole.lo = lo;
        whole.hi = hi;
        partner_bounds.push_back(whole);
        partner_begin.push_back(int(partners.size()));
        // Only the triangles that can come within `grow` of the chart (every test below is one
        // of distance or reach, and both are at most grow): a sphere among 65 others keeps the
        // few facing the chart, and the grid over them is built from those alone. A little
        // slack: a sample point may lie a rounding step outside the chart's bounds.
        const double slack = grow + 1e-9 * (1.0 + glm::length(chart_hi - chart_lo));
        for (const glm::uvec3& f : o.mesh.triangles) {
            WorldTriangle t;
            t.a = vertices[f.x];
            t.b = vertices[f.y];
            t.c = vertices[f.z];
            t.lo = glm::min(glm::min(t.a, t.b), t.c);
            t.hi = glm::max(glm::max(t.a, t.b), t.c);
            if (glm::any(glm::lessThan(t.hi + slack, chart_lo)) ||
                glm::any(glm::greaterThan(t.lo - slack, chart_hi)))
                continue;
            t.partner = int(partner_vertices.size());
            partners.push_back(t);
        }
        partner_vertices.push_back(std::move(vertices));
    }
    if (partners.empty()) return;
    partner_begin.push_back(int(partners.size()));
    // Few partner triangles (a box): test them all; many (a room's mesh): through a grid.
    constexpr size_t kGridFrom = 256;
    std::unique_ptr<TriangleGrid> grid;
    if (partners.size() >= kGridFrom) grid = std::make_unique<TriangleGrid>(partners, distance);
    std::vector<int> all;
    if (!grid) {
        all.resize(partners.size());
        std::iota(all.begin(), all.end(), 0);
    }

    // Sample each chart triangle at the centroids of an n×n split into equal sub-triangles.
    const double d2 = distance * distance;
    std::vector<double> reach2(partner_vertices.size()), partner_top(partner_vertices.size());
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
        const double longest =
            std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
        const int n = std::clamp(int(std::ceil(longest / spacing)), 1, 64);
        const double piece = area / double(n * n);
        // A partner's height above a sample's plane is max_w (w · normal) − p · normal: the
        // maximum over its vertices is the triangle's, once (not once per sample).
        if (reach > 0.0)
            for (size_t k = 0; k < partner_vertices.size(); ++k) {
                double top = -1e300;
                for (const glm::dvec3& w : partner_vertices[k])
                    top = std::max(top, glm::dot(w, normal));
                partner_top[k] = top;
            }
        const auto sample = [&](double u, double v) {
            const glm::dvec3 p = a + (b - a) * (u / n) + (c - a) * (v / n);
            const glm::dvec3 q_object = oa + (ob - oa) * (u / n) + (oc - oa) * (v / n);
            if (reach > 0.0)
                for (size_t k = 0; k < partner_vertices.size(); ++k) {
                    // The partner's height above the sample's plane.
                    const double height = std::max(0.0, partner_top[k] - glm::dot(p, normal));
                    reach2[k] = reach * reach * height * height;
                }
            ContactSample s;
            for (int i : grid ? grid->near(p) : all) {
                const WorldTriangle& t = partners[size_t(i)];
                if (outside(p, t, distance)) continue;
                const glm::dvec3 q = closest_on_triangle(p, t.a, t.b, t.c);
                const double e2 = glm::dot(q - p, q - p);
                s.near = s.near || e2 <= d2;
                s.covered = s.covered || e2 <= 1e-12 * d2;
                if (s.covered) break;
            }
            // Within reach of a partner: it only counts for a sample neither covered nor near.
            for (size_t k = 0; reach > 0.0 && !s.near && k < partner_vertices.size(); ++k) {
                if (!(reach2[k] > 0.0)) continue;
                const double r = std::min(std::sqrt(reach2[k]), partner_grow[k]);
                // Outside the partner's bounds grown by r: outside every triangle's (the same
                // answer, without the loop).
                if (outside(p, partner_bounds[k], r)) continue;
                for (int i = partner_begin[k]; i < partner_begin[k + 1]; ++i) {
                    const WorldTriangle& t = partners[size_t(i)];
                    if (outside(p, t, r)) continue;
                    const glm::dvec3 q = closest_on_triangle(p, t.a, t.b, t.c);
                    if (glm::dot(q - p, q - p) <= reach2[k]) {
                        s.within_reach = true;
                        break;
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
                              double spacing) {
    double near_area = 0.0, total_area = 0.0;
    for_each_contact_sample(scene, chart, distance, spacing, 0.0,
                            [&](const glm::dvec3&, double area, const ContactSample& s) {
                                total_area += area;
                                if (s.near) near_area += area;
                            });
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
    for (int c = 0; c < count; ++c) {
        fraction[size_t(c)] =
            layouts[size_t(c)].keep_base
                ? 0.0
                : chart_contact_fraction(scene, charts[size_t(c)],
                                         double(ls.refine_distance) * base_texel_size,
                                         0.25 * base_texel_size);
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
