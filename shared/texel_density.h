// Adaptive lightmap density (issue #12 item 4): finer texels on the charts where indirect light
// changes fast, at contacts with dynamic objects, within a total texel budget. Larsen ch. 8 lays
// every chart out at one texel size; this picks a subdivision of it per chart.
#pragma once

#include <functional>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "shared/lightmap.h"
#include "shared/scene.h"

namespace ag {

// The scene's objects' triangles in world space, kept across the charts of one pass so each
// object is transformed and ordered once, not once per chart. An object whose mesh has grown since
// (cut into tiles) is taken again; one moved since is not: make a new cache after moving objects.
class ContactCache {
public:
    ContactCache();
    ~ContactCache();
    ContactCache(const ContactCache&) = delete;
    ContactCache& operator=(const ContactCache&) = delete;
    struct Impl;
    std::unique_ptr<Impl> impl;
};

// The objects whose nearness makes `chart` a contact: for a chart of a static object, the dynamic
// objects; for a chart of a dynamic object, every other object (what it stands on or leans on).
// Returns the fraction of the chart's area within `distance` (world units) of their triangles, as
// placed now, measured at sample points no further apart than `spacing`.
double chart_contact_fraction(const Scene& scene, const Chart& chart, double distance,
                              double spacing, ContactCache* cache = nullptr);
// The samples behind chart_contact_fraction: `visit` gets each sample point in the chart's
// object space, the area it stands for, whether it lies within `distance` of a partner, and
// whether it touches one (within 10⁻⁶ × distance: the floor under a box standing on it, which
// no camera or gather sees). Nothing is visited when the chart has no partners.
struct ContactSample {
    bool near = false;     // within `distance` of a partner
    bool covered = false;  // touches one
    // Within `reach` × the partner's height above the sample's plane (how far it stands out
    // along the chart's normal) of that partner: the scale over which the partner's occlusion
    // of the sample's hemisphere, so its indirect light, changes (lightmap.refine_reach). Only
    // looked for where it decides anything, a sample neither near nor covered; false otherwise
    // and when reach ≤ 0.
    bool within_reach = false;
};
void for_each_contact_sample(const Scene& scene, const Chart& chart, double distance,
                             double spacing, double reach,
                             const std::function<void(const glm::dvec3& object_point, double area,
                                                      const ContactSample&)>& visit,
                             ContactCache* cache = nullptr);

// Charts keep this many texels between their triangles and their rectangle's edge, so every
// corner UV lies strictly inside the rectangle.
inline constexpr double kChartMargin = 0.01;

// A chart's texel rectangle (gutters not included) at `texel_size`, from its projected extent.
glm::ivec2 chart_texel_extent(glm::dvec2 extent, double texel_size);

// Where a chart's rectangle lies: its projected bounds plus a margin, centred (every chart cut
// by the crease and cone rules), or exactly on the texel grid of the chart it was cut from (the
// parts of a chart split into tiles, lightmap.refine_tile), so that the coarse part's texels and
// the fine part's meet along texel edges and neither has partly covered texels at the seam.
struct ChartLayout {
    glm::dvec2 lo{0.0};      // projected lower corner, object units
    glm::dvec2 extent{0.0};  // projected size, object units
    bool exact = false;      // the rectangle starts at `lo` and spans `extent` in whole texels
    bool keep_base = false;  // the coarse part of a tiled chart: never subdivided
};
// Texels of the layout's rectangle (gutters not included) at `texel_size`.
glm::ivec2 chart_layout_texels(const ChartLayout& layout, double texel_size);
// The (u, v) of the rectangle's lower corner at `texel_size`: `lo`, or the bounds centred in it.
glm::dvec2 chart_layout_origin(const ChartLayout& layout, double texel_size);

// Subdivision per chart (1 = the base texel size): charts are taken by contact fraction, highest
// first (ties by index), and each is subdivided `factor` times per edge while the atlas's texels,
// gutters included, stay within `budget` × the uniform layout's (every chart, the parts of tiled
// charts included, at the base size). Deterministic; all ones when factor ≤ 1 or no chart is a
// contact; `keep_base` charts stay 1.
std::vector<int> choose_chart_subdivision(const Scene& scene, const std::vector<Chart>& charts,
                                          const std::vector<ChartLayout>& layouts,
                                          double base_texel_size, int gutter);

}  // namespace ag
