// Helpers for gather tests (the CPU gather alone, and both backends through ag::Gatherer):
// lightmap atlas indexing, quads built in code, and the analytic form factor they are held to.
#pragma once

#include <cmath>
#include <glm/gtc/quaternion.hpp>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

#include "shared/charts.h"
#include "shared/scene.h"
#include "shared/scene_edit.h"
#include "shared/shapes.h"

namespace ag::test {

inline size_t atlas_index(const LightmapAtlas& atlas, const TexelRecord& t) {
    return size_t(t.y) * size_t(atlas.width) + size_t(t.x);
}

inline std::vector<glm::vec3> atlas_values(const Scene& scene) {
    return std::vector<glm::vec3>(size_t(scene.atlas.width) * size_t(scene.atlas.height),
                                  glm::vec3(0.0f));
}

inline std::vector<int> all_texels(const Scene& scene) {
    std::vector<int> ids(scene.atlas.texels.size());
    std::iota(ids.begin(), ids.end(), 0);
    return ids;
}

inline glm::vec3 world_position(const Scene& scene, const TexelRecord& t) {
    return scene.objects[size_t(t.object)].transform.apply_point(t.position);
}

inline Object quad_object(const std::string& name, float size, const glm::vec3& translation,
                          const glm::quat& rotation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f)) {
    Object o;
    o.name = name;
    o.mesh = make_quad(size, size);
    o.transform.translation = translation;
    o.transform.rotation = rotation;
    return o;
}

inline const glm::quat kFacingDown =
    glm::angleAxis(float(std::numbers::pi), glm::vec3(1.0f, 0.0f, 0.0f));

// Versions, surfaces and atlas for a scene built in code.
inline Scene finish(Scene s, float texel_size) {
    s.settings.lightmap.texel_size = texel_size;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

// Cosine-weighted fraction of the hemisphere of a point covered by a parallel rectangle at
// distance 1 with one corner straight above the point and sides X, Y (signed; the function is
// odd in each), the classic differential-area-to-rectangle form factor.
inline double corner_form_factor(double x, double y) {
    const double sx = std::sqrt(1.0 + x * x), sy = std::sqrt(1.0 + y * y);
    return (x / sx * std::atan(y / sx) + y / sy * std::atan(x / sy)) / (2.0 * std::numbers::pi);
}

// Form factor of a point at (px, pz) to the square [-a, a]² at height h above it.
inline double square_form_factor(double px, double pz, double a, double h) {
    const double x0 = (-a - px) / h, x1 = (a - px) / h, y0 = (-a - pz) / h, y1 = (a - pz) / h;
    return corner_form_factor(x1, y1) - corner_form_factor(x0, y1) - corner_form_factor(x1, y0) +
           corner_form_factor(x0, y0);
}

}  // namespace ag::test
