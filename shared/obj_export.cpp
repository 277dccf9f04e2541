#include "shared/obj_export.h"

#include <filesystem>
#include <sstream>

#include "shared/image.h"

namespace ag {

namespace {
std::string triple(const glm::vec3& v) {
    std::ostringstream s;
    s.precision(9);
    s << v.x << ' ' << v.y << ' ' << v.z;
    return s.str();
}
}  // namespace

void export_obj(const Scene& scene, const std::string& obj_path) {
    const std::filesystem::path p(obj_path);
    const std::string mtl_name = p.stem().string() + ".mtl";
    const std::string mtl_path = (p.parent_path() / mtl_name).string();

    std::ostringstream obj, mtl;
    obj.precision(9);
    obj << "# Afterglow scene '" << scene.name << "' from " << scene.path
        << ", world space, unit: " << scene.length_unit << "\n";
    obj << "mtllib " << mtl_name << "\n";
    for (const Light& l : scene.lights) {
        if (l.type == LightType::point)
            obj << "# point light '" << l.name << "' position " << triple(l.position)
                << " intensity " << triple(l.intensity) << " W/sr" << (l.enabled ? "" : " (off)")
                << "\n";
        else if (l.type == LightType::sun)
            obj << "# sun light '" << l.name << "' direction " << triple(l.direction)
                << " irradiance " << triple(l.irradiance) << (l.enabled ? "" : " (off)") << "\n";
        else if (l.type == LightType::spot)
            obj << "# spot light '" << l.name << "' position " << triple(l.position)
                << " direction " << triple(l.direction) << " cone " << l.cone_inner << " "
                << l.cone_outer << " intensity " << triple(l.intensity)
                << (l.enabled ? "" : " (off)") << "\n";
        else if (l.type == LightType::mesh)
            obj << "# mesh light '" << l.name << "': the emissive object of that name, radiance "
                << triple(l.radiance) << (l.enabled ? "" : " (off)") << "\n";
        else
            obj << "# quad light '" << l.name << "' corners " << triple(l.corners[0]) << " | "
                << triple(l.corners[1]) << " | " << triple(l.corners[2]) << " | "
                << triple(l.corners[3]) << " radiance " << triple(l.radiance)
                << (l.enabled ? "" : " (off)") << "\n";
    }

    size_t base = 1;  // OBJ indices are 1-based and global
    for (const Object& o : scene.objects) {
        const Material& m = o.material;
        mtl << "newmtl " << o.name << "\n";
        switch (m.type) {
            case MaterialType::diffuse:
                mtl << "Kd " << triple(m.albedo) << "\nKs 0 0 0\nillum 1\n";
                break;
            case MaterialType::mirror:
                mtl << "Kd 0 0 0\nKs 1 1 1\nillum 3\n";
                break;
            case MaterialType::glass:
                mtl << "Kd 0 0 0\nKs 1 1 1\nNi " << m.ior << "\nillum 7\n";
                break;
        }
        if (m.emission != glm::vec3(0.0f)) mtl << "Ke " << triple(m.emission) << "\n";
        mtl << "\n";

        obj << "o " << o.name << "\nusemtl " << o.name << "\n";
        for (const glm::vec3& v : o.mesh.positions)
            obj << "v " << triple(o.transform.apply_point(v)) << "\n";
        for (const glm::uvec3& t : o.mesh.triangles)
            obj << "f " << base + t.x << ' ' << base + t.y << ' ' << base + t.z << "\n";
        base += o.mesh.positions.size();
    }
    write_file_atomically(mtl_path, mtl.str());
    write_file_atomically(obj_path, obj.str());
}

}  // namespace ag
