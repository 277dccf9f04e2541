#include "shared/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace ag {

namespace {

constexpr int kSsimRadius = 5;  // 11×11 window
constexpr double kSsimSigma = 1.5, kSsimK1 = 0.01, kSsimK2 = 0.03;

std::string size_text(const Image& image) {
    return std::to_string(image.width) + "x" + std::to_string(image.height);
}

void check_sizes(const Image& test, const Image& reference, const Image* mask) {
    if (test.width != reference.width || test.height != reference.height)
        throw std::invalid_argument("image is " + size_text(test) + " but the reference is " +
                                    size_text(reference));
    if (test.width <= 0 || test.height <= 0) throw std::invalid_argument("images are empty");
    if (mask && (mask->width != reference.width || mask->height != reference.height))
        throw std::invalid_argument("mask is " + size_text(*mask) + " but the images are " +
                                    size_text(reference));
}

bool included(const Image* mask, int x, int y) {
    if (!mask) return true;
    const float* p = mask->at(x, y);
    for (int c = 0; c < mask->channels; ++c)
        if (p[c] != 0.0f) return true;
    return false;
}

// Separable Gaussian blur with the window truncated at the borders and renormalised there.
std::vector<double> blur(const std::vector<double>& v, int w, int h) {
    std::array<double, 2 * kSsimRadius + 1> g{};
    for (int i = -kSsimRadius; i <= kSsimRadius; ++i)
        g[size_t(i + kSsimRadius)] = std::exp(-double(i * i) / (2.0 * kSsimSigma * kSsimSigma));
    std::vector<double> tmp(v.size()), out(v.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double sum = 0.0, weight = 0.0;
            for (int i = std::max(-kSsimRadius, -x); i <= std::min(kSsimRadius, w - 1 - x); ++i) {
                sum += g[size_t(i + kSsimRadius)] * v[size_t(y) * size_t(w) + size_t(x + i)];
                weight += g[size_t(i + kSsimRadius)];
            }
            tmp[size_t(y) * size_t(w) + size_t(x)] = sum / weight;
        }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double sum = 0.0, weight = 0.0;
            for (int i = std::max(-kSsimRadius, -y); i <= std::min(kSsimRadius, h - 1 - y); ++i) {
                sum += g[size_t(i + kSsimRadius)] * tmp[size_t(y + i) * size_t(w) + size_t(x)];
                weight += g[size_t(i + kSsimRadius)];
            }
            out[size_t(y) * size_t(w) + size_t(x)] = sum / weight;
        }
    return out;
}

double pixel_rel_mse(const glm::vec3& a, const glm::vec3& b) {
    double sum = 0.0;
    for (int c = 0; c < 3; ++c) {
        const double d = double(a[c]) - double(b[c]);
        sum += d * d / (double(b[c]) * double(b[c]) + kRelMseEpsilon);
    }
    return sum / 3.0;
}

}  // namespace

glm::vec3 pixel_rgb(const Image& image, int x, int y) { return image.rgb(x, y); }

double ssim(const Image& test, const Image& reference, const Image* mask) {
    check_sizes(test, reference, mask);
    const int w = reference.width, h = reference.height;
    const size_t n = size_t(w) * size_t(h);
    std::vector<double> a(n), b(n), aa(n), bb(n), ab(n);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            a[i] = luminance(pixel_rgb(test, x, y));
            b[i] = luminance(pixel_rgb(reference, x, y));
            aa[i] = a[i] * a[i], bb[i] = b[i] * b[i], ab[i] = a[i] * b[i];
            if (included(mask, x, y)) lo = std::min(lo, b[i]), hi = std::max(hi, b[i]);
        }
    if (lo > hi) throw std::invalid_argument("the mask excludes every pixel");
    const double range = hi - lo > 0.0 ? hi - lo : 1.0;
    const double c1 = (kSsimK1 * range) * (kSsimK1 * range);
    const double c2 = (kSsimK2 * range) * (kSsimK2 * range);
    const std::vector<double> ma = blur(a, w, h), mb = blur(b, w, h);
    const std::vector<double> maa = blur(aa, w, h), mbb = blur(bb, w, h), mab = blur(ab, w, h);
    double sum = 0.0;
    size_t count = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (!included(mask, x, y)) continue;
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            const double va = std::max(0.0, maa[i] - ma[i] * ma[i]);
            const double vb = std::max(0.0, mbb[i] - mb[i] * mb[i]);
            const double cov = mab[i] - ma[i] * mb[i];
            sum += ((2.0 * ma[i] * mb[i] + c1) * (2.0 * cov + c2)) /
                   ((ma[i] * ma[i] + mb[i] * mb[i] + c1) * (va + vb + c2));
            ++count;
        }
    return sum / double(count);
}

ImageMetrics compare_images(const Image& test, const Image& reference, const Image* mask) {
    check_sizes(test, reference, mask);
    ImageMetrics m;
    double squared = 0.0, relative = 0.0, peak = -std::numeric_limits<double>::infinity();
    for (int y = 0; y < reference.height; ++y)
        for (int x = 0; x < reference.width; ++x) {
            if (!included(mask, x, y)) continue;
            const glm::vec3 a = pixel_rgb(test, x, y), b = pixel_rgb(reference, x, y);
            for (int c = 0; c < 3; ++c) {
                const double d = double(a[c]) - double(b[c]);
                squared += d * d;
                peak = std::max(peak, double(b[c]));
            }
            relative += pixel_rel_mse(a, b);
            ++m.pixels;
        }
    if (m.pixels == 0) throw std::invalid_argument("the mask excludes every pixel");
    const double mse = squared / (3.0 * double(m.pixels));
    m.rmse = std::sqrt(mse);
    m.rel_mse = relative / double(m.pixels);
    m.peak = peak > 0.0 ? peak : 1.0;
    m.psnr = mse > 0.0 ? 10.0 * std::log10(m.peak * m.peak / mse)
                       : std::numeric_limits<double>::infinity();
    m.ssim = ssim(test, reference, mask);
    return m;
}

int ldr_byte(float linear, float exposure_ev) {
    return int(std::lround(srgb_encode(linear * std::exp2(exposure_ev)) * 255.0f));
}

LdrMetrics compare_ldr(const Image& test, const Image& reference, float exposure_ev) {
    check_sizes(test, reference, nullptr);
    const int w = reference.width, h = reference.height;
    if (w < 2 * kSsimRadius + 1 || h < 2 * kSsimRadius + 1)
        throw std::invalid_argument("images are " + size_text(reference) +
                                    "; MSSIM needs at least 11x11");
    const size_t n = size_t(w) * size_t(h);
    LdrMetrics m;
    m.pixels = n;
    std::vector<double> a(n), b(n), aa(n), bb(n), ab(n);
    double squared = 0.0;
    int lo = 255, hi = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec3 ta = pixel_rgb(test, x, y), rb = pixel_rgb(reference, x, y);
            std::array<int, 3> qa{}, qb{};
            for (int c = 0; c < 3; ++c) {
                qa[size_t(c)] = ldr_byte(ta[c], exposure_ev);
                qb[size_t(c)] = ldr_byte(rb[c], exposure_ev);
                const double d = double(qa[size_t(c)] - qb[size_t(c)]);
                squared += d * d;
                lo = std::min(lo, qb[size_t(c)]);
                hi = std::max(hi, qb[size_t(c)]);
            }
            const auto luma = [](const std::array<int, 3>& q) {
                return std::round(0.2989 * q[0] + 0.5870 * q[1] + 0.1140 * q[2]);
            };
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            a[i] = luma(qa), b[i] = luma(qb);
            aa[i] = a[i] * a[i], bb[i] = b[i] * b[i], ab[i] = a[i] * b[i];
        }
    m.mse = squared / (3.0 * double(n));
    m.range = hi - lo;
    m.nrmse = m.range > 0 ? std::sqrt(m.mse) / double(m.range) : 0.0;
    // Inside the border of kSsimRadius the truncated blur is the full window ('valid' windows).
    const double c1 = (kSsimK1 * 255.0) * (kSsimK1 * 255.0);
    const double c2 = (kSsimK2 * 255.0) * (kSsimK2 * 255.0);
    const std::vector<double> ma = blur(a, w, h), mb = blur(b, w, h);
    const std::vector<double> maa = blur(aa, w, h), mbb = blur(bb, w, h), mab = blur(ab, w, h);
    double sum = 0.0;
    size_t count = 0;
    for (int y = kSsimRadius; y < h - kSsimRadius; ++y)
        for (int x = kSsimRadius; x < w - kSsimRadius; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            const double va = maa[i] - ma[i] * ma[i], vb = mbb[i] - mb[i] * mb[i];
            const double cov = mab[i] - ma[i] * mb[i];
            sum += ((2.0 * ma[i] * mb[i] + c1) * (2.0 * cov + c2)) /
                   ((ma[i] * ma[i] + mb[i] * mb[i] + c1) * (va + vb + c2));
            ++count;
        }
    m.mssim = sum / double(count);
    return m;
}

Image relative_error_heatmap(const Image& test, const Image& reference, const Image* mask,
                             double max_error) {
    check_sizes(test, reference, mask);
    // An inferno-like ramp, sRGB control points at 0, 1/4, 1/2, 3/4, 1.
    static const std::array<glm::vec3, 5> kRamp = {glm::vec3(0, 0, 4), glm::vec3(87, 16, 110),
                                                   glm::vec3(188, 55, 84), glm::vec3(249, 142, 9),
                                                   glm::vec3(252, 255, 164)};
    const auto linear = [](const glm::vec3& srgb) {
        return glm::vec3(srgb_decode(srgb.r), srgb_decode(srgb.g), srgb_decode(srgb.b));
    };
    Image out(reference.width, reference.height);
    for (int y = 0; y < reference.height; ++y)
        for (int x = 0; x < reference.width; ++x) {
            if (!included(mask, x, y)) {
                out.set_rgb(x, y, linear(glm::vec3(0.25f)));
                continue;
            }
            const double e =
                std::sqrt(pixel_rel_mse(pixel_rgb(test, x, y), pixel_rgb(reference, x, y)));
            const double t =
                max_error > 0.0 ? std::clamp(e / max_error, 0.0, 1.0) : (e > 0.0 ? 1.0 : 0.0);
            const double pos = t * double(kRamp.size() - 1);
            const size_t i = std::min(size_t(pos), kRamp.size() - 2);
            const float f = float(pos - double(i));
            out.set_rgb(x, y, linear(glm::mix(kRamp[i], kRamp[i + 1], f) / 255.0f));
        }
    return out;
}

}  // namespace ag
