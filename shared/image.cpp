#include "shared/image.h"

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "shared/input_error.h"

namespace ag {

namespace fs = std::filesystem;

float srgb_encode(float x) {
    x = std::clamp(x, 0.0f, 1.0f);
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

Image box_downsample(const Image& image, int factor) {
    if (factor <= 1) return image;
    assert(image.width % factor == 0 && image.height % factor == 0);
    Image out(image.width / factor, image.height / factor, image.channels);
    const float scale = 1.0f / float(factor * factor);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) {
            float* o = out.at(x, y);
            for (int sy = 0; sy < factor; ++sy)
                for (int sx = 0; sx < factor; ++sx) {
                    const float* p = image.at(factor * x + sx, factor * y + sy);
                    for (int c = 0; c < image.channels; ++c) o[c] += scale * p[c];
                }
        }
    return out;
}

float srgb_decode(float x) {
    return x <= 0.04045f ? x / 12.92f : std::pow((x + 0.055f) / 1.055f, 2.4f);
}

namespace {

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

// A temporary name beside `path` with the same extension (OIIO picks the format by extension).
std::string temporary_beside(const std::string& path) {
    const fs::path p(path);
    const std::string name =
        "." + p.stem().string() + ".tmp" + std::to_string(::getpid()) + p.extension().string();
    return (p.parent_path() / name).string();
}

void commit_temporary(const std::string& tmp, const std::string& path) {
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        std::error_code ignored;
        if (fs::is_directory(path, ignored)) ec = std::make_error_code(std::errc::is_a_directory);
        fs::remove(tmp, ignored);
        throw std::runtime_error(path +
                                 ": cannot move the written image into place: " + ec.message());
    }
}

}  // namespace

void write_file_atomically(const std::string& path, const std::string& bytes) {
    const std::string tmp = temporary_beside(path);
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), std::streamsize(bytes.size()));
        out.flush();
        if (!out) {
            std::error_code ec;
            fs::remove(tmp, ec);
            throw std::runtime_error(path + ": cannot write file");
        }
    }
    commit_temporary(tmp, path);
}

void write_image(const Image& image, const std::string& path, float exposure_ev) {
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != size_t(image.width) * image.height * image.channels)
        throw std::runtime_error(path + ": refusing to write an empty or malformed image");
    std::error_code dir_ec;
    if (fs::is_directory(path, dir_ec))
        throw std::runtime_error(path + ": cannot write image: is a directory");
    size_t non_finite = 0;
    for (const float v : image.pixels) non_finite += std::isfinite(v) ? 0 : 1;
    if (non_finite > 0)
        warn(path + ": " + std::to_string(non_finite) +
             " NaN or infinite pixel values written (PNG/JPEG: as black or white)");
    const std::string ext = lower_extension(path);
    const bool eight_bit = ext == ".png" || ext == ".jpg" || ext == ".jpeg";
    const std::string tmp = temporary_beside(path);

    auto out = OIIO::ImageOutput::create(path);
    if (!out)
        throw std::runtime_error(path + ": no image writer for this extension (" +
                                 OIIO::geterror() + ")");
    OIIO::ImageSpec spec(image.width, image.height, image.channels,
                         // 32-bit float everywhere: half overflows to +Inf above 65504.
                         eight_bit ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT);
    bool ok = false;
    if (eight_bit) {
        spec.attribute("oiio:ColorSpace", "sRGB");
        const float scale = std::exp2(exposure_ev);
        std::vector<unsigned char> bytes(image.pixels.size());
        for (size_t i = 0; i < bytes.size(); ++i) {
            const bool alpha = image.channels == 4 && i % 4 == 3;
            const float v = alpha ? std::clamp(image.pixels[i], 0.0f, 1.0f)
                                  : srgb_encode(image.pixels[i] * scale);
            bytes[i] = (unsigned char)std::lround(v * 255.0f);
        }
        ok = out->open(tmp, spec) && out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
    } else {
        spec.attribute("oiio:ColorSpace", "Linear");
        if (ext == ".exr") spec.attribute("compression", "zip");
        ok = out->open(tmp, spec) && out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
    }
    ok = out->close() && ok;
    if (!ok) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw std::runtime_error(path + ": cannot write image: " + out->geterror());
    }
    commit_temporary(tmp, path);
}

Image read_image(const std::string& path) {
    // OIIO reads devices and FIFOs without end ("/dev/zero" as a texture or reference hung).
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        throw_input_error(path, "",
                          fs::exists(path, ec) ? "cannot read image: expected a regular file"
                                               : "cannot read image: no such file");
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw_input_error(path, "", "cannot read image: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    // The header's size is checked before anything is allocated from it: a PNG of a hundred
    // bytes may claim 100000 x 100000 pixels, and `Image` would allocate (and zero) them all.
    if (spec.width < 1 || spec.height < 1 || spec.width > kMaxImageSide ||
        spec.height > kMaxImageSide || spec.nchannels < 1 || spec.depth != 1)
        throw_input_error(path, "",
                          "expected a 2D image of 1 to " + std::to_string(kMaxImageSide) +
                              " pixels on a side with at least one channel, got " +
                              std::to_string(spec.width) + " x " + std::to_string(spec.height) +
                              (spec.depth != 1 ? " x " + std::to_string(spec.depth) : "") +
                              " with " + std::to_string(spec.nchannels) + " channels");
    // Every reader takes RGB or RGBA: further channels (an EXR's depth, its AOVs) are not read.
    const int channels = std::min(spec.nchannels, 4);
    Image image;
    image.width = spec.width;
    image.height = spec.height;
    image.channels = channels;
    // Rows are decoded a band at a time into storage reserved (not yet touched) for the whole
    // image: a truncated file that claims 16384 x 16384 fails at its first missing band, having
    // zeroed and filled only what it held, not 4 GiB.
    const size_t row = size_t(spec.width) * size_t(channels);
    image.pixels.reserve(row * size_t(spec.height));
    // Tiled files (OpenEXR's tiles) are read a row of tiles at a time (OIIO's read_scanlines
    // divides by zero on them: SIGFPE).
    const bool tiled = spec.tile_width > 0 && spec.tile_height > 0;
    const int band = tiled ? std::max(1, 64 / spec.tile_height) * spec.tile_height : 64;
    for (int y = 0; y < spec.height; y += band) {
        const int end = std::min(spec.height, y + band);
        image.pixels.resize(row * size_t(end));
        float* data = image.pixels.data() + row * size_t(y);
        const bool ok =
            tiled ? in->read_tiles(0, 0, spec.x, spec.x + spec.width, spec.y + y, spec.y + end,
                                   spec.z, spec.z + 1, 0, channels, OIIO::TypeDesc::FLOAT, data)
                  : in->read_scanlines(0, 0, spec.y + y, spec.y + end, spec.z, 0, channels,
                                       OIIO::TypeDesc::FLOAT, data);
        if (!ok) throw_input_error(path, "", "cannot decode image: " + in->geterror());
    }
    const bool srgb = spec.format == OIIO::TypeDesc::UINT8 || spec.format == OIIO::TypeDesc::UINT16;
    if (srgb)
        for (size_t i = 0; i < image.pixels.size(); ++i)
            if (!(image.channels == 4 && i % 4 == 3))
                image.pixels[i] = srgb_decode(image.pixels[i]);
    in->close();
    return image;
}

}  // namespace ag
