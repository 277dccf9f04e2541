// afterglow bench photons|knn: measured speeds, with the ratios that matter taken in one run.
#include <chrono>
#include <cstdio>
#include <random>

#include "cpu/aim.h"
#include "cpu/caustic_tracer.h"
#include "cpu/cpu_gather.h"
#include "cpu/knn.h"
#include "cpu/photon_simulation.h"
#include "gpu/caustics_renderer.h"
#include "gpu/frame_renderer.h"
#include "gpu/gl.h"
#include "gpu/gl_context.h"
#include "gpu/hemi_plane_gather.h"
#include "gpu/lightmap_texture.h"
#include "gpu/scene_meshes.h"
#include "shared/charts.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/qmc.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/shapes.h"
#include "tools/afterglow/bench_gpu_pm.h"
#include "tools/afterglow/bench_irradiance_cache.h"
#include "tools/afterglow/bench_media.h"
#include "tools/afterglow/bench_soak.h"
#include "tools/afterglow/bench_vpl.h"
#include "tools/afterglow/commands.h"
#include "tools/afterglow/convergence.h"

namespace ag::cli {

const Command kBenchCommand{
    "bench",
    "photons|knn|gather|frame|caustics|settle|soak|gpu_pm|vpl|irradiance_cache|media [SCENE...|"
    "SCENE:SCRIPT...] [options]",
    "Benchmarks. 'photons SCENE': photon throughput with all bookkeeping against raw Embree rays "
    "for the same paths, on one thread, and memory per stored hit. 'knn': Larsen Table 8.1 "
    "(1,000,000 random photons in 1/10/100/1,000 maps; build and 500-nearest lookup) and Table "
    "14.1 (300–2,000 photons; build and 100-nearest lookup). 'gather SCENE...': Larsen Table 14.2, "
    "ms per gathered texel for plane sizes 8/16/32, GL batched and unbatched against CPU rays. "
    "'frame SCENE': frames per second of the whole pipeline (mean frame time of the best of "
    "--repeat runs, and its p95), static and with the first dynamic object moving every frame "
    "(--indirect picks the method). 'caustics SCENE': caustic photons "
    "traced per second per core and "
    "the share reaching a specular object; the screen filter over the whole screen against "
    "tile-culled filtering for a caustic covering about 1% and 5% of it (Larsen: 37.6 ms against "
    "0.38 ms for 1% of 512²). 'settle [SCENE:SCRIPT...]': for each scene and edit script "
    "(default: a ladder from cornell to conference), selective, full and full-budget at the same "
    "--frame-ms (default 33): frames and seconds from the edit until the indirect error is back "
    "within 10% of its settled value, frame times, work done, the area under the error curve and "
    "selective's speed-up over full-budget; a table, a CSV and a log-log plot of settle time "
    "against triangles (docs/convergence.md). 'soak [SCENE]': --frames frames (default 100000) "
    "of random edits (every dynamic object moved near its start and the first light's colour "
    "toggled, every frame) at --size N (default 64); RSS, frame time and the scene's change log "
    "sampled into --csv (default out/bench-soak.csv), growth from frame min(10000, N/10) to the "
    "end reported (docs/robustness.md). 'gpu_pm [SCENE]': Jimenez Kwast's Table 6.1 grid for "
    "--indirect gpu_pm (--paths x --radii, radius as a fraction of the scene diagonal) at --size "
    "(default 256x256): stored photons, frame time mean and sigma over --frames (default 20), "
    "pixels refined at full resolution, and with --reference the 8-bit MSE, NRMSE and MSSIM of the "
    "frame; --budget MS searches the paths of each radius for a fixed time (Table 6.2), "
    "reporting whether it held within --budget-tolerance; "
    "--no-direct times the method alone (docs/gpu_pm.md). 'vpl [SCENE]': Barczak 2006's claims on "
    "the VPL path "
    "at --size (default 256x192): 300 VPLs naive (every shadow map and every pixel) against K = "
    "150/100/50 map updates a frame, static maps, no visibility and exact CPU rays; fps against "
    "25-1000 VPLs; shadow-map cost against a mover's vertex count; the thesis's table rooms "
    "(SCENE's folder: vpl_table_bunny.json, vpl_table_torus.json) with the mover sliding, "
    "100-300 VPLs, all maps against K = 150/100/50 a frame (--rooms: only these) (docs/vpl.md). "
    "'irradiance_cache [SCENE]' (default "
    "scenes/cube_in_a_box.json): Gautron 2006 Tables 5.1 and 5.2 at --size WxH (default 128x128) "
    "over --frames (default 400): temporal radiance caching as the scene sets it against a new "
    "cache every frame and records kept forever; records made, record, splat and scan time, "
    "flicker over static pixels, indirect relMSE against pt references (--ref-spp) at four frames, "
    "the reprojection error (docs/irradiance_cache.md). 'media [SCENE]' (default "
    "scenes/media_glass_fog_point.json): Pfeuti 2009 at --size (default 48x48) and --grid "
    "(default 64): the reference and adaptive pipelines' RMSE against a --ref-photons (default "
    "2M marched) reference at doubling photon counts and the photons each needs at equal RMSE, "
    "Table 4.2's passes, Table 4.1's sampling orders, Table 4.5's uniform / adaptive / "
    "complement marching, his octree against fixed steps; --full: 128^3, one more count each and "
    "Tables 4.3/4.4 on our cube and bunny scenes (docs/media.md).",
    {
        integer("repeat", "N", "repetitions, best time kept", 1, 1000, 5),
        integer("queries", "N", "kNN queries per measurement", 1, 100000000, 2000),
        gl_option({gpu::GlBackend::osmesa, gpu::GlBackend::egl, gpu::GlBackend::automatic},
                  gpu::GlBackend::osmesa),
        integer("frames", "N",
                "frames per measurement for 'frame' (default 100), frames per run for 'settle' "
                "(default 90) and 'soak' (default 100000)",
                1, 100000),
        text("size", "N|WxH",
             "frame size: square N for 'frame' and 'caustics' (at least 64 there; default 512) "
             "and 'soak' (default 64), WxH for 'settle' (default 64x64)"),
        gather_option(),
        indirect_option(),
        frame_ms_option(),
        settings_option(),
        integer("threads", "N", "worker threads for 'settle' (default: settings.threads)", 0, 1024),
        text("csv", "FILE.csv",
             "'settle': the table as CSV (default out/bench-settle.csv); 'soak': the samples "
             "(default out/bench-soak.csv)"),
        text("plot", "FILE.png", "'settle': settle time against triangles, log-log; '' for none",
             "out/bench-settle.png"),
        text("cache", "DIR", "'settle': reference cache", "out/reference-cache"),
        integer("ref-spp", "N", "'settle': samples per pixel of a computed reference", 1, 1000000,
                64),
        integer("ref-photons", "N",
                "'settle': photons of a computed pm reference; 'media': photons marched for "
                "the reference (default 2000000)",
                1000, 100000000, 400000),
        flag("quick", "'settle': only the cornell scene (for tests)"),
        integer("phases", "K",
                "'settle': run each entry K times, the script starting 0, S, 2S, ... untimed "
                "frames after priming (S = --phase-step), so that full-budget meets the edit at "
                "K points of its round-robin sweep; prints the median speed-up",
                1, 100, 1),
        integer("phase-step", "S", "'settle': frames between the phases' starts", 1, 1000, 1),
        integer("track-every", "K",
                "'settle': also score every K-th frame against the reference of its own state "
                "and report the area under that error (how far the light lags a continuous move); "
                "0 = off (default: 4 for the ladder's continuous move, else off)",
                0, 1000, 0),
        number("changed-region", "T",
               "'settle': score only the pixels whose reference indirect light the script changes "
               "by more than the fraction T (the pm references of the state after the script's "
               "first frame and of the final state; default: the whole image)",
               0.001, 10.0),
        text("modes", "LIST",
             "'settle': the modes to run, comma-separated (selective, full, full-budget); "
             "selective's speed-up needs full-budget",
             "selective,full,full-budget"),
        text("paths", "LIST", "'gpu_pm': photon paths per frame, comma-separated",
             "500,1000,2500,5000,7500"),
        text("radii", "LIST", "'gpu_pm': radii as fractions of the scene diagonal, comma-separated",
             "0.0125,0.025,0.05,0.075,0.1"),
        text("reference", "REF.exr", "'gpu_pm': reference frame for the 8-bit metrics"),
        number("budget", "MS",
               "'gpu_pm': Table 6.2: per radius of --radii, the paths per frame that make the "
               "method's own time (G-buffer, photons, binning, estimate) about MS milliseconds",
               0.001, 1e6),
        number(
            "budget-tolerance", "FRAC",
            "'gpu_pm': --budget: a probe holds the budget when within +-FRAC of it (default "
            "0.1); a count holds when two of its probes are within it (at most 12 probes a radius)",
            0.001, 1.0),
        integer("budget-frames", "N",
                "'gpu_pm': --budget: frames per probe, whose median is its time (default 9)", 1,
                10000),
        flag("rooms", "'vpl': only the thesis's table rooms (bunny, torus) with a sliding mover"),
        flag("no-direct",
             "'gpu_pm': time the method alone (no direct light or compose; no frame metrics)"),
        integer("grid", "N", "'media': voxels along the grid's longest side (default 64)", 4, 512),
        flag("full", "'media': a 128^3 grid (his), one more photon count each, Tables 4.3/4.4"),
        integer("seeds", "N",
                "'media': each adaptive row of the equal-RMSE curve at seeds 0..N-1 (pilot jitter, "
                "Hammersley rotation), its RMSE the root mean square over them (default 1)",
                1, 256),
        flag("curve-only", "'media': the equal-RMSE curve alone (no Tables 4.1-4.5, no octree)"),
        flag("integer-level",
             "'media': the adaptive pipeline with his integer weight level (before session 14)"),
        flag("constant-density",
             "'media': the adaptive pipeline with his piecewise-constant photon density (before "
             "session 15)"),
        flag("versus-cpu",
             "'irradiance_cache': Gautron's Table 4.2 without Radiance: one frame by a CPU "
             "irradiance cache in Radiance's manner (eye rays, octree lookups, records on a miss) "
             "against GL splatting, same records gather and a (needs rc.source direct)"),
        flag("no-prime",
             "'settle': start each run from nothing instead of the converged state of frame 0"),
    },
    1,
    16,
};

namespace {

using Clock = std::chrono::steady_clock;

// --size: N (square) or WxH, positive integers up to kMaxImageSize; absent: the fallback.
void bench_size(const Args& args, int fallback_w, int fallback_h, int& width, int& height) {
    width = fallback_w, height = fallback_h;
    if (!args.has("size")) return;
    const std::string v = args.get("size");
    // Digits checked against the limit while reading: sscanf("%d") wraps on overflow
    // (4294967360 was read as 64).
    long long dims[2] = {0, 0};
    int n = 0;
    bool ok = !v.empty(), in_number = false;
    for (const char c : v) {
        if (c >= '0' && c <= '9') {
            if (!in_number) ++n, in_number = true;
            dims[n - 1] = dims[n - 1] * 10 + (c - '0');
            if (dims[n - 1] > kMaxImageSize) ok = false;
        } else if (c == 'x' && n == 1 && in_number) {
            in_number = false;
        } else {
            ok = false;
        }
        if (!ok) break;
    }
    if (n == 1 && v.find('x') == std::string::npos) dims[1] = dims[0];
    if (!ok || !in_number || dims[0] < 1 || dims[1] < 1)
        throw CliError("afterglow bench: --size: expects N or WxH with positive integers up to " +
                       std::to_string(kMaxImageSize) + ", got '" + v + "'");
    const int w = int(dims[0]), h = int(dims[1]);
    width = w, height = h;
}

double seconds_since(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

int bench_photons(const std::string& scene_path, int repeat) {
    Scene scene = load_scene(scene_path);
    ThreadPool pool(1);  // per-core figures
    cpu::PhotonSimulation sim(scene, pool);
    sim.trace_all();
    const int groups = scene.settings.photons.groups,
              per_group = scene.settings.photons.photons_per_group;
    const int photons = groups * per_group * int(scene.lights.size());

    // The same photon paths as rays: record every segment once.
    cpu::PhotonTracer tracer(scene, sim.rays());
    std::vector<cpu::Ray> rays;
    std::vector<cpu::TracedVertex> path;
    for (int l = 0; l < int(scene.lights.size()); ++l)
        for (int g = 0; g < groups; ++g)
            for (int p = 0; p < per_group; ++p) {
                path.clear();
                tracer.trace(l, g, p, path);
                glm::vec3 origin = scene.lights[size_t(l)].center();
                for (const cpu::TracedVertex& v : path) {
                    rays.push_back({origin, v.position - origin, 1e-4f, 1.0f + 1e-4f});
                    origin = v.position;
                }
                rays.push_back({origin, glm::vec3(0.0f, 0.0f, 1.0f), 1e-3f,
                                1e30f});  // the final miss / absorption ray
            }

    double best_full = 1e30, best_raw = 1e30, best_trace = 1e30, best_unordered = 1e30;
    size_t sink = 0;
    for (int r = 0; r < repeat; ++r) {
        // Tracing only: the same photons (QMC, sampling, rays) into a reused buffer, nothing kept.
        Clock::time_point t0 = Clock::now();
        for (int l = 0; l < int(scene.lights.size()); ++l)
            for (int g = 0; g < groups; ++g)
                for (int p = 0; p < per_group; ++p) {
                    path.clear();
                    tracer.trace(l, g, p, path);
                    sink += path.size();
                }
        best_trace = std::min(best_trace, seconds_since(t0));
        // Full: invalidate and retrace every group with hit removal/insertion and path storage.
        Clock::time_point t = Clock::now();
        sim.trace_all();
        best_full = std::min(best_full, seconds_since(t));
        t = Clock::now();
        for (const cpu::Ray& ray : rays) sink += size_t(sim.rays().intersect(ray).hit);
        best_raw = std::min(best_raw, seconds_since(t));
        // The same rays answered in Embree's own order among coincident faces: what the
        // coincident-face rule (cpu/ray_tracer.h) costs.
        t = Clock::now();
        for (const cpu::Ray& ray : rays) sink += size_t(sim.rays().intersect_unordered(ray).hit);
        best_unordered = std::min(best_unordered, seconds_since(t));
    }
    size_t vertices = 0, stored = sim.maps().hit_count();
    size_t bytes = stored * sizeof(cpu::PhotonHit);
    for (int l = 0; l < int(scene.lights.size()); ++l)
        for (int g = 0; g < groups; ++g) {
            const cpu::PhotonGroup& grp = sim.maps().group(l, g);
            vertices += grp.vertices.size();
            bytes += grp.vertices.size() * sizeof(cpu::PathVertex) +
                     grp.photon_begin.size() * sizeof(uint32_t) + sizeof(cpu::PhotonGroup);
        }
    std::printf(
        "scene %s: %zu triangles, %d photons (%d groups x %d per light), %zu path vertices, %zu "
        "stored hits\n",
        scene_path.c_str(), scene.triangle_count(), photons, groups, per_group, vertices, stored);
    std::printf("photons with bookkeeping: %.0f photons/s/core (%.3f ms for all)\n",
                photons / best_full, 1e3 * best_full);
    std::printf(
        "raw Embree, same segments: %.0f rays/s/core = %.0f photons/s/core (%zu rays, %.3f ms)\n",
        double(rays.size()) / best_raw, photons / best_raw, rays.size(), 1e3 * best_raw);
    std::printf(
        "raw Embree without the coincident-face rule: %.0f rays/s/core (%.3f ms); the rule costs "
        "%+.1f%% of the raw rays' time, %+.1f%% of the photons' with bookkeeping\n",
        double(rays.size()) / best_unordered, 1e3 * best_unordered,
        100.0 * (best_raw / best_unordered - 1.0), 100.0 * (best_raw - best_unordered) / best_full);
    std::printf(
        "tracing without bookkeeping (same photons, nothing stored): %.0f photons/s/core (%.3f "
        "ms)\n",
        photons / best_trace, 1e3 * best_trace);
    std::printf(
        "ratio with bookkeeping / without: %.2f;  with bookkeeping / raw Embree rays: %.2f\n",
        best_trace / best_full, best_raw / best_full);
    std::printf(
        "memory: %zu bytes for hits + paths = %.1f KB, %.1f bytes per stored hit (sizeof hit %zu, "
        "vertex %zu)\n",
        bytes, bytes / 1024.0, double(bytes) / double(std::max<size_t>(1, stored)),
        sizeof(cpu::PhotonHit), sizeof(cpu::PathVertex));
    return sink == size_t(-1) ? 1 : 0;
}

int bench_knn(int repeat, int queries) {
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    auto random_points = [&](size_t n) {
        std::vector<glm::vec3> p(n);
        for (glm::vec3& v : p) v = {u(rng), u(rng), u(rng)};
        return p;
    };
    std::vector<int> idx;
    std::vector<float> d2;
    auto measure = [&](size_t total, size_t maps, int k) {
        const size_t per_map = total / maps;
        std::vector<std::vector<glm::vec3>> sets;
        for (size_t m = 0; m < maps; ++m) sets.push_back(random_points(per_map));
        double best_build = 1e30, best_query = 1e30;
        std::vector<cpu::KnnIndex> trees(maps);
        for (int r = 0; r < repeat; ++r) {
            Clock::time_point t = Clock::now();
            for (size_t m = 0; m < maps; ++m) trees[m].build(sets[m]);
            best_build = std::min(best_build, seconds_since(t));
            const std::vector<glm::vec3> q = random_points(size_t(queries));
            t = Clock::now();
            for (int i = 0; i < queries; ++i)
                trees[size_t(i) % maps].query(q[size_t(i)], k, idx, d2);
            best_query = std::min(best_query, seconds_since(t) / queries);
        }
        std::printf(
            "  %8zu photons in %5zu maps of %7zu: build %9.3f ms, %d-nearest lookup %8.2f us\n",
            total, maps, per_map, 1e3 * best_build, k, 1e6 * best_query);
    };
    std::printf("Larsen Table 8.1: 1,000,000 random photons in M maps, 500 nearest\n");
    for (size_t maps : {1, 10, 100, 1000}) measure(1000000, maps, 500);
    std::printf("Larsen Table 14.1: one map, 100 nearest\n");
    for (size_t n : {300, 500, 1000, 2000}) measure(n, 1, 100);
    return 0;
}

std::unique_ptr<gpu::GlContext> bench_context(const Args& args) {
    auto context = gpu::make_gl_context(args.gl_backend());
    std::printf("GL: %s (%s, backend %s)\n", context->renderer().c_str(),
                context->version().c_str(), gpu::kGlBackendNames[size_t(context->backend())]);
    return context;
}

// Larsen Table 14.2: one final gather's cost against scene size and plane resolution.
int bench_gather(const std::vector<std::string>& scenes, int repeat, const Args& args) {
    auto context = bench_context(args);
    std::printf("%-26s %9s %6s %14s %14s %14s %14s %14s\n", "scene", "polygons", "plane",
                "GL batched", "GL unbatched", "CPU R² rays", "CPU 256 rays", "256 re-read");
    for (const std::string& path : scenes) {
        Scene scene = load_scene(path);
        args.apply_settings(scene);  // --set, e.g. gather.border_correction
        ThreadPool pool(1);
        cpu::PhotonSimulation sim(scene, pool);
        sim.trace_all();
        cpu::Aim aim(scene, pool);
        aim.rebuild_all(sim.maps());
        gpu::SceneMeshes meshes(scene);
        gpu::LightmapTexture aim_texture(scene.atlas);
        aim_texture.update_all(aim.radiance());
        std::vector<int> texels;
        for (int t = 0; t < int(scene.atlas.texels.size()) && t < 256; ++t) texels.push_back(t);
        for (int r : {8, 16, 32}) {
            scene.settings.gather.plane_resolution = r;
            gpu::HemiPlaneGather batched(scene, meshes, 256, &aim_texture),
                single(scene, meshes, 1, &aim_texture);
            single.set_max_per_pass(1);
            auto time_ms = [&](auto&& fn) {
                fn();  // warm-up
                double best = 1e30;
                for (int k = 0; k < repeat; ++k) {
                    const Clock::time_point t = Clock::now();
                    fn();
                    gpu::gl::Finish();
                    best = std::min(best, seconds_since(t));
                }
                return 1e3 * best / double(texels.size());
            };
            // Every backend through the one Gatherer interface the pipeline uses.
            auto time_gather = [&](Gatherer& g) { return time_ms([&] { g.gather(texels); }); };
            const double gl_batched = time_gather(batched);
            const double gl_single = time_gather(single);
            // Every ray traced (the ray cache would re-read the timed repetitions' rays).
            const int cache_mb = scene.settings.gather.ray_cache_mb;
            scene.settings.gather.ray_cache_mb = 0;
            scene.settings.gather.cpu_rays = r * r;
            cpu::CpuGather cpu_r(scene, sim.rays(), pool, &aim.radiance());
            const double cpu_rr = time_gather(cpu_r);
            scene.settings.gather.cpu_rays = 256;
            cpu::CpuGather cpu_256(scene, sim.rays(), pool, &aim.radiance());
            const double cpu_256_ms = time_gather(cpu_256);
            // The same texels again with nothing moved: every first hit from the ray cache
            // (the warm-up fills it), as after a light or albedo edit.
            scene.settings.gather.ray_cache_mb = std::max(cache_mb, 1);
            cpu::CpuGather cpu_cached(scene, sim.rays(), pool, &aim.radiance());
            const double cpu_cached_ms = time_gather(cpu_cached);
            scene.settings.gather.ray_cache_mb = cache_mb;
            std::printf("%-26s %9zu %3dx%-3d %11.3f ms %11.3f ms %11.3f ms %11.3f ms %11.4f ms\n",
                        path.c_str(), scene.triangle_count(), r, r, gl_batched, gl_single, cpu_rr,
                        cpu_256_ms, cpu_cached_ms);
        }
    }
    std::printf(
        "(ms per gathered texel, best of %d; CPU on one thread; re-read: 256 rays whose first hits "
        "come from the ray cache, gather.ray_cache_mb)\n",
        repeat);
    return 0;
}

// Frames per second of the whole pipeline (photons on workers, AIMs, gathers, caustics, frame).
int bench_frame(const std::string& path, int repeat, const Args& args) {
    auto context = bench_context(args);
    const int frames = args.get_int("frames", 100);
    int size = 0, height = 0;
    bench_size(args, 512, 512, size, height);
    if (height != size) throw CliError("afterglow bench frame: --size expects a square N");
    Scene scene = load_scene(path);
    args.apply_settings(scene);
    Pipeline pipeline(scene, PipelineOptions{size, size});
    FrameLoop loop(pipeline);
    for (int f = 0; f < 60 && !pipeline.converged(); ++f) loop.step();  // settle first
    int mover = -1;
    for (int o = 0; o < int(scene.objects.size()) && mover < 0; ++o)
        if (scene.objects[size_t(o)].dynamic &&
            scene.objects[size_t(o)].material.type == MaterialType::diffuse)
            mover = o;
    for (int moving = 0; moving < 2; ++moving) {
        if (moving && mover < 0) break;
        double best = 1e30;
        PipelineStats sum;
        std::vector<double> best_frame_ms;  // each frame's wall time in the best repetition
        for (int r = 0; r < repeat; ++r) {
            const Clock::time_point t = Clock::now();
            PipelineStats acc;
            std::vector<double> frame_ms;
            for (int f = 0; f < frames; ++f) {
                const Clock::time_point frame_start = Clock::now();
                if (moving) {
                    loop.begin_edits();
                    translate_object(scene, mover, {f % 40 < 20 ? 2.0f : -2.0f, 0.0f, 0.0f});
                }
                const PipelineStats s = loop.step();
                frame_ms.push_back(1e3 * seconds_since(frame_start));
                acc.photon_ms += s.photon_ms, acc.aim_ms += s.aim_ms,
                    acc.caustic_ms += s.caustic_ms;
                acc.gather_ms += s.gather_ms, acc.draw_ms += s.draw_ms, acc.wait_ms += s.wait_ms;
                acc.photons.groups_invalidated += s.photons.groups_invalidated;
                acc.photons.photons_retraced += s.photons.photons_retraced;
                acc.iim_texels_gathered += s.iim_texels_gathered;
            }
            const double secs = seconds_since(t);
            if (secs < best) best = secs, sum = acc, best_frame_ms = std::move(frame_ms);
        }
        const double n = frames;
        std::printf(
            "%s, %dx%d, %s: %.1f fps (%.2f ms/frame, p95 %.2f ms); per frame: draw %.2f, gather "
            "%.2f, waited %.2f ms on the GL thread; photons %.2f, AIM %.2f, caustics %.2f ms on "
            "workers; %.1f groups invalidated, %.0f photons retraced, %.1f IIM texels gathered; "
            "gather backend %s\n",
            path.c_str(), size, size, moving ? "cube moving every frame" : "static", n / best,
            1e3 * best / n, p95(best_frame_ms), sum.draw_ms / n, sum.gather_ms / n, sum.wait_ms / n,
            sum.photon_ms / n, sum.aim_ms / n, sum.caustic_ms / n,
            sum.photons.groups_invalidated / n, sum.photons.photons_retraced / n,
            sum.iim_texels_gathered / n, kGatherBackendNames[size_t(pipeline.gather_backend())]);
    }
    // The frame of an edit draws the direct light anew: deferred (one full-screen pass per light
    // sample over the G-buffer's surface) against forward (every diffuse object again per light
    // sample), the same renderer and scene in the same run. Each render counts as an edit's
    // (the scene's version moves on), so every one draws every term and the direct light.
    {
        gpu::SceneMeshes meshes(scene);
        gpu::LightmapTexture iim(scene.atlas);
        double ms[2] = {0.0, 0.0};
        for (int forward = 0; forward < 2; ++forward) {
            gpu::FrameRenderer renderer(scene, meshes, size, size);
            renderer.set_direct_pass(forward ? gpu::FrameRenderer::DirectPass::forward
                                             : gpu::FrameRenderer::DirectPass::deferred);
            renderer.render(iim.id());  // compiles the programs
            gpu::gl::Finish();
            double best = 1e30;
            for (int r = 0; r < repeat; ++r) {
                const Clock::time_point t = Clock::now();
                for (int f = 0; f < 10; ++f) {
                    ++scene.version;
                    renderer.render(iim.id());
                }
                gpu::gl::Finish();
                best = std::min(best, seconds_since(t) / 10.0);
            }
            ms[forward] = 1e3 * best;
        }
        int samples = int(gpu::light_samples(scene).size());
        std::printf(
            "%s, %dx%d, an edit's frame drawn (%d light samples, %zu triangles): direct light "
            "deferred %.2f ms, forward %.2f ms (%.2fx)\n",
            path.c_str(), size, size, samples, scene.triangle_count(), ms[0], ms[1],
            ms[1] / std::max(1e-9, ms[0]));
    }
    return 0;
}

int bench_caustics(const std::string& path, int repeat, const Args& args) {
    Scene scene = load_scene(path);
    {
        ThreadPool pool(1);
        cpu::CausticTracer tracer(scene, pool);
        tracer.trace_all();  // warm-up
        double best = 1e30;
        cpu::CausticStats st;
        for (int r = 0; r < repeat; ++r) {
            const Clock::time_point t = Clock::now();
            st = tracer.trace_all();
            best = std::min(best, seconds_since(t));
        }
        std::printf(
            "%s: %d caustic photons in %.2f ms on one core = %.0f photons/s/core; %.1f%% reached a "
            "specular "
            "object, %.1f%% were stored (L S+ D)\n",
            path.c_str(), st.traced, 1e3 * best, st.traced / best,
            100.0 * st.hit_specular / std::max(1, st.traced),
            100.0 * st.stored / std::max(1, st.traced));
    }
    auto context = bench_context(args);
    int size = 0, height = 0;
    bench_size(args, 512, 512, size, height);
    if (size < 64 || height != size)
        throw CliError("afterglow bench caustics: --size expects N >= 64, got " +
                       std::to_string(size));
    // A synthetic caustic: a disc of photons on the floor under the camera's view, sized so that
    // it covers the asked share of the screen.
    Scene floor_scene;
    floor_scene.path = "bench";
    Object floor;
    floor.name = "floor";
    floor.mesh = make_quad(100.0f, 100.0f);
    floor_scene.objects.push_back(floor);
    floor_scene.camera.eye = {0.0f, 10.0f, -0.01f};
    floor_scene.camera.target = {0.0f, 0.0f, 0.0f};
    floor_scene.camera.fov_y = 60.0f;
    floor_scene.camera.width = floor_scene.camera.height = size;
    floor_scene.settings = scene.settings;
    floor_scene.settings.lightmap.texel_size = 10.0f;
    init_versions(floor_scene);
    make_surfaces_and_atlas(floor_scene);
    gpu::SceneMeshes meshes(floor_scene);
    gpu::CausticsRenderer caustics(floor_scene, meshes, size, size);
    const float view = 2.0f * 10.0f * std::tan(glm::radians(30.0f));  // visible floor width
    for (double share : {0.01, 0.05}) {
        const float r = view * float(std::sqrt(share / 3.14159265358979));
        std::vector<glm::vec3> positions, powers;
        for (int i = 0; i < 10000; ++i) {
            const float a = float(radical_inverse(2, uint64_t(i))) * 6.2831853f;
            const float d = r * std::sqrt(float(radical_inverse(3, uint64_t(i))));
            positions.push_back({d * std::cos(a), 0.0f, d * std::sin(a)});
            powers.push_back(glm::vec3(1e-4f));
        }
        double full = 1e30, culled = 1e30, queries = 1e30;
        int tiles = 0;
        for (int k = 0; k < repeat + 1; ++k) {  // the first round warms up
            caustics.render(positions, powers, false);
            if (k) full = std::min(full, caustics.filter_ms());
            caustics.render(positions, powers, true);
            if (k)
                culled = std::min(culled, caustics.filter_ms()),
                queries = std::min(queries, caustics.query_ms());
            tiles = caustics.tiles_filtered();
        }
        std::printf(
            "caustic over %.0f%% of %dx%d: full-screen filter %.2f ms; culled %.2f ms (%d of %d "
            "tiles of %d px) "
            "+ %.2f ms for the occlusion queries\n",
            100.0 * share, size, size, full, culled, tiles, caustics.tiles_total(),
            scene.settings.caustics.tile_size, queries);
    }
    return 0;
}

}  // namespace

int run_bench(const Args& args) {
    const std::string what = args.positionals()[0];
    const int repeat = args.get_int("repeat");
    if (what == "photons") {
        if (args.positionals().size() < 2) throw CliError("afterglow bench photons: missing SCENE");
        return bench_photons(args.positionals()[1], repeat);
    }
    if (what == "knn") return bench_knn(repeat, args.get_int("queries"));
    if (what == "gather") {
        std::vector<std::string> scenes(args.positionals().begin() + 1, args.positionals().end());
        if (scenes.empty())
            scenes = {"scenes/cornell_34.json", "scenes/bumpy_13k.json", "scenes/bumpy_133k.json"};
        return bench_gather(scenes, repeat, args);
    }
    if (what == "caustics")
        return bench_caustics(
            args.positionals().size() > 1 ? args.positionals()[1] : "scenes/cornell.json", repeat,
            args);
    if (what == "frame")
        return bench_frame(
            args.positionals().size() > 1 ? args.positionals()[1] : "scenes/cornell.json", repeat,
            args);
    if (what == "settle") {
        int width = 0, height = 0;
        bench_size(args, 64, 64, width, height);
        return bench_settle(args, width, height);
    }
    if (what == "soak") {
        int size = 0, height = 0;
        bench_size(args, 64, 64, size, height);
        if (height != size) throw CliError("afterglow bench soak: --size expects a square N");
        return bench_soak(
            args, args.positionals().size() > 1 ? args.positionals()[1] : "scenes/cornell.json",
            size);
    }
    if (what == "gpu_pm") {
        int width = 0, height = 0;
        bench_size(args, 256, 256, width, height);
        return bench_gpu_pm(
            args,
            args.positionals().size() > 1 ? args.positionals()[1] : "scenes/cornell_kwast.json",
            width, height);
    }
    if (what == "vpl") {
        auto context = bench_context(args);
        int width = 0, height = 0;
        bench_size(args, 256, 192, width, height);
        return bench_vpl(
            args, args.positionals().size() > 1 ? args.positionals()[1] : "scenes/cornell.json",
            width, height, repeat);
    }
    if (what == "irradiance_cache") {
        int width = 0, height = 0;
        bench_size(args, 128, 128, width, height);
        const std::string scene =
            args.positionals().size() > 1 ? args.positionals()[1] : "scenes/cube_in_a_box.json";
        if (args.has("versus-cpu"))
            return bench_irradiance_cache_versus_cpu(args, scene, width, height);
        return bench_irradiance_cache(args, scene, width, height);
    }
    if (what == "media") {
        auto context = bench_context(args);
        int width = 0, height = 0;
        bench_size(args, 48, 48, width, height);
        return bench_media(args,
                           args.positionals().size() > 1 ? args.positionals()[1]
                                                         : "scenes/media_glass_fog_point.json",
                           width, height);
    }
    throw CliError("afterglow bench: unknown benchmark '" + what +
                   "' (expected photons, knn, gather, frame, caustics, settle, soak, gpu_pm, vpl, "
                   "irradiance_cache or media)");
}

static const Registration kRegistration(kBenchCommand, run_bench, 90);

}  // namespace ag::cli
