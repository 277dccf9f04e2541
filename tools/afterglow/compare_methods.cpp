// afterglow compare-methods SCENE: every indirect method and variant through the same scene-edit
// script, scored frame by frame against path-traced references of the states the edits lead to
// (docs/compare_methods.md): error against wall-clock time, settle time after each edit, frame
// time, flicker and memory, in one plot and one table.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "cpu/reference/reference.h"
#include "gpu/gl.h"
#include "gpu/gl_context.h"
#include "shared/frame_terms.h"
#include "shared/image.h"
#include "shared/input_error.h"
#include "shared/metrics.h"
#include "shared/parallel.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/scene_file.h"
#include "shared/script.h"
#include "tools/afterglow/commands.h"
#include "tools/afterglow/convergence.h"
#include "tools/afterglow/progress.h"

namespace ag::cli {

namespace {

// One method or variant: an indirect method, a pipeline mode and the settings that make the
// variant (the shape of a scene file's "settings" block).
struct Variant {
    std::string name;
    IndirectMethodKind method = IndirectMethodKind::iim;
    PipelineMode mode = PipelineMode::selective;
    std::string settings;        // JSON
    bool single_bounce = false;  // also scored against the 1-bounce references
    std::string what;
    bool by_default = true;  // in the default run (else only by --methods)
};

const std::vector<Variant> kVariants = {
    {"iim-gl", IndirectMethodKind::iim, PipelineMode::selective, R"({"gather":{"backend":"gl"}})",
     false, "Larsen: selective photons, AIM, IIM by the GL hemi-plane gather"},
    {"iim-cpu", IndirectMethodKind::iim, PipelineMode::selective, R"({"gather":{"backend":"cpu"}})",
     false, "the same, IIM gathered with Embree rays"},
    {"iim-full-budget", IndirectMethodKind::iim, PipelineMode::full_budget,
     R"({"gather":{"backend":"gl"}})", false,
     "everything recomputed round robin within the same frame budget (--baseline full-budget)"},
    {"vpl-gl", IndirectMethodKind::vpl, PipelineMode::selective, R"({"vpl":{"backend":"gl"}})",
     false, "Barczak: photon VPLs, octahedral shadow maps"},
    {"vpl-cpu", IndirectMethodKind::vpl, PipelineMode::selective, R"({"vpl":{"backend":"cpu"}})",
     false, "the same, visibility by Embree shadow rays"},
    {"rc", IndirectMethodKind::irradiance_cache, PipelineMode::selective,
     R"({"rc":{"max_lifespan":0}})", false,
     "Gautron: irradiance cache splatting, records of the AIMs, no temporal caching"},
    {"rc-temporal", IndirectMethodKind::irradiance_cache, PipelineMode::selective,
     R"({"rc":{"max_lifespan":20}})", false, "the same with temporal caching (dt_max 20)"},
    {"gpu_pm-1b", IndirectMethodKind::gpu_pm, PipelineMode::selective,
     R"({"gpu_pm":{"bounces":1}})", true, "Jimenez Kwast: GPU photon mapping, one bounce"},
    {"gpu_pm-3b", IndirectMethodKind::gpu_pm, PipelineMode::selective,
     R"({"gpu_pm":{"bounces":3}})", false, "the same storing three bounces"},
    // Only by --methods (issue #20's default run is unchanged): the thesis's static VPL set,
    // which stays wrong when a coloured object moves (scenes/compare_coloured.json).
    {"vpl-static", IndirectMethodKind::vpl, PipelineMode::selective,
     R"({"vpl":{"backend":"gl","source":"random_walk"}})", false,
     "Barczak's own VPLs: random walks traced once (static), octahedral shadow maps", false},
};

// A stretch of frames from one edit (or the start) to the next: its frames are scored against
// the reference of the state at its end.
struct Segment {
    int begin = 0, end = 0;         // frames [begin, end)
    int edit_last = -1;             // the last edited frame of the edit that opens it (-1: none)
    Image reference, reference_1b;  // indirect term of the state at `end` (all bounces, one)
};

// The script run ahead on a copy: edit bursts (runs of consecutive edited frames) open segments.
std::vector<Segment> find_segments(const Scene& scene, const std::string& script_path, int frames) {
    std::vector<bool> edited(size_t(frames), false);
    if (!script_path.empty()) {
        Scene ahead = scene;
        Script script(script_path);
        script.on_start(ahead);
        for (int f = 0; f < frames; ++f) {
            const uint64_t before = ahead.version;
            script.on_frame(ahead, f, f / kScriptFramesPerSecond);
            edited[size_t(f)] = ahead.version != before;
        }
    }
    std::vector<Segment> segments(1);
    for (int f = 0; f < frames; ++f) {
        if (!edited[size_t(f)]) continue;
        if (f == 0 || !edited[size_t(f - 1)]) {
            if (f > 0) {
                segments.back().end = f;
                segments.emplace_back().begin = f;
            }
        }
        segments.back().edit_last = f;
    }
    segments.back().end = frames;
    return segments;
}

struct SegmentResult {
    SettleAnalysis settle;  // within the segment, against its own settled value
    double ssim = 0.0;      // mean over the same tail as settle.settled
};

struct MethodResult {
    std::string name, what, missing;  // `missing`: why it did not run (empty: it ran)
    bool single_bounce = false;
    ConvergenceRun run;
    std::vector<double> relmse_1b, ssim_1b;  // per frame, single-bounce methods
    std::vector<SegmentResult> segments;
    double settled_1b = 0.0, ms_mean = 0.0, ms_p95 = 0.0, flicker = 0.0, memory_mib = 0.0;
};

size_t tail_length(size_t n) { return std::min(n, std::max<size_t>(3, n / 10)); }

double tail_mean(const std::vector<double>& v, size_t begin, size_t end) {
    const size_t from = end - tail_length(end - begin);
    double s = 0.0;
    for (size_t i = from; i < end; ++i) s += v[i];
    return s / double(end - from);
}

// Mean absolute change of the colour channels from one frame to the next over their mean.
struct Flicker {
    Image previous;
    double change = 0.0, level = 0.0;
    void add(const Image& image) {
        if (!previous.pixels.empty()) {
            for (size_t p = 0; p < size_t(image.width) * size_t(image.height); ++p)
                for (size_t c = 0; c < 3; ++c) {
                    const size_t i = p * size_t(image.channels) + c;
                    change += std::abs(double(image.pixels[i]) - double(previous.pixels[i]));
                    level += std::abs(double(image.pixels[i]));
                }
        }
        previous = image;
    }
    double value() const { return level > 0.0 ? change / level : 0.0; }
};

std::string fixed(double v, int decimals) {
    char b[64];
    std::snprintf(b, sizeof b, "%.*f", decimals, v);
    return b;
}

// What one variant does through the edits; `missing` holds the reason if it cannot run here.
MethodResult run_variant(const Variant& v, const Scene& base, const std::string& script_path,
                         int frames, int width, int height, int threads, bool prime,
                         const std::vector<Segment>& segments, bool quiet) {
    MethodResult r;
    r.name = v.name, r.what = v.what, r.single_bounce = v.single_bounce;
    Scene scene = base;
    std::vector<int> segment_of(static_cast<size_t>(frames));
    for (size_t s = 0; s < segments.size(); ++s)
        for (int f = segments[s].begin; f < segments[s].end; ++f) segment_of[size_t(f)] = int(s);
    const Segment& last = segments.back();
    const int flicker_from = last.end - int(tail_length(size_t(last.end - last.begin)));
    Flicker flicker;
    try {
        apply_settings_json(scene, v.settings, "compare-methods variant " + v.name);
        scene.settings.indirect.method = v.method;
        const double rss_before = resident_bytes();
        double rss_peak = rss_before;
        Progress progress("compare-methods " + v.name, frames, !quiet);
        r.run = run_convergence(
            scene, script_path, v.mode, frames, width, height, "indirect",
            [&](int f) -> const Image& {
                return segments[size_t(segment_of[size_t(f)])].reference;
            },
            threads, prime, [&](int done) { progress.update(done); },
            [&](int f, const Image& image) {
                rss_peak = std::max(rss_peak, resident_bytes());
                if (f >= flicker_from - 1) flicker.add(image);
                if (v.single_bounce) {
                    const ImageMetrics m =
                        compare_images(image, segments[size_t(segment_of[size_t(f)])].reference_1b);
                    r.relmse_1b.push_back(m.rel_mse), r.ssim_1b.push_back(m.ssim);
                }
            });
        progress.finish();
        r.memory_mib = (rss_peak - rss_before) / (1024.0 * 1024.0);
    } catch (const std::exception& e) {
        r.missing = e.what();
        // The variant may have thrown before reading an error it caused; left pending, it would
        // fail the next variant at its first check_gl.
        const std::string pending = gpu::take_gl_errors();
        if (!pending.empty())
            r.missing += " (GL errors it left pending, now cleared: " + pending + ")";
        return r;
    }
    r.flicker = flicker.value();
    const std::vector<FrameRecord>& fr = r.run.frames;
    std::vector<double> ms, ssim;
    for (size_t f = 0; f < fr.size(); ++f) {
        ms.push_back(1e3 * (fr[f].wall_s - (f ? fr[f - 1].wall_s : 0.0)));
        ssim.push_back(fr[f].ssim);
    }
    r.ms_mean = mean(ms), r.ms_p95 = p95(ms);
    for (const Segment& s : segments) {
        SegmentResult sr;
        const std::vector<FrameRecord> part(fr.begin() + s.begin, fr.begin() + s.end);
        sr.settle = analyse_settle(part, 0.0, frame_start_s(fr, size_t(s.begin)));
        if (sr.settle.within >= 0) sr.settle.within += s.begin;
        sr.settle.last_edit += s.begin;
        sr.ssim = tail_mean(ssim, size_t(s.begin), size_t(s.end));
        r.segments.push_back(sr);
    }
    if (v.single_bounce)
        r.settled_1b = tail_mean(r.relmse_1b, size_t(last.begin), size_t(last.end));
    return r;
}

struct PtPoint {
    int spp = 0;
    double seconds = 0.0, relmse = 0.0, ssim = 0.0;
};

}  // namespace

const Command kCompareMethodsCommand{
    "compare-methods",
    "SCENE [--script S.lua] [options]",
    "Run every indirect method and variant (iim with the GL and the CPU gather, iim as "
    "full-budget, vpl with GL and CPU visibility, irradiance_cache without and with temporal "
    "caching, gpu_pm with one and three bounces) through the same scene-edit script, and path "
    "tracing at increasing samples per pixel. Each frame's indirect term is scored against the "
    "path-traced reference of the state the current edit leads to (one reference per edit, cached "
    "by a hash of the state); single-bounce methods also against single-bounce references. A "
    "method that cannot run here is listed as missing with the reason. Writes PREFIX.png (error "
    "against wall-clock time, edits marked), PREFIX.csv and PREFIX.md (the table: settled relMSE "
    "and SSIM, seconds from each edit until within 10% of that edit's settled error, ms per frame, "
    "flicker, memory) and PREFIX.frames.csv (docs/compare_methods.md).",
    {
        text("script", "S.lua", "scene-edit script (default: the scene's \"script\")"),
        integer("frames,n", "N", "frames to run", 2, 1000000, 150),
        size_option("image size", "96x96"),
        text("methods", "A,B,...",
             "the variants to run (default all: iim-gl, iim-cpu, iim-full-budget, vpl-gl, "
             "vpl-cpu, rc, rc-temporal, gpu_pm-1b, gpu_pm-3b; also vpl-static, the thesis's static "
             "VPL set)"),
        text("pt-spp", "N,N,...",
             "path tracing from scratch at these samples per pixel (final state); '' for none",
             "1,4,16,64"),
        text("out", "PREFIX", "output prefix (default out/compare, or out/compare-NAME)"),
        text("cache", "DIR", "reference cache", "out/reference-cache"),
        integer("ref-spp", "N", "samples per pixel of each pt reference", 1, 1000000, 1024),
        gl_option({gpu::GlBackend::osmesa, gpu::GlBackend::egl, gpu::GlBackend::automatic},
                  gpu::GlBackend::osmesa),
        frame_ms_option(),
        settings_option(),
        integer("threads", "N", "worker threads (default: settings.threads)", 0, 1024),
        flag("no-prime",
             "start from nothing (default: from the converged state of frame 0, untimed, so the "
             "run measures the edits)"),
        flag("quiet,q", "no progress bars"),
    },
    1,
    1,
};

int run_compare_methods(const Args& args) {
    const int frames = args.get_int("frames");
    int width = 0, height = 0;
    args.get_size("size", width, height);
    const std::string scene_path = args.positionals()[0];
    Scene scene = load_scene(scene_path);
    args.apply_settings(scene);
    scene.camera.width = width;
    scene.camera.height = height;
    const std::string script_path = args.get("script", scene.script);
    const std::string name = std::filesystem::path(scene_path).stem().string();
    const std::string prefix =
        args.get("out", name == "compare" ? "out/compare" : "out/compare-" + name);
    const int threads = args.get_int("threads", scene.settings.threads);
    const bool prime = !args.has("no-prime"), quiet = args.has("quiet");

    std::vector<Variant> variants;
    if (args.has("methods")) {
        std::stringstream in(args.get("methods"));
        for (std::string item; std::getline(in, item, ',');) {
            auto it = std::find_if(kVariants.begin(), kVariants.end(),
                                   [&](const Variant& v) { return v.name == item; });
            if (it == kVariants.end()) {
                std::string known;
                for (const Variant& v : kVariants) known += (known.empty() ? "" : ", ") + v.name;
                throw CliError("afterglow compare-methods: --methods: no variant '" + item +
                               "' (expected some of: " + known + ")");
            }
            variants.push_back(*it);
        }
    } else {
        for (const Variant& v : kVariants)
            if (v.by_default) variants.push_back(v);
    }
    std::vector<int> pt_spp;
    {
        std::stringstream in(args.get("pt-spp"));
        for (std::string item; std::getline(in, item, ',');) {
            char* end = nullptr;
            const long n = std::strtol(item.c_str(), &end, 10);
            if (item.empty() || *end != '\0' || n < 1 || n > 1000000)
                throw CliError(
                    "afterglow compare-methods: --pt-spp: expected positive integers, "
                    "got '" +
                    item + "'");
            pt_spp.push_back(int(n));
        }
    }

    // One pt reference per segment, of the state at its end, all bounces and single-bounce.
    std::vector<Segment> segments = find_segments(scene, script_path, frames);
    bool single_bounce = false;
    for (const Variant& v : variants) single_bounce |= v.single_bounce;
    ReferenceRequest request;
    request.name = name;
    request.cache = args.get("cache");
    request.spp = args.get_int("ref-spp");
    request.threads = threads;
    request.path_traced = true;
    request.log_prefix = "afterglow compare-methods";
    std::string final_reference;
    for (Segment& s : segments) {
        request.indirect_bounces = -1;
        final_reference = cached_reference(scene, script_path, s.end, request);
        s.reference = read_reference(final_reference, "indirect", width, height);
        if (!single_bounce) continue;
        request.indirect_bounces = 1;
        s.reference_1b = read_reference(cached_reference(scene, script_path, s.end, request),
                                        "indirect", width, height);
    }

    auto context = gpu::make_gl_context(args.gl_backend());
    const std::string renderer = context->renderer();
    std::vector<MethodResult> results;
    for (const Variant& v : variants) {
        results.push_back(run_variant(v, scene, script_path, frames, width, height, threads, prime,
                                      segments, quiet));
        if (!results.back().missing.empty())
            std::fprintf(stderr, "afterglow compare-methods: %s is missing: %s\n", v.name.c_str(),
                         results.back().missing.c_str());
    }

    // pt from scratch on the final state, another seed than the reference's.
    std::vector<PtPoint> pt;
    if (!pt_spp.empty()) {
        Scene final_state = scene;
        if (!script_path.empty()) {
            Script ahead(script_path);
            run_script_ahead(ahead, final_state, frames);
        }
        ThreadPool pool(threads);
        for (int spp : pt_spp) {
            cpu::ReferenceSettings rs;
            rs.method = cpu::ReferenceMethod::path_tracing;
            rs.spp = spp;
            rs.seed = scene.settings.seed + 1000;
            const auto t0 = std::chrono::steady_clock::now();
            const cpu::ReferenceResult image = cpu::render_reference(final_state, rs, pool);
            const double seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            const ImageMetrics m = compare_images(image.components[size_t(FrameTerm::indirect)],
                                                  segments.back().reference);
            pt.push_back({spp, seconds, m.rel_mse, m.ssim});
        }
    }

    // Per-frame record of every method, the table as CSV and Markdown.
    std::ostringstream frames_csv, table_csv, md;
    frames_csv << "method,segment,frame,wall_s,frame_ms,edited,relmse,ssim,relmse_1b,ssim_1b,spp\n";
    for (const MethodResult& r : results) {
        if (!r.missing.empty()) continue;
        size_t s = 0;
        for (size_t f = 0; f < r.run.frames.size(); ++f) {
            const FrameRecord& x = r.run.frames[f];
            while (int(f) >= segments[s].end) ++s;
            frames_csv << r.name << ',' << s << ',' << x.frame << ',' << x.wall_s << ','
                       << x.frame_ms << ',' << (x.edited ? 1 : 0) << ',' << x.relmse << ','
                       << x.ssim << ',';
            if (r.single_bounce)
                frames_csv << r.relmse_1b[f] << ',' << r.ssim_1b[f];
            else
                frames_csv << ',';
            frames_csv << ",\n";
        }
    }
    for (const PtPoint& p : pt)
        frames_csv << "pt," << segments.size() - 1 << ",-1," << p.seconds << ',' << 1e3 * p.seconds
                   << ",0," << p.relmse << ',' << p.ssim << ",,," << p.spp << "\n";

    table_csv << "method,missing,settled_relmse,settled_ssim,settled_relmse_1b";
    md << "| method | settled relMSE | SSIM | relMSE vs 1 bounce |";
    std::string md_rule = "|---|---|---|---|";
    for (size_t s = 1; s < segments.size(); ++s) {
        table_csv << ",settle_s_edit" << s << ",settle_frames_edit" << s;
        md << " settle s, edit " << s << " (" << segments[s].begin << "–" << segments[s].edit_last
           << ") |";
        md_rule += "---|";
    }
    table_csv << ",frame_ms_mean,frame_ms_p95,flicker,rss_growth_mib\n";
    md << " ms/frame mean | p95 | flicker | RSS growth MiB |\n" << md_rule << "---|---|---|---|\n";
    for (const MethodResult& r : results) {
        if (!r.missing.empty()) {
            std::string reason = r.missing;
            std::replace(reason.begin(), reason.end(), ',', ';');
            std::replace(reason.begin(), reason.end(), '\n', ' ');
            table_csv << r.name << ',' << reason << ",,,";
            for (size_t s = 1; s < segments.size(); ++s) table_csv << ",,";
            table_csv << ",,,\n";
            md << "| " << r.name << " | missing: " << reason << " |\n";
            continue;
        }
        const SegmentResult& fin = r.segments.back();
        table_csv << r.name << ",," << fin.settle.settled << ',' << fin.ssim << ','
                  << (r.single_bounce ? fixed(r.settled_1b, 6) : "");
        md << "| " << r.name << " | " << fixed(fin.settle.settled, 4) << " | " << fixed(fin.ssim, 3)
           << " | " << (r.single_bounce ? fixed(r.settled_1b, 4) : "") << " |";
        for (size_t s = 1; s < segments.size(); ++s) {
            const SettleAnalysis& a = r.segments[s].settle;
            table_csv << ',' << (a.settled_ok() ? fixed(a.seconds, 4) : "") << ','
                      << (a.settled_ok() ? std::to_string(a.frames) : "");
            md << ' '
               << (a.settled_ok() ? fixed(a.seconds, 2) + " (" + std::to_string(a.frames) + " fr)"
                                  : std::string("not settled"))
               << " |";
        }
        table_csv << ',' << r.ms_mean << ',' << r.ms_p95 << ',' << r.flicker << ',' << r.memory_mib
                  << "\n";
        md << ' ' << fixed(r.ms_mean, 1) << " | " << fixed(r.ms_p95, 1) << " | "
           << fixed(r.flicker, 5) << " | " << fixed(r.memory_mib, 1) << " |\n";
    }
    for (const PtPoint& p : pt) {
        table_csv << "pt-" << p.spp << "spp,," << p.relmse << ',' << p.ssim << ',';
        md << "| pt " << p.spp << " spp (from scratch) | " << fixed(p.relmse, 4) << " | "
           << fixed(p.ssim, 3) << " | |";
        for (size_t s = 1; s < segments.size(); ++s) {
            table_csv << ",,";
            md << " one image |";
        }
        table_csv << ',' << 1e3 * p.seconds << ",,,\n";
        md << ' ' << fixed(1e3 * p.seconds, 1) << " | | | |\n";
    }
    std::ostringstream notes;
    notes << "\n"
          << scene_path << (script_path.empty() ? "" : " with " + script_path) << ", " << width
          << "x" << height << ", " << frames << " frames"
          << (prime ? ", each run starting from the converged state of frame 0" : "")
          << "; GL: " << renderer << ". Indirect term against " << request.spp
          << "-spp pt references of the state each edit leads to (frames ";
    for (size_t s = 0; s < segments.size(); ++s)
        notes << (s ? ", " : "") << segments[s].begin << "–" << segments[s].end - 1
              << " → state at " << segments[s].end;
    notes << "). Settled: mean of the last tenth (≥ 3) of the final segment's frames; settle s: "
             "wall time from the start of an edit's last frame (that frame included) until the "
             "error stays within 10% of that "
             "segment's own settled value; flicker: mean |frame-to-frame change| over the mean "
             "value, over the last tenth of the final (still) segment, all pixels static; RSS "
             "growth: peak resident set during the run above the resident set before the "
             "method's pipeline was built (llvmpipe keeps GL buffers in CPU memory, so they are "
             "included; memory freed by earlier methods may be reused, so this is a lower bound); "
             "pt: one image from scratch (its seconds under ms/frame).\n";
    md << notes.str();

    const std::filesystem::path dir = std::filesystem::absolute(prefix).parent_path();
    std::filesystem::create_directories(dir);
    write_file_atomically(prefix + ".frames.csv", frames_csv.str());
    write_file_atomically(prefix + ".csv", table_csv.str());
    write_file_atomically(prefix + ".md", md.str());
    std::printf("%s", md.str().c_str());
    std::printf("wrote %s.csv, %s.md and %s.frames.csv\n", prefix.c_str(), prefix.c_str(),
                prefix.c_str());
    const std::string command = "/usr/bin/python3 tools/plot_compare_methods.py '" + prefix +
                                ".png' '" + prefix + ".frames.csv' --title '" + name + ", " +
                                std::to_string(width) + "x" + std::to_string(height) + ", " +
                                renderer + "'";
    if (std::system(command.c_str()) != 0)
        std::cerr << "afterglow compare-methods: warning: plotting failed (" << command << ")\n";
    else
        std::printf("wrote %s.png\n", prefix.c_str());
    int missing = 0;
    for (const MethodResult& r : results) missing += r.missing.empty() ? 0 : 1;
    if (missing == int(results.size()) && !results.empty()) {
        std::fprintf(stderr, "afterglow compare-methods: no method could run\n");
        return 1;
    }
    return 0;
}

static const Registration kRegistration(kCompareMethodsCommand, run_compare_methods, 42);

}  // namespace ag::cli
