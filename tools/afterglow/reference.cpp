// afterglow reference SCENE --method pt|pm -o ref.exr: reference images for the GPU frame (path
// tracing or traditional photon mapping, Larsen ch. 4 and Fig. 14.3/14.5), split by component.
#include "cpu/reference/reference.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

#include "shared/image.h"
#include "shared/scene_file.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kReferenceCommand{
    "reference",
    "SCENE --method pt|pm -o OUT.exr [options]",
    "Render a reference image of the scene's camera by path tracing (pt) or photon mapping with "
    "final gathering (pm). Writes OUT.exr (full), OUT.direct.exr, OUT.indirect.exr, "
    "OUT.caustics.exr, OUT.specular.exr (they sum to the full image) and OUT.png; passes of one "
    "sample per pixel until --spp or --time is reached.",
    {
        {"method", "m", "pt|pm", "path tracing or photon mapping (required)"},
        {"output", "o", "OUT.exr", "the full image; components and a PNG go beside it"},
        {"spp", "", "N", "samples per pixel (default 64 for pt, 16 for pm unless --time is given)"},
        {"time", "", "SECONDS", "stop after this long (whole passes only; photon maps included)"},
        {"size", "", "WxH", "image size (default: the scene camera's resolution)"},
        {"threads", "", "N", "worker threads (default: settings.threads, 0 = all cores)"},
        {"seed", "", "N", "seed for all sequences (default: the scene's settings.seed)"},
        {"photons", "", "N", "pm: photons emitted for the global map (default 1000000)"},
        {"caustic-photons", "", "N", "pm: photons aimed at mirrors and glass (default 1000000)"},
        {"knn", "", "K", "pm: photons per global density estimate (default 100)"},
        {"caustic-knn", "", "K", "pm: photons per caustic density estimate (default 50)"},
        {"caustic-radius", "", "R", "pm: caustic search radius cap (default 1% of scene size)"},
        {"gather-rays", "", "N", "pm: final-gather rays per sample (default 64; x spp per pixel)"},
        {"area-samples", "", "N", "pm: shadow rays per quad light per sample (default 16)"},
        {"quiet", "q", "", "no progress bar (there is none unless stderr is a terminal)"},
    },
    1,
    1,
};

namespace {

void parse_size(const std::string& text, int& width, int& height) {
    const size_t x = text.find('x');
    try {
        size_t used_w = 0, used_h = 0;
        if (x == std::string::npos) throw std::invalid_argument(text);
        const std::string w = text.substr(0, x), h = text.substr(x + 1);
        width = std::stoi(w, &used_w);
        height = std::stoi(h, &used_h);
        if (used_w != w.size() || used_h != h.size() || width < 1 || height < 1 || width > 16384 ||
            height > 16384)
            throw std::invalid_argument(text);
    } catch (const std::exception&) {
        throw CliError("afterglow reference: --size expects WxH with 1 <= W, H <= 16384, got '" +
                       text + "'");
    }
}

std::string format_seconds(double s) {
    char buf[32];
    if (s < 60.0)
        std::snprintf(buf, sizeof buf, "%.1f s", s);
    else
        std::snprintf(buf, sizeof buf, "%d:%02d min", int(s) / 60, int(s) % 60);
    return buf;
}

void print_progress(const cpu::ReferenceProgress& p) {
    constexpr int kWidth = 30;
    const double f = std::clamp(p.fraction, 0.0, 1.0);
    const int filled = int(f * kWidth);
    std::string bar(size_t(filled), '#');
    bar.resize(kWidth, '.');
    std::string line = "\r" + p.stage + " [" + bar + "] " + std::to_string(int(f * 100.0)) + "%";
    if (p.stage == "render") line += "  " + std::to_string(p.passes_done) + " spp";
    line += "  " + format_seconds(p.elapsed);
    if (p.eta >= 0.0) line += ", ETA " + format_seconds(p.eta);
    line += "   ";
    std::fputs(line.c_str(), stderr);
    std::fflush(stderr);
}

}  // namespace

int run_reference(const Args& args) {
    const std::string where = "afterglow reference";
    if (!args.has("method")) throw CliError(where + ": missing --method pt|pm");
    cpu::ReferenceSettings settings;
    const std::string method = args.get("method");
    if (method == "pt")
        settings.method = cpu::ReferenceMethod::path_tracing;
    else if (method == "pm")
        settings.method = cpu::ReferenceMethod::photon_mapping;
    else
        throw CliError(where + ": --method expects pt or pm, got '" + method + "'");
    if (!args.has("output")) throw CliError(where + ": missing -o OUT.exr");
    const std::string out = args.get("output");
    if (out.size() < 5 || out.substr(out.size() - 4) != ".exr")
        throw CliError(where + ": -o expects a file name ending in .exr, got '" + out + "'");

    Scene scene = load_scene(args.positionals()[0]);
    if (args.has("size")) parse_size(args.get("size"), scene.camera.width, scene.camera.height);
    settings.seed =
        uint32_t(args.get_int("seed", int(scene.settings.seed & 0x7fffffffu), 0, 2147483647));
    settings.time_limit = args.get_double("time", 0.0);
    if (settings.time_limit < 0.0) throw CliError(where + ": --time expects seconds >= 0");
    const bool pm = settings.method == cpu::ReferenceMethod::photon_mapping;
    settings.spp = args.get_int("spp", settings.time_limit > 0.0 ? 0 : (pm ? 16 : 64), 1, 1 << 24);
    settings.photons = args.get_int("photons", settings.photons, 0, 1 << 30);
    settings.caustic_photons =
        args.get_int("caustic-photons", settings.caustic_photons, 0, 1 << 30);
    settings.knn = args.get_int("knn", settings.knn, 1, 10000);
    settings.caustic_knn = args.get_int("caustic-knn", settings.caustic_knn, 1, 10000);
    settings.caustic_radius = float(args.get_double("caustic-radius", 0.0));
    if (settings.caustic_radius < 0.0f) throw CliError(where + ": --caustic-radius expects R >= 0");
    settings.gather_rays = args.get_int("gather-rays", settings.gather_rays, 1, 1 << 20);
    settings.area_light_samples =
        args.get_int("area-samples", settings.area_light_samples, 1, 1 << 16);
    ThreadPool pool(args.get_int("threads", scene.settings.threads, 0, 1024));

    // The bar only where someone watches: a terminal, as `afterglow render` does.
    const bool quiet = args.has("quiet") || !isatty(fileno(stderr));
    const cpu::ReferenceResult result = cpu::render_reference(
        scene, settings, pool, quiet ? cpu::ReferenceProgressFn{} : print_progress);
    if (!quiet) std::fputs("\n", stderr);

    const std::string stem = out.substr(0, out.size() - 4);
    write_image(result.full, out);
    for (int c = 0; c < kFrameTermCount; ++c)
        write_image(result.components[size_t(c)],
                    stem + "." + kFrameTermNames[size_t(c)] + ".exr");
    write_image(result.full, stem + ".png", 0.0f);

    std::cout << "reference " << method << ": " << scene.camera.width << " x "
              << scene.camera.height << ", " << result.spp << " spp in "
              << format_seconds(result.seconds) << " on " << pool.size() << " threads";
    if (pm)
        std::cout << " (photon maps " << format_seconds(result.photon_seconds) << ": "
                  << result.global_photons << " global, " << result.caustic_photons
                  << " caustic photons; " << settings.gather_rays << " gather rays per sample)";
    std::cout << "\n";
    std::cerr << where << ": wrote " << out << ", " << stem
              << ".{direct,indirect,caustics,specular}.exr and " << stem << ".png\n";
    return 0;
}

static const Registration kRegistration(kReferenceCommand, run_reference, 50);

}  // namespace ag::cli
