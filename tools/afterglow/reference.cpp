// afterglow reference SCENE --method pt|pm -o ref.exr: reference images for the GPU frame (path
// tracing or traditional photon mapping, Larsen ch. 4 and Fig. 14.3/14.5), split by component.
#include "cpu/reference/reference.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

#include "cpu/media_tracking.h"
#include "shared/image.h"
#include "shared/scene_file.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kReferenceCommand{
    "reference",
    "SCENE --method pt|pm -o OUT.exr [options]",
    "Render a reference image of the scene's camera by path tracing (pt) or photon mapping with "
    "final gathering (pm). Writes OUT.exr (full), OUT.direct.exr, OUT.indirect.exr, "
    "OUT.caustics.exr, OUT.specular.exr, OUT.volume.exr (they sum to the full image) and OUT.png; "
    "participating media (pt only) by delta tracking; passes of one "
    "sample per pixel until --spp or --time is reached.",
    {
        choice("method,m", "pt|pm", "path tracing or photon mapping (required)", {"pt", "pm"}),
        text("output,o", "OUT.exr", "the full image; components and a PNG go beside it"),
        integer("spp", "N",
                "samples per pixel (default 64 for pt, 16 for pm unless --time is given)", 1,
                1 << 24),
        number("time", "SECONDS", "stop after this long (whole passes only; photon maps included)",
               0, 1e9),
        size_option("image size (default: the scene camera's resolution)"),
        integer("threads", "N", "worker threads (default: settings.threads, 0 = all cores)", 0,
                1024),
        integer("seed", "N", "seed for all sequences (default: the scene's settings.seed)", 0,
                2147483647),
        integer("photons", "N", "pm: photons emitted for the global map", 0, 1 << 30,
                cpu::ReferenceSettings{}.photons),
        integer("caustic-photons", "N", "pm: photons aimed at mirrors and glass", 0, 1 << 30,
                cpu::ReferenceSettings{}.caustic_photons),
        integer("knn", "K", "pm: photons per global density estimate", 1, 10000,
                cpu::ReferenceSettings{}.knn),
        integer("caustic-knn", "K", "pm: photons per caustic density estimate", 1, 10000,
                cpu::ReferenceSettings{}.caustic_knn),
        number("caustic-radius", "R", "pm: caustic search radius cap (default 1% of scene size)", 0,
               1e9),
        integer("gather-rays", "N", "pm: final-gather rays per sample (x spp per pixel)", 1,
                1 << 20, cpu::ReferenceSettings{}.gather_rays),
        integer("area-samples", "N", "pm: shadow rays per quad light per sample", 1, 1 << 16,
                cpu::ReferenceSettings{}.area_light_samples),
        integer("indirect-bounces", "N",
                "diffuse bounces the indirect term keeps (1 = single bounce, 0 = none; default "
                "all)",
                0, 1 << 16),
        integer("volume-bounces", "N",
                "pt: scattering events in media per path (0: media only attenuate; 1: single "
                "scattering)",
                0, 1 << 20, cpu::ReferenceSettings{}.volume_bounces),
        integer("light-paths", "N",
                "pt: light paths per pass from point, spot and sun lights through mirrors and "
                "glass (default: one per pixel)",
                1, 1 << 30),
        flag("no-light-tracing",
             "pt: leave out light from point, spot and sun lights through mirrors and glass "
             "(L S+ D paths; the references before session 17)"),
        flag("quiet,q", "no progress bar (there is none unless stderr is a terminal)"),
    },
    1,
    1,
};

namespace {

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
    settings.method =
        method == "pt" ? cpu::ReferenceMethod::path_tracing : cpu::ReferenceMethod::photon_mapping;
    if (!args.has("output")) throw CliError(where + ": missing -o OUT.exr");
    const std::string out = args.get("output");
    if (out.size() < 5 || out.substr(out.size() - 4) != ".exr")
        throw CliError(where + ": -o expects a file name ending in .exr, got '" + out + "'");

    Scene scene = load_scene(args.positionals()[0]);
    args.get_size("size", scene.camera.width, scene.camera.height);
    settings.seed = uint32_t(args.get_int("seed", int(scene.settings.seed & 0x7fffffffu)));
    settings.time_limit = args.get_double("time", 0.0);
    const bool pm = settings.method == cpu::ReferenceMethod::photon_mapping;
    if (pm && cpu::has_media(scene))
        throw CliError(where + ": " + scene.path +
                       " has participating media, which pm does not render; use --method pt");
    settings.spp = args.get_int("spp", settings.time_limit > 0.0 ? 0 : (pm ? 16 : 64));
    settings.photons = args.get_int("photons");
    settings.caustic_photons = args.get_int("caustic-photons");
    settings.knn = args.get_int("knn");
    settings.caustic_knn = args.get_int("caustic-knn");
    settings.caustic_radius = float(args.get_double("caustic-radius", 0.0));
    settings.gather_rays = args.get_int("gather-rays");
    settings.area_light_samples = args.get_int("area-samples");
    settings.indirect_bounces = args.get_int("indirect-bounces", -1);
    settings.volume_bounces = args.get_int("volume-bounces");
    settings.light_paths = args.get_int("light-paths", 0);
    settings.light_tracing = !args.has("no-light-tracing");
    ThreadPool pool(args.get_int("threads", scene.settings.threads));

    // The bar only where someone watches: a terminal, as `afterglow render` does.
    const bool quiet = args.has("quiet") || !isatty(fileno(stderr));
    const cpu::ReferenceResult result = cpu::render_reference(
        scene, settings, pool, quiet ? cpu::ReferenceProgressFn{} : print_progress);
    if (!quiet) std::fputs("\n", stderr);

    const std::string stem = out.substr(0, out.size() - 4);
    write_image(result.full, out);
    for (int c = 0; c < kFrameTermCount; ++c)
        write_image(result.components[size_t(c)], stem + "." + kFrameTermNames[size_t(c)] + ".exr");
    write_image(result.full, stem + ".png", 0.0f);

    std::cout << "reference " << method << ": " << scene.camera.width << " x "
              << scene.camera.height << ", " << result.spp << " spp in "
              << format_seconds(result.seconds) << " on " << pool.size() << " threads";
    if (pm)
        std::cout << " (photon maps " << format_seconds(result.photon_seconds) << ": "
                  << result.global_photons << " global, " << result.caustic_photons
                  << " caustic photons; " << settings.gather_rays << " gather rays per sample)";
    else if (result.light_paths > 0)
        std::cout << " (+ " << result.light_paths << " light paths through mirrors and glass)";
    std::cout << "\n";
    if (!pm && settings.light_tracing && result.light_paths == 0 &&
        result.light_tracing_skipped.rfind("participating media", 0) == 0)
        std::cerr << where << ": " << scene.path
                  << ": no light tracing through mirrors and glass with participating media; "
                     "light from point, spot and sun lights through them is missing\n";
    std::cerr << where << ": wrote " << out << ", " << stem
              << ".{direct,indirect,caustics,specular,volume}.exr and " << stem << ".png\n";
    return 0;
}

static const Registration kRegistration(kReferenceCommand, run_reference, 50);

}  // namespace ag::cli
