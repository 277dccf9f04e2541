// Fuzz target: a JSON scene file → Scene (parse_scene: settings, camera, materials, lights,
// objects, shapes, mesh files, surfaces, charts and the atlas). Mesh and script paths resolve in a
// scratch folder holding one small file of each kind, so seeds can reach the mesh readers too.
#include "shared/scene_file.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

const std::string& scene_path() {
    static const std::string path = [] {
        using ag::fuzz::write_scratch;
        write_scratch("cube.obj",
                      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                      "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 3 4 8 7\nf 2 3 7 6\nf 1 5 8 4\n");
        write_scratch("tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        write_scratch("edit.lua", "function on_frame(scene, frame, time) end\n");
        return (ag::fuzz::scratch_dir() / "fuzz.json").string();
    }();
    return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text = ag::fuzz::as_string(data, size);
    ag::fuzz::expect_input_errors_only([&] { ag::parse_scene(text, scene_path()); });
    return 0;
}
