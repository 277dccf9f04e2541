#include "shared/image.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

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

TEST(Image, BoxDownsampleAveragesEachBlock) {
    Image image(4, 2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) image.set_rgb(x, y, glm::vec3(float(x + 4 * y), 1.0f, -1.0f));
    const Image half = box_downsample(image, 2);
    ASSERT_EQ(half.width, 2);
    ASSERT_EQ(half.height, 1);
    EXPECT_EQ(half.rgb(0, 0), glm::vec3((0.0f + 1.0f + 4.0f + 5.0f) / 4.0f, 1.0f, -1.0f));
    EXPECT_EQ(half.rgb(1, 0), glm::vec3((2.0f + 3.0f + 6.0f + 7.0f) / 4.0f, 1.0f, -1.0f));
    EXPECT_EQ(box_downsample(image, 1).pixels, image.pixels);
}

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
        EXPECT_EQ(back.pixels[i], img.pixels[i]);  // 32-bit float: exact
    EXPECT_GT(back.rgb(3, 3).b, 3.0f);             // values above 1 survive
}

// Half floats overflow to +Inf above 65504; a wall of emission 70000 or a 1e11 W/sr lamp must
// survive the EXR.
TEST(Image, ExrKeepsValuesAboveTheHalfFloatRange) {
    const fs::path p = temp_dir() / "bright.exr";
    Image img(2, 1);
    img.set_rgb(0, 0, glm::vec3(70000.0f));
    img.set_rgb(1, 0, glm::vec3(1e11f, 3e38f, 1.0f));
    write_image(img, p.string());
    const Image back = read_image(p.string());
    EXPECT_EQ(back.rgb(0, 0).x, 70000.0f);
    EXPECT_EQ(back.rgb(1, 0).x, 1e11f);
    EXPECT_EQ(back.rgb(1, 0).y, 3e38f);
}

TEST(Image, NonFinitePixelsAreWrittenWithACountedWarning) {
    const fs::path p = temp_dir() / "nan.exr";
    Image img(2, 2);
    img.pixels[0] = std::nanf("");
    img.pixels[4] = INFINITY;
    ::testing::internal::CaptureStderr();
    write_image(img, p.string());
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("nan.exr: 2 NaN or infinite pixel values"), std::string::npos) << err;
    ::testing::internal::CaptureStderr();
    write_image(Image(2, 2), p.string());
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

TEST(Image, OutputPathThatIsADirectoryIsNamed) {
    const fs::path d = temp_dir() / "out.exr";
    fs::create_directories(d);
    try {
        write_image(gradient(4, 4), d.string());
        FAIL() << "wrote over a directory";
    } catch (const std::runtime_error& e) {
        EXPECT_EQ(std::string(e.what()), d.string() + ": cannot write image: is a directory");
    }
    const fs::path f = temp_dir() / "out.txt";
    fs::create_directories(f);
    try {
        write_file_atomically(f.string(), "x");
        FAIL() << "wrote over a directory";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("out.txt: cannot move the written image into place: "
                                             "Is a directory"),
                  std::string::npos)
            << e.what();
    }
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

// A header is checked before anything is allocated from it: this PPM of a few bytes claims
// 100000 x 100000 pixels (120 GB as float RGB; std::bad_alloc, or the OOM killer, before).
TEST(Image, AHeaderClaimingHugeDimensionsIsRefusedBeforeAllocating) {
    for (const auto& [name, dims] :
         {std::pair{"huge.ppm", "100000 100000"}, std::pair{"wide.ppm", "16385 1"}}) {
        const fs::path p = temp_dir() / name;
        std::ofstream(p, std::ios::binary) << "P6\n" << dims << "\n255\n" << std::string(12, 'x');
        try {
            read_image(p.string());
            FAIL() << "expected InputError for " << name;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(p.string()), std::string::npos) << what;
            EXPECT_NE(what.find("2D image of 1 to 16384 pixels on a side"), std::string::npos)
                << what;
        }
    }
    const fs::path p = temp_dir() / "edge.ppm";
    std::ofstream(p, std::ios::binary) << "P6\n16384 1\n255\n" << std::string(16384 * 3, 'x');
    EXPECT_EQ(read_image(p.string()).width, 16384);
}

// A file holding a few bytes of the 16384 x 16384 its header claims fails at its first band of
// rows: the 3 GiB of floats are reserved, not zeroed (before, `Image` zeroed all of them first).
TEST(Image, ATruncatedFileClaimingTheLargestSizeFailsWithoutFillingIt) {
    const fs::path p = temp_dir() / "truncated.ppm";
    std::ofstream(p, std::ios::binary) << "P6\n16384 16384\n255\n" << std::string(300, 'x');
    rusage before{};
    getrusage(RUSAGE_SELF, &before);
    EXPECT_THROW(read_image(p.string()), InputError);
    rusage after{};
    getrusage(RUSAGE_SELF, &after);
    EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 1024L * 1024L)  // KiB: under 1 GiB more
        << "peak RSS " << before.ru_maxrss << " KiB before, " << after.ru_maxrss << " after";
}

// Readers take RGB or RGBA: an EXR's further channels are not read, and a grey image reads as
// grey through rgb() (it read past the pixel's one float before).
TEST(Image, AtMostFourChannelsAreReadAndGreyReadsAsGrey) {
    const fs::path p = temp_dir() / "five.exr";
    Image five(3, 2, 5);
    for (size_t i = 0; i < five.pixels.size(); ++i) five.pixels[i] = float(i % 5);
    write_image(five, p.string());
    const Image back = read_image(p.string());
    EXPECT_EQ(back.channels, 4);
    ASSERT_EQ(back.pixels.size(), size_t(3 * 2 * 4));
    EXPECT_EQ(back.rgb(2, 1), glm::vec3(0.0f, 1.0f, 2.0f));
    Image grey(2, 1, 1);
    grey.pixels = {0.25f, 0.5f};
    EXPECT_EQ(grey.rgb(1, 0), glm::vec3(0.5f));
}

// OpenImageIO reads devices without end: /dev/zero as a reference image or texture hung.
TEST(Image, OnlyRegularFilesAreRead) {
    for (const std::string& p : {std::string("/dev/zero"), temp_dir().string()}) {
        try {
            read_image(p);
            FAIL() << "expected InputError for " << p;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()), p + ": cannot read image: expected a regular file");
        }
    }
    try {
        read_image((temp_dir() / "absent.exr").string());
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("absent.exr: cannot read image: no such file"),
                  std::string::npos)
            << e.what();
    }
}

// A tiled OpenEXR (5 x 3, 2 x 2 tiles, half, uncompressed; made by oiiotool): read a row of tiles
// at a time. Reading tiled files a band of scanlines at a time, OIIO divided by zero (SIGFPE).
TEST(Image, TiledExrIsReadTileRowByTileRow) {
    static const char kTiled[] =
        "\x76\x2f\x31\x01\x02\x02\x00\x00\x63\x61\x70\x44\x61\x74\x65\x00\x73\x74\x72\x69\x6e\x67"
        "\x00\x13"
        "\x00\x00\x00\x32\x30\x32\x36\x3a\x31\x31\x3a\x32\x35\x20\x30\x30\x3a\x30\x33\x3a\x30\x30"
        "\x63\x68"
        "\x61\x6e\x6e\x65\x6c\x73\x00\x63\x68\x6c\x69\x73\x74\x00\x37\x00\x00\x00\x42\x00\x01\x00"
        "\x00\x00"
        "\x00\x00\x00\x00\x01\x00\x00\x00\x01\x00\x00\x00\x47\x00\x01\x00\x00\x00\x00\x00\x00\x00"
        "\x01\x00"
        "\x00\x00\x01\x00\x00\x00\x52\x00\x01\x00\x00\x00\x00\x00\x00\x00\x01\x00\x00\x00\x01\x00"
        "\x00\x00"
        "\x00\x63\x6f\x6d\x70\x72\x65\x73\x73\x69\x6f\x6e\x00\x63\x6f\x6d\x70\x72\x65\x73\x73\x69"
        "\x6f\x6e"
        "\x00\x01\x00\x00\x00\x00\x64\x61\x74\x61\x57\x69\x6e\x64\x6f\x77\x00\x62\x6f\x78\x32\x69"
        "\x00\x10"
        "\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x04\x00\x00\x00\x02\x00\x00\x00\x64\x69\x73"
        "\x70\x6c"
        "\x61\x79\x57\x69\x6e\x64\x6f\x77\x00\x62\x6f\x78\x32\x69\x00\x10\x00\x00\x00\x00\x00\x00"
        "\x00\x00"
        "\x00\x00\x00\x04\x00\x00\x00\x02\x00\x00\x00\x6c\x69\x6e\x65\x4f\x72\x64\x65\x72\x00\x6c"
        "\x69\x6e"
        "\x65\x4f\x72\x64\x65\x72\x00\x01\x00\x00\x00\x00\x70\x69\x78\x65\x6c\x41\x73\x70\x65\x63"
        "\x74\x52"
        "\x61\x74\x69\x6f\x00\x66\x6c\x6f\x61\x74\x00\x04\x00\x00\x00\x00\x00\x80\x3f\x73\x63\x72"
        "\x65\x65"
        "\x6e\x57\x69\x6e\x64\x6f\x77\x43\x65\x6e\x74\x65\x72\x00\x76\x32\x66\x00\x08\x00\x00\x00"
        "\x00\x00"
        "\x00\x00\x00\x00\x00\x00\x73\x63\x72\x65\x65\x6e\x57\x69\x6e\x64\x6f\x77\x57\x69\x64\x74"
        "\x68\x00"
        "\x66\x6c\x6f\x61\x74\x00\x04\x00\x00\x00\x00\x00\x80\x3f\x74\x69\x6c\x65\x73\x00\x74\x69"
        "\x6c\x65"
        "\x64\x65\x73\x63\x00\x09\x00\x00\x00\x02\x00\x00\x00\x02\x00\x00\x00\x00\x00\xab\x01\x00"
        "\x00\x00"
        "\x00\x00\x00\xd7\x01\x00\x00\x00\x00\x00\x00\x03\x02\x00\x00\x00\x00\x00\x00\x23\x02\x00"
        "\x00\x00"
        "\x00\x00\x00\x43\x02\x00\x00\x00\x00\x00\x00\x63\x02\x00\x00\x00\x00\x00\x00\x00\x00\x00"
        "\x00\x00"
        "\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x18\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00"
        "\x00\x00"
        "\x00\x00\x34\x00\x00\x00\x30\x00\x38\x00\x38\x00\x00\x00\x34\x01\x00\x00\x00\x00\x00\x00"
        "\x00\x00"
        "\x00\x00\x00\x00\x00\x00\x00\x18\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x38\x00"
        "\x3a\x00"
        "\x34\x00\x36\x00\x38\x00\x38\x00\x38\x00\x3a\x02\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00"
        "\x00\x00"
        "\x00\x00\x00\x0c\x00\x00\x00\x00\x00\x00\x00\x00\x3c\x00\x38\x00\x38\x00\x3c\x00\x00\x00"
        "\x00\x01"
        "\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x0c\x00\x00\x00\x00\x00\x00\x34\x00\x3c\x00"
        "\x3c\x00"
        "\x00\x00\x34\x01\x00\x00\x00\x01\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x0c\x00\x00"
        "\x00\x00"
        "\x38\x00\x3a\x00\x3c\x00\x3c\x00\x38\x00\x3a\x02\x00\x00\x00\x01\x00\x00\x00\x00\x00\x00"
        "\x00\x00"
        "\x00\x00\x00\x06\x00\x00\x00\x00\x3c\x00\x3c\x00\x3c";
    const fs::path p = temp_dir() / "tiled.exr";
    std::ofstream(p, std::ios::binary).write(kTiled, sizeof kTiled - 1);
    const Image image = read_image(p.string());
    ASSERT_EQ(image.width, 5);
    ASSERT_EQ(image.height, 3);
    EXPECT_EQ(image.rgb(0, 0), glm::vec3(0.0f));
    EXPECT_EQ(image.rgb(4, 0), glm::vec3(1.0f, 0.0f, 0.0f));
    EXPECT_EQ(image.rgb(3, 1), glm::vec3(0.75f, 0.5f, 0.375f));
    EXPECT_EQ(image.rgb(4, 2), glm::vec3(1.0f));
}

}  // namespace ag
