// Linear float RGB(A) images and their files. OpenImageIO writes linear EXR and sRGB PNG (our own
// sRGB transform, so the curve is exactly IEC 61966-2-1), always through a temporary file and a
// rename: an interrupted run never leaves a truncated image. The only place that includes OIIO.
#pragma once

#include <glm/glm.hpp>
#include <string>
#include <vector>

namespace ag {

struct Image {
    int width = 0, height = 0, channels = 3;
    std::vector<float> pixels;  // row-major, top row first, `channels` floats per pixel

    Image() = default;
    Image(int w, int h, int c = 3)
        : width(w), height(h), channels(c), pixels(size_t(w) * h * c, 0.0f) {}
    float* at(int x, int y) { return &pixels[(size_t(y) * width + x) * channels]; }
    const float* at(int x, int y) const { return &pixels[(size_t(y) * width + x) * channels]; }
    // A one- or two-channel image (a grey EXR read from a file) reads as grey.
    glm::vec3 rgb(int x, int y) const {
        const float* p = at(x, y);
        return channels >= 3 ? glm::vec3(p[0], p[1], p[2]) : glm::vec3(p[0]);
    }
    void set_rgb(int x, int y, const glm::vec3& c) {
        float* p = at(x, y);
        p[0] = c.r;
        p[1] = c.g;
        p[2] = c.b;
    }
};

// The mean of each factor × factor block (a box pixel filter, as the reference renderers'
// jittered pixel samples integrate): width and height must be multiples of `factor`.
Image box_downsample(const Image& image, int factor);

float srgb_encode(float linear);  // [0,1] linear → [0,1] sRGB
float srgb_decode(float encoded);

// Writes by extension: .exr (linear half/float), .png (sRGB 8-bit, clamped after exposure
// scaling by 2^exposure_ev), others OIIO knows (.hdr, .tif) as linear float. Throws
// std::runtime_error naming the file on failure; the destination is untouched then.
void write_image(const Image& image, const std::string& path, float exposure_ev = 0.0f);

// The largest image side read_image accepts: the largest `--size` (16384² pixels, 4 GiB of RGBA
// floats, is the most a header can make it allocate).
inline constexpr int kMaxImageSide = 16384;

// Reads any OIIO format to linear float (PNG/JPEG decoded from sRGB), at most its first four
// channels. Throws InputError naming the file if it cannot be read or its header claims more than
// kMaxImageSide pixels on a side.
Image read_image(const std::string& path);

// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
void write_file_atomically(const std::string& path, const std::string& bytes);

}  // namespace ag
