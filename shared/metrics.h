// Image error metrics for comparing renders with references (DESIGN.md, Conventions): RMSE,
// relMSE, PSNR, and SSIM on luminance (Wang et al. 2004), with an optional mask; and a heat map
// of the per-pixel relative error.
#pragma once

#include <cstddef>
#include <glm/glm.hpp>

#include "shared/image.h"

namespace ag {

// relMSE = mean((x − y)² / (y² + ε)): ε keeps dark reference pixels from dominating.
inline constexpr double kRelMseEpsilon = 0.01;

struct ImageMetrics {
    double rmse = 0.0;     // over included pixels and the three colour channels
    double rel_mse = 0.0;  // per channel, averaged like the RMSE
    double psnr = 0.0;     // dB; +inf for identical images
    double ssim = 1.0;     // mean SSIM of the luminance over included pixels
    double peak = 1.0;  // PSNR peak: the reference's largest channel value, or 1 if that is ≤ 0
    size_t pixels = 0;  // included pixels
};

// Rec. 709 luminance of linear RGB.
inline float luminance(const glm::vec3& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

// The colour of pixel (x, y) whatever the channel count (1 or 2 channels: grey, the first).
glm::vec3 pixel_rgb(const Image& image, int x, int y);

// `test` against `reference` (same size). `mask` (same size, or null): a pixel counts where any
// of its channels is nonzero. SSIM uses an 11×11 Gaussian window (σ = 1.5) truncated and
// renormalised at the borders, K1 = 0.01, K2 = 0.03 and dynamic range L = max − min of the
// reference luminance over included pixels (1 if that is 0); windows see all pixels, the mask
// picks the window centres averaged. Throws std::invalid_argument on a size mismatch or a mask
// that excludes every pixel.
ImageMetrics compare_images(const Image& test, const Image& reference, const Image* mask = nullptr);

// SSIM alone (same conventions as compare_images).
double ssim(const Image& test, const Image& reference, const Image* mask = nullptr);

// Per-pixel relative error e = sqrt(mean over channels of (x − y)² / (y² + ε)) mapped through
// a colour ramp (black, purple, orange, pale yellow) from 0 to `max_error`; excluded pixels are
// grey. Linear RGB, ready for write_image as PNG at exposure 0. Same exceptions as above.
// The thesis metrics of Jimenez Kwast (2016, §4.1) on 8-bit images: both images are taken to
// what a PNG of them holds (linear × 2^exposure_ev, clamped, sRGB-encoded, rounded to 0..255).
//  - mse: Eq. 4.1 per R, G, B channel, averaged over the three, in 8-bit units² (his Table 6.1
//    ranges 139.55..902.23);
//  - nrmse: √mse / (I_max − I_min), the reference's 8-bit range over all channels. His printed
//    Eq. 4.2 divides the MSE itself by the range, but every table row satisfies √MSE/NRMSE ≈ 206
//    (902.23 / 0.1458, 167.09 / 0.0627, 3589.49 / 0.2908), so the RMSE is what he divided;
//  - mssim: Wang et al. (2004) as in their reference code: 8-bit luma Y = round(0.2989 R + 0.5870 G
//    + 0.1140 B) (the usual rgb2gray), 11×11 Gaussian window σ = 1.5, K1 = 0.01, K2 = 0.03,
//    L = 255, mean over the windows that lie wholly inside the image, no downsampling.
// He states neither the window nor the colour handling; these are Wang's defaults.
struct LdrMetrics {
    double mse = 0.0;
    double nrmse = 0.0;  // 0 when the reference is flat
    double mssim = 1.0;
    int range = 0;  // I_max − I_min of the reference, 8-bit
    size_t pixels = 0;
};

// Throws std::invalid_argument on a size mismatch or an image smaller than 11×11.
LdrMetrics compare_ldr(const Image& test, const Image& reference, float exposure_ev = 0.0f);

// The 8-bit value a PNG written at `exposure_ev` holds for a linear channel value.
int ldr_byte(float linear, float exposure_ev = 0.0f);

Image relative_error_heatmap(const Image& test, const Image& reference, const Image* mask,
                             double max_error);

}  // namespace ag
