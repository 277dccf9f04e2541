// afterglow compare A B: error metrics of image A against the reference B (shared/metrics.h),
// optionally masked, with a heat map of the per-pixel relative error.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <utility>

#include "shared/image.h"
#include "shared/metrics.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kCompareCommand{
    "compare",
    "A.exr B.exr [--mask M.png] [--heatmap OUT.png]",
    "Compare image A with the reference B: RMSE, relMSE = mean((a-b)^2/(b^2+0.01)), PSNR (peak = "
    "the reference's maximum) and SSIM on luminance. Exit 1 if an image cannot be read or the "
    "sizes differ, or an image holds NaN or infinite values.",
    {
        text("mask", "M.png", "only pixels where the mask is nonzero count"),
        text("heatmap", "OUT.png", "write the per-pixel relative error as a colour ramp"),
        number("heatmap-max", "E", "relative error shown at the top of the ramp", 1e-6, 1e6, 0.5),
        flag("json", "print the metrics as one JSON object"),
        flag("ldr",
             "instead: the 8-bit metrics of Jimenez Kwast (2016): MSE per channel in 8-bit units, "
             "NRMSE = sqrt(MSE) / (reference max - min) (his printed eq. 4.2 divides the MSE; his "
             "tables divide its root), MSSIM on 8-bit luma (Wang et al. 2004: 11x11 Gaussian, "
             "sigma 1.5, K1 0.01, K2 0.03, L 255, whole windows), of the PNGs the images would "
             "make"),
        number("exposure", "EV", "with --ldr: exposure in stops before the 8-bit encoding", -30.0,
               30.0, 0.0),
    },
    2,
    2,
};

int run_compare(const Args& args) {
    const std::string a_path = args.positionals()[0], b_path = args.positionals()[1];
    const Image a = read_image(a_path), b = read_image(b_path);
    Image mask;
    if (args.has("mask")) mask = read_image(args.get("mask"));
    const Image* mask_ptr = args.has("mask") ? &mask : nullptr;
    const double heatmap_max = args.get_double("heatmap-max");
    // NaN or Inf would make every metric NaN and the comparison meaningless.
    for (const auto& [path, image] : {std::pair{&a_path, &a}, std::pair{&b_path, &b}}) {
        size_t non_finite = 0;
        for (const float v : image->pixels) non_finite += std::isfinite(v) ? 0 : 1;
        if (non_finite > 0) {
            std::cerr << "afterglow compare: " << *path << ": " << non_finite
                      << " NaN or infinite pixel values; expected finite images\n";
            return 1;
        }
    }

    if (args.has("ldr")) {
        LdrMetrics l;
        try {
            l = compare_ldr(a, b, float(args.get_double("exposure")));
        } catch (const std::invalid_argument& e) {
            std::cerr << "afterglow compare: " << a_path << " vs " << b_path << ": " << e.what()
                      << "\n";
            return 1;
        }
        if (args.has("json")) {
            std::cout << nlohmann::json{{"mse", l.mse},
                                        {"nrmse", l.nrmse},
                                        {"mssim", l.mssim},
                                        {"range", l.range},
                                        {"pixels", l.pixels}}
                             .dump()
                      << "\n";
            return 0;
        }
        std::printf("mse     %.2f (8-bit)\nnrmse   %.4f (range %d)\nmssim   %.4f\npixels  %zu\n",
                    l.mse, l.nrmse, l.range, l.mssim, l.pixels);
        return 0;
    }
    ImageMetrics m;
    try {
        m = compare_images(a, b, mask_ptr);
        if (args.has("heatmap"))
            write_image(relative_error_heatmap(a, b, mask_ptr, heatmap_max), args.get("heatmap"));
    } catch (const std::invalid_argument& e) {
        std::cerr << "afterglow compare: " << a_path << " vs " << b_path
                  << (mask_ptr ? " (mask " + args.get("mask") + ")" : "") << ": " << e.what()
                  << "\n";
        return 1;
    }

    if (args.has("json")) {
        const nlohmann::json j = {
            {"rmse", m.rmse},
            {"relmse", m.rel_mse},
            {"psnr", std::isinf(m.psnr) ? nlohmann::json(nullptr) : nlohmann::json(m.psnr)},
            {"psnr_peak", m.peak},
            {"ssim", m.ssim},
            {"pixels", m.pixels}};
        std::cout << j.dump() << "\n";
        return 0;
    }
    std::printf(
        "rmse    %.6g\nrelmse  %.6g\npsnr    %.4g dB (peak %.4g)\nssim    %.6f\npixels  %zu of "
        "%d\n",
        m.rmse, m.rel_mse, m.psnr, m.peak, m.ssim, m.pixels, b.width * b.height);
    if (args.has("heatmap"))
        std::cerr << "afterglow compare: wrote " << args.get("heatmap") << " (relative error 0 to "
                  << heatmap_max << ")\n";
    return 0;
}

static const Registration kRegistration(kCompareCommand, run_compare, 55);

}  // namespace ag::cli
