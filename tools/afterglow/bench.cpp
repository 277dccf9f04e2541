// afterglow bench photons|knn: measured speeds, with the ratios that matter taken in one run.
#include <chrono>
#include <cstdio>
#include <random>

#include "cpu/knn.h"
#include "cpu/photon_simulation.h"
#include "shared/scene_file.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kBenchCommand{
    "bench",
    "photons|knn [SCENE] [options]",
    "Benchmarks. 'photons SCENE': photon throughput with all bookkeeping against raw Embree rays "
    "for the same paths, on one thread, and memory per stored hit. 'knn': Larsen Table 8.1 "
    "(1,000,000 random photons in 1/10/100/1,000 maps; build and 500-nearest lookup) and Table "
    "14.1 (300–2,000 photons; build and 100-nearest lookup).",
    {
        {"repeat", "", "N", "repetitions, best time kept (default 5)"},
        {"queries", "", "N", "kNN queries per measurement (default 2000)"},
    },
    1,
    2,
};

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

int bench_photons(const std::string& scene_path, int repeat) {
    Scene scene = load_scene(scene_path);
    ThreadPool pool(1);  // per-core figures
    cpu::PhotonSimulation sim(scene, pool);
    sim.trace_all();
    const int groups = scene.settings.photons.groups, per_group = scene.settings.photons.photons_per_group;
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
                rays.push_back({origin, glm::vec3(0.0f, 0.0f, 1.0f), 1e-3f, 1e30f});  // the final miss / absorption ray
            }

    double best_full = 1e30, best_raw = 1e30, best_trace = 1e30;
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
    }
    size_t vertices = 0, stored = sim.maps().hit_count();
    size_t bytes = stored * sizeof(cpu::PhotonHit);
    for (int l = 0; l < int(scene.lights.size()); ++l)
        for (int g = 0; g < groups; ++g) {
            const cpu::PhotonGroup& grp = sim.maps().group(l, g);
            vertices += grp.vertices.size();
            bytes += grp.vertices.size() * sizeof(cpu::PathVertex) + grp.photon_begin.size() * sizeof(uint32_t) +
                     sizeof(cpu::PhotonGroup);
        }
    std::printf("scene %s: %zu triangles, %d photons (%d groups x %d per light), %zu path vertices, %zu stored hits\n",
                scene_path.c_str(), scene.triangle_count(), photons, groups, per_group, vertices, stored);
    std::printf("photons with bookkeeping: %.0f photons/s/core (%.3f ms for all)\n", photons / best_full, 1e3 * best_full);
    std::printf("raw Embree, same segments: %.0f rays/s/core = %.0f photons/s/core (%zu rays, %.3f ms)\n",
                double(rays.size()) / best_raw, photons / best_raw, rays.size(), 1e3 * best_raw);
    std::printf("tracing without bookkeeping (same photons, nothing stored): %.0f photons/s/core (%.3f ms)\n",
                photons / best_trace, 1e3 * best_trace);
    std::printf("ratio with bookkeeping / without: %.2f;  with bookkeeping / raw Embree rays: %.2f\n",
                best_trace / best_full, best_raw / best_full);
    std::printf("memory: %zu bytes for hits + paths = %.1f KB, %.1f bytes per stored hit (sizeof hit %zu, vertex %zu)\n",
                bytes, bytes / 1024.0, double(bytes) / double(std::max<size_t>(1, stored)), sizeof(cpu::PhotonHit),
                sizeof(cpu::PathVertex));
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
            for (int i = 0; i < queries; ++i) trees[size_t(i) % maps].query(q[size_t(i)], k, idx, d2);
            best_query = std::min(best_query, seconds_since(t) / queries);
        }
        std::printf("  %8zu photons in %5zu maps of %7zu: build %9.3f ms, %d-nearest lookup %8.2f us\n", total, maps,
                    per_map, 1e3 * best_build, k, 1e6 * best_query);
    };
    std::printf("Larsen Table 8.1: 1,000,000 random photons in M maps, 500 nearest\n");
    for (size_t maps : {1, 10, 100, 1000}) measure(1000000, maps, 500);
    std::printf("Larsen Table 14.1: one map, 100 nearest\n");
    for (size_t n : {300, 500, 1000, 2000}) measure(n, 1, 100);
    return 0;
}

}  // namespace

int run_bench(const Args& args) {
    const std::string what = args.positionals()[0];
    const int repeat = args.get_int("repeat", 5, 1, 1000);
    if (what == "photons") {
        if (args.positionals().size() < 2) throw CliError("afterglow bench photons: missing SCENE");
        return bench_photons(args.positionals()[1], repeat);
    }
    if (what == "knn") return bench_knn(repeat, args.get_int("queries", 2000, 1, 100000000));
    throw CliError("afterglow bench: unknown benchmark '" + what + "' (expected photons or knn)");
}

static const Registration kRegistration(kBenchCommand, run_bench, 90);

}  // namespace ag::cli
