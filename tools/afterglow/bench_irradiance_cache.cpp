#include "tools/afterglow/bench_irradiance_cache.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <optional>

#include "cpu/irradiance_cache_cpu.h"
#include "cpu/reference/reference.h"
#include "gpu/gl.h"
#include "gpu/gl_context.h"
#include "gpu/scene_meshes.h"
#include "shared/metrics.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/pipeline/irradiance_cache_method.h"
#include "shared/scene_file.h"
#include "shared/script.h"

namespace ag::cli {

namespace {

using Clock = std::chrono::steady_clock;

enum class Variant { temporal, per_frame, forever };
constexpr const char* kVariantNames[] = {"temporal", "per-frame", "forever"};

struct RcRun {
    uint64_t records_made = 0;
    size_t peak_records = 0;
    double gather_ms = 0.0, splat_ms = 0.0, scan_ms = 0.0, wall_s = 0.0;
    double flicker = 0.0;  // mean |I_t − I_{t−1}| / mean I over static pixels, indirect term
    std::vector<double> ref_rel_mse;      // per reference frame, indirect term
    std::vector<double> reprojected;      // per predicted record: |E_pred − E(t+1)| / E(t+1)
    std::vector<double> not_reprojected;  // |E(t) − E(t+1)| / E(t+1)
};

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}
double mean(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / double(v.size());
}

RcRun run_variant(const Scene& loaded, const std::string& script_path, Variant variant, int width,
                  int height, int frames, const std::vector<int>& ref_frames,
                  const std::vector<Image>& refs) {
    Scene scene = loaded;
    if (variant == Variant::forever) {
        scene.settings.rc.max_lifespan = 1 << 30;
        scene.settings.rc.temporal_accuracy = 1e6f;
    }
    PipelineOptions options{width, height};
    options.mode = variant == Variant::per_frame ? PipelineMode::full : PipelineMode::selective;
    Pipeline pipeline(scene, options);
    std::optional<Script> script;
    if (!script_path.empty()) script.emplace(script_path);
    FrameLoop loop(pipeline, script ? &*script : nullptr);
    auto* method = dynamic_cast<IrradianceCacheMethod*>(&pipeline.indirect());
    if (!method) throw CliError("afterglow bench irradiance_cache: the method is not in use");

    RcRun run;
    std::vector<glm::vec3> first_positions;
    std::vector<char> still;
    std::vector<double> change(size_t(width) * size_t(height), 0.0),
        level(size_t(width) * size_t(height), 0.0);
    Image previous;
    std::vector<IrradianceCacheMethod::Prediction> pending;
    std::vector<Bounds> dynamic_bounds;  // of the frame the predictions were made
    auto on_dynamic = [&](const glm::vec3& p) {
        for (const Bounds& b : dynamic_bounds)
            if (glm::all(glm::greaterThanEqual(p, b.min)) && glm::all(glm::lessThanEqual(p, b.max)))
                return true;
        return false;
    };
    const Clock::time_point t0 = Clock::now();
    for (int f = 0; f < frames; ++f) {
        loop.step();
        pipeline.sync();
        const IrradianceCacheStats& s = method->last_stats();
        run.records_made += uint64_t(s.added + s.replaced);
        run.peak_records = std::max(run.peak_records, method->records().size());
        run.gather_ms += s.gather_ms;
        run.splat_ms += s.splat_ms;
        run.scan_ms += s.scan_ms;
        // Table 5.1: last frame's predictions of this frame, against a gather now.
        if (!pending.empty()) {
            cpu::RayTracer rays(scene);
            ThreadPool pool(1);
            cpu::IrradianceGather gather(scene, rays, pool);
            const cpu::RecordRadiance radiance = method->radiance_source(scene, rays);
            cpu::RecordGatherOptions o = method->gather_options();
            for (size_t k = 0; k < pending.size(); ++k) {
                const IrradianceRecord& r = pending[k].record;
                // Records on a moving object stay where they were made (Gautron), so at t+1 they
                // float off its surface: they are replaced, not predicted.
                if (on_dynamic(r.position)) continue;
                const IrradianceRecord truth =
                    gather.gather_one({r.position, r.normal, pending[k].key}, radiance, o);
                const double e1 = luminance(truth.iim);
                if (e1 <= 1e-6) continue;
                run.reprojected.push_back(std::abs(luminance(pending[k].predicted) - e1) / e1);
                run.not_reprojected.push_back(std::abs(luminance(r.iim) - e1) / e1);
            }
            pending.clear();
        }
        if (variant == Variant::temporal && f % 20 == 5) {
            pending = method->last_predictions();
            dynamic_bounds.clear();
            for (const Object& o : scene.objects) {
                if (!o.dynamic) continue;
                Bounds b;
                for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
                const glm::vec3 skin(0.01f * scene.diagonal());
                b.min -= skin;
                b.max += skin;
                dynamic_bounds.push_back(b);
            }
        }

        const std::vector<SplatPixel> px = method->splat().read_gbuffer();
        if (first_positions.empty()) {
            for (const SplatPixel& p : px) first_positions.push_back(p.position);
            still.assign(px.size(), 1);
        }
        for (size_t i = 0; i < px.size(); ++i)
            if (!px[i].covered || px[i].position != first_positions[i]) still[i] = 0;
        const gpu::FrameImages images = pipeline.images();
        const Image& indirect = images.aov[size_t(FrameTerm::indirect)];
        if (previous.width == indirect.width) {
            // G-buffer rows are bottom-up, images top-down.
            for (int y = 0; y < height; ++y)
                for (int x = 0; x < width; ++x) {
                    const size_t i = size_t(height - 1 - y) * size_t(width) + size_t(x);
                    const double a = luminance(indirect.rgb(x, y)),
                                 b = luminance(previous.rgb(x, y));
                    change[i] += std::abs(a - b);
                    level[i] += a;
                }
        }
        previous = indirect;
        for (size_t k = 0; k < ref_frames.size(); ++k)
            if (ref_frames[k] == f) {
                const Image& ref = refs[k].width ? refs[k] : indirect;
                run.ref_rel_mse.push_back(compare_images(indirect, ref).rel_mse);
            }
    }
    run.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
    double c = 0.0, l = 0.0;
    for (size_t i = 0; i < still.size(); ++i)
        if (still[i]) c += change[i], l += level[i];
    run.flicker = l > 0.0 ? c / l : 0.0;
    return run;
}

}  // namespace

int bench_irradiance_cache(const Args& args, const std::string& scene_path, int width, int height) {
    auto context = gpu::make_gl_context(args.gl_backend());
    Scene scene = load_scene(scene_path);
    args.apply_settings(scene);
    scene.settings.indirect.method = IndirectMethodKind::irradiance_cache;
    // Every frame complete: what Table 5.2 times is the whole animation, not a progressive fill.
    scene.settings.rc.records_per_frame = 1 << 30;
    const int frames = args.get_int("frames", 400);
    const std::string script_path = scene.script;
    // References of the indirect term at a few frames: single-bounce pt for `direct` records.
    std::vector<int> ref_frames;
    for (int f : {frames / 4, frames / 2, 3 * frames / 4, frames - 1})
        if (f >= 1 && (ref_frames.empty() || ref_frames.back() != f)) ref_frames.push_back(f);
    std::vector<Image> refs(ref_frames.size());
    const int ref_spp = args.get_int("ref-spp", 64);
    {
        ThreadPool pool(args.get_int("threads", 0));
        for (size_t k = 0; k < ref_frames.size(); ++k) {
            Scene at = scene;
            if (!script_path.empty()) {
                Script ahead(script_path);
                run_script_ahead(ahead, at, ref_frames[k] + 1);
            }
            at.camera.width = width;
            at.camera.height = height;
            cpu::ReferenceSettings rs;
            rs.spp = ref_spp;
            rs.seed = 7;
            rs.indirect_bounces = scene.settings.rc.source == RcSource::direct ? 1 : -1;
            refs[k] = cpu::render_reference(at, rs, pool).components[size_t(FrameTerm::indirect)];
        }
    }
    std::printf(
        "%s, %dx%d, %d frames, rc.source %s, a %.2f, a^t %.3f, dt_max %d; references: pt "
        "%s at %d spp, frames",
        scene_path.c_str(), width, height, frames, kRcSourceNames[size_t(scene.settings.rc.source)],
        scene.settings.rc.accuracy, scene.settings.rc.temporal_accuracy,
        scene.settings.rc.max_lifespan,
        scene.settings.rc.source == RcSource::direct ? "--indirect-bounces 1" : "(all)", ref_spp);
    for (int f : ref_frames) std::printf(" %d", f);
    std::printf("\n");
    std::printf("%-10s %10s %8s %10s %9s %9s %8s %9s %10s\n", "variant", "records", "peak",
                "record_ms", "splat_ms", "scan_ms", "wall_s", "flicker", "relMSE");
    RcRun per_frame;
    for (Variant v : {Variant::per_frame, Variant::temporal, Variant::forever}) {
        const RcRun r = run_variant(scene, script_path, v, width, height, frames, ref_frames, refs);
        std::printf("%-10s %10llu %8zu %10.1f %9.1f %9.1f %8.2f %9.5f %10.5f\n",
                    kVariantNames[int(v)], (unsigned long long)r.records_made, r.peak_records,
                    r.gather_ms, r.splat_ms, r.scan_ms, r.wall_s, r.flicker, mean(r.ref_rel_mse));
        if (v == Variant::per_frame) per_frame = r;
        if (v != Variant::per_frame) {
            std::printf(
                "  against per-frame: %.2fx fewer records, record time %.2fx, flicker "
                "%.2fx, relMSE %.2fx (per reference frame:",
                double(per_frame.records_made) / double(std::max<uint64_t>(1, r.records_made)),
                per_frame.gather_ms / std::max(1e-9, r.gather_ms),
                r.flicker / std::max(1e-12, per_frame.flicker),
                mean(r.ref_rel_mse) / std::max(1e-12, mean(per_frame.ref_rel_mse)));
            for (size_t k = 0; k < r.ref_rel_mse.size(); ++k)
                std::printf(" %.4f/%.4f", r.ref_rel_mse[k],
                            k < per_frame.ref_rel_mse.size() ? per_frame.ref_rel_mse[k] : 0.0);
            std::printf(")\n");
        }
        if (v == Variant::temporal && !r.reprojected.empty())
            std::printf(
                "  Table 5.1, %zu records: reprojection error mean %.1f%%, median %.1f%%, "
                "max %.1f%%; without reprojection mean %.1f%%, median %.1f%%, max %.1f%%\n",
                r.reprojected.size(), 100.0 * mean(r.reprojected), 100.0 * median(r.reprojected),
                100.0 * *std::max_element(r.reprojected.begin(), r.reprojected.end()),
                100.0 * mean(r.not_reprojected), 100.0 * median(r.not_reprojected),
                100.0 * *std::max_element(r.not_reprojected.begin(), r.not_reprojected.end()));
    }
    return 0;
}

namespace {

// Relative RMS difference of two E/π images over the pixels where both are lit (luminance).
double relative_rms(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
        const double x = luminance(a[i]), y = luminance(b[i]);
        if (x <= 0.0 || y <= 0.0) continue;
        num += (x - y) * (x - y);
        den += y * y;
    }
    return den > 0.0 ? std::sqrt(num / den) : 0.0;
}

// GL rows bottom-up → top-down.
std::vector<glm::vec3> flip_rows(const std::vector<glm::vec3>& v, int width, int height) {
    std::vector<glm::vec3> out(v.size());
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            out[size_t(height - 1 - y) * size_t(width) + size_t(x)] =
                v[size_t(y) * size_t(width) + size_t(x)];
    return out;
}

}  // namespace

int bench_irradiance_cache_versus_cpu(const Args& args, const std::string& scene_path, int width,
                                      int height) {
    auto context = gpu::make_gl_context(args.gl_backend());
    Scene scene = load_scene(scene_path);
    args.apply_settings(scene);
    scene.settings.indirect.method = IndirectMethodKind::irradiance_cache;
    if (scene.settings.rc.source != RcSource::direct)
        throw CliError(
            "afterglow bench irradiance_cache --versus-cpu: compares single-bounce records (as "
            "Gautron's Table 4.2 does): add --set rc.source=direct");
    scene.settings.rc.records_per_frame = 1 << 30;
    scene.settings.rc.max_lifespan = 0;
    scene.camera.width = width;
    scene.camera.height = height;
    const float a = scene.settings.rc.accuracy;
    std::printf(
        "%s, %dx%d, a %.3f, %d x %d strata per record, rc.source direct, one thread for records; "
        "Gautron's Table 4.2 at 1000x1000: Sponza a 0.1, Radiance 645 s, splatting 13.7 s "
        "(47.1x); Sibenik a 0.15, 425 s, 14.3 s (29.7x)\n",
        scene_path.c_str(), width, height, a, scene.settings.rc.theta_strata,
        scene.settings.rc.phi_strata);

    // Ours: GL G-buffer, records where the GPU scan finds cache misses, GPU splat (twice: the
    // first frame builds the cache; the second splats the full cache once, as a still frame).
    const std::vector<glm::vec3> no_aim;
    // Wall times (ms) by phase, and the process's CPU time over the whole frame (every thread,
    // llvmpipe's included): on a shared machine the CPU time is the steadier measure of work.
    std::printf("%-22s %8s %11s %10s %10s %10s %9s %10s %9s\n", "", "records", "records_ms",
                "ms/record", "interp_ms", "total_ms", "speed-up", "cpu_ms", "speed-up");
    struct Row {
        int records = 0;
        double record_ms = 0.0, interp_ms = 0.0, cpu_ms = 0.0;
        double total() const { return record_ms + interp_ms; }
    };
    auto print = [&](const char* name, const Row& r, const Row* baseline) {
        std::printf("%-22s %8d %11.1f %10.3f %10.1f %10.1f %8.2fx %10.1f %8.2fx\n", name, r.records,
                    r.record_ms, r.record_ms / std::max(1, r.records), r.interp_ms, r.total(),
                    baseline ? baseline->total() / r.total() : 1.0, r.cpu_ms,
                    baseline ? baseline->cpu_ms / std::max(1e-9, r.cpu_ms) : 1.0);
    };
    auto cpu_ms_now = [] { return 1000.0 * double(std::clock()) / double(CLOCKS_PER_SEC); };

    cpu::RayTracer rays(scene);
    ThreadPool pool(1);
    cpu::IrradianceGather gather(scene, rays, pool);
    const gpu::SceneMeshes meshes(scene);
    std::vector<glm::vec3> gpu_term;
    std::vector<IrradianceRecord> gpu_records;
    std::vector<SplatPixel> gl_pixels;  // the GL G-buffer, rows top-down
    double gpu_splat_ms = 0.0;
    Row ours[2];
    for (int scan = 0; scan < 2; ++scan) {
        Scene s = scene;
        s.settings.rc.scan = scan == 0 ? RcScan::gpu : RcScan::cpu;
        IrradianceCacheMethod method(s, meshes, no_aim, width, height);
        PipelineStats stats;
        IndirectInputs in;
        const double c0 = cpu_ms_now();
        const Clock::time_point t0 = Clock::now();
        method.update(in, stats);
        gpu::gl::Finish();
        const double wall = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        ours[scan].cpu_ms = cpu_ms_now() - c0;
        const IrradianceCacheStats first = method.last_stats();
        ours[scan].records = first.records;
        ours[scan].record_ms = first.gather_ms;
        ours[scan].interp_ms = wall - first.gather_ms;  // G-buffer, splats, scans, normalise
        if (scan == 0) {
            in.frame = 1;
            method.update(in, stats);
            gpu_splat_ms = method.last_stats().splat_ms;
            gpu_term = flip_rows(method.splat().read_term(), width, height);
            gpu_records = method.records();
            const std::vector<SplatPixel> up = method.splat().read_gbuffer();
            gl_pixels.resize(up.size());
            for (int y = 0; y < height; ++y)
                for (int x = 0; x < width; ++x)
                    gl_pixels[size_t(height - 1 - y) * size_t(width) + size_t(x)] =
                        up[size_t(y) * size_t(width) + size_t(x)];
        }
    }
    const cpu::RecordGatherOptions options = [&] {
        IrradianceCacheMethod m(scene, meshes, no_aim, 8, 8);
        return m.gather_options();
    }();
    const cpu::RecordRadiance radiance =
        cpu::direct_radiance_source(scene, rays, scene.settings.rc.shadow_samples);
    const double c1 = cpu_ms_now();
    const Clock::time_point t1 = Clock::now();
    const cpu::CpuCacheFrame cpu_frame =
        cpu::render_irradiance_cache_cpu(scene, rays, gather, radiance, options, a, width, height);
    const double cpu_wall = std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
    Row radiance_row;
    radiance_row.records = int(cpu_frame.records.size());
    radiance_row.record_ms = cpu_frame.record_ms;
    radiance_row.interp_ms = cpu_wall - cpu_frame.record_ms;  // eye rays, lookups, inserts
    radiance_row.cpu_ms = cpu_ms_now() - c1;
    print("CPU (Radiance's way)", radiance_row, nullptr);
    print("GL splat, GPU scan", ours[0], &radiance_row);
    print("GL splat, CPU scan", ours[1], &radiance_row);
    {
        // Radiance's way on the GL G-buffer's points and normals: tells whether a difference in
        // record cost comes from the points gathered at or from the path around the gather.
        const double c = cpu_ms_now();
        const Clock::time_point t = Clock::now();
        const cpu::CpuCacheFrame g = cpu::render_irradiance_cache_cpu(
            scene, gl_pixels, gather, radiance, options, a, width, height);
        Row row;
        row.records = int(g.records.size());
        row.record_ms = g.record_ms;
        row.interp_ms =
            std::chrono::duration<double, std::milli>(Clock::now() - t).count() - g.record_ms;
        row.cpu_ms = cpu_ms_now() - c;
        print("CPU, GL G-buffer", row, &radiance_row);
    }

    // The same records (the GPU scan's) interpolated both ways.
    const std::vector<SplatPixel> eye = cpu::eye_ray_pixels(scene, rays, width, height);
    const Clock::time_point t2 = Clock::now();
    const std::vector<glm::vec3> cpu_same = cpu::interpolate_cpu(scene, gpu_records, eye, a);
    const double cpu_interp_ms =
        std::chrono::duration<double, std::milli>(Clock::now() - t2).count();
    std::printf(
        "same %zu records, interpolation alone: CPU octree lookups %.1f ms, GL G-buffer + splat "
        "%.1f ms (%.2fx); eye rays %.1f ms\n",
        gpu_records.size(), cpu_interp_ms, gpu_splat_ms,
        cpu_interp_ms / std::max(1e-9, gpu_splat_ms), cpu_frame.eye_ms);
    std::printf(
        "E/pi relative RMS: CPU (own records) vs GL splat %.4f; CPU interpolation of the GL "
        "records vs GL splat %.4f\n",
        relative_rms(cpu_frame.term, gpu_term), relative_rms(cpu_same, gpu_term));
    return 0;
}

}  // namespace ag::cli
