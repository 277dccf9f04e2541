// Mesh files through OpenMesh IO: read into a polygon mesh, fan-triangulate into plain arrays.
#include "shared/mesh_io.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>

#include "shared/input_error.h"

namespace ag {
namespace {

using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<>;

constexpr const char* kFormats[] = {".obj", ".ply", ".off", ".stl"};
constexpr const char* kFormatList = ".obj, .ply, .off or .stl";

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

bool supported(const std::string& ext) {
    return std::find_if(std::begin(kFormats), std::end(kFormats),
                        [&](const char* f) { return ext == f; }) != std::end(kFormats);
}

// OpenMesh refuses faces with a repeated vertex and only prints that; counting them lets the
// degenerate-triangle warning account for every face the file had.
class CountingImporter : public OpenMesh::IO::ImporterT<PolyMesh> {
public:
    using ImporterT::ImporterT;
    int rejected = 0;
    OpenMesh::FaceHandle add_face(const VHandles& indices) override {
        const OpenMesh::FaceHandle fh = ImporterT::add_face(indices);
        if (!fh.is_valid()) ++rejected;
        return fh;
    }
    using ImporterT::add_face;
};

}  // namespace

Mesh load_mesh(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw_input_error(path, "", "cannot open mesh file: no such file");
    if (!std::filesystem::is_regular_file(path, ec))
        throw_input_error(path, "", "cannot open mesh file: not a regular file");
    const std::string ext = lower_extension(path);
    if (!supported(ext))
        throw_input_error(
            path, "",
            "unsupported mesh format \"" + ext + "\"; expected " + std::string(kFormatList));
    if (!std::ifstream(path, std::ios::binary))
        throw_input_error(path, "", "cannot open mesh file: permission denied or unreadable");

    PolyMesh poly;
    CountingImporter importer(poly);
    OpenMesh::IO::Options options;
    if (!OpenMesh::IO::IOManager().read(path, importer, options))
        throw_input_error(path, "",
                          "cannot read mesh file: not a valid " + ext.substr(1) +
                              " file (see the mesh reader's message above)");

    Mesh mesh;
    mesh.positions.reserve(poly.n_vertices());
    for (const auto vh : poly.vertices()) {
        const auto p = poly.point(vh);
        mesh.positions.push_back({p[0], p[1], p[2]});
    }
    // Fan triangulation keeps the polygon's winding; file polygons are assumed convex.
    for (const auto fh : poly.faces()) {
        std::vector<unsigned> loop;
        for (const auto vh : poly.fv_range(fh)) loop.push_back(unsigned(vh.idx()));
        for (size_t k = 2; k < loop.size(); ++k)
            mesh.triangles.push_back({loop[0], loop[k - 1], loop[k]});
    }

    const int total = int(mesh.triangles.size()) + importer.rejected;
    if (total == 0)
        throw_input_error(path, "", "mesh has no faces; expected at least one triangle");
    const int dropped = remove_degenerate_triangles(mesh) + importer.rejected;
    if (mesh.triangles.empty())
        throw_input_error(path, "",
                          "all " + std::to_string(total) +
                              " faces are degenerate (zero area or repeated vertices)");
    if (dropped > 0)
        warn(path + ": dropped " + std::to_string(dropped) + " of " + std::to_string(total) +
             " faces as degenerate (zero area or repeated vertices)");
    return mesh;
}

void save_mesh(const Mesh& mesh, const std::string& path) {
    const std::string ext = lower_extension(path);
    if (!supported(ext))
        throw_input_error(
            path, "",
            "unsupported mesh format \"" + ext + "\"; expected " + std::string(kFormatList));
    PolyMesh poly;
    std::vector<OpenMesh::VertexHandle> handles;
    handles.reserve(mesh.positions.size());
    for (const glm::vec3& p : mesh.positions)
        handles.push_back(poly.add_vertex(PolyMesh::Point(p.x, p.y, p.z)));
    for (const glm::uvec3& t : mesh.triangles) {
        std::vector<OpenMesh::VertexHandle> face = {handles[t.x], handles[t.y], handles[t.z]};
        // Non-manifold triangles cannot join the halfedge structure; give them their own
        // vertices (as OpenMesh's importer does) so that no triangle is lost on the way out.
        if (!poly.add_face(face).is_valid()) {
            for (int k = 0; k < 3; ++k)
                face[size_t(k)] = poly.add_vertex(poly.point(face[size_t(k)]));
            poly.add_face(face);
        }
    }
    // OpenMesh logs "[OBJWriter] : write file" on every save; keep its error stream only.
    OpenMesh::mostream& log = omlog();
    const bool was_logging = log.is_enabled();
    log.disable();
    const bool written = OpenMesh::IO::write_mesh(poly, path);
    if (was_logging) log.enable();
    if (!written) throw_input_error(path, "", "cannot write mesh file (does the folder exist?)");
}

}  // namespace ag
