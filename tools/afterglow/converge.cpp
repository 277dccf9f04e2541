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
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/script.h"
#include "tools/afterglow/commands.h"
#include "tools/afterglow/pipeline.h"
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
        {"script", "", "S.lua", "scene-edit script (default: the scene's \"script\")"},
        {"reference", "", "REF.exr", "reference image (its .COMPONENT.exr beside it is used for --component)"},
        {"frames", "n", "N", "frames to run (default 120)"},
        {"size", "", "WxH", "image size (default 96x96)"},
        {"component", "", "NAME", "indirect (default), direct, caustics, specular or full"},
        {"baseline", "", "MODE", "selective (default) or full: recompute everything every frame"},
        {"csv", "", "FILE.csv", "where to write the per-frame record (default out/NAME.MODE.csv)"},
        {"plot", "", "FILE.png", "plot of error against time (default out/NAME.MODE.png); '' for none"},
        {"compare", "", "OTHER.csv", "also draw this run's CSV on the plot"},
        {"cache", "", "DIR", "reference cache (default out/reference-cache)"},
        {"ref-spp", "", "N", "samples per pixel of a computed reference (default 64)"},
        {"ref-photons", "", "N", "photons of a computed pm reference (default 400000)"},
        {"gl", "", "BACKEND", "osmesa (default), egl, auto"},
        {"gather", "", "BACKEND", "gl, cpu or auto (default: the scene's setting)"},
        {"threads", "", "N", "worker threads (default: settings.threads)"},
        {"quiet", "q", "", "no progress bar"},
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
        add(l.type), add(l.position), add(l.intensity), add(l.corners), add(l.radiance), add(l.enabled);
    }
    add(scene.camera.eye), add(scene.camera.target), add(scene.camera.up), add(scene.camera.fov_y);
    add(scene.camera.width), add(scene.camera.height);
    add(rs.method), add(rs.spp), add(rs.seed), add(rs.photons), add(rs.caustic_photons), add(rs.knn);
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
    const int frames = args.get_int("frames", 120, 1, 1000000);
    const std::string component = args.get("component", "indirect");
    if (component != "full" && !parse_frame_term(component))
        throw CliError("afterglow converge: --component expects full, direct, indirect, caustics or specular, got '" +
                       component + "'");
    const std::string mode = args.get("baseline", "selective");
    if (mode != "selective" && mode != "full")
        throw CliError("afterglow converge: --baseline expects selective or full, got '" + mode + "'");
    int width = 96, height = 96;
    if (args.has("size")) {
        char x = 0, extra = 0;
        if (std::sscanf(args.get("size").c_str(), "%d%c%d%c", &width, &x, &height, &extra) != 3 || x != 'x' ||
            width <= 0 || height <= 0 || width > 16384 || height > 16384)
            throw CliError("afterglow converge: --size expects WxH, got '" + args.get("size") + "'");
    }
    const gpu::GlBackend backend = [&] {
        try {
            return gpu::parse_gl_backend(args.get("gl", "osmesa"));
        } catch (const std::invalid_argument& e) {
            throw CliError(std::string("afterglow converge: --gl: ") + e.what());
        }
    }();

    const std::string scene_path = args.positionals()[0];
    Scene scene = load_scene(scene_path);
    scene.camera.width = width;
    scene.camera.height = height;
    if (args.has("gather")) {
        size_t i = 0;
        while (i < kGatherBackendNames.size() && args.get("gather") != kGatherBackendNames[i]) ++i;
        if (i == kGatherBackendNames.size()) throw CliError("afterglow converge: --gather expects gl, cpu or auto");
        scene.settings.gather.backend = GatherBackend(i);
    }
    const std::string script_path = args.get("script", scene.script);
    const std::string name = std::filesystem::path(scene_path).stem().string();
    const std::string csv_path = args.get("csv", "out/" + name + "." + mode + ".csv");
    const std::string plot_path = args.get("plot", "out/" + name + "." + mode + ".png");
    const int threads = args.get_int("threads", scene.settings.threads, 0, 1024);

    // The reference: given, or rendered for the scene's final state (the script run ahead on a
    // copy) and cached by a hash of that state.
    std::string reference_path = args.get("reference", "");
    if (reference_path.empty()) {
        Scene final_state = scene;
        if (!script_path.empty()) {
            Script ahead(script_path);
            ahead.on_start(final_state);
            for (int f = 0; f < frames; ++f) ahead.on_frame(final_state, f, f / 30.0);
        }
        cpu::ReferenceSettings rs;
        rs.method = cpu::ReferenceMethod::photon_mapping;
        rs.spp = args.get_int("ref-spp", 64, 1, 1000000);
        rs.photons = args.get_int("ref-photons", 400000, 1000, 100000000);
        rs.caustic_photons = rs.photons;
        rs.seed = scene.settings.seed;
        char hex[32];
        std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(state_hash(final_state, rs)));
        const std::string cache = args.get("cache", "out/reference-cache");
        std::filesystem::create_directories(cache);
        reference_path = cache + "/" + name + "-" + hex + ".exr";
        if (!std::filesystem::exists(component_path(reference_path, "indirect"))) {
            std::cerr << "afterglow converge: rendering the pm reference of the final state (" << rs.spp << " spp, "
                      << rs.photons << " photons) into " << reference_path << "\n";
            ThreadPool pool(threads);
            const cpu::ReferenceResult ref = cpu::render_reference(final_state, rs, pool);
            for (int c = 0; c < kFrameTermCount; ++c)
                write_image(ref.components[size_t(c)], component_path(reference_path, kFrameTermNames[size_t(c)]));
            write_image(ref.full, reference_path);
        } else {
            std::cerr << "afterglow converge: reference from the cache: " << reference_path << "\n";
        }
    }
    const Image reference = read_image(component_path(reference_path, component));
    if (reference.width != width || reference.height != height)
        throw_input_error(component_path(reference_path, component), "",
                          "expected a " + std::to_string(width) + "x" + std::to_string(height) + " image, got " +
                              std::to_string(reference.width) + "x" + std::to_string(reference.height));

    std::optional<Script> script;
    if (!script_path.empty()) script.emplace(script_path);
    auto context = gpu::make_gl_context(backend);
    const bool full = mode == "full";
    if (full) {
        // Brute force through the same pipeline: every photon, AIM surface and texel is redone
        // every frame (no selection, no blending).
        scene.settings.photons.retrace_budget = 1 << 30;
        scene.settings.aim.surfaces_per_frame = 1 << 30;
        scene.settings.aim.delta_threshold = 0.0f;
        scene.settings.gather.texels_per_frame = 1 << 30;
        scene.settings.gather.blend_frames = 1;
    }
    Pipeline pipeline(scene, width, height, threads);

    std::ostringstream csv;
    csv << "method,frame,wall_s,frame_ms,edited,relmse,rmse,ssim,groups_invalidated,photons_retraced,"
           "aim_texels,iim_texels,iim_pending\n";
    Progress progress("converge", frames, !args.has("quiet"));
    std::vector<double> errors, times;
    std::vector<int> edited_frames;
    double wall = 0.0;
    if (script) script->on_start(scene);
    for (int f = 0; f < frames; ++f) {
        const Clock::time_point t0 = Clock::now();
        pipeline.sync();
        const uint64_t before = scene.version;
        if (script && !script->on_frame(scene, f, f / 30.0)) warn(*script->last_error());
        const bool edited = scene.version != before;
        if (full)  // "moving" every light to where it is invalidates all of its photon groups
            for (int l = 0; l < int(scene.lights.size()); ++l)
                if (scene.lights[size_t(l)].enabled) set_light_position(scene, l, scene.lights[size_t(l)].center());
        const PipelineStats st = pipeline.frame();
        pipeline.sync();
        wall += std::chrono::duration<double>(Clock::now() - t0).count();
        // Metrics are taken outside the timed part.
        const gpu::FrameImages images = pipeline.images();
        const Image& test = component == "full" ? images.frame
                                                : images.aov[size_t(*parse_frame_term(component))];
        const ImageMetrics m = compare_images(test, reference);
        errors.push_back(m.rel_mse);
        times.push_back(wall);
        if (edited) edited_frames.push_back(f);
        csv << mode << ',' << f << ',' << wall << ',' << st.frame_ms << ',' << (edited ? 1 : 0) << ',' << m.rel_mse << ','
            << m.rmse << ',' << m.ssim << ',' << st.photons.groups_invalidated << ',' << st.photons.photons_retraced << ','
            << st.photons.aim_texels_rebuilt << ',' << st.iim_texels_gathered << ',' << st.iim_texels_pending << "\n";
        progress.update(f + 1);
    }
    progress.finish();
    std::filesystem::create_directories(std::filesystem::absolute(csv_path).parent_path());
    write_file_atomically(csv_path, csv.str());

    // Settled value: the mean of the last tenth of the frames (at least 3).
    const size_t tail = std::max<size_t>(3, errors.size() / 10);
    double settled = 0.0;
    for (size_t i = errors.size() - std::min(tail, errors.size()); i < errors.size(); ++i) settled += errors[i];
    settled /= double(std::min(tail, errors.size()));
    const int last_edit = edited_frames.empty() ? 0 : edited_frames.back();
    int within = -1;
    for (int f = int(errors.size()) - 1; f >= last_edit; --f) {
        if (std::abs(errors[size_t(f)] - settled) > 0.1 * settled) break;
        within = f;
    }
    std::printf("converge %s (%s, %s): %d frames, %.2f s; settled relMSE %.5f (%s); last edit at frame %d (%.2f s)\n",
                scene_path.c_str(), mode.c_str(), component.c_str(), frames, wall, settled, reference_path.c_str(),
                last_edit, last_edit < int(times.size()) ? times[size_t(last_edit)] : 0.0);
    if (within >= 0)
        std::printf("within 10%% of the settled error from frame %d: %d frames, %.3f s after the last edit\n", within,
                    within - last_edit, times[size_t(within)] - times[size_t(last_edit)]);
    else
        std::printf("the error did not settle within 10%% after the last edit\n");
    std::printf("wrote %s\n", csv_path.c_str());

    if (!plot_path.empty()) {
        std::string command = "/usr/bin/python3 tools/plot_convergence.py '" + plot_path + "' '" + csv_path + "'";
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
