// PLACEHOLDER so the tree links; being replaced by the charts implementation.
#include "shared/charts.h"
namespace ag {
std::vector<int> segment_surfaces(const Mesh& mesh, float, int* surface_count) {
    *surface_count = 1;
    return std::vector<int>(mesh.triangles.size(), 0);
}
void make_surfaces_and_atlas(Scene&) {}
}  // namespace ag
