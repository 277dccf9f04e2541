// Plain-array mesh helpers.
#include "shared/mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <tuple>

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

int remove_duplicate_triangles(Mesh& mesh) {
    // Corners rotated so the lexicographically smallest comes first: one key per orientation.
    using Key = std::array<float, 9>;
    auto less = [](const glm::vec3& a, const glm::vec3& b) {
        return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    };
    std::set<Key> seen;
    std::vector<char> keep(mesh.triangles.size(), 1);
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
        const glm::uvec3 t = mesh.triangles[i];
        const glm::vec3 c[3] = {mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]};
        int first = 0;
        for (int k = 1; k < 3; ++k)
            if (less(c[k], c[first])) first = k;
        Key key;
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d) key[size_t(3 * k + d)] = c[(first + k) % 3][d];
        keep[i] = seen.insert(key).second ? 1 : 0;
    }
    const size_t before = mesh.triangles.size();
    filter_triangles(mesh, [&](int i) { return keep[size_t(i)] != 0; });
    return int(before - mesh.triangles.size());
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
