#include "tools/afterglow/bench_media.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "gpu/media_marcher.h"
#include "shared/image.h"
#include "shared/media_grid.h"
#include "shared/metrics.h"
#include "shared/pipeline/media_method.h"
#include "shared/scene_file.h"

namespace ag::cli {

namespace {

struct Row {
    std::string pipeline;
    int photons = 0;               // generated (importance-sampled, for the adaptive pipeline)
    size_t marched = 0;            // marched, pilots included
    double rmse = 0.0, rel = 0.0;  // against the reference image; rel = rmse / its mean
    MediaMethodTiming timing;
};

double image_mean(const Image& image) {
    double sum = 0.0;
    for (float v : image.pixels) sum += v;
    return image.pixels.empty() ? 0.0 : sum / double(image.pixels.size());
}

Row run(const Scene& scene, const MediaMethodSettings& settings, const Image& reference,
        const std::string& name) {
    const MediaMethodResult r = render_media(scene, settings);
    Row row;
    row.pipeline = name;
    row.photons = settings.photons;
    row.marched = r.photons_marched + r.pilots_marched;
    row.timing = r.timing;
    if (!reference.pixels.empty()) {
        row.rmse = compare_images(r.volume, reference).rmse;
        row.rel = row.rmse / image_mean(reference);
    }
    return row;
}

// Marched photons at which the uniform curve (marched ascending, RMSE descending) reaches
// `rmse`, by log-log interpolation; beyond its ends by the nearest pair's slope (`extrapolated`).
double photons_at(const std::vector<Row>& curve, double rmse, bool& extrapolated) {
    size_t k = 0;
    while (k + 2 < curve.size() && curve[k + 1].rmse > rmse) ++k;
    const Row &a = curve[k], &b = curve[k + 1];
    extrapolated = rmse > a.rmse || rmse < b.rmse;
    const double t = (std::log(rmse) - std::log(a.rmse)) / (std::log(b.rmse) - std::log(a.rmse));
    return std::exp(std::log(double(a.marched)) +
                    t * (std::log(double(b.marched)) - std::log(double(a.marched))));
}

// His numbers for one of Tables 4.2–4.4 (ms; the photon counts marched).
struct HisPasses {
    const char* table;
    int voxelisation, pilot_marching, distribution, march_reference, march_adaptive, mipmap,
        filtering, copy, viewing, total_reference, total_adaptive, photons_reference,
        photons_adaptive;
};
constexpr HisPasses kSphere{"4.2 (sphere)", 25,   10, 5, 110, 85, 16, 14, 44, 189, 373, 395,
                            122000,         50000};
constexpr HisPasses kCube{"4.3 (cube)", 43, 11,  5,   144, 100,    17,
                          13,           48, 212, 452, 456, 125000, 46000};
constexpr HisPasses kArmadillo{"4.4 (Armadillo; ours: the Stanford bunny)",
                               68,
                               11,
                               6,
                               163,
                               134,
                               16,
                               13,
                               44,
                               179,
                               459,
                               478,
                               106000,
                               49000};

void print_passes(const HisPasses& his, const Row& reference, const Row& adaptive) {
    const MediaMethodTiming &r = reference.timing, &a = adaptive.timing;
    std::printf("| pass | Pfeuti ref. | Pfeuti adaptive | ours ref. | ours adaptive |\n");
    std::printf("|---|---|---|---|---|\n");
    const auto line = [](const char* pass, const std::string& his_r, const std::string& his_a,
                         double ours_r, double ours_a) {
        std::printf("| %s | %s | %s | %.0f ms | %.0f ms |\n", pass, his_r.c_str(), his_a.c_str(),
                    1e3 * ours_r, 1e3 * ours_a);
    };
    const auto ms = [](int v) { return std::to_string(v) + " ms"; };
    line("voxelisation (+ smoothing)", ms(his.voxelisation), ms(his.voxelisation),
         r.voxelisation + r.smoothing, a.voxelisation + a.smoothing);
    line("octree (CPU, once per grid)", "5 ms", "5 ms", r.octree, a.octree);
    line("pilot photon generation", "-", "< 1 ms", 0.0, a.pilot_generation);
    line("pilot photon marching", "-", ms(his.pilot_marching), 0.0, a.pilot_marching);
    line("photon distribution", "-", ms(his.distribution), 0.0, a.distribution);
    line("photon generation", "< 1 ms", "2 ms", r.photon_generation, a.photon_generation);
    line("photon marching", ms(his.march_reference), ms(his.march_adaptive), r.photon_marching,
         a.photon_marching);
    line("mipmap generation + filtering", "-", ms(his.mipmap + his.filtering), 0.0,
         a.reconstruction);
    std::printf("| copy | %d ms | %d ms | — | — |\n", his.copy, his.copy);
    line("viewing pass", ms(his.viewing), ms(his.viewing), r.viewing, a.viewing);
    line("total", ms(his.total_reference), ms(his.total_adaptive), r.total(), a.total());
    std::printf("| photons marched | %d | %d | %zu | %zu |\n", his.photons_reference,
                his.photons_adaptive, reference.marched, adaptive.marched);
    std::printf("| RMSE (relative) against the reference | — | — | %.5f (%.4f) | %.5f (%.4f) |\n",
                reference.rmse, reference.rel, adaptive.rmse, adaptive.rel);
}

// Uniform photons generated per photon marched (those that miss the grid are dropped).
double hit_fraction(const Scene& scene, const MediaMethodSettings& base) {
    MediaMethodSettings probe = base;
    probe.photons = 20000;
    return std::max(1e-3,
                    double(render_media(scene, probe, false).photons_marched) / probe.photons);
}

// A uniform reference of `target` marched photons.
Image reference_image(const Scene& scene, const MediaMethodSettings& base, double hit, int target) {
    MediaMethodSettings settings = base;
    settings.photons = int(std::ceil(target / hit));
    const MediaMethodResult ref = render_media(scene, settings);
    std::printf("reference: %d photons generated, %zu marched (%.1f s marching)\n\n",
                settings.photons, ref.photons_marched, ref.timing.photon_marching);
    return ref.volume;
}

// One of his Tables 4.2–4.4: the passes of both pipelines at his photon counts (marched; the
// adaptive count with its pilots).
void passes_table(const Scene& scene, const MediaMethodSettings& base, double hit,
                  const Image& reference, const HisPasses& his) {
    std::printf("\nTable %s: passes at his photon counts\n\n", his.table);
    MediaMethodSettings s = base;
    s.photons = int(his.photons_reference / hit);
    const Row table_reference = run(scene, s, reference, "reference");
    // The adaptive photons meet the grid more often than uniform ones: their share from a probe.
    s.adaptive.enabled = true;
    s.photons = his.photons_adaptive;
    const MediaMethodResult probe = render_media(scene, s, false);
    s.photons = int(double(his.photons_adaptive) *
                    (double(his.photons_adaptive) - double(probe.pilots_marched)) /
                    double(std::max<size_t>(probe.photons_marched, 1)));
    const Row table_adaptive = run(scene, s, reference, "adaptive");
    print_passes(his, table_reference, table_adaptive);
}

// His Table 4.5 (ch. 4.3.3): the adaptive pipeline's marching pass (two statistics a crossing)
// on uniform photons U, on photons through the pilots' density A, and on photons through its
// complement C — the uniform density split as 1 = p/M + (1 − p/M), M = max p, so that A and C
// share U's count (N/M and N − N/M) and together have its density. His question: are the
// importance-sampled photons the expensive ones to march? No conflict counts: our fixed-point
// adds never retry.
void table_4_5(const Scene& scene, const MediaMethodSettings& base) {
    const Light* light = nullptr;
    for (const Light& l : scene.lights)
        if (l.enabled && (l.type == LightType::point || l.type == LightType::spot)) {
            light = &l;
            break;
        }
    if (!light) return;
    MediaMethodSettings s = base;
    s.adaptive.enabled = true;
    s.photons = 1000;  // the pilots' density and the grids are what this run is for
    const MediaMethodResult pilot = render_media(scene, s, false);
    const float intensity = glm::dot(light->value(), glm::vec3(1.0f / 3.0f));
    const PhotonSource source = photon_source(light->position, intensity, pilot.grids.bounds);
    const int side = s.adaptive.pilot_side;
    std::vector<float> a_cells(pilot.density.begin(), pilot.density.end());
    const float peak = *std::max_element(a_cells.begin(), a_cells.end());
    std::vector<float> c_cells(a_cells.size());
    for (size_t i = 0; i < a_cells.size(); ++i) c_cells[i] = 1.0f - a_cells[i] / peak;
    const PhotonDensity a_density(side, a_cells);
    const bool complement = *std::max_element(c_cells.begin(), c_cells.end()) > 0.0f;
    const PhotonDensity c_density = complement ? PhotonDensity(side, c_cells) : PhotonDensity();
    gpu::MediaMarchSettings march;
    march.step = base.march_step;
    march.deposit = base.deposit;
    const gpu::MediaMarcher marcher;
    // Photons of one kind: count Hammersley points, through `density` (none: uniform).
    const auto march_set = [&](int count, const PhotonDensity* density, size_t& marched) {
        std::vector<MediaPhoton> photons;
        std::vector<glm::vec4> inverse;
        MediaPhoton photon;
        for (int i = 0; i < count; ++i) {
            const glm::vec2 h = hammersley(i, count, glm::vec2(0.0f));
            const glm::vec2 uv = density ? density->sample(h) : h;
            const double p = density ? density->pdf(uv) : 1.0;
            if (!source_photon(source, uv, p, count, photon)) continue;
            photons.push_back(photon);
            inverse.emplace_back(float(1.0 / p), 0.0f, 0.0f, 0.0f);
        }
        marched = photons.size();
        return marcher.march(pilot.grids, photons, march, inverse, 2).seconds;
    };
    std::printf(
        "\nTable 4.5: the adaptive marching pass on uniform (U), adaptive (A) and complement (C) "
        "photons (M = %.2f; his conflicts: none to count)\n\n",
        peak);
    std::printf(
        "| U generated | U marched | A marched | C marched | U ms | A ms | C ms | µs a photon U | "
        "A | C |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for (int n : {40000, 60000, 80000, 100000, 122000}) {
        size_t mu = 0, ma = 0, mc = 0;
        const double tu = march_set(n, nullptr, mu);
        const int na = int(std::lround(double(n) / peak));
        const double ta = march_set(na, &a_density, ma);
        const double tc = complement ? march_set(n - na, &c_density, mc) : 0.0;
        const auto per = [](double t, size_t m) { return m > 0 ? 1e6 * t / double(m) : 0.0; };
        std::printf("| %d | %zu | %zu | %zu | %.0f | %.0f | %.0f | %.2f | %.2f | %.2f |\n", n, mu,
                    ma, mc, 1e3 * tu, 1e3 * ta, 1e3 * tc, per(tu, mu), per(ta, ma), per(tc, mc));
    }
}

}  // namespace

int bench_media(const Args& args, const std::string& scene_path, int width, int height) {
    Scene scene = load_scene(scene_path);
    scene.camera.width = width;
    scene.camera.height = height;
    const bool full = args.has("full");
    MediaMethodSettings base;
    base.grid = args.get_int("grid", full ? 128 : 64);
    // His pipelines as he measured them: photons from the light only (the adaptive pipeline
    // does not bounce photons off surfaces, so the reference must not either).
    base.surface_bounces = 0;
    // His viewing pass is the volume term alone: not the fog's light on the surfaces (the frame's
    // indirect term, ours), which would add its march rays to the pass's time.
    base.fog_on_surfaces_rays = 0;
    base.adaptive.fractional_level = !args.has("integer-level");
    base.adaptive.bilinear_density = !args.has("constant-density");
    std::printf(
        "bench media: %s at %dx%d, %d voxels along the longest side (llvmpipe timings: a "
        "software rasteriser on shared CPU cores, not a GPU)\n",
        scene_path.c_str(), width, height, base.grid);

    // The reference: uniform Hammersley photons until --ref-photons (default 2M) are marched.
    const int target = args.get_int("ref-photons", 2000000);
    const double hit = hit_fraction(scene, base);
    const Image reference = reference_image(scene, base, hit, target);

    // Equal-RMSE curve: the reference pipeline at doubling photon counts against the adaptive
    // one (his 64² pilots), each against the reference image.
    std::vector<int> uniform_counts{25000, 50000, 100000, 200000, 400000, 800000};
    std::vector<int> adaptive_counts{12500, 25000, 50000, 100000, 200000};
    if (full) {
        uniform_counts.push_back(1600000);
        adaptive_counts.push_back(400000);
    }
    std::vector<Row> uniform, adaptive;
    for (int n : uniform_counts) {
        MediaMethodSettings s = base;
        s.photons = n;
        uniform.push_back(run(scene, s, reference, "reference"));
    }
    // The adaptive pipeline's error depends on the seed (the pilots' jitter, the rotation of its
    // Hammersley points; ±12% between seeds at 50,000 on fog_sphere_point): with --seeds N each
    // row is the root mean square over N seeds, the expected error, not one seed's luck.
    const int seeds = args.get_int("seeds", 1);
    std::vector<std::pair<double, double>> seed_range;  // per adaptive row: best, worst seed
    for (int n : adaptive_counts) {
        MediaMethodSettings s = base;
        s.photons = n;
        s.adaptive.enabled = true;
        Row row;
        double square = 0.0, best = 1e30, worst = 0.0;
        for (int k = 0; k < seeds; ++k) {
            s.adaptive.seed = uint32_t(k);
            const Row one = run(scene, s, reference, "adaptive");
            if (k == 0) row = one;
            square += one.rmse * one.rmse / seeds;
            best = std::min(best, one.rmse);
            worst = std::max(worst, one.rmse);
        }
        row.rmse = std::sqrt(square);
        row.rel = row.rmse / image_mean(reference);
        adaptive.push_back(row);
        seed_range.emplace_back(best, worst);
    }
    if (seeds > 1)
        std::printf(
            "Adaptive rows: RMSE the root mean square over seeds 0..%d; the marched count and "
            "times are seed 0's.\n\n",
            seeds - 1);
    std::printf("Photons at equal RMSE (volume image against the reference):\n\n");
    std::printf(
        "| pipeline | photons generated | marched (+ pilots) | RMSE | relative RMSE | "
        "uniform marched at this RMSE | adaptive / uniform | march ms | total ms |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    for (const Row& r : uniform)
        std::printf("| %s | %d | %zu | %.5f | %.4f | | | %.0f | %.0f |\n", r.pipeline.c_str(),
                    r.photons, r.marched, r.rmse, r.rel, 1e3 * r.timing.photon_marching,
                    1e3 * r.timing.total());
    for (const Row& r : adaptive) {
        bool extrapolated = false;
        const double equal = photons_at(uniform, r.rmse, extrapolated);
        std::printf("| %s | %d | %zu | %.5f | %.4f | %.0f%s | %.2f | %.0f | %.0f |\n",
                    r.pipeline.c_str(), r.photons, r.marched, r.rmse, r.rel, equal,
                    extrapolated ? " (extrapolated)" : "", double(r.marched) / equal,
                    1e3 * (r.timing.pilot_marching + r.timing.photon_marching),
                    1e3 * r.timing.total());
    }
    if (seeds > 1) {
        std::printf("\nAdaptive / uniform for the best and the worst of the %d seeds:", seeds);
        for (size_t k = 0; k < adaptive.size(); ++k) {
            bool extrapolated = false;
            const double marched = double(adaptive[k].marched);
            std::printf(" %d: %.2f-%.2f;", adaptive[k].photons,
                        marched / photons_at(uniform, seed_range[k].first, extrapolated),
                        marched / photons_at(uniform, seed_range[k].second, extrapolated));
        }
        std::printf("\n");
    }
    if (args.has("curve-only")) return 0;

    passes_table(scene, base, hit, reference, kSphere);

    // Table 4.1: the order of 122,000 marched photons on the plane.
    std::printf("\nTable 4.1: photon marching time by sampling order (122,000 photons)\n\n");
    std::printf("| order | Pfeuti | ours march | RMSE | relative RMSE |\n|---|---|---|---|---|\n");
    const char* his[] = {"154 ms", "158 ms", "191 ms", "148 ms", "194 ms", "163 ms", "109 ms"};
    for (int k = 0; k < 7; ++k) {
        MediaMethodSettings o = base;
        o.photons = int(122000 / std::max(hit, 1e-3));
        o.sampling = PlaneSampling(k);
        const Row r = run(scene, o, reference, kPlaneSamplingNames[k]);
        std::printf("| %s | %s | %.0f ms | %.5f | %.4f |\n", kPlaneSamplingNames[k], his[k],
                    1e3 * r.timing.photon_marching, r.rmse, r.rel);
    }
    table_4_5(scene, base);

    // His octree (ch. 3.1.3): the same photons in fixed steps and through the octree's cubes.
    std::printf(
        "\nOctree: 122,000 photons marched in fixed steps and with the octree's long steps\n\n");
    std::printf(
        "| steps | octree build | photon marching | RMSE | relative RMSE "
        "|\n|---|---|---|---|---|\n");
    double march_ms[2] = {0.0, 0.0};
    for (const bool octree : {false, true}) {
        MediaMethodSettings o = base;
        o.photons = int(122000 / std::max(hit, 1e-3));
        o.octree = octree;
        const Row r = run(scene, o, reference, octree ? "octree" : "fixed");
        march_ms[octree ? 1 : 0] = 1e3 * r.timing.photon_marching;
        std::printf("| %s | %.1f ms | %.0f ms | %.6f | %.5f |\n", octree ? "octree" : "fixed",
                    1e3 * r.timing.octree, 1e3 * r.timing.photon_marching, r.rmse, r.rel);
    }
    std::printf("\nphoton marching with the octree / fixed steps: %.2f\n",
                march_ms[0] > 0.0 ? march_ms[1] / march_ms[0] : 0.0);
    // Tables 4.3 and 4.4 on our cube (perturbed index and scattering) and bunny scenes, each
    // against its own reference.
    if (full)
        for (const auto& [path, his_table] :
             {std::pair{"scenes/media_noise_cube_point.json", kCube},
              std::pair{"scenes/media_bunny_fog.json", kArmadillo}}) {
            Scene other = load_scene(path);
            other.camera.width = width;
            other.camera.height = height;
            std::printf("\n%s:\n", path);
            const double other_hit = hit_fraction(other, base);
            const Image other_reference = reference_image(other, base, other_hit, target);
            passes_table(other, base, other_hit, other_reference, his_table);
        }
    return 0;
}

}  // namespace ag::cli
