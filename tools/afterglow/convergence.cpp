// Convergence runs (convergence.h): the cached pm reference of a final state, a progressive run
// with the error after every frame, and the settle rule.
#include "tools/afterglow/convergence.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "cpu/reference/reference.h"
#include "shared/frame_terms.h"
#include "shared/input_error.h"
#include "shared/metrics.h"
#include "shared/parallel.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/script.h"

namespace ag::cli {

namespace {

using Clock = std::chrono::steady_clock;

uint64_t fnv1a(uint64_t h, const void* data, size_t n) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

// A hash of everything the reference image depends on: geometry, texture coordinates, materials
// (albedo textures and glass interiors included) and transforms, lights, media, camera and the
// reference settings.
uint64_t state_hash(const Scene& scene, const cpu::ReferenceSettings& rs) {
    uint64_t h = 1469598103934665603ull;
    auto add = [&](const auto& v) { h = fnv1a(h, &v, sizeof v); };
    auto add_noise = [&](const MediumNoise& n) { add(n.amplitude), add(n.frequency), add(n.seed); };
    auto add_medium = [&](const Medium& m) {
        add(m.bounds.min), add(m.bounds.max), add(m.sigma_s), add(m.sigma_a), add(m.phase_k);
        add_noise(m.noise);
    };
    for (const Object& o : scene.objects) {
        h = fnv1a(h, o.mesh.positions.data(), o.mesh.positions.size() * sizeof(glm::vec3));
        h = fnv1a(h, o.mesh.triangles.data(), o.mesh.triangles.size() * sizeof(glm::uvec3));
        h = fnv1a(h, o.mesh.texcoords.data(), o.mesh.texcoords.size() * sizeof(glm::vec2));
        add(o.transform.translation), add(o.transform.rotation);
        add(o.material.type), add(o.material.albedo), add(o.material.ior), add(o.material.emission);
        add(o.material.emits_light);
        if (const Texture* t = o.material.albedo_map.get()) {
            add(t->width), add(t->height);
            h = fnv1a(h, t->texels.data(), t->texels.size() * sizeof(glm::vec3));
        }
        add(o.material.has_interior);
        if (o.material.has_interior) add_medium(o.material.interior);
        add_noise(o.material.ior_noise);
    }
    for (const Light& l : scene.lights) {
        add(l.type), add(l.position), add(l.intensity), add(l.corners), add(l.radiance),
            add(l.enabled), add(l.direction), add(l.irradiance), add(l.cone_inner),
            add(l.cone_outer), add(l.object);
    }
    for (const Medium& m : scene.media) add_medium(m);
    add(scene.camera.eye), add(scene.camera.target), add(scene.camera.up), add(scene.camera.fov_y);
    add(scene.camera.width), add(scene.camera.height);
    add(rs.method), add(rs.spp), add(rs.seed), add(rs.photons), add(rs.caustic_photons),
        add(rs.knn);
    add(rs.caustic_knn), add(rs.gather_rays), add(rs.area_light_samples), add(rs.max_depth);
    add(rs.indirect_bounces), add(rs.volume_bounces), add(rs.light_tracing), add(rs.light_paths);
    return h;
}

// What this build's reference renderer makes of `scene`: a hash of a small render of it (8 × 8
// pixels at the image's centre, one sample each, a few thousand photons or light paths), with
// `rs`'s method and settings otherwise. Part of a cached reference's name, so a cache filled by
// another build whose renderer draws differently is not read back (the name held no trace of the
// renderer: session 25 measured cornell's continuous move at a tracking area of 0.22 against a
// cache of unknown age, where references rendered by this build give 0.05). Deterministic on any
// thread count (the renderer's samples depend on the pixel only); memoised per scene state.
uint64_t renderer_fingerprint(const Scene& scene, const cpu::ReferenceSettings& rs, int threads) {
    cpu::ReferenceSettings probe = rs;
    probe.spp = 1;
    probe.time_limit = 0.0;
    probe.photons = probe.caustic_photons = 4000;
    probe.light_paths = 4096;
    const int w = std::min(8, scene.camera.width), hgt = std::min(8, scene.camera.height);
    probe.region = {(scene.camera.width - w) / 2, (scene.camera.height - hgt) / 2, w, hgt};
    const uint64_t key = state_hash(scene, probe);
    static std::mutex mutex;
    static std::map<uint64_t, uint64_t> known;
    {
        std::lock_guard lock(mutex);
        if (auto it = known.find(key); it != known.end()) return it->second;
    }
    ThreadPool pool(threads);
    const cpu::ReferenceResult r = cpu::render_reference(scene, probe, pool);
    uint64_t h = 1469598103934665603ull;
    h = fnv1a(h, r.full.pixels.data(), r.full.pixels.size() * sizeof(float));
    for (const Image& c : r.components)
        h = fnv1a(h, c.pixels.data(), c.pixels.size() * sizeof(float));
    std::lock_guard lock(mutex);
    known[key] = h;
    return h;
}

}  // namespace

std::string component_path(const std::string& exr, const std::string& component) {
    if (component == "full") return exr;
    const std::filesystem::path p(exr);
    return (p.parent_path() / (p.stem().string() + "." + component + ".exr")).string();
}

std::string cached_reference(const Scene& scene, const std::string& script_path, int frames,
                             const ReferenceRequest& request) {
    Scene final_state = scene;
    if (!script_path.empty()) {
        Script ahead(script_path);
        run_script_ahead(ahead, final_state, frames);
    }
    cpu::ReferenceSettings rs;
    rs.method = request.path_traced ? cpu::ReferenceMethod::path_tracing
                                    : cpu::ReferenceMethod::photon_mapping;
    rs.spp = request.spp;
    rs.photons = request.photons;
    rs.indirect_bounces = request.indirect_bounces;
    rs.caustic_photons = rs.photons;
    rs.seed = scene.settings.seed;
    // The state before the script's edits probes the renderer: one probe per scene and run.
    const uint64_t key =
        state_hash(final_state, rs) ^ (renderer_fingerprint(scene, rs, request.threads) * 31);
    char hex[32];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(key));
    std::filesystem::create_directories(request.cache);
    const std::string reference_path = request.cache + "/" + request.name + "-" + hex + ".exr";
    if (!std::filesystem::exists(component_path(reference_path, "indirect"))) {
        std::cerr << request.log_prefix << ": rendering the "
                  << cpu::kReferenceMethodNames[size_t(rs.method)] << " reference of the state ("
                  << rs.spp << " spp";
        if (!request.path_traced) std::cerr << ", " << rs.photons << " photons";
        if (rs.indirect_bounces >= 0) std::cerr << ", " << rs.indirect_bounces << " bounce(s)";
        std::cerr << ") into " << reference_path << "\n";
        ThreadPool pool(request.threads);
        const cpu::ReferenceResult ref = cpu::render_reference(final_state, rs, pool);
        for (int c = 0; c < kFrameTermCount; ++c)
            write_image(ref.components[size_t(c)],
                        component_path(reference_path, kFrameTermNames[size_t(c)]));
        write_image(ref.full, reference_path);
    } else {
        std::cerr << request.log_prefix << ": reference from the cache: " << reference_path << "\n";
    }
    return reference_path;
}

Image read_reference(const std::string& reference_path, const std::string& component, int width,
                     int height) {
    const std::string path = component_path(reference_path, component);
    Image reference = read_image(path);
    if (reference.width != width || reference.height != height)
        throw_input_error(path, "",
                          "expected a " + std::to_string(width) + "x" + std::to_string(height) +
                              " image, got " + std::to_string(reference.width) + "x" +
                              std::to_string(reference.height));
    return reference;
}

SettleAnalysis analyse_settle(const std::vector<FrameRecord>& frames, double target,
                              double first_start_s) {
    SettleAnalysis a;
    if (frames.empty()) return a;
    const size_t n = frames.size();
    // Settled value: the converged state's error, else the mean of the last tenth of the frames
    // (at least 3).
    const size_t tail = std::min(n, std::max<size_t>(3, n / 10));
    for (size_t i = n - tail; i < n; ++i) a.settled += frames[i].relmse;
    a.settled /= double(tail);
    if (target > 0.0) a.settled = target;
    for (size_t i = 0; i < n; ++i)
        if (frames[i].edited) {
            if (a.first_edit < 0) a.first_edit = int(i);
            a.last_edit = int(i);
        }
    for (int f = int(n) - 1; f >= a.last_edit; --f) {
        if (std::abs(frames[size_t(f)].relmse - a.settled) > 0.1 * a.settled) break;
        a.within = f;
    }
    if (a.within >= 0) {
        a.frames = a.within - a.last_edit;
        a.seconds = frames[size_t(a.within)].wall_s -
                    frame_start_s(frames, size_t(a.last_edit), first_start_s);
    }
    return a;
}

ConvergenceRun run_convergence(Scene scene, const std::string& script_path, PipelineMode mode,
                               int frames, int width, int height, const std::string& component,
                               const Image& reference, int threads, bool prime,
                               const std::function<void(int)>& on_frame, int lead_in) {
    return run_convergence(
        std::move(scene), script_path, mode, frames, width, height, component,
        [&](int) -> const Image& { return reference; }, threads, prime, on_frame, {}, lead_in);
}

ConvergenceRun run_convergence(Scene scene, const std::string& script_path, PipelineMode mode,
                               int frames, int width, int height, const std::string& component,
                               const ReferenceAt& reference_at, int threads, bool prime,
                               const std::function<void(int)>& on_frame,
                               const std::function<void(int, const Image&)>& on_image,
                               int lead_in) {
    scene.camera.width = width;
    scene.camera.height = height;
    // Each frame is scored as drawn, one sample at each pixel centre: a running mean of
    // sub-pixel offsets (frame.accumulate_frames) would add its own convergence after the method
    // settles, and the reference's pixel filter is not what these curves measure.
    scene.settings.frame.accumulate_frames = 1;
    const std::optional<FrameTerm> term =
        component == "full" ? std::nullopt : parse_frame_term(component);
    std::optional<Script> script;
    if (!script_path.empty()) script.emplace(script_path);
    Pipeline pipeline(scene, PipelineOptions{width, height, threads, mode});
    // Untimed: start from the converged state of frame 0, where a user would make the edit.
    if (prime) pipeline.prime();

    ConvergenceRun run;
    run.mode = mode;
    run.indirect = scene.settings.indirect.method;
    run.component = component;
    run.frames.reserve(size_t(frames));
    double wall = 0.0;
    FrameLoop loop(pipeline, script ? &*script : nullptr);
    loop.on_script_error = [](const std::string& message) { warn(message); };
    for (int f = 0; f < lead_in; ++f) loop.step(/*play=*/false);  // untimed, before the script
    pipeline.sync();
    for (int f = 0; f < frames; ++f) {
        const Clock::time_point t0 = Clock::now();
        const PipelineStats st = loop.step();
        const Clock::time_point t1 = Clock::now();
        wall += std::chrono::duration<double>(t1 - t0).count();
        // Metrics are taken outside the timed part. Photon work that runs on past the frame
        // (a frame-time target) goes on meanwhile: that time is counted, or it would be free.
        const bool busy = pipeline.workers_busy();
        const bool pipeline_converged = pipeline.converged();
        const gpu::FrameImages images = pipeline.images();
        const Image& test = term ? images.aov[size_t(*term)] : images.frame;
        const ImageMetrics m = compare_images(test, reference_at(f));
        const Clock::time_point t2 = Clock::now();
        if (busy) wall += std::chrono::duration<double>(t2 - t1).count();
        FrameRecord r;
        r.frame = f;
        r.wall_s = wall;
        r.frame_ms = st.frame_ms;
        r.edited = loop.edited();
        r.relmse = m.rel_mse, r.rmse = m.rmse, r.ssim = m.ssim;
        r.groups_invalidated = uint64_t(st.photons.groups_invalidated);
        r.photons_retraced = uint64_t(st.photons.photons_retraced);
        r.aim_texels = uint64_t(st.photons.aim_texels_rebuilt);
        r.iim_texels = st.iim_texels_gathered;
        r.iim_pending = st.iim_texels_pending;
        r.rays_traced = st.gather_rays - st.gather_rays_reused;
        r.rays_reused = st.gather_rays_reused;
        r.workers_behind = st.workers_behind;
        r.gather_ms = st.gather_ms, r.draw_ms = st.draw_ms, r.wait_ms = st.wait_ms;
        r.gather_plan_ms = st.budget_gather_ms;
        r.photon_ms = st.photon_ms, r.aim_ms = st.aim_ms;
        r.early_hand_over = st.early_hand_over;
        r.caustics_draw_ms = st.caustics_draw_ms;
        r.faces_relit = st.cube_faces_relit;
        r.photons_grown = uint64_t(st.photons.photons_grown);
        // A frame whose workers handed nothing over has no photon frame (frame 0): the sets are
        // what the last hand-over left.
        r.layers = st.photons.frame > 0 || run.frames.empty() ? st.photons.layers
                                                              : run.frames.back().layers;
        r.converged = pipeline_converged;
        run.frames.push_back(r);
        if (on_image) on_image(f, test);
        if (on_frame) on_frame(f + 1);
        if (busy) wall += std::chrono::duration<double>(Clock::now() - t2).count();
    }
    run.wall_s = wall;
    run.settle = analyse_settle(run.frames);
    return run;
}

double resident_bytes() {
    std::ifstream statm("/proc/self/statm");  // size resident shared ..., in pages
    long long size = 0, resident = 0;
    statm >> size >> resident;
    return double(resident) * double(sysconf(_SC_PAGESIZE));
}

double mean(const std::vector<double>& v) {
    if (v.empty()) return 0.0;
    double s = 0.0;
    for (double x : v) s += x;
    return s / double(v.size());
}

double p95(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t i = size_t(std::ceil(0.95 * double(v.size()))) - 1;
    return v[std::min(i, v.size() - 1)];
}

double converged_error(const Scene& scene, const std::string& script_path, int frames, int width,
                       int height, const std::string& component, const Image& reference,
                       int threads, const Image* mask) {
    Scene final_state = scene;
    if (!script_path.empty()) {
        Script ahead(script_path);
        run_script_ahead(ahead, final_state, frames);
    }
    final_state.camera.width = width;
    final_state.camera.height = height;
    // Scored as the runs are: single frames. Priming draws frames until the pipeline converges;
    // with nothing changing between them the frame would average sub-pixel offsets, and the
    // settled value would be lower than any single frame of a run can reach.
    final_state.settings.frame.accumulate_frames = 1;
    const std::optional<FrameTerm> term =
        component == "full" ? std::nullopt : parse_frame_term(component);
    Pipeline pipeline(final_state,
                      PipelineOptions{width, height, threads, PipelineMode::selective});
    pipeline.prime();
    const gpu::FrameImages images = pipeline.images();
    return compare_images(term ? images.aov[size_t(*term)] : images.frame, reference, mask).rel_mse;
}

Image changed_region(const Image& before, const Image& after, double fraction) {
    if (before.width != after.width || before.height != after.height)
        throw std::invalid_argument("changed_region: the images differ in size");
    double mean = 0.0;
    for (int y = 0; y < after.height; ++y)
        for (int x = 0; x < after.width; ++x) mean += double(luminance(after.rgb(x, y)));
    mean /= std::max(1.0, double(after.width) * double(after.height));
    Image mask(after.width, after.height, 1);
    for (int y = 0; y < after.height; ++y)
        for (int x = 0; x < after.width; ++x) {
            const double a = luminance(before.rgb(x, y)), b = luminance(after.rgb(x, y));
            const double larger = std::max(a, b);
            if (larger > 0.01 * mean && std::abs(b - a) > fraction * larger)
                mask.at(x, y)[0] = 1.0f;
        }
    return mask;
}

std::string convergence_csv(const ConvergenceRun& run) {
    std::ostringstream csv;
    csv << "method,frame,wall_s,frame_ms,edited,relmse,rmse,ssim,groups_invalidated,photons_"
           "retraced,aim_texels,iim_texels,iim_pending,rays_traced,rays_reused,workers_behind,"
           "gather_ms,draw_ms,wait_ms,"
           "gather_plan_ms,photon_ms,aim_ms,early_hand_over,photons_grown,layers,converged,"
           "caustics_draw_ms,faces_relit\n";
    // The pipeline mode names the IIM's runs; another indirect method's curve is named after it
    // (and its mode, unless selective) so both join one methods plot.
    std::string method = kPipelineModeNames[size_t(run.mode)];
    if (run.indirect != IndirectMethodKind::iim)
        method = std::string(kIndirectMethodNames[size_t(run.indirect)]) +
                 (run.mode == PipelineMode::selective ? "" : "-" + method);
    for (const FrameRecord& r : run.frames)
        csv << method << ',' << r.frame << ',' << r.wall_s << ',' << r.frame_ms << ','
            << (r.edited ? 1 : 0) << ',' << r.relmse << ',' << r.rmse << ',' << r.ssim << ','
            << r.groups_invalidated << ',' << r.photons_retraced << ',' << r.aim_texels << ','
            << r.iim_texels << ',' << r.iim_pending << ',' << r.rays_traced << ',' << r.rays_reused
            << ',' << (r.workers_behind ? 1 : 0) << ',' << r.gather_ms << ',' << r.draw_ms << ','
            << r.wait_ms << ',' << r.gather_plan_ms << ',' << r.photon_ms << ',' << r.aim_ms << ','
            << (r.early_hand_over ? 1 : 0) << ',' << r.photons_grown << ',' << r.layers << ','
            << (r.converged ? 1 : 0) << ',' << r.caustics_draw_ms << ',' << r.faces_relit << "\n";
    return csv.str();
}

}  // namespace ag::cli
