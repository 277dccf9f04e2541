// afterglow bench settle: the yardstick of DESIGN.md "Scheduling by time, not by counts". For a
// ladder of scenes and edit scripts, the time from an edit until the indirect error is back within
// 10% of its settled value, selective against recomputing everything (full) and against
// recomputing everything round robin within the same frame-time target (full-budget).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>

#include "gpu/gl_context.h"
#include "shared/image.h"
#include "shared/metrics.h"
#include "shared/scene_file.h"
#include "tools/afterglow/cli.h"
#include "tools/afterglow/convergence.h"

namespace ag::cli {

namespace {

struct LadderEntry {
    std::string scene, script;
    int frames = 90;  // long enough for full-budget to recompute everything once at 33 ms
    // The frame-time target without --frame-ms; 0 = 33 ms. The large scenes name their own: on
    // two llvmpipe cores drawing them took about 110 ms (bumpy) and 100-150 ms (conference, while
    // the direct term accumulates after an edit), so at 33 ms every mode would get only its
    // minimum share and no frame would come near the target. With the direct light deferred
    // (session 11) drawing takes 20-40 ms; the targets stay, so the ladder compares with the
    // earlier sessions' (docs/convergence.md also reports bumpy at --frame-ms 100).
    double frame_ms = 0.0;
    // Continuous moves: every `track_every` frames the frame is also scored against the
    // reference of its own state (not the final one), so the area measures how far the light
    // lags the move rather than how far the object is from where it stops; 0 = not tracked.
    int track_every = 0;
};

// The default ladder: small to large scenes, step edits (geometry, material, visibility, light)
// and one continuous move (for the area under the error curve).
const std::vector<LadderEntry> kLadder = {
    {"scenes/cornell.json", "scenes/cornell_cube_jump.lua"},
    {"scenes/cornell.json", "scenes/cornell_albedo_step.lua"},
    {"scenes/cornell.json", "scenes/cornell_move_cube.lua", 90, 0.0, 4},
    {"scenes/two_rooms.json", "scenes/two_rooms_door_step.lua"},
    {"scenes/two_rooms.json", "scenes/two_rooms_light_off_step.lua"},
    {"scenes/bumpy_133k_box.json", "scenes/bumpy_133k_jump.lua", 120, 200.0},
    {"scenes/conference.json", "scenes/conference_box_jump.lua", 240, 200.0},
    {"scenes/conference.json", "scenes/conference_lamp_off_step.lua", 240, 200.0},
};

std::vector<PipelineMode> parse_modes(const std::string& list) {
    std::vector<PipelineMode> modes;
    std::stringstream in(list);
    for (std::string name; std::getline(in, name, ',');) {
        bool found = false;
        for (size_t m = 0; m < kPipelineModeNames.size(); ++m)
            if (name == kPipelineModeNames[m]) {
                if (std::find(modes.begin(), modes.end(), PipelineMode(m)) == modes.end())
                    modes.push_back(PipelineMode(m));
                found = true;
            }
        if (!found)
            throw CliError(
                "afterglow bench settle: --modes: expected selective, full or "
                "full-budget, got '" +
                name + "'");
    }
    if (modes.empty()) throw CliError("afterglow bench settle: --modes: no mode given");
    return modes;
}

// What one mode did on one scene × script.
struct SettleResult {
    PipelineMode mode = PipelineMode::selective;
    SettleAnalysis settle;
    double frame_mean_settle = 0, frame_p95_settle = 0, frame_mean = 0, frame_p95 = 0;  // ms
    uint64_t photons = 0, aim_texels = 0, iim_texels = 0;  // first edit .. settled (or the end)
    double auc = 0.0;                // ∫ relMSE dt after the first edit over the common window
    double tracking_auc = -1.0;      // the same against each frame's own state; −1: not tracked
    double after_last_edit_s = 0.0;  // wall time from the start of the last edit's frame to the end
};

// Wall time of frame f in ms (its share of the run's wall time).
double frame_wall_ms(const ConvergenceRun& run, size_t f) {
    return 1e3 * (run.frames[f].wall_s - (f ? run.frames[f - 1].wall_s : 0.0));
}

// The time from which the error after the first edit is integrated: when the edit happened, i.e.
// the end of the frame before it (0 when the first frame carries it).
double edit_time(const ConvergenceRun& run) {
    const int e = std::max(0, run.settle.first_edit);
    return e > 0 ? run.frames[size_t(e - 1)].wall_s : 0.0;
}

// ∫ relMSE dt from the first edit over `window` seconds: the image on screen (and its error) is
// the last one drawn until the next frame replaces it, so the edit frame's time is charged at the
// error of the frame before it.
double error_area(const ConvergenceRun& run, double window) {
    const int e = std::max(0, run.settle.first_edit);
    const double t0 = edit_time(run), end = t0 + window;
    double area = 0.0, t = t0;
    for (size_t f = size_t(e); f < run.frames.size() && t < end; ++f) {
        const double shown = f ? run.frames[f - 1].relmse : run.frames[f].relmse;
        const double next = std::min(run.frames[f].wall_s, end);
        area += shown * (next - t);
        t = next;
    }
    if (t < end && !run.frames.empty()) area += run.frames.back().relmse * (end - t);
    return area;
}

// The run with each frame's error replaced by its error against its own state's reference,
// held from one sampled frame to the next (`tracked`: frame → relMSE; frames before the first
// sample keep their own error).
ConvergenceRun tracked_run(ConvergenceRun run, const std::map<int, double>& tracked) {
    double held = -1.0;
    for (FrameRecord& r : run.frames) {
        if (auto it = tracked.find(r.frame); it != tracked.end()) held = it->second;
        if (held >= 0.0) r.relmse = held;
    }
    return run;
}

SettleResult analyse(const ConvergenceRun& run) {
    SettleResult r;
    r.mode = run.mode;
    r.settle = run.settle;
    const size_t n = run.frames.size();
    const size_t from = size_t(std::max(0, run.settle.last_edit));
    const size_t to = run.settle.within >= 0 ? size_t(run.settle.within) : n - 1;
    std::vector<double> all, window;
    for (size_t f = 0; f < n; ++f) {
        all.push_back(frame_wall_ms(run, f));
        if (f >= from && f <= to) window.push_back(all.back());
    }
    r.frame_mean = mean(all), r.frame_p95 = p95(all);
    if (n > from) r.after_last_edit_s = run.frames[n - 1].wall_s - frame_start_s(run.frames, from);
    r.frame_mean_settle = mean(window), r.frame_p95_settle = p95(window);
    for (size_t f = size_t(std::max(0, run.settle.first_edit)); f <= to && f < n; ++f) {
        r.photons += run.frames[f].photons_retraced;
        r.aim_texels += run.frames[f].aim_texels;
        r.iim_texels += uint64_t(run.frames[f].iim_texels);
    }
    return r;
}

std::string stem(const std::string& path) { return std::filesystem::path(path).stem().string(); }

// "-" for a run that did not settle.
std::string fixed(double v, int decimals, bool valid = true) {
    if (!valid) return "-";
    char b[64];
    std::snprintf(b, sizeof b, "%.*f", decimals, v);
    return b;
}

// "median M× (min A×, max B×, N phases)" over the phases where full-budget settled, plus the
// lower bounds of those where it did not.
std::string phase_summary(std::vector<double> speedups, std::vector<double> bounds) {
    std::ostringstream out;
    if (speedups.empty()) {
        out << "full-budget settled in no phase";
    } else {
        std::sort(speedups.begin(), speedups.end());
        const size_t n = speedups.size();
        const double median =
            n % 2 ? speedups[n / 2] : 0.5 * (speedups[n / 2 - 1] + speedups[n / 2]);
        out << "median " << fixed(median, 2) << "x (min " << fixed(speedups.front(), 2) << "x, max "
            << fixed(speedups.back(), 2) << "x, " << n << " phase" << (n == 1 ? "" : "s") << ")";
    }
    if (!bounds.empty()) {
        std::sort(bounds.begin(), bounds.end());
        out << "; full-budget unsettled in " << bounds.size() << " more (selective at least "
            << fixed(bounds.front(), 1) << "x sooner there)";
    }
    return out.str();
}

}  // namespace

int bench_settle(const Args& args, int width, int height) {
    const int frames_flag = args.has("frames") ? args.get_int("frames") : 0;
    const std::vector<PipelineMode> modes = parse_modes(args.get("modes"));
    const bool frame_ms_given = args.has("frame-ms");
    const double frame_ms_flag = args.get_double("frame-ms", 33.0);
    const std::string csv_path = args.get("csv", "out/bench-settle.csv");
    const std::string plot_path = args.get("plot", "out/bench-settle.png");
    const std::string component = "indirect";
    const int phases = args.get_int("phases", 1);
    const int phase_step = args.get_int("phase-step", 1);
    const double region_fraction =
        args.has("changed-region") ? args.get_double("changed-region", 0.1) : 0.0;
    std::ostringstream summary;  // the speed-up over phases, per entry

    std::vector<LadderEntry> ladder;
    for (size_t i = 1; i < args.positionals().size(); ++i) {
        const std::string& p = args.positionals()[i];
        const size_t colon = p.find(':');
        if (colon == std::string::npos || colon == 0 || colon + 1 == p.size())
            throw CliError("afterglow bench settle: expected SCENE:SCRIPT, got '" + p + "'");
        LadderEntry e{p.substr(0, colon), p.substr(colon + 1)};
        for (const LadderEntry& known : kLadder)  // a ladder entry named again keeps its own
            if (known.scene == e.scene && known.script == e.script) e = known;
        ladder.push_back(e);
    }
    if (ladder.empty())
        for (const LadderEntry& e : kLadder)
            if (!args.has("quick") || e.scene == "scenes/cornell.json") ladder.push_back(e);

    auto context = gpu::make_gl_context(args.gl_backend());
    const bool prime = !args.has("no-prime");
    std::printf(
        "bench settle: %dx%d, --frame-ms %s, %s; indirect relMSE against the pm reference of the "
        "final state%s; settled = %s, settle = from the last edit until the error stays within "
        "10%% of it\n",
        width, height,
        frame_ms_given ? fixed(frame_ms_flag, 1).c_str() : "33 (bumpy and conference 200)",
        prime ? "each run starts from the converged state of frame 0 (untimed)"
              : "each run starts from nothing",
        region_fraction > 0.0 ? (", over the pixels whose reference changes by more than " +
                                 fixed(region_fraction, 3) + " (--changed-region)")
                                    .c_str()
                              : "",
        prime ? "the error of the converged final state" : "the mean of the last tenth of frames");
    std::printf("%-10s %8s %-22s %4s %-11s %9s %6s %8s %15s %15s %9s %9s %9s %9s %8s\n", "scene",
                "tris", "script", "lead", "mode", "settled", "frames", "settle_s",
                "ms mean/p95 set", "ms mean/p95 all", "photons", "AIM tx", "IIM tx", "area",
                "speedup");

    std::ostringstream csv;
    csv << "scene,script,triangles,lead_in,mode,frame_ms_target,width,height,frames,settled_relmse,"
           "first_"
           "edit,last_edit,settle_frames,settle_s,frame_ms_mean_settle,frame_ms_p95_settle,frame_"
           "ms_mean,frame_ms_p95,photons_retraced,aim_texels,iim_texels,error_area,error_area_"
           "window_s,speedup_vs_full_budget,speedup_at_least,tracking_area,region_pixels\n";
    const std::filesystem::path runs_dir =
        std::filesystem::absolute(csv_path).parent_path() / (stem(csv_path) + ".runs");
    int measured = 0;
    for (const LadderEntry& entry : ladder) {
        const int frames = frames_flag > 0 ? frames_flag : entry.frames;
        const double frame_ms =
            frame_ms_given ? frame_ms_flag : (entry.frame_ms > 0.0 ? entry.frame_ms : 33.0);
        Scene scene;
        try {
            if (!std::filesystem::exists(entry.scene))
                throw std::runtime_error(entry.scene + ": no such file");
            if (!std::filesystem::exists(entry.script))
                throw std::runtime_error(entry.script + ": no such file");
            scene = load_scene(entry.scene);
        } catch (const std::exception& e) {
            std::printf("skipping %s with %s: %s\n", entry.scene.c_str(), entry.script.c_str(),
                        e.what());
            continue;
        }
        // Settling is about repair after an edit: refinement of settled texels (which only
        // selective does, and which takes the static error further down over ~165 frames on
        // cornell) would move the target the baselines are measured against. --set
        // gather.refine_passes=N turns it back on.
        scene.settings.gather.refine_passes = 1;
        // Progressive photon refinement likewise (photons.refine_layers, docs/fidelity.md):
        // settling is measured with the photon budget of a fresh pipeline; --set turns it on.
        scene.settings.photons.refine_layers = 1;
        args.apply_settings(scene);
        scene.settings.schedule.frame_ms = float(frame_ms);
        scene.camera.width = width;
        scene.camera.height = height;
        const int threads = args.get_int("threads", scene.settings.threads);

        ReferenceRequest request;
        request.name = stem(entry.scene);
        request.cache = args.get("cache");
        request.spp = args.get_int("ref-spp");
        request.photons = args.get_int("ref-photons");
        request.threads = threads;
        request.log_prefix = "afterglow bench settle";
        const std::string reference_path = cached_reference(scene, entry.script, frames, request);
        const Image reference = read_reference(reference_path, component, width, height);
        // --changed-region: the error only where the edit changes the light, so that an edit
        // whose change is small against the whole image's error is still seen.
        Image region;
        const Image* mask = nullptr;
        size_t region_pixels = 0;
        if (region_fraction > 0.0) {
            const Image before = read_reference(cached_reference(scene, entry.script, 1, request),
                                                component, width, height);
            region = changed_region(before, reference, region_fraction);
            for (float v : region.pixels) region_pixels += v != 0.0f;
            if (region_pixels == 0) {
                std::printf(
                    "skipping %s with %s: no pixel's indirect light changes by more than "
                    "%g\n",
                    entry.scene.c_str(), entry.script.c_str(), region_fraction);
                continue;
            }
            mask = &region;
            // The region to look at: the final state's indirect light where it is scored.
            Image shown(width, height);
            for (int y = 0; y < height; ++y)
                for (int x = 0; x < width; ++x)
                    shown.set_rgb(
                        x, y, region.at(x, y)[0] != 0.0f ? reference.rgb(x, y) : glm::vec3(0.0f));
            std::filesystem::create_directories(runs_dir);
            write_image(
                shown,
                (runs_dir / (request.name + "." + stem(entry.script) + ".region.png")).string());
            std::printf("%s with %s: %zu of %d pixels change by more than %g\n",
                        request.name.c_str(), stem(entry.script).c_str(), region_pixels,
                        width * height, region_fraction);
        }

        // Every mode converges to the same state (repair == rebuild): its error is the settled
        // value all three are measured against, so a mode that never got there within the run
        // does not settle on a plateau of its own.
        const double target = prime ? converged_error(scene, entry.script, frames, width, height,
                                                      component, reference, threads, mask)
                                    : 0.0;
        // Tracked entries: the reference of the state after f + 1 script frames for every
        // track_every-th frame f (states after the last edit share one cached reference).
        const int track_every =
            args.has("track-every") ? args.get_int("track-every", 0) : entry.track_every;
        std::map<int, Image> own_state;
        if (track_every > 0)
            for (int f = 0; f < frames; f += track_every)
                own_state[f] = read_reference(cached_reference(scene, entry.script, f + 1, request),
                                              component, width, height);
        // Full-budget's settle depends on where its round-robin sweep is when the edit lands:
        // each phase starts the script `lead_in` untimed frames later.
        std::vector<double> speedups, bounds;
        for (int phase = 0; phase < phases; ++phase) {
            const int lead_in = phase * phase_step;
            std::vector<ConvergenceRun> runs;
            double speedup_of_phase = 0.0, bound_of_phase = 0.0;
            const std::string phase_suffix = phases > 1 ? ".lead" + std::to_string(lead_in) : "";
            std::vector<std::map<int, double>> tracked;
            for (PipelineMode mode : modes) {
                std::map<int, double>& errors = tracked.emplace_back();
                std::map<int, double> in_region;
                runs.push_back(run_convergence(
                    scene, entry.script, mode, frames, width, height, component,
                    [&](int) -> const Image& { return reference; }, threads, prime, {},
                    [&](int f, const Image& image) {
                        if (auto it = own_state.find(f); it != own_state.end())
                            errors[f] = compare_images(image, it->second).rel_mse;
                        if (mask) in_region[f] = compare_images(image, reference, mask).rel_mse;
                    },
                    lead_in));
                if (mask)
                    for (FrameRecord& r : runs.back().frames) r.relmse = in_region.at(r.frame);
                runs.back().settle = analyse_settle(runs.back().frames, target);
                std::filesystem::create_directories(runs_dir);
                write_file_atomically(
                    (runs_dir / (request.name + "." + stem(entry.script) + "." +
                                 kPipelineModeNames[size_t(mode)] + phase_suffix + ".csv"))
                        .string(),
                    convergence_csv(runs.back()));
            }
            // The error area over the same window for every mode: the shortest run after the edit.
            double window = 1e30;
            for (const ConvergenceRun& run : runs)
                window = std::min(window, run.wall_s - edit_time(run));
            std::vector<SettleResult> results;
            for (size_t m = 0; m < runs.size(); ++m) {
                results.push_back(analyse(runs[m]));
                results.back().auc = error_area(runs[m], window);
                if (!tracked[m].empty())
                    results.back().tracking_auc =
                        error_area(tracked_run(runs[m], tracked[m]), window);
            }
            // A mode settles only where the others do: a run whose own plateau is more than 10%
            // above the best mode's never reached the converged state within the run (it is "-").
            double best = 1e30;
            for (const SettleResult& r : results) best = std::min(best, r.settle.settled);
            if (target > 0.0) best = target;
            auto settled = [&](const SettleResult& r) {
                return r.settle.settled_ok() && r.settle.settled <= 1.1 * best;
            };
            const SettleResult* budget = nullptr;
            for (const SettleResult& r : results)
                if (r.mode == PipelineMode::full_budget) budget = &r;
            for (const SettleResult& r : results) {
                const bool ok = settled(r);
                const bool speedup_ok = ok && budget && settled(*budget) && r.settle.seconds > 0;
                const double speedup = speedup_ok ? budget->settle.seconds / r.settle.seconds : 0.0;
                // Full-budget still unsettled at the end of its run: it settles later than the
                // run's time after the edit, so selective is at least that much sooner.
                const bool bound_ok = ok && budget && !settled(*budget) && r.settle.seconds > 0;
                const double at_least =
                    bound_ok ? budget->after_last_edit_s / r.settle.seconds : 0.0;
                if (r.mode == PipelineMode::selective) {
                    speedup_of_phase = speedup;
                    bound_of_phase = at_least;
                }
                const char* mode = kPipelineModeNames[size_t(r.mode)];
                std::printf(
                    "%-10s %8zu %-22s %4d %-11s %9.5f %6s %8s %7.1f/%-7.1f %7.1f/%-7.1f %9llu "
                    "%9llu "
                    "%9llu %9.5f %8s\n",
                    request.name.c_str(), scene.triangle_count(), stem(entry.script).c_str(),
                    lead_in, mode, r.settle.settled,
                    ok ? std::to_string(r.settle.frames).c_str() : "-",
                    fixed(r.settle.seconds, 3, ok).c_str(), r.frame_mean_settle, r.frame_p95_settle,
                    r.frame_mean, r.frame_p95, static_cast<unsigned long long>(r.photons),
                    static_cast<unsigned long long>(r.aim_texels),
                    static_cast<unsigned long long>(r.iim_texels), r.auc,
                    r.mode != PipelineMode::selective ? ""
                    : speedup_ok                      ? (fixed(speedup, 2) + "x").c_str()
                    : bound_ok                        ? (">" + fixed(at_least, 1) + "x").c_str()
                                                      : "-");
                csv << request.name << ',' << stem(entry.script) << ',' << scene.triangle_count()
                    << ',' << lead_in << ',' << mode << ',' << frame_ms << ',' << width << ','
                    << height << ',' << frames << ',' << r.settle.settled << ','
                    << r.settle.first_edit << ',' << r.settle.last_edit << ','
                    << (ok ? std::to_string(r.settle.frames) : "") << ','
                    << (ok ? fixed(r.settle.seconds, 6) : "") << ',' << r.frame_mean_settle << ','
                    << r.frame_p95_settle << ',' << r.frame_mean << ',' << r.frame_p95 << ','
                    << r.photons << ',' << r.aim_texels << ',' << r.iim_texels << ',' << r.auc
                    << ',' << window << ',' << (speedup_ok ? fixed(speedup, 4) : "") << ','
                    << (bound_ok ? fixed(at_least, 4) : "") << ','
                    << (r.tracking_auc >= 0.0 ? fixed(r.tracking_auc, 6) : "") << ','
                    << region_pixels << "\n";
            }
            if (track_every > 0) {
                std::printf(
                    "%-10s %-22s %4d tracking area (against each frame's own state, every "
                    "%d frames):",
                    request.name.c_str(), stem(entry.script).c_str(), lead_in, track_every);
                for (const SettleResult& r : results)
                    std::printf(" %s %.5f", kPipelineModeNames[size_t(r.mode)], r.tracking_auc);
                std::printf("\n");
            }
            if (speedup_of_phase > 0.0) speedups.push_back(speedup_of_phase);
            if (bound_of_phase > 0.0) bounds.push_back(bound_of_phase);
        }
        if (phases > 1) {
            std::sort(speedups.begin(), speedups.end());
            std::printf("%-10s %-22s speed-up over %d phases: %s\n", request.name.c_str(),
                        stem(entry.script).c_str(), phases,
                        phase_summary(speedups, bounds).c_str());
            summary << request.name << " " << stem(entry.script) << ": "
                    << phase_summary(speedups, bounds) << "\n";
        }
        std::fflush(stdout);
        ++measured;
    }
    std::printf(
        "(settle_s: wall time from the start of the last edit's frame, that frame included; ms "
        "mean/p95 over the frames from the last edit "
        "until settled, and over all frames; photons re-traced, AIM texels rebuilt and IIM texels "
        "gathered from the first edit until settled; area: ∫ relMSE dt from the first edit over "
        "the shortest mode's remaining run; speedup: full-budget's settle time over "
        "selective's, '>N' where full-budget had not settled when its run ended)\n");
    if (!summary.str().empty())
        std::printf("selective's speed-up over full-budget, by phase of full-budget's sweep:\n%s",
                    summary.str().c_str());
    if (measured == 0) {
        std::fprintf(stderr, "afterglow bench settle: nothing measured\n");
        return 1;
    }
    std::filesystem::create_directories(std::filesystem::absolute(csv_path).parent_path());
    write_file_atomically(csv_path, csv.str());
    std::printf("wrote %s (and each run's converge CSV under %s)\n", csv_path.c_str(),
                runs_dir.string().c_str());
    if (!plot_path.empty()) {
        const std::string command =
            "/usr/bin/python3 tools/plot_settle.py '" + plot_path + "' '" + csv_path + "'";
        if (std::system(command.c_str()) != 0)
            std::cerr << "afterglow bench settle: warning: plotting failed (" << command << ")\n";
        else
            std::printf("wrote %s\n", plot_path.c_str());
    }
    return 0;
}

}  // namespace ag::cli
