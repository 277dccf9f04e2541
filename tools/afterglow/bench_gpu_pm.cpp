#include "tools/afterglow/bench_gpu_pm.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

#include "gpu/frame_renderer.h"
#include "gpu/g_buffer.h"
#include "gpu/gl_context.h"
#include "gpu/gpu_photon_mapper.h"
#include "gpu/scene_meshes.h"
#include "shared/budget_search.h"
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

struct MeanSigma {
    double mean = 0.0, sigma = 0.0, median = 0.0;  // the median reads through a loaded machine
};

MeanSigma mean_sigma(std::vector<double> v) {
    MeanSigma m;
    std::sort(v.begin(), v.end());
    m.median = v.empty() ? 0.0 : 0.5 * (v[(v.size() - 1) / 2] + v[v.size() / 2]);
    for (const double x : v) m.mean += x / double(v.size());
    for (const double x : v) m.sigma += (x - m.mean) * (x - m.mean) / double(v.size());
    m.sigma = std::sqrt(m.sigma);
    return m;
}

double ms_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// One cell of the grid: `frames` timed frames after 2 untimed, each tracing its photons anew.
struct Cell {
    MeanSigma method;  // G-buffer, photons, binning, estimate
    MeanSigma frame;   // and the direct light and compose (not with --no-direct)
    uint32_t stored = 0;
    int refined = 0;
};

Cell run_cell(Scene& scene, gpu::GBuffer& g_buffer, gpu::FrameRenderer* renderer, int paths,
              float radius, int frames) {
    scene.settings.gpu_pm.paths = paths;
    scene.settings.gpu_pm.frames = 1;
    scene.settings.gpu_pm.radius = radius;
    gpu::GpuPhotonMapper mapper(scene, g_buffer);
    std::vector<double> method, frame;
    for (int f = 0; f < frames + 2; ++f) {
        gpu::gl::Finish();
        const auto t = std::chrono::steady_clock::now();
        g_buffer.render();
        mapper.clear_photons();
        mapper.trace();
        mapper.render();
        gpu::gl::Finish();
        if (f >= 2) method.push_back(ms_since(t));
        if (!renderer) continue;
        renderer->render(gpu::IndirectTerm{mapper.texture(), gpu::IndirectSpace::screen, 0});
        gpu::gl::Finish();
        if (f >= 2) frame.push_back(ms_since(t));
    }
    Cell c;
    c.method = mean_sigma(method);
    if (renderer) c.frame = mean_sigma(frame);
    c.stored = mapper.stored_photons();
    c.refined = mapper.refined_pixels();
    return c;
}

// Table 6.2: the paths whose method time is `budget` ms at this radius, searched per radius
// (the paths per ms differ with the radius: longer tile lists) through the median of
// `probe_frames` frames per probe, until a probe lands within the tolerance
// (shared/budget_search.h).
BudgetResult paths_for_budget(Scene& scene, gpu::GBuffer& g_buffer, float radius,
                              const BudgetSearch& search, int probe_frames) {
    return search_budget(search, [&](int paths) {
        return run_cell(scene, g_buffer, nullptr, paths, radius, probe_frames).method.median;
    });
}

}  // namespace

int bench_gpu_pm(const Args& args, const std::string& scene_path, int width, int height) {
    const std::vector<double> paths = parse_list(args.get("paths"), "paths");
    const std::vector<double> radii = parse_list(args.get("radii"), "radii");
    const bool no_direct = args.has("no-direct");
    const bool budget = args.has("budget");
    if (args.has("reference") && no_direct)
        throw CliError(
            "afterglow bench gpu_pm: --reference compares the composed frame; --no-direct has "
            "none");
    auto context = gpu::make_gl_context(args.gl_backend());
    std::printf("GL: %s (%s)\n", context->renderer().c_str(), context->version().c_str());
    Scene scene = load_scene(scene_path);
    args.apply_settings(scene);
    const int frames = args.get_int("frames", 20);
    Image reference;
    const bool has_reference = args.has("reference");
    if (has_reference && no_direct)
        throw CliError(
            "afterglow bench gpu_pm: --reference compares the composed frame; --no-direct has "
            "none");
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
    std::unique_ptr<gpu::FrameRenderer> renderer;
    if (!no_direct) renderer = std::make_unique<gpu::FrameRenderer>(scene, meshes, width, height);
    std::printf(
        "%s, %dx%d, %d frames per cell, photons traced anew each frame; mean and sigma of the "
        "method's time (G-buffer, photons, binning, estimate)%s\n",
        scene_path.c_str(), width, height, frames,
        no_direct ? "" : " and of the frame's (with direct light and compose)");
    BudgetSearch search;
    const int probe_frames = args.get_int("budget-frames", 9);
    if (budget) {
        search.budget_ms = args.get_double("budget");
        search.tolerance = args.get_double("budget-tolerance", 0.1);
        std::printf(
            "paths per radius chosen for %.3g ms of the method's time (Table 6.2): each probe the "
            "median of %d frames, held when two probes of one count are within +-%.3g%%\n",
            search.budget_ms, probe_frames, 100.0 * search.tolerance);
    }
    std::printf("%8s %9s %8s %9s %8s %8s %9s %8s %8s %8s %8s %7s\n", "paths", "(stored)", "radius",
                "gpu_pm ms", "sigma", "median", "frame ms", "sigma", "refined", "MSE", "NRMSE",
                "MSSIM");
    auto report = [&](int n, double r) -> Cell {
        const Cell c = run_cell(scene, g_buffer, renderer.get(), n, float(r), frames);
        std::printf("%8d %9u %8.4g %9.2f %8.2f %8.2f", n, c.stored, r, c.method.mean,
                    c.method.sigma, c.method.median);
        if (renderer)
            std::printf(" %9.2f %8.2f", c.frame.mean, c.frame.sigma);
        else
            std::printf(" %9s %8s", "-", "-");
        std::printf(" %8d", c.refined);
        if (has_reference) {
            const LdrMetrics m = compare_ldr(renderer->read_back().frame, reference);
            std::printf(" %8.2f %8.4f %7.4f", m.mse, m.nrmse, m.mssim);
        }
        std::printf("\n");
        std::fflush(stdout);
        return c;
    };
    if (budget) {
        // The search's own verdict, and the cell's: its frames are timed after the search, so
        // its median is a second, independent check that the budget held.
        std::vector<std::pair<BudgetResult, Cell>> rows;
        for (const double r : radii) {
            BudgetResult found = paths_for_budget(scene, g_buffer, float(r), search, probe_frames);
            rows.emplace_back(found, report(found.count, r));
        }
        const double band = search.tolerance * search.budget_ms;
        int held = 0, cells_held = 0;
        std::printf(
            "\nbudget search per radius: the paths found, the probe's median, the line's ms per "
            "1000 paths and fixed ms, whether the search held, the cell's median and whether it "
            "held; the probes (paths:ms)\n");
        std::printf("%8s %8s %9s %10s %9s %5s %9s %5s  %s\n", "radius", "paths", "probe ms",
                    "ms/1000", "fixed ms", "held", "cell ms", "held", "probes");
        for (size_t i = 0; i < rows.size(); ++i) {
            const auto& [found, cell] = rows[i];
            const bool cell_held = std::abs(cell.method.median - search.budget_ms) <= band;
            held += found.held;
            cells_held += cell_held;
            std::printf("%8.4g %8d %9.2f %10.3f %9.2f %5s %9.2f %5s ", radii[i], found.count,
                        found.ms, 1000.0 * found.ms_per_count, found.fixed_ms,
                        found.held ? "yes" : "no", cell.method.median, cell_held ? "yes" : "no");
            for (const BudgetProbe& p : found.probes) std::printf(" %d:%.2f", p.count, p.ms);
            std::printf("\n");
        }
        std::printf(
            "budget %.3g ms held (within +-%.3g%%) by the search in %d of %zu radii, by "
            "the cells' medians in %d of %zu\n",
            search.budget_ms, 100.0 * search.tolerance, held, rows.size(), cells_held, rows.size());
    } else {
        for (const double n : paths)
            for (const double r : radii) report(int(n), r);
    }
    return 0;
}

}  // namespace ag::cli
