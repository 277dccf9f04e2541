// Reading the lightmap atlas at a surface point, and repairing texels a gather cannot see from
// (Larsen ch. 10, 11): AIM lookups at final-gather hits and IIM hole filling for both backends.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "shared/lightmap.h"

namespace ag {

// A gather whose rays (or hemi-plane pixels) see back faces of diffuse surfaces more often than
// this starts behind or inside geometry: its texel is invalid and is repaired from neighbours.
inline constexpr float kBackFaceInvalidFraction = 0.1f;

// Atlas texel coordinates of a point on a triangle (texel (x, y) spans [x, x+1) × [y, y+1)),
// from Embree's barycentrics (u, v): p = (1-u-v)·v0 + u·v1 + v·v2.
glm::vec2 lightmap_uv(const LightmapAtlas& atlas, int object, int triangle, glm::vec2 barycentric);

// The chart holding `triangle` of `object`, or -1 where it has none (mirrors, glass).
int triangle_chart(const LightmapAtlas& atlas, int object, int triangle);

// Bilinear lookup of `texels` (width × height, row-major) at a point on a triangle, over the
// four nearest texel centres that exist and belong to the triangle's chart (weights
// renormalised; the nearest texel of the chart if none of the four does), so values never bleed
// across charts or from gutters. Zero for objects without charts.
glm::vec3 sample_lightmap(const LightmapAtlas& atlas, const std::vector<glm::vec3>& texels,
                          int object, int triangle, glm::vec2 barycentric);

// Screen coverage (the IIM schedule's "how much of the screen a texel covers"): a pixel whose
// frame reads the lightmap bilinearly at `lookup` (atlas texel coordinates, as lightmap_uv)
// depends on the four texels around it; `weight` (the pixel's share of the screen) is split
// among the texel records among the four by their bilinear weights (gutters hold copies of
// their chart's texels), or goes to the record under the lookup where only gutters surround
// it. `coverage` is per texel record. The GL pass and the CPU rays both count through this.
void add_lookup_coverage(const LightmapAtlas& atlas, glm::vec2 lookup, float weight,
                         std::vector<float>& coverage);

// Fills the texels whose record is marked invalid (valid_per_record[r] == 0) from valid texels of
// the same chart: layer by layer outwards from the valid ones, each texel the mean of its valid
// or already filled 8-neighbours, so islands fill too. Texels of a chart with no valid texel
// become 0. `values` is atlas-sized (width × height); valid texels are never written.
void repair_invalid_texels(const LightmapAtlas& atlas, std::vector<glm::vec3>& values,
                           const std::vector<char>& valid_per_record);

// The same fill, but only the records in `targets` are written: other invalid texels (e.g. not
// gathered yet) are filled in passing so the fill can cross them, but keep their values.
void repair_invalid_texels(const LightmapAtlas& atlas, std::vector<glm::vec3>& values,
                           const std::vector<char>& valid_per_record,
                           const std::vector<int>& targets);

}  // namespace ag
