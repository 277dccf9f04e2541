// The sub-texel cells of a lightmap chart that one of its triangles covers: the walk that the
// atlas's coverage masks (shared/charts.cpp) and the AIM's covered-cell test (cpu/aim.cpp) share.
#pragma once

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <vector>

#include "shared/charts.h"
#include "shared/lightmap.h"

namespace ag {

// Calls visit(x, y, i, j, u, v) for every cell (i, j) of the kCoverageSubdivision² grid of every
// texel (x, y) of `chart` (atlas texel coordinates, clamped to the chart's rectangle) whose centre
// (x + (i + ½)/n, y + (j + ½)/n) lies on triangle `tri`'s UV image `uvs[3·tri ..]`. (u, v) are the
// centre's barycentric coordinates: corner 0 + u·(corner 1 − corner 0) + v·(corner 2 − corner 0).
// A triangle of (nearly) zero UV area visits nothing and returns false.
// The barycentric coordinates (u, v) of the centre of cell (i, j) of atlas texel (x, y) on the
// triangle with UV corners a, b, c and det = cross(b − a, c − a): the arithmetic
// visit_triangle_cells uses, so that a cell visited again later gets the same point to the bit.
inline glm::dvec2 cell_barycentrics(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c,
                                    double det, int x, int y, int i, int j) {
    const auto cross = [](const glm::dvec2& p, const glm::dvec2& q) {
        return p.x * q.y - p.y * q.x;
    };
    constexpr int n = kCoverageSubdivision;
    const glm::dvec2 q(x + (i + 0.5) / n, y + (j + 0.5) / n);
    return {cross(q - a, c - a) / det, cross(b - a, q - a) / det};
}

template <class Visit>
bool visit_triangle_cells(const Chart& chart, const std::vector<glm::vec2>& uvs, int tri,
                          Visit&& visit) {
    const auto cross = [](const glm::dvec2& p, const glm::dvec2& q) {
        return p.x * q.y - p.y * q.x;
    };
    const glm::dvec2 a(uvs[3 * size_t(tri)]), b(uvs[3 * size_t(tri) + 1]),
        c(uvs[3 * size_t(tri) + 2]);
    const double det = cross(b - a, c - a);
    if (std::abs(det) < 1e-12) return false;
    constexpr int n = kCoverageSubdivision;
    const glm::dvec2 lo = glm::min(glm::min(a, b), c), hi = glm::max(glm::max(a, b), c);
    const int x0 = std::max(chart.x, int(std::floor(lo.x))),
              x1 = std::min(chart.x + chart.width - 1, int(std::floor(hi.x)));
    const int y0 = std::max(chart.y, int(std::floor(lo.y))),
              y1 = std::min(chart.y + chart.height - 1, int(std::floor(hi.y)));
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const glm::dvec2 uv = cell_barycentrics(a, b, c, det, x, y, i, j);
                    if (uv.x >= 0.0 && uv.y >= 0.0 && uv.x + uv.y <= 1.0)
                        visit(x, y, i, j, uv.x, uv.y);
                }
    return true;
}

}  // namespace ag
