// Error metrics: identities, values worked out by hand on tiny images, masks and bad input.
#include "shared/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
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

}  // namespace ag
