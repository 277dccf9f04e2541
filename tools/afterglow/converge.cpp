// afterglow converge SCENE: convergence over time. Runs the progressive pipeline with a scene-edit
// script and records, after every frame, wall time and the error against a reference of the
// scene's final state, with the pipeline's own counters; writes a CSV and a plot.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>

#include "gpu/gl_context.h"
#include "shared/frame_terms.h"
#include "shared/image.h"
#include "shared/metrics.h"
#include "shared/scene_file.h"
#include "tools/afterglow/commands.h"
#include "tools/afterglow/convergence.h"
#include "tools/afterglow/progress.h"

namespace ag::cli {

const Command kConvergeCommand{
    "converge",
    "SCENE [--script S.lua] [--reference REF.exr] [options]",
    "Run the progressive pipeline (and a scene-edit script) for N frames and record after every "
    "frame the wall time, the error of one component against a reference of the scene's final "
    "state (computed with the pm reference and cached by a hash of that state unless --reference "
    "is given) and the pipeline's counters. Writes a CSV and a PNG plot of error against time and "
    "prints the time from the last edit until the error is within 10% of its settled value. "
    "--baseline full recomputes everything every frame, full-budget everything round robin within "
    "the same --frame-ms, for comparison on the same plot (bench settle runs all three).",
    {
        text("script", "S.lua", "scene-edit script (default: the scene's \"script\")"),
        text("reference", "REF.exr",
             "reference image (its .COMPONENT.exr beside it is used for --component)"),
        integer("frames,n", "N", "frames to run", 1, 1000000, 120),
        size_option("image size", "96x96"),
        choice(
            "component", "NAME", "the component compared (a frame term, or full):",
            [] {
                std::vector<std::string> names{"full"};
                names.insert(names.end(), kFrameTermNames.begin(), kFrameTermNames.end());
                return names;
            }(),
            "indirect"),
        choice("baseline", "MODE",
               "selective (Larsen), full (everything every frame) or full-budget (everything "
               "round robin within the same --frame-ms):",
               {kPipelineModeNames.begin(), kPipelineModeNames.end()}, "selective"),
        text("csv", "FILE.csv", "where to write the per-frame record (default out/NAME.MODE.csv)"),
        text("plot", "FILE.png",
             "plot of error against time (default out/NAME.MODE.png); '' for none"),
        text("compare", "OTHER.csv", "also draw this run's CSV on the plot"),
        text("reference-frames", "F1,F2,...",
             "also score these frames against references of the script's state at each of them "
             "(cached like the final one): the ghosting check of temporal methods"),
        text("cache", "DIR", "reference cache", "out/reference-cache"),
        integer("ref-spp", "N", "samples per pixel of a computed reference", 1, 1000000, 64),
        integer("ref-photons", "N", "photons of a computed pm reference", 1000, 100000000, 400000),
        integer("reference-bounces", "N",
                "score against a reference whose indirect term keeps N diffuse bounces (1 for "
                "single-bounce methods; default all)",
                0, 1 << 16),
        gl_option({gpu::GlBackend::osmesa, gpu::GlBackend::egl, gpu::GlBackend::automatic},
                  gpu::GlBackend::osmesa),
        gather_option(),
        indirect_option(),
        frame_ms_option(),
        settings_option(),
        integer("threads", "N", "worker threads (default: settings.threads)", 0, 1024),
        flag("prime",
             "start from the converged state (untimed: every photon, AIM and IIM texel "
             "computed before frame 0), so the run measures the edits alone"),
        flag("quiet,q", "no progress bar"),
    },
    1,
    1,
};

int run_converge(const Args& args) {
    const int frames = args.get_int("frames");
    const std::string component = args.get("component");
    const std::string mode = args.get("baseline");
    int width = 0, height = 0;
    args.get_size("size", width, height);
    const gpu::GlBackend backend = args.gl_backend();

    const std::string scene_path = args.positionals()[0];
    Scene scene = load_scene(scene_path);
    args.apply_settings(scene);
    scene.camera.width = width;
    scene.camera.height = height;
    const std::string script_path = args.get("script", scene.script);
    const std::string name = std::filesystem::path(scene_path).stem().string();
    const std::string csv_path = args.get("csv", "out/" + name + "." + mode + ".csv");
    const std::string plot_path = args.get("plot", "out/" + name + "." + mode + ".png");
    const int threads = args.get_int("threads", scene.settings.threads);

    // --reference-frames, checked before any reference is rendered.
    std::vector<int> reference_frames;
    if (args.has("reference-frames")) {
        std::stringstream list(args.get("reference-frames"));
        for (std::string item; std::getline(list, item, ',');) {
            char* end = nullptr;
            const long f = std::strtol(item.c_str(), &end, 10);
            if (item.empty() || *end != '\0' || f < 0 || f >= frames)
                throw CliError("afterglow converge: --reference-frames: \"" + item +
                               "\" is not a frame in 0.." + std::to_string(frames - 1));
            reference_frames.push_back(int(f));
        }
    }
    // The reference: given, or rendered for the scene's final state (the script run ahead on a
    // copy) and cached by a hash of that state.
    std::string reference_path = args.get("reference", "");
    ReferenceRequest request;
    request.name = name;
    request.cache = args.get("cache");
    request.spp = args.get_int("ref-spp");
    request.photons = args.get_int("ref-photons");
    request.threads = threads;
    request.indirect_bounces = args.get_int("reference-bounces", -1);
    if (reference_path.empty())
        reference_path = cached_reference(scene, script_path, frames, request);
    const Image reference = read_reference(reference_path, component, width, height);
    // --reference-frames: the state at frame F is the script run for F + 1 frames.
    std::map<int, Image> at_frame;
    std::map<int, std::string> at_frame_path;
    for (const int f : reference_frames) {
        at_frame_path[f] = cached_reference(scene, script_path, f + 1, request);
        at_frame[f] = read_reference(at_frame_path[f], component, width, height);
    }
    std::map<int, double> at_frame_error;

    auto context = gpu::make_gl_context(backend);
    Progress progress("converge", frames, !args.has("quiet"));
    const ConvergenceRun run = run_convergence(
        scene, script_path, PipelineMode(args.get_choice("baseline")), frames, width, height,
        component, [&](int) -> const Image& { return reference; }, threads, args.has("prime"),
        [&](int done) { progress.update(done); },
        [&](int frame, const Image& image) {
            if (auto it = at_frame.find(frame); it != at_frame.end())
                at_frame_error[frame] = compare_images(image, it->second).rel_mse;
        });
    progress.finish();
    std::filesystem::create_directories(std::filesystem::absolute(csv_path).parent_path());
    write_file_atomically(csv_path, convergence_csv(run));

    const SettleAnalysis& s = run.settle;
    std::printf(
        "converge %s (%s, %s): %d frames, %.2f s; settled relMSE %.5f (%s); last edit at frame %d "
        "(%.2f s)\n",
        scene_path.c_str(), mode.c_str(), component.c_str(), frames, run.wall_s, s.settled,
        reference_path.c_str(), s.last_edit, frame_start_s(run.frames, size_t(s.last_edit)));
    if (s.settled_ok())
        std::printf(
            "within 10%% of the settled error from frame %d: %d frames, %.3f s after the last "
            "edit\n",
            s.within, s.frames, s.seconds);
    else
        std::printf("the error did not settle within 10%% after the last edit\n");
    for (const auto& [f, e] : at_frame_error)
        std::printf("frame %d: relMSE %.5f against its own state (%s)\n", f, e,
                    at_frame_path[f].c_str());
    std::printf("wrote %s\n", csv_path.c_str());

    if (!plot_path.empty()) {
        std::string command =
            "/usr/bin/python3 tools/plot_convergence.py '" + plot_path + "' '" + csv_path + "'";
        if (args.has("compare")) command += " '" + args.get("compare") + "'";
        command += " --title '" + name + ": " + component + " relMSE against time'";
        if (std::system(command.c_str()) != 0)
            std::cerr << "afterglow converge: warning: plotting failed (" << command << ")\n";
        else
            std::printf("wrote %s\n", plot_path.c_str());
    }
    return 0;
}

static const Registration kRegistration(kConvergeCommand, run_converge, 40);

}  // namespace ag::cli
