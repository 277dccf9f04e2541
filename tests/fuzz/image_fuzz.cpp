// Fuzz target: image files through shared/image and shared/texture (OpenImageIO): reference
// images for compare, converge and fidelity, and textures named by scene and glTF materials. The
// input's first line names the extension ("exr", "png", "hdr", "jpg", "tif", "ppm"); the rest is
// the file, read as read_image and then as load_texture reads it.
#include <string_view>

#include "shared/image.h"
#include "shared/texture.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string input = ag::fuzz::as_string(data, size);
    const size_t eol = input.find('\n');
    if (eol == std::string::npos) return 0;
    const std::string_view format(input.data(), eol);
    for (const char* ext : {"exr", "png", "hdr", "jpg", "tif", "ppm"}) {
        if (format != ext) continue;
        const std::string file =
            ag::fuzz::write_scratch(std::string("image.") + ext, input.substr(eol + 1));
        ag::fuzz::expect_input_errors_only([&] { ag::read_image(file); });
        ag::fuzz::expect_input_errors_only([&] { ag::load_texture(file); });
    }
    return 0;
}
