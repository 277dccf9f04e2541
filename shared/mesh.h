// Triangle meshes as plain indexed arrays: they feed Embree and GL buffers directly.
// OpenMesh is used only for preprocessing (files, connectivity), in mesh_io.cpp and charts.cpp.
#pragma once

#include <cstddef>
#include <glm/glm.hpp>
#include <string>
#include <vector>

namespace ag {

struct Mesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::uvec3> triangles;  // counter-clockwise seen from the front
    // Texture coordinates per triangle corner (3 per triangle, in the triangles' order), or empty
    // for a mesh without them. Per corner, so UV seams never split the vertices charts join.
    std::vector<glm::vec2> texcoords;

    bool has_texcoords() const { return !texcoords.empty(); }
    // Texture coordinates at Embree's barycentrics (u, v) on `triangle`: (1-u-v)·t0 + u·t1 + v·t2.
    glm::vec2 texcoord(int triangle, glm::vec2 barycentric) const {
        const glm::vec2* t = &texcoords[3 * size_t(triangle)];
        return (1.0f - barycentric.x - barycentric.y) * t[0] + barycentric.x * t[1] +
               barycentric.y * t[2];
    }
};

// Keeps the triangles (and their texture coordinates) for which keep(index) is true.
template <class Keep>
void filter_triangles(Mesh& mesh, Keep keep) {
    std::vector<glm::uvec3> triangles;
    std::vector<glm::vec2> texcoords;
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
        if (!keep(int(i))) continue;
        triangles.push_back(mesh.triangles[i]);
        if (mesh.has_texcoords())
            texcoords.insert(texcoords.end(), mesh.texcoords.begin() + std::ptrdiff_t(3 * i),
                             mesh.texcoords.begin() + std::ptrdiff_t(3 * i + 3));
    }
    mesh.triangles = std::move(triangles);
    mesh.texcoords = std::move(texcoords);
}

struct Bounds {
    glm::vec3 min{1e30f};
    glm::vec3 max{-1e30f};
    void add(const glm::vec3& p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    bool empty() const { return min.x > max.x; }
    glm::vec3 center() const { return 0.5f * (min + max); }
    glm::vec3 extent() const { return max - min; }
};

// Unnormalised face normal (length = 2 × area).
glm::vec3 triangle_cross(const Mesh& mesh, int triangle);
glm::vec3 triangle_normal(const Mesh& mesh, int triangle);  // unit; zero for a degenerate one
float triangle_area(const Mesh& mesh, int triangle);
float mesh_area(const Mesh& mesh);
Bounds mesh_bounds(const Mesh& mesh);

// True if the triangle has (near) zero area relative to its longest edge, or repeated indices.
bool is_degenerate_triangle(const Mesh& mesh, int triangle);

// Drops degenerate triangles and unused vertices; returns how many triangles were dropped.
int remove_degenerate_triangles(Mesh& mesh);

// Drops triangles that repeat an earlier one: the same three corner positions in the same
// orientation (any rotation of the corners). Renderers that add light per fragment would count
// such a face twice, ray tracers once. Returns how many were dropped.
int remove_duplicate_triangles(Mesh& mesh);

// Bakes a uniform or per-axis scale into the positions (scene files may scale meshes).
void scale_mesh(Mesh& mesh, const glm::vec3& scale);

}  // namespace ag
