// Plain-array mesh helpers.
#include "shared/mesh.h"

#include <algorithm>
#include <cmath>

namespace ag {

glm::vec3 triangle_cross(const Mesh& mesh, int triangle) {
    const glm::uvec3 t = mesh.triangles[size_t(triangle)];
    const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
    return glm::cross(b - a, c - a);
}

glm::vec3 triangle_normal(const Mesh& mesh, int triangle) {
    const glm::vec3 n = triangle_cross(mesh, triangle);
    const float len = glm::length(n);
    return len > 0.0f ? n / len : glm::vec3(0.0f);
}

float triangle_area(const Mesh& mesh, int triangle) {
    return 0.5f * glm::length(triangle_cross(mesh, triangle));
}

float mesh_area(const Mesh& mesh) {
    double area = 0.0;
    for (int i = 0; i < int(mesh.triangles.size()); ++i) area += triangle_area(mesh, i);
    return float(area);
}

Bounds mesh_bounds(const Mesh& mesh) {
    Bounds b;
    for (const glm::vec3& p : mesh.positions) b.add(p);
    return b;
}

bool is_degenerate_triangle(const Mesh& mesh, int triangle) {
    const glm::uvec3 t = mesh.triangles[size_t(triangle)];
    if (t.x == t.y || t.y == t.z || t.x == t.z) return true;
    const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
    const float longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    if (!(longest > 0.0f) || !std::isfinite(longest)) return true;
    // Area relative to the longest edge squared: a sliver thinner than 1e-6 of its length.
    return glm::length(glm::cross(b - a, c - a)) <= 1e-6f * longest * longest;
}

int remove_degenerate_triangles(Mesh& mesh) {
    const size_t before = mesh.triangles.size();
    std::vector<char> degenerate(before);
    for (size_t i = 0; i < before; ++i) degenerate[i] = is_degenerate_triangle(mesh, int(i));
    filter_triangles(mesh, [&](int i) { return !degenerate[size_t(i)]; });
    std::vector<glm::uvec3> kept = std::move(mesh.triangles);
    const int dropped = int(before - kept.size());
    // Compact vertices so no unused position remains.
    std::vector<int> remap(mesh.positions.size(), -1);
    std::vector<glm::vec3> positions;
    for (glm::uvec3& t : kept)
        for (int k = 0; k < 3; ++k) {
            int& r = remap[t[k]];
            if (r < 0) {
                r = int(positions.size());
                positions.push_back(mesh.positions[t[k]]);
            }
            t[k] = unsigned(r);
        }
    mesh.positions = std::move(positions);
    mesh.triangles = std::move(kept);
    return dropped;
}

void scale_mesh(Mesh& mesh, const glm::vec3& scale) {
    for (glm::vec3& p : mesh.positions) p *= scale;
    // A mirroring scale flips the winding; restore counter-clockwise fronts.
    if (scale.x * scale.y * scale.z < 0.0f) {
        for (glm::uvec3& t : mesh.triangles) std::swap(t.y, t.z);
        for (size_t i = 0; i + 2 < mesh.texcoords.size(); i += 3)
            std::swap(mesh.texcoords[i + 1], mesh.texcoords[i + 2]);
    }
}

}  // namespace ag
