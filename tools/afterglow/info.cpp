// afterglow info SCENE: what a scene holds after loading (triangles, surfaces, charts, atlas).
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <set>
#include <sstream>
#include <vector>

#include "shared/scene_file.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kInfoCommand{
    "info",
    "SCENE [options]",
    "Load a scene file and print its triangles, objects, surfaces, charts, atlas size, texel count "
    "and lights.",
    {
        flag("objects", "also list every object"),
        flag("settings", "also print the effective settings as JSON"),
        flag("timing", "also print where loading spent its time (files, surfaces, atlas)"),
        settings_option(),
    },
    1,
    1,
};

namespace {

std::string fmt_vec(const glm::vec3& v) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "(%g, %g, %g)", double(v.x), double(v.y), double(v.z));
    return buf;
}
// ", N finer (object: K charts at S, ...; ...)" for the charts adaptive density subdivided, by
// object in scene order, the first eight objects named; "tile of T texels" for the fine part of
// a chart cut into tiles (lightmap.refine_tile), e.g. "floor: tile of 860 texels at 15; block:
// 5 charts at 15".
std::string refined_charts(const Scene& scene) {
    int finer = 0;
    for (const Chart& c : scene.atlas.charts) finer += c.texel_size < scene.atlas.texel_size;
    if (finer == 0) return "";
    std::vector<int> tile_texels(scene.atlas.charts.size(), 0);
    for (const TexelRecord& t : scene.atlas.texels)
        if (t.chart >= 0 && size_t(t.chart) < tile_texels.size()) ++tile_texels[size_t(t.chart)];
    // Per object: (texel size, charts) in first-seen order, and the tiles' texels.
    struct Group {
        std::vector<std::pair<float, int>> sizes;
        std::vector<std::pair<int, float>> tiles;  // texels, texel size
    };
    std::vector<Group> groups(scene.objects.size());
    std::vector<int> order;
    for (size_t ci = 0; ci < scene.atlas.charts.size(); ++ci) {
        const Chart& c = scene.atlas.charts[ci];
        if (!(c.texel_size < scene.atlas.texel_size)) continue;
        Group& g = groups[size_t(c.object)];
        if (g.sizes.empty() && g.tiles.empty()) order.push_back(c.object);
        if (c.tile_group >= 0) {
            g.tiles.emplace_back(tile_texels[ci], c.texel_size);
            continue;
        }
        auto it = std::find_if(g.sizes.begin(), g.sizes.end(),
                               [&](const auto& e) { return e.first == c.texel_size; });
        if (it == g.sizes.end())
            g.sizes.emplace_back(c.texel_size, 1);
        else
            ++it->second;
    }
    std::ostringstream out;
    out << ", " << finer << " finer (";
    constexpr size_t kNamed = 8;
    for (size_t i = 0; i < std::min(order.size(), kNamed); ++i) {
        const Group& g = groups[size_t(order[i])];
        out << (i ? "; " : "") << scene.objects[size_t(order[i])].name << ":";
        bool first = true;
        for (const auto& [size, count] : g.sizes) {
            out << (first ? " " : ", ") << count << (count == 1 ? " chart at " : " charts at ")
                << size;
            first = false;
        }
        for (const auto& [texels, size] : g.tiles) {
            out << (first ? " " : ", ") << "tile of " << texels << " texels at " << size;
            first = false;
        }
    }
    if (order.size() > kNamed) out << "; " << order.size() - kNamed << " more objects";
    out << ")";
    return out.str();
}

}  // namespace

int run_info(const Args& args) {
    char buf_timing[256];
    Scene scene = load_scene(args.positionals()[0]);
    args.apply_settings(scene);
    int dynamic = 0;
    for (const Object& o : scene.objects) dynamic += o.dynamic ? 1 : 0;
    size_t atlas_texels = size_t(scene.atlas.width) * size_t(scene.atlas.height);

    std::ostream& out = std::cout;
    out << "scene      " << scene.name << " (" << scene.path
        << "), length unit: " << scene.length_unit << "\n"
        << "triangles  " << scene.triangle_count() << "\n"
        << "objects    " << scene.objects.size() << " (" << dynamic << " dynamic)\n"
        << "surfaces   " << scene.surfaces.size() << "\n"
        << "charts     " << scene.atlas.charts.size() << refined_charts(scene) << "\n"
        << "atlas      " << scene.atlas.width << " x " << scene.atlas.height
        << " texels, texel size " << scene.atlas.texel_size << " " << scene.length_unit
        << ", gutter " << scene.atlas.gutter << "\n"
        << "texels     " << scene.atlas.texels.size() << " used of " << atlas_texels << "\n"
        << "lights     " << scene.lights.size() << "\n";
    for (const Light& l : scene.lights) {
        out << "  " << l.name << ": ";
        if (l.type == LightType::point)
            out << "point at " << fmt_vec(l.position) << ", intensity " << fmt_vec(l.intensity)
                << " W/sr";
        else if (l.type == LightType::sun)
            out << "sun along " << fmt_vec(l.direction) << ", irradiance " << fmt_vec(l.irradiance)
                << ", photon disc radius " << l.sun_radius;
        else if (l.type == LightType::spot)
            out << "spot at " << fmt_vec(l.position) << " along " << fmt_vec(l.direction)
                << ", cone " << l.cone_inner << "-" << l.cone_outer << " deg, intensity "
                << fmt_vec(l.intensity) << " W/sr";
        else if (l.type == LightType::mesh)
            out << "mesh (object " << scene.objects[size_t(l.object)].name << ", "
                << l.triangle_cdf.size() << " triangles) centred at " << fmt_vec(l.center())
                << ", area " << l.area() << ", radiance " << fmt_vec(l.radiance);
        else
            out << "quad centred at " << fmt_vec(l.center()) << ", area " << l.quad_area()
                << ", radiance " << fmt_vec(l.radiance);
        out << ", power " << fmt_vec(l.power()) << " W" << (l.enabled ? "" : " (off)") << "\n";
    }
    out << "camera     eye " << fmt_vec(scene.camera.eye) << " target "
        << fmt_vec(scene.camera.target) << ", fov " << scene.camera.fov_y << " deg, "
        << scene.camera.width << " x " << scene.camera.height << "\n";
    if (!scene.script.empty()) out << "script     " << scene.script << "\n";

    if (args.has("objects")) {
        out << "objects:\n";
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            const Object& o = scene.objects[i];
            std::set<int> surfaces(
                scene.triangle_surface.size() > i ? scene.triangle_surface[i].begin()
                                                  : std::vector<int>::const_iterator{},
                scene.triangle_surface.size() > i ? scene.triangle_surface[i].end()
                                                  : std::vector<int>::const_iterator{});
            int charts = 0;
            for (const Chart& c : scene.atlas.charts) charts += c.object == int(i) ? 1 : 0;
            out << "  " << o.name << ": " << o.mesh.triangles.size() << " triangles, "
                << surfaces.size() << " surfaces, " << charts << " charts, "
                << kMaterialTypeNames[size_t(o.material.type)] << " '" << o.material.name << "'"
                << (o.dynamic ? ", dynamic" : "") << ", from " << o.source << "\n";
        }
    }
    if (args.has("timing")) {
        const LoadTiming& t = scene.load_timing;
        std::snprintf(buf_timing, sizeof buf_timing,
                      "load       %.3f s: files (JSON, meshes, models) %.3f s, surfaces and "
                      "charts %.3f s, atlas packing %.3f s, texel records %.3f s\n",
                      t.files + t.surfaces + t.packing + t.texels, t.files, t.surfaces, t.packing,
                      t.texels);
        out << buf_timing;
    }
    if (args.has("settings")) out << settings_to_json(scene.settings) << "\n";
    return 0;
}

static const Registration kRegistration(kInfoCommand, run_info, 10);

}  // namespace ag::cli
