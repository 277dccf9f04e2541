#include "shared/image.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "shared/input_error.h"

namespace ag {

namespace fs = std::filesystem;

namespace {
fs::path temp_dir() {
    fs::path d = fs::temp_directory_path() / ("ag_image_test_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

Image gradient(int w, int h) {
    Image img(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            img.set_rgb(x, y, {x / float(w - 1), y / float(h - 1), 0.25f + 3.0f * (x == y)});
    return img;
}
}  // namespace

TEST(Image, SrgbCurveRoundTripsAndMatchesStandard) {
    EXPECT_NEAR(srgb_encode(0.0f), 0.0f, 1e-7);
    EXPECT_NEAR(srgb_encode(1.0f), 1.0f, 1e-6);
    EXPECT_NEAR(srgb_encode(0.18f), 0.4613561f, 1e-5);  // middle grey
    for (float x = 0.0f; x <= 1.0f; x += 0.01f) EXPECT_NEAR(srgb_decode(srgb_encode(x)), x, 1e-5);
}

TEST(Image, ExrRoundTripIsLinearAndKeepsHdr) {
    const fs::path p = temp_dir() / "a.exr";
    const Image img = gradient(17, 9);
    write_image(img, p.string());
    const Image back = read_image(p.string());
    ASSERT_EQ(back.width, 17);
    ASSERT_EQ(back.height, 9);
    ASSERT_EQ(back.channels, 3);
    for (size_t i = 0; i < img.pixels.size(); ++i)
        EXPECT_NEAR(back.pixels[i], img.pixels[i], 2e-3f * std::max(1.0f, img.pixels[i]));  // half
    EXPECT_GT(back.rgb(3, 3).b, 3.0f);  // values above 1 survive
}

TEST(Image, PngRoundTripThroughSrgb) {
    const fs::path p = temp_dir() / "a.png";
    const Image img = gradient(16, 8);
    write_image(img, p.string());
    const Image back = read_image(p.string());
    ASSERT_EQ(back.width, 16);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) {
                const float v = std::min(1.0f, img.at(x, y)[c]);
                // 8-bit quantisation in sRGB space: at most half a step after decoding.
                EXPECT_NEAR(srgb_encode(back.at(x, y)[c]), srgb_encode(v), 0.5f / 255.0f + 1e-5f);
            }
}

TEST(Image, ExposureScalesPng) {
    const fs::path p = temp_dir() / "e.png";
    Image img(2, 1);
    img.set_rgb(0, 0, glm::vec3(0.1f));
    img.set_rgb(1, 0, glm::vec3(0.2f));
    write_image(img, p.string(), 1.0f);  // +1 EV doubles
    const Image back = read_image(p.string());
    EXPECT_NEAR(back.rgb(0, 0).x, 0.2f, 0.005f);
    EXPECT_NEAR(back.rgb(1, 0).x, 0.4f, 0.008f);
}

TEST(Image, WritesAtomicallyLeavingNoTemporaries) {
    const fs::path d = temp_dir() / "atomic";
    fs::create_directories(d);
    write_image(gradient(8, 8), (d / "x.exr").string());
    write_image(gradient(8, 8), (d / "x.png").string());
    int files = 0;
    for (const auto& e : fs::directory_iterator(d)) {
        ++files;
        EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
    }
    EXPECT_EQ(files, 2);
}

TEST(Image, FailedWriteLeavesDestinationUntouched) {
    const fs::path d = temp_dir() / "keep";
    fs::create_directories(d);
    const fs::path p = d / "y.png";
    write_image(gradient(4, 4), p.string());
    const auto size_before = fs::file_size(p);
    Image broken(4, 4);
    broken.pixels.resize(3);  // malformed
    EXPECT_THROW(write_image(broken, p.string()), std::runtime_error);
    EXPECT_THROW(write_image(gradient(4, 4), (d / "missing_dir" / "z.png").string()),
                 std::runtime_error);
    EXPECT_EQ(fs::file_size(p), size_before);
}

TEST(Image, UnreadableFileIsAnInputErrorNamingIt) {
    const fs::path p = temp_dir() / "not_an_image.exr";
    std::ofstream(p) << "hello";
    try {
        read_image(p.string());
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("not_an_image.exr"), std::string::npos) << e.what();
    }
}

}  // namespace ag
