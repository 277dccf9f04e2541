#include "tools/afterglow/bench_vpl.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <glm/gtc/constants.hpp>

#include "cpu/ray_tracer.h"
#include "cpu/vpl_shading.h"
#include "cpu/vpl_source.h"
#include "cpu/vpl_visibility.h"
#include "gpu/gl.h"
#include "gpu/scene_meshes.h"
#include "gpu/vpl_gather.h"
#include "gpu/vpl_shadow_maps.h"
#include "shared/charts.h"
#include "shared/mesh_decimate.h"
#include "shared/mesh_io.h"
#include "shared/metrics.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/shapes.h"

namespace ag::cli {

namespace {

using Clock = std::chrono::steady_clock;

// Best wall time of `repeat` runs of `f` (GL finished), ms; one warm-up run first.
template <class F>
double best_ms(int repeat, F&& f) {
    f();
    gpu::gl::Finish();
    double best = 1e30;
    for (int r = 0; r < repeat; ++r) {
        const Clock::time_point t = Clock::now();
        f();
        gpu::gl::Finish();
        best = std::min(best, std::chrono::duration<double, std::milli>(Clock::now() - t).count());
    }
    return best;
}

std::vector<glm::vec3> column(const std::vector<cpu::SurfacePoint>& p, int w, int h, bool normals) {
    std::vector<glm::vec3> out(p.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const cpu::SurfacePoint& s = p[size_t(y) * size_t(w) + size_t(x)];
            out[size_t(h - 1 - y) * size_t(w) + size_t(x)] = normals ? s.normal : s.position;
        }
    return out;
}

// relMSE (shared/metrics.h's form, ε = kRelMseEpsilon) and relative L1 of x against y.
std::pair<double, double> errors(const std::vector<glm::vec3>& x, const std::vector<glm::vec3>& y) {
    double mse = 0.0, l1 = 0.0, norm = 0.0;
    for (size_t i = 0; i < x.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double d = double(x[i][c]) - double(y[i][c]);
            mse += d * d / (double(y[i][c]) * double(y[i][c]) + kRelMseEpsilon);
            l1 += std::abs(d);
            norm += std::abs(double(y[i][c]));
        }
    return {mse / double(3 * std::max<size_t>(1, x.size())), norm > 0.0 ? l1 / norm : 0.0};
}

// The thesis's table room (§5.2, §5.4) with each of its movers sliding 8 mm a frame across the
// table: whole frames (K map updates round robin + the per-pixel sum) against the number of
// lights and K. The G-buffer points stay those of the first frame (the maps see the mover move;
// the points it uncovers are not re-cast): the cost of the frame's parts, not its image.
// "Mverts": vertices the map passes transformed per frame (millions), the thesis's cost measure,
// a count that does not move with the machine's load.
void table_rooms(const Args& args, const std::string& scene_path, int width, int height, int repeat,
                 ThreadPool& pool) {
    const std::filesystem::path folder = std::filesystem::path(scene_path).parent_path();
    for (const char* room : {"vpl_table_bunny.json", "vpl_table_torus.json"}) {
        const std::string room_path = (folder / room).string();
        Scene t;
        try {
            t = load_scene(room_path);
        } catch (const std::exception& e) {
            std::printf("\n(%s left out: %s)\n", room, e.what());
            continue;
        }
        args.apply_settings(t);
        const VplSettings& vs = t.settings.vpl;
        const float scale = glm::one_over_pi<float>();
        int mover = -1;
        for (size_t o = 0; o < t.objects.size(); ++o)
            if (t.objects[o].dynamic) mover = int(o);
        if (mover < 0) continue;
        cpu::RayTracer t_rays(t);
        const std::vector<Vpl> t_all = cpu::random_walk_vpls(t, t_rays, 300, 5, t.settings.seed);
        const std::vector<cpu::SurfacePoint> t_points =
            cpu::camera_points(t, t_rays, width, height, pool);
        gpu::SceneMeshes t_meshes(t);
        Bounds tb;
        for (const Object& o : t.objects)
            for (const glm::vec3& p : o.mesh.positions) tb.add(o.transform.apply_point(p));
        gpu::VplShadowMaps t_maps(t, t_meshes, vs.map_size, vs.map,
                                  1e-4f * glm::length(tb.extent()));
        gpu::VplGather t_gather(width, height);
        t_gather.set_points(column(t_points, width, height, false),
                            column(t_points, width, height, true));
        int frame = 0;
        auto slide = [&] {  // 8 mm a frame, 100 frames one way and back
            const float step = (frame++ / 100) % 2 == 0 ? 0.008f : -0.008f;
            translate_object(t, mover, glm::vec3(step, 0.0f, 0.0f));
        };
        std::printf("\n%s: %zu triangles, mover '%s' %zu vertices, %zu random-walk VPLs\n", room,
                    t.triangle_count(), t.objects[size_t(mover)].name.c_str(),
                    t.objects[size_t(mover)].mesh.positions.size(), t_all.size());
        std::printf("%8s %-22s %10s %8s %10s\n", "VPLs", "map updates a frame", "ms/frame", "fps",
                    "Mverts");
        for (size_t count : {100, 200, 300}) {
            if (count > t_all.size()) break;
            const std::vector<Vpl> v(t_all.begin(), t_all.begin() + std::ptrdiff_t(count));
            t_maps.set_vpls(v);
            t_maps.render_all();
            const int c = int(v.size());
            // All of them without culling: the naive row; then all and K a frame culled.
            std::vector<int> updates{-c, c};
            for (int k : {150, 100, 50})
                if (k < c) updates.push_back(k);
            updates.push_back(0);  // static maps
            for (int signed_k : updates) {
                const int k = std::abs(signed_k);
                t_maps.set_culling(signed_k >= 0);
                int next = 0;
                const uint64_t before = t_maps.vertices_transformed();
                const double ms = best_ms(repeat, [&] {
                    slide();
                    const int run = std::min(k, c - next);  // round robin, wrapping to 0
                    t_maps.render(next, run);
                    t_maps.render(0, k - run);
                    next = (next + k) % c;
                    t_gather.shade(t_maps, vs.clamp, scale);
                });
                const double mverts =
                    double(t_maps.vertices_transformed() - before) / double(repeat + 1) / 1e6;
                char label[48];
                if (signed_k == -c)
                    std::snprintf(label, sizeof label, "all %d (naive)", c);
                else if (k == c)
                    std::snprintf(label, sizeof label, "all %d, culled", c);
                else if (k == 0)
                    std::snprintf(label, sizeof label, "none (static maps)");
                else
                    std::snprintf(label, sizeof label, "K = %d", k);
                std::printf("%8zu %-22s %10.2f %8.2f %10.2f\n", count, label, ms, 1000.0 / ms,
                            mverts);
                std::fflush(stdout);
            }
        }
    }
}

}  // namespace

int bench_vpl(const Args& args, const std::string& scene_path, int width, int height, int repeat) {
    if (args.has("rooms")) {
        ThreadPool pool(0);
        table_rooms(args, scene_path, width, height, repeat, pool);
        return 0;
    }
    Scene scene = load_scene(scene_path);
    args.apply_settings(scene);
    const VplSettings& vs = scene.settings.vpl;
    cpu::RayTracer rays(scene);
    ThreadPool pool(scene.settings.threads);
    // The thesis's indirect VPLs: cosine random walks, up to 5 bounces; enough for the sweep.
    const std::vector<Vpl> all = cpu::random_walk_vpls(scene, rays, 600, 5, scene.settings.seed);
    std::vector<cpu::RayHit> hits;
    const std::vector<cpu::SurfacePoint> points =
        cpu::camera_points(scene, rays, width, height, pool, &hits);
    gpu::SceneMeshes meshes(scene);
    Bounds b;
    for (const Object& o : scene.objects)
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    const float near = 1e-4f * glm::length(b.extent());
    gpu::VplShadowMaps maps(scene, meshes, vs.map_size, vs.map, near);
    gpu::VplGather gather(width, height);
    gather.set_points(column(points, width, height, false), column(points, width, height, true));
    const float scale = glm::one_over_pi<float>();
    auto take = [&](size_t n) {
        return std::vector<Vpl>(all.begin(), all.begin() + std::ptrdiff_t(std::min(n, all.size())));
    };
    std::printf("scene %s, %zu triangles, %dx%d, %d² %s maps, %zu random-walk VPLs available\n",
                scene_path.c_str(), scene.triangle_count(), width, height, vs.map_size,
                kVplMapKindNames[size_t(vs.map)], all.size());

    // 1. Naive against each optimisation at 300 lights.
    const std::vector<Vpl> v300 = take(300);
    maps.set_vpls(v300);
    maps.render_all();
    const int n = int(v300.size());
    // Per pixel, the patch (leaf of the visibility database) its hit lies in; per (patch, VPL),
    // the F/P/N label: what the GL sum reads to skip pairs.
    auto patches_and_labels = [&](const cpu::VisibilityDatabase& db) {
        std::vector<int> patch(points.size(), 0);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const cpu::RayHit& h = hits[size_t(y) * size_t(width) + size_t(x)];
                const int leaf = h.hit ? db.leaf_at(h.object, h.triangle, h.barycentric) : -1;
                patch[size_t(height - 1 - y) * size_t(width) + size_t(x)] = std::max(0, leaf);
            }
        std::vector<uint32_t> labels(db.nodes().size() * v300.size());
        for (size_t node = 0; node < db.nodes().size(); ++node)
            for (int l = 0; l < n; ++l)
                labels[node * v300.size() + size_t(l)] = uint32_t(db.state(int(node), l));
        return std::pair{patch, labels};
    };
    // Naive: every object drawn into every map (no culling before the vertex stage).
    maps.set_culling(false);
    const double naive = best_ms(repeat, [&] {
        maps.render_all();
        gather.shade(maps, vs.clamp, scale);
    });
    uint64_t before = maps.vertices_transformed();
    const double maps_only = best_ms(repeat, [&] { maps.render_all(); });
    const double naive_vertices = double(maps.vertices_transformed() - before);
    maps.set_culling(true);
    before = maps.vertices_transformed();
    const double culled_maps = best_ms(repeat, [&] { maps.render_all(); });
    const double culled_vertices = double(maps.vertices_transformed() - before);
    const double sum_only = best_ms(repeat, [&] { gather.shade(maps, vs.clamp, scale); });
    const double unshadowed = best_ms(repeat, [&] { gather.shade(maps, vs.clamp, scale, false); });
    std::printf("\n%d VPLs               %10s %8s %9s\n", n, "ms/frame", "fps", "speed-up");
    auto row = [&](const char* what, double ms) {
        std::printf("%-24s %10.2f %8.2f %8.2fx\n", what, ms, 1000.0 / ms, naive / ms);
    };
    row("naive (all maps + sum)", naive);
    row("culled maps (all + sum)", best_ms(repeat, [&] {
            maps.render_all();
            gather.shade(maps, vs.clamp, scale);
        }));
    for (bool culling : {false, true})
        for (int k : {150, 100, 50}) {
            if (!culling && k != 100) continue;
            maps.set_culling(culling);
            int next = 0;
            const double ms = best_ms(repeat, [&] {
                maps.render(next, k);
                next = (next + k) % n;
                gather.shade(maps, vs.clamp, scale);
            });
            char label[64];
            std::snprintf(label, sizeof label, "K=%d%s", k, culling ? ", culled" : ", no culling");
            row(label, ms);
        }
    maps.set_culling(true);
    row("static maps (sum only)", sum_only);
    {
        // Barczak's visibility determination (VD): F/P/N labels per (patch, VPL); only P pairs
        // read a shadow map, F and "behind" pairs are skipped. Against every pair labelled P.
        const Clock::time_point t = Clock::now();
        const cpu::VisibilityDatabase db(scene, v300, 2);
        const double build_ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
        auto [patch, labels] = patches_and_labels(db);
        gather.set_points(column(points, width, height, false), column(points, width, height, true),
                          patch);
        gather.set_labels(labels);
        const double vd = best_ms(repeat, [&] { gather.shade(maps, vs.clamp, scale, true, true); });
        std::fill(labels.begin(), labels.end(), 1u);
        gather.set_labels(labels);
        const double all_p =
            best_ms(repeat, [&] { gather.shade(maps, vs.clamp, scale, true, true); });
        row("VD labels, static maps", vd);
        row("all labelled P, static", all_p);
        const cpu::VisibilityCounters c = db.counters();
        std::printf(
            "(VD: %zu patches, leaf pairs N %llu / P %llu / F %llu / behind %llu, built in "
            "%.1f ms on the CPU)\n",
            db.nodes().size(), (unsigned long long)c.none, (unsigned long long)c.partial,
            (unsigned long long)c.full, (unsigned long long)c.behind, build_ms);
    }
    row("no visibility (floor)", unshadowed);
    std::printf("(of the naive frame: maps %.2f ms, per-pixel sum %.2f ms)\n", maps_only, sum_only);
    std::printf(
        "(all %d maps: naive %.2f ms, culled before the vertex stage %.2f ms (%.2fx); vertices "
        "transformed %.3f of naive)\n",
        n, maps_only, culled_maps, maps_only / culled_maps, culled_vertices / naive_vertices);
    {
        std::vector<glm::vec3> e(points.size(), glm::vec3(0.0f));
        const Clock::time_point t = Clock::now();
        cpu::add_vpl_irradiance(rays, points, v300.data(), v300.size(), vs.clamp, e.data(), pool);
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
        std::printf("%-24s %10.2f %8.2f %8.2fx  (%d threads)\n", "exact CPU rays", ms, 1000.0 / ms,
                    naive / ms, pool.size());
    }

    // 1b. Cutting the per-pixel sum, each step added to the one before, with its error against
    // the full sum (the naive frame's image) so no speed-up hides an error.
    {
        maps.set_vpls(v300);
        maps.render_all();
        gather.clear_tiles();
        gather.set_points(column(points, width, height, false),
                          column(points, width, height, true));
        gather.shade(maps, vs.clamp, scale);
        const std::vector<glm::vec3> full = gather.read_back();
        std::vector<glm::vec3> exact(points.size(), glm::vec3(0.0f));
        cpu::add_vpl_irradiance(rays, points, v300.data(), v300.size(), vs.clamp, exact.data(),
                                pool);
        std::vector<glm::vec3> exact_gl(exact.size());  // rows bottom-first, E/π like the gather
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                exact_gl[size_t(height - 1 - y) * size_t(width) + size_t(x)] =
                    exact[size_t(y) * size_t(width) + size_t(x)] * scale;
        const auto [gl_mse, gl_l1] = errors(full, exact_gl);
        std::printf(
            "\ncutting the sum (%d VPLs, K = 100 map updates a frame; error against the full sum; "
            "the full sum against Embree rays: relMSE %.5f, rel. L1 %.4f)\n",
            n, gl_mse, gl_l1);
        size_t lit_points = 0;
        for (const cpu::SurfacePoint& p : points) lit_points += p.normal != glm::vec3(0.0f) ? 1 : 0;
        const double full_work = double(lit_points) * double(n);
        std::printf("%-34s %9s %7s %9s %9s %9s %9s %10s %10s %9s %9s\n", "step", "ms/frame", "fps",
                    "speed-up", "sum ms", "static x", "relMSE", "rel. L1", "tiles ms", "work",
                    "lookups");
        auto step = [&](const char* what, double tiles_ms) {
            int next = 0;
            const double frame = best_ms(repeat, [&] {
                maps.render(next, 100);
                next = (next + 100) % n;
                gather.shade(maps, vs.clamp, scale);
            });
            maps.render_all();
            const double sum = best_ms(repeat, [&] { gather.shade(maps, vs.clamp, scale); });
            gather.shade(maps, vs.clamp, scale);
            const auto [mse, l1] = errors(gather.read_back(), full);
            // Work: VPLs evaluated per point, and shadow lookups, as shares of the full sum's.
            double work = 1.0, lookups = 1.0;
            if (tiles_ms > 0.0) {
                work = double(gather.tile_counts().evaluations) / full_work;
                lookups = double(gather.tile_counts().evaluated_lookups) / full_work;
            }
            std::printf("%-34s %9.2f %7.2f %8.2fx %9.2f %8.2fx %9.2e %10.4f %10.2f %9.4f %9.4f\n",
                        what, frame, 1000.0 / frame, naive / frame, sum, naive / sum, mse, l1,
                        tiles_ms, work, lookups);
        };
        auto timed = [](auto&& f) {
            const Clock::time_point t = Clock::now();
            f();
            return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
        };
        std::printf("%-34s %9.2f %7.2f %8.2fx %9.2f %8.2fx %9.2e %10.4f %10s %9.4f %9.4f\n",
                    "naive (all maps + sum)", naive, 1000.0 / naive, 1.0, sum_only,
                    naive / sum_only, 0.0, 0.0, "-", 1.0, 1.0);
        maps.set_culling(false);
        step("+ K=100 map updates a frame", 0.0);
        maps.set_culling(true);
        step("+ culling before the vertex stage", 0.0);
        double ms = timed([&] { gather.set_tiles(v300, 1); });
        const gpu::VplGather::TileCounts plain = gather.tile_counts();
        step("+ tile lists (both cosines > 0)", ms);
        // VD labels folded into the tile lists (Barczak §4.3.1).
        const Clock::time_point db_start = Clock::now();
        const cpu::VisibilityDatabase db(scene, v300, 2);
        const double db_ms =
            std::chrono::duration<double, std::milli>(Clock::now() - db_start).count();
        auto [patch, labels] = patches_and_labels(db);
        gather.set_points(column(points, width, height, false), column(points, width, height, true),
                          patch);
        ms = timed([&] { gather.set_tiles(v300, 1, &labels); });
        const gpu::VplGather::TileCounts fpn = gather.tile_counts();
        step("+ F/P/N labels in the tile lists", db_ms + ms);
        for (bool wide : {true, false})
            for (int k : {2, 3, 4}) {
                ms = timed([&] { gather.set_tiles(v300, k, &labels, wide); });
                char label[64];
                std::snprintf(label, sizeof label, "+ interleave %dx%d, %s filter", k, k,
                              wide ? "(2n-1)^2" : "n x n");
                step(label, ms);
            }
        std::printf(
            "(tile pairs %llu: listed %llu with lookups %llu; with F/P/N labels listed %llu, "
            "lookups %llu; 'sum ms': the sum alone, as with static maps, 'static x' naive / that; "
            "'tiles ms': the CPU building the lists (F/P/N: and the database), once per change of "
            "points or VPLs; work, lookups: VPLs evaluated and shadow lookups per point, as shares "
            "of the full sum's %zu points x %d VPLs)\n",
            (unsigned long long)plain.pairs, (unsigned long long)plain.entries,
            (unsigned long long)plain.lookups, (unsigned long long)fpn.entries,
            (unsigned long long)fpn.lookups, lit_points, n);
        gather.clear_tiles();
        gather.set_points(column(points, width, height, false),
                          column(points, width, height, true));
    }

    // 2. Frame rate against the number of VPLs.
    std::printf("\n%8s %14s %14s %14s  (K=100: culled map passes)\n", "VPLs", "naive fps",
                "K=100 fps", "static fps");
    for (size_t count : {25, 50, 100, 200, 300, 600, 1000}) {
        if (count > all.size()) break;
        maps.set_vpls(take(count));
        maps.render_all();
        const int c = int(count);
        maps.set_culling(false);  // naive
        const double nv = best_ms(repeat, [&] {
            maps.render_all();
            gather.shade(maps, vs.clamp, scale);
        });
        maps.set_culling(true);
        int next = 0;
        const double k100 = best_ms(repeat, [&] {
            maps.render(next, std::min(100, c));
            next = (next + 100) % c;
            gather.shade(maps, vs.clamp, scale);
        });
        const double st = best_ms(repeat, [&] { gather.shade(maps, vs.clamp, scale); });
        std::printf("%8zu %14.2f %14.2f %14.2f\n", count, 1000.0 / nv, 1000.0 / k100, 1000.0 / st);
    }

    // 3. Shadow-map update cost against the mover's vertex count (thesis: bunny 3000 vs torus
    // 820 vertices, time in their ratio): 300 maps of a scene holding only the mover.
    std::printf("\n%-28s %9s %14s %14s\n", "mover", "vertices", "300 maps ms", "us/kvertex");
    std::vector<std::pair<std::string, Mesh>> movers;
    for (int s : {1, 2, 3, 4})
        movers.emplace_back("sphere subdivision " + std::to_string(s), make_sphere(1.0f, s));
    {
        // The thesis's movers: a torus of 41 × 20 = 820 vertices, and the Stanford bunny (the
        // full-resolution scan, and decimated to the thesis's ~3000 vertices).
        movers.emplace_back("torus", make_torus(0.7f, 0.3f, 41, 20));
        // Where the scenes find it: ../../shared/external-scenes from the scene's folder.
        const std::string bunny = (std::filesystem::path(scene_path).parent_path() /
                                   "../../shared/external-scenes/stanford-bunny/bun_zipper.ply")
                                      .string();
        try {
            movers.emplace_back("stanford bunny", load_mesh(bunny));
            movers.emplace_back("bunny decimated to 3000",
                                decimate_mesh(movers.back().second, 3000));
        } catch (const std::exception& e) {
            std::printf("(bunny left out: %s)\n", e.what());
        }
    }
    for (auto& [name, mesh] : movers) {
        Scene m;
        m.path = name;
        Object o;
        o.name = name;
        o.mesh = mesh;
        m.objects.push_back(o);
        init_versions(m);
        make_surfaces_and_atlas(m);
        gpu::SceneMeshes mm(m);
        gpu::VplShadowMaps mover_maps(m, mm, vs.map_size, vs.map, 1e-3f);
        mover_maps.set_culling(false);  // the thesis's measure: every vertex for every map
        std::vector<Vpl> ring;
        for (int i = 0; i < 300; ++i) {
            const float a = 6.2831853f * float(i) / 300.0f;
            const glm::vec3 p(3.0f * std::cos(a), -1.5f, 3.0f * std::sin(a));
            ring.push_back(Vpl{p, glm::normalize(-p), glm::vec3(1.0f)});
        }
        mover_maps.set_vpls(ring);
        const double ms = best_ms(repeat, [&] { mover_maps.render_all(); });
        const size_t verts = o.mesh.positions.size();
        std::printf("%-28s %9zu %14.2f %14.2f\n", name.c_str(), verts, ms,
                    1000.0 * ms / (300.0 * double(verts) / 1000.0));
    }
    std::printf("(best of %d; GL timings include glFinish)\n", repeat);

    table_rooms(args, scene_path, width, height, repeat, pool);
    return 0;
}

}  // namespace ag::cli
