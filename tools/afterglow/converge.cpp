// afterglow converge SCENE: convergence over time. Runs the progressive pipeline with a scene-edit
// script and records, after every frame, wall time and the error against a reference of the
// scene's final state, with the pipeline's own counters; writes a CSV and a plot.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "cpu/reference/reference.h"
#include "gpu/gl_context.h"
#include "shared/frame_terms.h"
#include "shared/image.h"
#include "shared/input_error.h"
#include "shared/metrics.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/scene_file.h"
#include "shared/script.h"
#include "tools/afterglow/commands.h"
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
    "--baseline full recomputes everything every frame, for comparison on the same plot.",
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
        text("cache", "DIR", "reference cache", "out/reference-cache"),
        integer("ref-spp", "N", "samples per pixel of a computed reference", 1, 1000000, 64),
        integer("ref-photons", "N", "photons of a computed pm reference", 1000, 100000000, 400000),
        gl_option({gpu::GlBackend::osmesa, gpu::GlBackend::egl, gpu::GlBackend::automatic},
                  gpu::GlBackend::osmesa),
        gather_option(),
        indirect_option(),
        frame_ms_option(),
        settings_option(),
        integer("threads", "N", "worker threads (default: settings.threads)", 0, 1024),
        flag("quiet,q", "no progress bar"),
    },
    1,
    1,
};

namespace {

using Clock = std::chrono::steady_clock;

uint64_t fnv1a(uint64_t h, const void* data, size_t n) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

// A hash of everything the reference image depends on: geometry, materials and transforms,
// lights, camera and the reference settings.
uint64_t state_hash(const Scene& scene, const cpu::ReferenceSettings& rs) {
    uint64_t h = 1469598103934665603ull;
    auto add = [&](const auto& v) { h = fnv1a(h, &v, sizeof v); };
    for (const Object& o : scene.objects) {
        h = fnv1a(h, o.mesh.positions.data(), o.mesh.positions.size() * sizeof(glm::vec3));
        h = fnv1a(h, o.mesh.triangles.data(), o.mesh.triangles.size() * sizeof(glm::uvec3));
        add(o.transform.translation), add(o.transform.rotation);
        add(o.material.type), add(o.material.albedo), add(o.material.ior), add(o.material.emission);
    }
    for (const Light& l : scene.lights) {
        add(l.type), add(l.position), add(l.intensity), add(l.corners), add(l.radiance),
            add(l.enabled);
    }
    add(scene.camera.eye), add(scene.camera.target), add(scene.camera.up), add(scene.camera.fov_y);
    add(scene.camera.width), add(scene.camera.height);
    add(rs.method), add(rs.spp), add(rs.seed), add(rs.photons), add(rs.caustic_photons),
        add(rs.knn);
    add(rs.caustic_knn), add(rs.gather_rays), add(rs.area_light_samples), add(rs.max_depth);
    return h;
}

std::string component_path(const std::string& exr, const std::string& component) {
    if (component == "full") return exr;
    const std::filesystem::path p(exr);
    return (p.parent_path() / (p.stem().string() + "." + component + ".exr")).string();
}

}  // namespace

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

    // The reference: given, or rendered for the scene's final state (the script run ahead on a
    // copy) and cached by a hash of that state.
    std::string reference_path = args.get("reference", "");
    if (reference_path.empty()) {
        Scene final_state = scene;
        if (!script_path.empty()) {
            Script ahead(script_path);
            run_script_ahead(ahead, final_state, frames);
        }
        cpu::ReferenceSettings rs;
        rs.method = cpu::ReferenceMethod::photon_mapping;
        rs.spp = args.get_int("ref-spp");
        rs.photons = args.get_int("ref-photons");
        rs.caustic_photons = rs.photons;
        rs.seed = scene.settings.seed;
        char hex[32];
        std::snprintf(hex, sizeof hex, "%016llx",
                      static_cast<unsigned long long>(state_hash(final_state, rs)));
        const std::string cache = args.get("cache");
        std::filesystem::create_directories(cache);
        reference_path = cache + "/" + name + "-" + hex + ".exr";
        if (!std::filesystem::exists(component_path(reference_path, "indirect"))) {
            std::cerr << "afterglow converge: rendering the pm reference of the final state ("
                      << rs.spp << " spp, " << rs.photons << " photons) into " << reference_path
                      << "\n";
            ThreadPool pool(threads);
            const cpu::ReferenceResult ref = cpu::render_reference(final_state, rs, pool);
            for (int c = 0; c < kFrameTermCount; ++c)
                write_image(ref.components[size_t(c)],
                            component_path(reference_path, kFrameTermNames[size_t(c)]));
            write_image(ref.full, reference_path);
        } else {
            std::cerr << "afterglow converge: reference from the cache: " << reference_path << "\n";
        }
    }
    const Image reference = read_image(component_path(reference_path, component));
    if (reference.width != width || reference.height != height)
        throw_input_error(component_path(reference_path, component), "",
                          "expected a " + std::to_string(width) + "x" + std::to_string(height) +
                              " image, got " + std::to_string(reference.width) + "x" +
                              std::to_string(reference.height));

    std::optional<Script> script;
    if (!script_path.empty()) script.emplace(script_path);
    auto context = gpu::make_gl_context(backend);
    Pipeline pipeline(
        scene, PipelineOptions{width, height, threads, PipelineMode(args.get_choice("baseline"))});

    std::ostringstream csv;
    csv << "method,frame,wall_s,frame_ms,edited,relmse,rmse,ssim,groups_invalidated,photons_"
           "retraced,"
           "aim_texels,iim_texels,iim_pending\n";
    Progress progress("converge", frames, !args.has("quiet"));
    std::vector<double> errors, times;
    std::vector<int> edited_frames;
    double wall = 0.0;
    FrameLoop loop(pipeline, script ? &*script : nullptr);
    loop.on_script_error = [](const std::string& message) { warn(message); };
    for (int f = 0; f < frames; ++f) {
        const Clock::time_point t0 = Clock::now();
        const PipelineStats st = loop.step();
        pipeline.sync();
        wall += std::chrono::duration<double>(Clock::now() - t0).count();
        // Metrics are taken outside the timed part.
        const gpu::FrameImages images = pipeline.images();
        const Image& test =
            component == "full" ? images.frame : images.aov[size_t(*parse_frame_term(component))];
        const ImageMetrics m = compare_images(test, reference);
        const bool edited = loop.edited();
        errors.push_back(m.rel_mse);
        times.push_back(wall);
        if (edited) edited_frames.push_back(f);
        csv << mode << ',' << f << ',' << wall << ',' << st.frame_ms << ',' << (edited ? 1 : 0)
            << ',' << m.rel_mse << ',' << m.rmse << ',' << m.ssim << ','
            << st.photons.groups_invalidated << ',' << st.photons.photons_retraced << ','
            << st.photons.aim_texels_rebuilt << ',' << st.iim_texels_gathered << ','
            << st.iim_texels_pending << "\n";
        progress.update(f + 1);
    }
    progress.finish();
    std::filesystem::create_directories(std::filesystem::absolute(csv_path).parent_path());
    write_file_atomically(csv_path, csv.str());

    // Settled value: the mean of the last tenth of the frames (at least 3).
    const size_t tail = std::max<size_t>(3, errors.size() / 10);
    double settled = 0.0;
    for (size_t i = errors.size() - std::min(tail, errors.size()); i < errors.size(); ++i)
        settled += errors[i];
    settled /= double(std::min(tail, errors.size()));
    const int last_edit = edited_frames.empty() ? 0 : edited_frames.back();
    int within = -1;
    for (int f = int(errors.size()) - 1; f >= last_edit; --f) {
        if (std::abs(errors[size_t(f)] - settled) > 0.1 * settled) break;
        within = f;
    }
    std::printf(
        "converge %s (%s, %s): %d frames, %.2f s; settled relMSE %.5f (%s); last edit at frame %d "
        "(%.2f s)\n",
        scene_path.c_str(), mode.c_str(), component.c_str(), frames, wall, settled,
        reference_path.c_str(), last_edit,
        last_edit < int(times.size()) ? times[size_t(last_edit)] : 0.0);
    if (within >= 0)
        std::printf(
            "within 10%% of the settled error from frame %d: %d frames, %.3f s after the last "
            "edit\n",
            within, within - last_edit, times[size_t(within)] - times[size_t(last_edit)]);
    else
        std::printf("the error did not settle within 10%% after the last edit\n");
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
