// afterglow render SCENE -o out.exr: the progressive pipeline, headless, for N frames.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

#include "gpu/gl_context.h"
#include "shared/frame_terms.h"
#include "shared/image.h"
#include "shared/input_error.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/scene_file.h"
#include "shared/script.h"
#include "tools/afterglow/commands.h"
#include "tools/afterglow/progress.h"

namespace ag::cli {

const Command kRenderCommand{
    "render",
    "SCENE -o OUT.exr [options]",
    "Run the progressive pipeline headless for N frames (photon work on worker threads while the "
    "GL thread gathers and draws) and write the last frame as EXR and PNG. --aov also writes the "
    "direct, indirect, specular and caustics terms, which sum to the frame.",
    {
        text("output,o", "OUT.exr",
             "the EXR to write; a PNG with the same stem is written beside it"),
        integer("frames,n", "N", "frames to run", 1, 1000000, 30),
        size_option("image size (default: the scene camera's resolution)"),
        integer("supersample", "S",
                "render S x S samples per pixel and average them (a box pixel filter, as the "
                "reference renderers use; what comparisons with them need at edges)",
                1, 16, 1),
        flag("aov",
             "also write OUT.direct.exr, .indirect, .caustics, .specular, .volume (and PNGs)"),
        gl_option({gpu::GlBackend::osmesa, gpu::GlBackend::egl, gpu::GlBackend::automatic},
                  gpu::GlBackend::osmesa),
        gather_option(),
        indirect_option(),
        frame_ms_option(),
        settings_option(),
        number("exposure", "EV", "PNG exposure in stops (radiance 1 is white at 0)", -100, 100, 0),
        integer("threads", "N", "worker threads for photon work (default: settings.threads)", 0,
                1024),
        text("script", "S.lua",
             "scene-edit script (default: the scene's \"script\"); frame time = frame / 30 s"),
        flag("quiet,q", "no progress bar"),
    },
    1,
    1,
};

namespace {

std::string with_suffix(const std::string& exr, const std::string& suffix, const std::string& ext) {
    const std::filesystem::path p(exr);
    return (p.parent_path() / (p.stem().string() + suffix + ext)).string();
}

}  // namespace

int run_render(const Args& args) {
    if (!args.has("output")) throw CliError("afterglow render: missing -o OUT.exr");
    const std::string out = args.get("output");
    if (std::filesystem::path(out).extension() != ".exr")
        throw CliError("afterglow render: -o expects a file name ending in .exr, got '" + out +
                       "'");
    const int frames = args.get_int("frames");
    const gpu::GlBackend backend = args.gl_backend();
    const float exposure = float(args.get_double("exposure"));

    Scene scene = load_scene(args.positionals()[0]);
    args.apply_settings(scene);
    int width = scene.camera.width, height = scene.camera.height;
    args.get_size("size", width, height);
    const int supersample = args.get_int("supersample");
    const int threads = args.get_int("threads", scene.settings.threads);

    std::optional<Script> script;
    const std::string script_path = args.get("script", scene.script);
    if (!script_path.empty()) script.emplace(script_path);  // a syntax error stops here (exit 1)

    auto context = gpu::make_gl_context(backend);
    Pipeline pipeline(scene, PipelineOptions{width * supersample, height * supersample, threads});
    if (scene.settings.gather.backend == GatherBackend::automatic && pipeline.iim_method())
        std::fprintf(stderr, "afterglow render: gather backend %s (%s)\n",
                     kGatherBackendNames[size_t(pipeline.gather_backend())],
                     pipeline.gather_backend_reason().c_str());
    Progress progress("render", frames, !args.has("quiet"));
    double total_ms = 0.0;
    const PipelineStats last =
        run_frames(pipeline, script ? &*script : nullptr, frames, [&](const FrameEvent& e) {
            total_ms += e.stats->frame_ms;
            progress.update(e.frame + 1);
        });
    progress.finish();

    if (const auto* rc = dynamic_cast<const IrradianceCacheMethod*>(&pipeline.indirect())) {
        const IrradianceCacheStats& s = rc->last_stats();
        std::fprintf(stderr,
                     "afterglow render: irradiance cache: %zu records (%llu made in all; last "
                     "frame %d new, %d replaced, %d deleted), splat %.2f ms, scan %.2f ms, "
                     "records %.2f ms\n",
                     rc->records().size(), (unsigned long long)s.records_made, s.added, s.replaced,
                     s.deleted, s.splat_ms, s.scan_ms, s.gather_ms);
    }
    // A static scene's frame is the running mean of the frames since anything it shows last
    // changed (frame.accumulate_frames: sub-pixel offsets; direct.accumulate_frames: area-light
    // samples): say how far it got, so a comparison knows what it compares.
    std::fprintf(stderr,
                 "afterglow render: the frame is the mean of the last %d frames (%s; converged: "
                 "%s)\n",
                 pipeline.renderer().accumulated_frames(),
                 pipeline.renderer().accumulation_complete() ? "complete" : "still accumulating",
                 pipeline.converged() ? "yes" : "no");
    gpu::FrameImages images = pipeline.images();
    images.frame = box_downsample(images.frame, supersample);
    for (Image& aov : images.aov) aov = box_downsample(aov, supersample);
    std::filesystem::create_directories(std::filesystem::absolute(out).parent_path());
    write_image(images.frame, out);
    write_image(images.frame, with_suffix(out, "", ".png"), exposure);
    if (args.has("aov"))
        for (size_t a = 0; a < images.aov.size(); ++a) {
            const std::string suffix = std::string(".") + kFrameTermNames[a];
            write_image(images.aov[a], with_suffix(out, suffix, ".exr"));
            write_image(images.aov[a], with_suffix(out, suffix, ".png"), exposure);
        }
    std::fprintf(stderr,
                 "afterglow render: %d frames of %dx%d in %.1f ms (%.1f fps) on %s [%s]\n"
                 "last frame: %.2f ms (gather %.2f, draw %.2f, waited %.2f for photons %.2f + AIM "
                 "%.2f + caustics %.2f on "
                 "workers); "
                 "photons verified %d, groups invalidated %d, retraced %d, queued %d; AIM texels "
                 "%d; IIM texels "
                 "gathered %d, pending %d, repaired %d; caustic photons traced %d (%d reached a "
                 "specular object, %d "
                 "stored), tiles filtered %d\n",
                 frames, width, height, total_ms, 1000.0 * frames / std::max(1e-9, total_ms),
                 context->renderer().c_str(), gpu::kGlBackendNames[size_t(context->backend())],
                 last.frame_ms, last.gather_ms, last.draw_ms, last.wait_ms, last.photon_ms,
                 last.aim_ms, last.caustic_ms, last.photons.photons_verified,
                 last.photons.groups_invalidated, last.photons.photons_retraced,
                 last.photons.groups_queued, last.photons.aim_texels_rebuilt,
                 last.iim_texels_gathered, last.iim_texels_pending, last.iim_texels_invalid,
                 last.caustics.traced, last.caustics.hit_specular, last.caustics.stored,
                 last.caustic_tiles_filtered);
    std::cerr << "afterglow render: wrote " << out << " and " << with_suffix(out, "", ".png")
              << "\n";
    return 0;
}

static const Registration kRegistration(kRenderCommand, run_render, 5);

}  // namespace ag::cli
