// Triangle meshes as plain indexed arrays: they feed Embree and GL buffers directly.
// OpenMesh is used only for preprocessing (files, connectivity), in mesh_io.cpp and charts.cpp.
#pragma once

#include <glm/glm.hpp>
#include <string>
#include <vector>

namespace ag {

struct Mesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::uvec3> triangles;  // counter-clockwise seen from the front
};

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

// Bakes a uniform or per-axis scale into the positions (scene files may scale meshes).
void scale_mesh(Mesh& mesh, const glm::vec3& scale);

}  // namespace ag
