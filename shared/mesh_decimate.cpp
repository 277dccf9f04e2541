#include "shared/mesh_decimate.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <stdexcept>
#include <string>
#include <vector>

namespace ag {

namespace {
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<>;
}  // namespace

Mesh decimate_mesh(const Mesh& mesh, size_t target_vertices) {
    TriMesh tm;
    std::vector<TriMesh::VertexHandle> handles;
    handles.reserve(mesh.positions.size());
    for (const glm::vec3& p : mesh.positions) handles.push_back(tm.add_vertex({p.x, p.y, p.z}));
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const glm::uvec3 tri = mesh.triangles[t];
        if (!tm.add_face(handles[tri.x], handles[tri.y], handles[tri.z]).is_valid())
            throw std::invalid_argument("decimate_mesh: triangle " + std::to_string(t) +
                                        " is not manifold");
    }
    OpenMesh::Decimater::DecimaterT<TriMesh> decimater(tm);
    OpenMesh::Decimater::ModQuadricT<TriMesh>::Handle quadric;
    decimater.add(quadric);
    decimater.initialize();
    decimater.decimate_to(target_vertices);
    tm.garbage_collection();

    Mesh out;
    out.positions.reserve(tm.n_vertices());
    for (const TriMesh::VertexHandle v : tm.vertices()) {
        const TriMesh::Point p = tm.point(v);
        out.positions.push_back({p[0], p[1], p[2]});
    }
    out.triangles.reserve(tm.n_faces());
    for (const TriMesh::FaceHandle f : tm.faces()) {
        glm::uvec3 tri;
        int k = 0;
        for (const TriMesh::VertexHandle v : tm.fv_range(f)) tri[k++] = unsigned(v.idx());
        out.triangles.push_back(tri);
    }
    return out;
}

}  // namespace ag
