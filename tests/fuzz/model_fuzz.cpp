// Fuzz target: model files through shared/model_io (OBJ with its MTL library through
// tinyobjloader; glTF and GLB through tinygltf). The input's first line names the format ("obj",
// "gltf" or "glb"); the rest is the file. For OBJ, a line "#mtl" splits it: what follows is
// written as model.mtl beside it (seeds name it with `mtllib model.mtl`). A glTF's external
// buffers and images resolve in the scratch folder, which holds buf.bin (one triangle) and tex.png.
#include <cstring>
#include <string_view>

#include "shared/model_io.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

void write_neighbours() {
    static const bool written = [] {
        // Three float vec3 positions (0,0,0), (1,0,0), (0,1,0), then indices 0 1 2 as uint16.
        std::string buf(42, '\0');
        const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        const uint16_t idx[3] = {0, 1, 2};
        std::memcpy(buf.data(), p, sizeof p);
        std::memcpy(buf.data() + sizeof p, idx, sizeof idx);
        ag::fuzz::write_scratch("buf.bin", buf);
        ag::fuzz::write_scratch("tex.png", "not a png");
        return true;
    }();
    (void)written;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    write_neighbours();
    const std::string input = ag::fuzz::as_string(data, size);
    const size_t eol = input.find('\n');
    if (eol == std::string::npos) return 0;
    const std::string_view format(input.data(), eol);
    std::string body = input.substr(eol + 1);
    if (format == "obj") {
        const size_t split = body.find("\n#mtl\n");
        ag::fuzz::write_scratch("model.mtl",
                                split == std::string::npos ? "" : body.substr(split + 6));
        if (split != std::string::npos) body.resize(split + 1);
    } else if (format != "gltf" && format != "glb") {
        return 0;
    }
    const std::string file = ag::fuzz::write_scratch("model." + std::string(format), body);
    ag::fuzz::expect_input_errors_only([&] { ag::load_model(file); });
    return 0;
}
