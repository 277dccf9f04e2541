// Adaptive lightmap density (issue #12 item 4): finer texels on the charts where indirect light
// changes fast, at contacts with dynamic objects, within a total texel budget. Larsen ch. 8 lays
// every chart out at one texel size; this picks a subdivision of it per chart.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "shared/lightmap.h"
#include "shared/scene.h"

namespace ag {

// The objects whose nearness makes `chart` a contact: for a chart of a static object, the dynamic
// objects; for a chart of a dynamic object, every other object (what it stands on or leans on).
// Returns the fraction of the chart's area within `distance` (world units) of their triangles, as
// placed now, measured at sample points no further apart than `spacing`.
double chart_contact_fraction(const Scene& scene, const Chart& chart, double distance,
                              double spacing);

// Charts keep this many texels between their triangles and their rectangle's edge, so every
// corner UV lies strictly inside the rectangle.
inline constexpr double kChartMargin = 0.01;

// A chart's texel rectangle (gutters not included) at `texel_size`, from its projected extent.
glm::ivec2 chart_texel_extent(glm::dvec2 extent, double texel_size);

// Subdivision per chart (1 = the base texel size): charts are taken by contact fraction, highest
// first (ties by index), and each is subdivided `factor` times per edge while the atlas's texels,
// gutters included, stay within `budget` × the uniform layout's. `extents`: each chart's projected
// size in object units. Deterministic; all ones when factor ≤ 1 or no chart is a contact.
std::vector<int> choose_chart_subdivision(const Scene& scene, const std::vector<Chart>& charts,
                                          const std::vector<glm::dvec2>& extents,
                                          double base_texel_size, int gutter);

}  // namespace ag
