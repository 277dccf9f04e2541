#include "tools/afterglow/bench_gpu_pm.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <vector>

#include "gpu/frame_renderer.h"
#include "gpu/g_buffer.h"
#include "gpu/gl_context.h"
#include "gpu/gpu_photon_mapper.h"
#include "gpu/scene_meshes.h"
#include "shared/image.h"
#include "shared/metrics.h"
#include "shared/scene_file.h"

namespace ag::cli {

namespace {

std::vector<double> parse_list(const std::string& text, const char* what) {
    std::vector<double> out;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0' || !(v > 0.0))
            throw CliError(std::string("afterglow bench gpu_pm: --") + what +
                           ": expects positive numbers separated by commas, got '" + text + "'");
        out.push_back(v);
    }
    return out;
}

}  // namespace

int bench_gpu_pm(const Args& args, const std::string& scene_path, int width, int height) {
    const std::vector<double> paths = parse_list(args.get("paths"), "paths");
    const std::vector<double> radii = parse_list(args.get("radii"), "radii");
    auto context = gpu::make_gl_context(args.gl_backend());
    std::printf("GL: %s (%s)\n", context->renderer().c_str(), context->version().c_str());
    Scene scene = load_scene(scene_path);
    args.apply_settings(scene);
    const int frames = args.get_int("frames", 20);
    Image reference;
    const bool has_reference = args.has("reference");
    if (has_reference) {
        reference = read_image(args.get("reference"));
        if (reference.width != width || reference.height != height)
            throw CliError("afterglow bench gpu_pm: " + args.get("reference") + " is " +
                           std::to_string(reference.width) + "x" +
                           std::to_string(reference.height) + "; expected --size " +
                           std::to_string(width) + "x" + std::to_string(height));
    }
    gpu::SceneMeshes meshes(scene);
    gpu::GBuffer g_buffer(scene, meshes, width, height);
    // Every frame draws its direct light (no running mean that stops drawing once it is full).
    scene.settings.direct.accumulate_frames = 1;
    gpu::FrameRenderer renderer(scene, meshes, width, height);
    std::printf(
        "%s, %dx%d, %d frames per cell (mean and sigma of the frame time; G-buffer, "
        "photons traced anew, binning, estimate, direct light and compose)\n",
        scene_path.c_str(), width, height, frames);
    std::printf("%8s %9s %8s %9s %8s %9s %8s %8s %8s %7s\n", "paths", "(stored)", "radius",
                "mean ms", "sigma", "gpu_pm ms", "refined", "MSE", "NRMSE", "MSSIM");
    for (const double n : paths)
        for (const double r : radii) {
            scene.settings.gpu_pm.paths = int(n);
            scene.settings.gpu_pm.frames = 1;
            scene.settings.gpu_pm.radius = float(r);
            gpu::GpuPhotonMapper mapper(scene, g_buffer);
            std::vector<double> ms;
            double pm_ms = 0.0;  // G-buffer, photons, binning and estimate alone
            for (int f = 0; f < frames + 2; ++f) {
                gpu::gl::Finish();
                const auto t = std::chrono::steady_clock::now();
                g_buffer.render();
                mapper.clear_photons();
                mapper.trace();
                mapper.render();
                gpu::gl::Finish();
                const double pm =
                    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t)
                        .count();
                if (f >= 2) pm_ms += pm / double(frames);
                renderer.render(gpu::IndirectTerm{mapper.texture(), gpu::IndirectSpace::screen, 0});
                gpu::gl::Finish();
                if (f >= 2)
                    ms.push_back(std::chrono::duration<double, std::milli>(
                                     std::chrono::steady_clock::now() - t)
                                     .count());
            }
            double mean = 0.0, var = 0.0;
            for (const double v : ms) mean += v / double(ms.size());
            for (const double v : ms) var += (v - mean) * (v - mean) / double(ms.size());
            std::printf("%8d %9u %8.4g %9.2f %8.2f %9.2f %8d", int(n), mapper.stored_photons(), r,
                        mean, std::sqrt(var), pm_ms, mapper.refined_pixels());
            if (has_reference) {
                const LdrMetrics m = compare_ldr(renderer.read_back().frame, reference);
                std::printf(" %8.2f %8.4f %7.4f", m.mse, m.nrmse, m.mssim);
            }
            std::printf("\n");
            std::fflush(stdout);
        }
    return 0;
}

}  // namespace ag::cli
