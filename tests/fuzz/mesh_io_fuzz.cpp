// Fuzz target: mesh files through shared/mesh_io (OBJ, PLY, OFF, STL). The input's first line
// names the format ("obj", "ply", "off" or "stl"); the rest is the file, written to a scratch file
// with that extension and loaded as a scene would load it.
#include <array>
#include <string_view>

#include "shared/mesh_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string input = ag::fuzz::as_string(data, size);
    const size_t eol = input.find('\n');
    if (eol == std::string::npos) return 0;
    const std::string_view format(input.data(), eol);
    for (const char* ext : {"obj", "ply", "off", "stl"}) {
        if (format != ext) continue;
        const std::string file =
            ag::fuzz::write_scratch(std::string("mesh.") + ext, input.substr(eol + 1));
        ag::fuzz::expect_input_errors_only([&] { ag::load_mesh(file); });
    }
    return 0;
}
