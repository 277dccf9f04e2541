// Fuzz target: Lua source as a scene-edit script (shared/script) against the Cornell box: loaded,
// then on_start and three on_frame calls, each under a small instruction and memory budget. Every
// run starts from the same scene; a script's errors are reported, never thrown, except at load.
#include "shared/scene_file.h"
#include "shared/script.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const ag::Scene cornell = ag::load_scene(AG_SOURCE_DIR "/scenes/cornell.json");
    ag::ScriptLimits limits;
    limits.instructions = 200'000;
    limits.memory_bytes = size_t(16) << 20;
    const std::string source = ag::fuzz::as_string(data, size);
    ag::fuzz::expect_input_errors_only([&] {
        ag::Script script = ag::Script::from_string(source, "fuzz.lua", limits);
        ag::Scene scene = cornell;
        script.on_start(scene);
        for (int frame = 1; frame <= 3; ++frame) script.on_frame(scene, frame, frame / 30.0);
    });
    return 0;
}
