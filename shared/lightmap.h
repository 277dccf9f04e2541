// The lightmap layout: charts packed into one atlas and a record per texel. This is the contract
// between cpu/ (AIM fill, CPU gather) and gpu/ (IIM gather, frame); Larsen ch. 8, 10, 11.
#pragma once

#include <glm/glm.hpp>
#include <vector>

namespace ag {

// A chart: triangles of one surface whose normals lie within a cone around `axis`, laid flat by
// orthogonal projection onto the plane spanned by (u_axis, v_axis) (object space). Its texels
// occupy the atlas rectangle [x, x+width) × [y, y+height), gutters not included.
struct Chart {
    int object = -1;
    int surface = -1;
    std::vector<int> triangles;  // triangle indices into the object's mesh
    glm::vec3 axis{0.0f};        // projection direction: the chart's mean normal
    glm::vec3 u_axis{0.0f};      // unit; texel coordinate = dot(p, u_axis) / texel_size - u0 + x
    glm::vec3 v_axis{0.0f};
    glm::vec2 origin{0.0f};     // (u, v) in object units of the chart's lower-left corner
    int x = 0, y = 0;           // atlas position of the first texel
    int width = 0, height = 0;  // in texels
    float texel_size = 0.0f;    // world units per texel edge in this chart (adaptive density)
    // Charts cut from one chart by lightmap.refine_tile (its fine part near a contact and its
    // coarse rest) share this id, the index of the coarse part, and their frame; −1 otherwise.
    // Together they cover one flat layout, so the AIM's disc may reach from one into the other.
    int tile_group = -1;
};

// What one atlas texel stands for. Position and normal are in the object's space, so rigid
// motion keeps records valid: world = object.transform.apply_point(position).
struct TexelRecord {
    int object = -1;
    int surface = -1;
    int chart = -1;
    int triangle = -1;         // triangle that holds `position`
    int x = 0, y = 0;          // atlas texel coordinates
    glm::vec3 position{0.0f};  // texel centre, snapped inside a chart triangle
    glm::vec3 normal{0.0f};    // unit face normal there
    float area = 0.0f;         // world area of the chart triangles the texel covers
};

struct LightmapAtlas {
    int width = 0, height = 0;  // in texels
    float texel_size = 0.0f;    // world units per texel edge, the coarsest (Chart::texel_size)
    int gutter = 0;             // texels kept free around every chart
    std::vector<Chart> charts;
    std::vector<TexelRecord> texels;  // only texels that cover some chart triangle
    std::vector<int> texel_index;     // width*height, row-major from y=0; -1 = unused/gutter
    // Per object, per triangle corner (3 per triangle): atlas texel coordinates of the vertex.
    // Texel (x, y) spans [x, x+1) × [y, y+1); GL coordinates are these divided by width/height.
    std::vector<std::vector<glm::vec2>> corner_uvs;

    int texel_at(int tx, int ty) const {
        return texel_index[size_t(ty) * size_t(width) + size_t(tx)];
    }
};

}  // namespace ag
