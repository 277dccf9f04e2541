// afterglow fidelity SCENE: the per-stage error budget of the indirect term (docs/fidelity.md).
#include "shared/pipeline/fidelity.h"

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "gpu/gl_context.h"
#include "shared/image.h"
#include "shared/scene_file.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kFidelityCommand{
    "fidelity",
    "SCENE [options]",
    "Error budget of the indirect term per stage, at the texel centres once photons and AIMs are "
    "complete: (a) AIM radiance against path-traced outgoing radiance, (b) gathers of the AIMs "
    "(GL and CPU hemi-plane with no correction, renormalisation, border stretch; the pipeline's "
    "gather) against a full-hemisphere ray gather of the same AIMs, (c) that against path-traced "
    "irradiance, (d) the frame's indirect term against gathering at every pixel, (e) with "
    "--reference, both against a pt image. Prints a table; --csv writes it with per-texel values.",
    {
        integer("pt-paths", "N", "path-traced paths per texel centre", 1, 10000000, 4096),
        integer("reference-rays", "N", "rays of the full-hemisphere reference gather", 1, 10000000,
                4096),
        integer("pixel-rays", "N", "rays of the per-pixel gather, stage (d)", 1, 10000000, 1024),
        integer("pt-pixels", "N",
                "path-traced paths at every pixel centre (no light tracing): stage (e) holds the "
                "per-pixel gather and the --reference image to it at the same points (0 = off)",
                0, 10000000, 0),
        size_option("image size of stage (d)", "96x96"),
        text("reference", "PT.exr",
             "pt reference at the same size (its PT.indirect.exr is read), for stage (e)"),
        text("csv", "OUT.csv", "write the rows and the per-texel values as CSV"),
        text("images", "PREFIX", "write PREFIX.frame.exr/.png and PREFIX.pixel.exr/.png (stage d)"),
        flag("no-variants",
             "leave out stage (b)'s hemi-plane variants (GL and CPU gathers under each border "
             "correction): the slow part on a fine layout; the pipeline's gather and the other "
             "stages stay"),
        flag("regions", "print the per-object rows too (the CSV always has them)"),
        gl_option({gpu::GlBackend::osmesa, gpu::GlBackend::egl, gpu::GlBackend::automatic},
                  gpu::GlBackend::osmesa),
        gather_option(),
        settings_option(),
        integer("threads", "N", "worker threads (default: settings.threads)", 0, 1024),
    },
    1,
    1,
};

int run_fidelity(const Args& args) {
    Scene scene = load_scene(args.positionals()[0]);
    args.apply_settings(scene);
    FidelityOptions options;
    options.pt_paths = args.get_int("pt-paths");
    options.reference_rays = args.get_int("reference-rays");
    options.pixel_rays = args.get_int("pixel-rays");
    options.pt_pixels = args.get_int("pt-pixels");
    options.gather_variants = !args.has("no-variants");
    options.width = 96;
    options.height = 96;
    args.get_size("size", options.width, options.height);
    if (args.has("reference")) {
        const std::filesystem::path p(args.get("reference"));
        const std::string indirect =
            (p.parent_path() / (p.stem().string() + ".indirect.exr")).string();
        options.reference_indirect = read_image(indirect);
        if (options.reference_indirect.width != options.width ||
            options.reference_indirect.height != options.height)
            throw CliError("afterglow fidelity: " + indirect + " is " +
                           std::to_string(options.reference_indirect.width) + "x" +
                           std::to_string(options.reference_indirect.height) + ", expected " +
                           std::to_string(options.width) + "x" + std::to_string(options.height) +
                           " (--size)");
    }
    auto context = gpu::make_gl_context(args.gl_backend());
    ThreadPool pool(args.get_int("threads", scene.settings.threads));
    const FidelityReport report = measure_fidelity(scene, options, pool);

    std::cout << "# afterglow fidelity " << args.positionals()[0] << ": "
              << scene.atlas.texels.size() << " texels, pt " << options.pt_paths
              << " paths/texel, reference gather " << options.reference_rays << " rays; "
              << report.routed << " texels see mirrors or glass (GL gather: handed to the rays)\n";
    FidelityReport shown = report;
    if (!args.has("regions"))
        std::erase_if(shown.rows, [](const FidelityRow& r) { return r.region != "all"; });
    std::cout << fidelity_table(shown);
    if (args.has("csv")) {
        write_file_atomically(args.get("csv"), fidelity_csv(scene, report));
        std::cerr << "afterglow fidelity: wrote " << args.get("csv") << "\n";
    }
    if (args.has("images") && report.frame_indirect.width > 0) {
        const std::string prefix = args.get("images");
        write_image(report.frame_indirect, prefix + ".frame.exr");
        write_image(report.frame_indirect, prefix + ".frame.png");
        write_image(report.pixel_indirect, prefix + ".pixel.exr");
        write_image(report.pixel_indirect, prefix + ".pixel.png");
    }
    return 0;
}

static const Registration kRegistration(kFidelityCommand, run_fidelity, 58);

}  // namespace ag::cli
