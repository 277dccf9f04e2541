// Error metrics: identities, values worked out by hand on tiny images, masks and bad input.
#include "shared/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

namespace ag {

namespace {

Image grey(int w, int h, std::initializer_list<float> values) {
    Image image(w, h);
    size_t i = 0;
    for (float v : values) {
        image.set_rgb(int(i % size_t(w)), int(i / size_t(w)), glm::vec3(v));
        ++i;
    }
    return image;
}

Image noise_image(int w, int h, uint32_t seed) {
    Image image(w, h);
    for (size_t i = 0; i < image.pixels.size(); ++i) {
        seed = seed * 1664525u + 1013904223u;
        image.pixels[i] = float(seed >> 8) / 16777216.0f * 2.0f;
    }
    return image;
}

}  // namespace

TEST(Metrics, IdenticalImagesAreAPerfectMatch) {
    const Image x = noise_image(23, 17, 7);
    const ImageMetrics m = compare_images(x, x);
    EXPECT_EQ(m.rmse, 0.0);
    EXPECT_EQ(m.rel_mse, 0.0);
    EXPECT_TRUE(std::isinf(m.psnr));
    EXPECT_NEAR(m.ssim, 1.0, 1e-12);
    EXPECT_NEAR(ssim(x, x), 1.0, 1e-12);
    EXPECT_EQ(m.pixels, size_t(23 * 17));
}

// 2 × 2 grey test image (1, 2, 3, 4) against a constant reference 1: differences 0, 1, 2, 3.
TEST(Metrics, RmseRelMsePsnrByHand) {
    const ImageMetrics m = compare_images(grey(2, 2, {1, 2, 3, 4}), grey(2, 2, {1, 1, 1, 1}));
    EXPECT_NEAR(m.rmse, std::sqrt(14.0 / 4.0), 1e-9);           // (0 + 1 + 4 + 9) / 4
    EXPECT_NEAR(m.rel_mse, (14.0 / 4.0) / (1.0 + 0.01), 1e-9);  // y² + 0.01 = 1.01 everywhere
    EXPECT_NEAR(m.peak, 1.0, 0.0);
    EXPECT_NEAR(m.psnr, 10.0 * std::log10(1.0 / 3.5), 1e-9);  // −5.44 dB
}

// Per channel: relMSE divides by each channel's own reference value.
TEST(Metrics, RelMseIsPerChannel) {
    Image a(1, 1), b(1, 1);
    a.set_rgb(0, 0, {1.0f, 0.0f, 0.5f});
    b.set_rgb(0, 0, {0.0f, 0.0f, 1.0f});
    const ImageMetrics m = compare_images(a, b);
    EXPECT_NEAR(m.rel_mse, (1.0 / 0.01 + 0.0 + 0.25 / 1.01) / 3.0, 1e-9);
    EXPECT_NEAR(m.rmse, std::sqrt((1.0 + 0.25) / 3.0), 1e-9);
    EXPECT_NEAR(m.peak, 1.0, 0.0);
}

TEST(Metrics, PsnrPeakIsTheReferenceMaximumOrOne) {
    const ImageMetrics bright = compare_images(grey(2, 1, {4, 0}), grey(2, 1, {4, 2}));
    EXPECT_NEAR(bright.peak, 4.0, 0.0);
    EXPECT_NEAR(bright.psnr, 10.0 * std::log10(16.0 / 2.0), 1e-9);  // MSE = (0 + 4) / 2
    const ImageMetrics black = compare_images(grey(2, 1, {1, 0}), grey(2, 1, {0, 0}));
    EXPECT_NEAR(black.peak, 1.0, 0.0);
    EXPECT_NEAR(black.psnr, 10.0 * std::log10(1.0 / 0.5), 1e-9);
}

// Constant images: no variance, so SSIM = (2 μx μy + C1) / (μx² + μy² + C1) with
// C1 = (0.01 L)², and L = 1 because a constant reference has no range.
TEST(Metrics, SsimOfConstantImagesByHand) {
    const double c1 = 0.01 * 0.01;
    EXPECT_NEAR(
        ssim(grey(3, 2, {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f}), grey(3, 2, {1, 1, 1, 1, 1, 1})),
        (2.0 * 0.5 * 1.0 + c1) / (0.25 + 1.0 + c1), 1e-9);
}

// Two pixels (1, 0) against the reference (0, 1). Each pixel's window is itself (weight 1) and its
// neighbour (weight g = exp(−1 / (2 · 1.5²))), renormalised: a = 1 / (1 + g), b = g / (1 + g).
// Both pixels see μx = a, μy = b (or swapped), σx² = σy² = ab, σxy = −ab; L = 1.
TEST(Metrics, SsimOfTwoPixelsByHand) {
    const double g = std::exp(-1.0 / 4.5), a = 1.0 / (1.0 + g), b = g / (1.0 + g);
    const double c1 = 1e-4, c2 = 9e-4;
    const double expected =
        (2.0 * a * b + c1) * (-2.0 * a * b + c2) / ((a * a + b * b + c1) * (2.0 * a * b + c2));
    const Image x = grey(2, 1, {1, 0}), y = grey(2, 1, {0, 1});
    EXPECT_NEAR(ssim(x, y), expected, 1e-9);
    const ImageMetrics m = compare_images(x, y);
    EXPECT_NEAR(m.rmse, 1.0, 1e-12);
    EXPECT_NEAR(m.rel_mse, (1.0 / 0.01 + 1.0 / 1.01) / 2.0, 1e-9);
    EXPECT_NEAR(m.psnr, 0.0, 1e-12);
}

// SSIM is on luminance: a colour change that keeps Rec. 709 luminance is invisible to it.
TEST(Metrics, SsimUsesRec709Luminance) {
    Image a(1, 1), b(1, 1);
    a.set_rgb(0, 0, {1.0f, 0.0f, 0.0f});
    b.set_rgb(0, 0, {0.0f, 0.2126f / 0.7152f, 0.0f});
    EXPECT_NEAR(ssim(a, b), 1.0, 1e-6);
    EXPECT_NEAR(luminance({0.0f, 1.0f, 0.0f}), 0.7152f, 1e-7f);
}

TEST(Metrics, MaskSelectsPixels) {
    const Image test = grey(2, 2, {1, 1, 1, 9});
    const Image reference = grey(2, 2, {1, 1, 1, 1});
    Image mask = grey(2, 2, {1, 1, 1, 0});
    const ImageMetrics masked = compare_images(test, reference, &mask);
    EXPECT_EQ(masked.pixels, 3u);
    EXPECT_EQ(masked.rmse, 0.0);
    EXPECT_EQ(masked.rel_mse, 0.0);
    EXPECT_NEAR(masked.ssim, ssim(test, reference, &mask), 0.0);
    // Any nonzero channel includes a pixel.
    mask.at(1, 1)[2] = 0.5f;
    const ImageMetrics all = compare_images(test, reference, &mask);
    EXPECT_EQ(all.pixels, 4u);
    EXPECT_NEAR(all.rmse, std::sqrt(64.0 / 4.0), 1e-9);
    // Single-channel masks (PNG greyscale) work the same way.
    Image mono(2, 2, 1);
    mono.pixels = {1.0f, 0.0f, 0.0f, 0.0f};
    EXPECT_EQ(compare_images(test, reference, &mono).pixels, 1u);
}

TEST(Metrics, RejectsSizeMismatchAndEmptyMask) {
    EXPECT_THROW(compare_images(Image(4, 4), Image(4, 3)), std::invalid_argument);
    const Image small_mask(2, 2, 1), empty_mask(4, 4);
    EXPECT_THROW(compare_images(Image(4, 4), Image(4, 4), &small_mask), std::invalid_argument);
    EXPECT_THROW(compare_images(Image(4, 4), Image(4, 4), &empty_mask), std::invalid_argument);
    EXPECT_THROW(relative_error_heatmap(Image(4, 4), Image(3, 4), nullptr, 1.0),
                 std::invalid_argument);
}

TEST(Metrics, HeatmapRampsFromBlackAndGreysOutMaskedPixels) {
    const Image test = grey(3, 1, {1, 2, 100});
    const Image reference = grey(3, 1, {1, 1, 1});
    const Image mask = grey(3, 1, {1, 1, 0});
    const Image heat = relative_error_heatmap(test, reference, &mask, 1.0);
    ASSERT_EQ(heat.width, 3);
    EXPECT_LT(glm::length(heat.rgb(0, 0)), 0.01f);                    // no error: black
    EXPECT_GT(luminance(heat.rgb(1, 0)), luminance(heat.rgb(0, 0)));  // e = 1/√1.01: near the top
    EXPECT_NEAR(heat.rgb(2, 0).r, heat.rgb(2, 0).g, 1e-6f);           // masked: grey
    EXPECT_NEAR(heat.rgb(2, 0).g, heat.rgb(2, 0).b, 1e-6f);
}

// 8-bit metrics (Jimenez Kwast 2016 §4.1). Images built from byte values decode back to them.
namespace {
Image from_bytes(int w, int h, const std::function<glm::ivec3(int, int)>& byte) {
    Image image(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::ivec3 b = byte(x, y);
            image.set_rgb(
                x, y,
                glm::vec3(srgb_decode(float(b.r) / 255.0f), srgb_decode(float(b.g) / 255.0f),
                          srgb_decode(float(b.b) / 255.0f)));
        }
    return image;
}
}  // namespace

TEST(LdrMetrics, BytesRoundTripThroughTheLinearImage) {
    for (int b = 0; b < 256; ++b) EXPECT_EQ(ldr_byte(srgb_decode(float(b) / 255.0f)), b);
    EXPECT_EQ(ldr_byte(7.0f), 255);  // clamped like the PNG
    EXPECT_EQ(ldr_byte(-1.0f), 0);
    EXPECT_EQ(ldr_byte(0.25f, 2.0f), 255);  // exposure scales before encoding
}

TEST(LdrMetrics, MseAndNrmseOfAKnownByteOffset) {
    // Reference bytes 20..226 (range 206, as in the thesis's numbers); the test image is 5 brighter
    // in red, 3 darker in blue: MSE = (25 + 0 + 9) / 3, NRMSE = √MSE / 206.
    const auto ref = from_bytes(32, 24, [](int x, int y) {
        return glm::ivec3(20 + (x * 7 + y * 3) % 200, 100, x == 0 && y == 0 ? 226 : 50);
    });
    const auto test = from_bytes(32, 24, [](int x, int y) {
        return glm::ivec3(25 + (x * 7 + y * 3) % 200, 100, x == 0 && y == 0 ? 223 : 47);
    });
    const LdrMetrics m = compare_ldr(test, ref);
    EXPECT_EQ(m.range, 206);
    EXPECT_NEAR(m.mse, 34.0 / 3.0, 1e-9);
    EXPECT_NEAR(m.nrmse, std::sqrt(34.0 / 3.0) / 206.0, 1e-12);
    EXPECT_EQ(m.pixels, size_t(32 * 24));
    const LdrMetrics same = compare_ldr(ref, ref);
    EXPECT_EQ(same.mse, 0.0);
    EXPECT_EQ(same.nrmse, 0.0);
    EXPECT_NEAR(same.mssim, 1.0, 1e-12);
}

TEST(LdrMetrics, MssimOfFlatImagesIsTheLuminanceTerm) {
    // σ = 0 in both: SSIM = (2 μx μy + C1) / (μx² + μy² + C1), C1 = (0.01·255)².
    const auto a = from_bytes(16, 16, [](int, int) { return glm::ivec3(100); });
    const auto b = from_bytes(16, 16, [](int, int) { return glm::ivec3(140); });
    const double c1 = 2.55 * 2.55;
    EXPECT_NEAR(compare_ldr(a, b).mssim, (2.0 * 100 * 140 + c1) / (100.0 * 100 + 140 * 140 + c1),
                1e-12);
}

TEST(LdrMetrics, MssimAveragesOnlyWholeWindows) {
    // A pixel differing on the border lies in no whole window's centre but in several windows;
    // one in a corner lies in exactly one window (centre (5,5)), so MSSIM drops less there.
    const auto base = [](int x, int y) { return glm::ivec3((x * 37 + y * 91) % 256); };
    const auto ref = from_bytes(21, 21, base);
    const auto corner = from_bytes(
        21, 21, [&](int x, int y) { return x == 0 && y == 0 ? glm::ivec3(255) : base(x, y); });
    const auto middle = from_bytes(
        21, 21, [&](int x, int y) { return x == 10 && y == 10 ? glm::ivec3(255) : base(x, y); });
    const double c = compare_ldr(corner, ref).mssim, mid = compare_ldr(middle, ref).mssim;
    EXPECT_LT(c, 1.0);
    EXPECT_LT(mid, c);
    EXPECT_THROW(compare_ldr(from_bytes(10, 30, base), from_bytes(10, 30, base)),
                 std::invalid_argument);
}

}  // namespace ag
