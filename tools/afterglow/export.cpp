// afterglow export SCENE -o out.obj: the scene in world space as OBJ + MTL.
#include <iostream>

#include "shared/obj_export.h"
#include "shared/scene_file.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kExportCommand{
    "export",
    "SCENE -o OUT.obj",
    "Write the whole scene in world space as Wavefront OBJ with an MTL beside it (Kd, Ks, Ni, Ke); "
    "lights become comment lines.",
    {text("output,o", "OUT.obj", "the OBJ file to write (the .mtl gets the same stem)")},
    1,
    1,
};

int run_export(const Args& args) {
    if (!args.has("output")) throw CliError("afterglow export: missing -o OUT.obj");
    const std::string out = args.get("output");
    if (out.size() < 4 || out.substr(out.size() - 4) != ".obj")
        throw CliError("afterglow export: -o expects a file name ending in .obj, got '" + out +
                       "'");
    const Scene scene = load_scene(args.positionals()[0]);
    export_obj(scene, out);
    std::cerr << "afterglow export: wrote " << out << " (" << scene.triangle_count()
              << " triangles)\n";
    return 0;
}

static const Registration kRegistration(kExportCommand, run_export, 20);

}  // namespace ag::cli
