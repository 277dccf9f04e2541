// afterglow photons SCENE --frames N --dump FILE: runs the CPU photon simulation and AIM stage
// (Larsen ch. 9, 10), optionally under a scene-edit script, and reports the state per surface, per
// light and per frame (with what the moved-object query invalidated and cost).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "cpu/aim.h"
#include "cpu/photon_simulation.h"
#include "shared/image.h"
#include "shared/input_error.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/script.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kPhotonsCommand{
    "photons",
    "SCENE [--frames N] [--script S.lua] [--no-query] [--dump FILE.json] [--threads N]",
    "Run selective photon tracing and AIM rebuilds for N frames on worker threads, under the "
    "scene's "
    "edit script if given, and report per-frame counters (groups invalidated by the moved-object "
    "query, segments it tested, its time); --dump writes per-surface hit counts, flux, delta_f, "
    "delta_i, per-light "
    "group states and per-frame counters (photons grown for refinement, complete photon sets) as "
    "JSON.",
    {
        integer("frames,n", "N", "frames to run", 0, 10000000, 1),
        text("dump", "FILE.json", "write the state as JSON (atomically)"),
        integer("threads", "N", "worker threads (default: settings.threads, 0 = all cores)", 0,
                1024),
        text("script", "S.lua",
             "scene-edit script run before each frame (default: none); frame time = frame / 30 s"),
        flag("no-query", "find moved objects by round-robin verification only (for comparison)"),
        settings_option(),
        flag("quiet,q", "no per-frame lines on stderr"),
        text("aim", "FILE", "write the AIM atlas (radiance per texel, scaled up 8x) as EXR or PNG"),
        number("exposure", "EV",
               "exposure for a PNG written by --aim (default: auto, 99th percentile to 0.8)", -100,
               100),
    },
    1,
    1,
};

int run_photons(const Args& args) {
    const int frames = args.get_int("frames");
    Scene scene = load_scene(args.positionals()[0]);
    args.apply_settings(scene);
    const int threads = args.get_int("threads", scene.settings.threads);
    ThreadPool pool(threads);
    cpu::PhotonSimulation sim(scene, pool);
    sim.set_query_invalidation(!args.has("no-query"));
    cpu::Aim aim(scene, pool);
    std::optional<Script> script;
    if (args.has("script"))
        script.emplace(args.get("script"));  // a syntax error stops here (exit 1)
    if (script && !script->on_start(scene)) warn(*script->last_error());

    nlohmann::json frame_log = nlohmann::json::array();
    const auto start = std::chrono::steady_clock::now();
    for (int f = 0; f < frames; ++f) {
        if (script && !script->on_frame(scene, f, f / 30.0))
            warn(*script->last_error() + " (edit skipped)");
        const auto t0 = std::chrono::steady_clock::now();
        cpu::PhotonFrameStats st = sim.frame();
        trim_changes(scene, sim.changes_seen());  // the simulation is the log's only reader here
        const auto t1 = std::chrono::steady_clock::now();
        st.aim_texels_rebuilt = aim.update(sim.maps(), &st.aim_surfaces_rebuilt);
        const auto t2 = std::chrono::steady_clock::now();
        const double photon_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
        const double aim_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
        frame_log.push_back({{"frame", st.frame},
                             {"photons_verified", st.photons_verified},
                             {"groups_invalidated", st.groups_invalidated},
                             {"groups_invalidated_by_query", st.groups_invalidated_by_query},
                             {"objects_moved", st.objects_moved},
                             {"query_segments_tested", st.query_segments_tested},
                             {"query_ms", st.query_ms},
                             {"photons_retraced", st.photons_retraced},
                             {"groups_queued", st.groups_queued},
                             {"photons_grown", st.photons_grown},
                             {"layers", st.layers},
                             {"aim_surfaces_rebuilt", st.aim_surfaces_rebuilt},
                             {"aim_texels_rebuilt", st.aim_texels_rebuilt},
                             {"photon_ms", photon_ms},
                             {"aim_ms", aim_ms}});
        if (!args.has("quiet")) {
            std::fprintf(stderr,
                         "frame %4d: verified %5d, invalidated %4d, retraced %6d, queued %4d, "
                         "grown %6d, AIM %3d surfaces %5d texels  (%.2f + %.2f ms)\n",
                         int(st.frame), st.photons_verified, st.groups_invalidated,
                         st.photons_retraced, st.groups_queued, st.photons_grown,
                         st.aim_surfaces_rebuilt, st.aim_texels_rebuilt, photon_ms, aim_ms);
            if (st.objects_moved > 0)
                std::fprintf(stderr,
                             "            query: %d moved, %d groups invalidated, %llu segments "
                             "tested, %.3f ms\n",
                             st.objects_moved, st.groups_invalidated_by_query,
                             static_cast<unsigned long long>(st.query_segments_tested),
                             st.query_ms);
        }
    }
    const double total_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "frames " << frames << " in " << total_s << " s, " << sim.maps().hit_count()
              << " photon hits on " << scene.surfaces.size() << " surfaces, " << pool.size()
              << " worker threads\n";
    std::cout << "photon sets (photons.refine_layers) " << sim.layers() << " of "
              << sim.target_layers() << ", stored paths and hits "
              << double(sim.maps().stored_bytes()) / (1024.0 * 1024.0) << " MiB\n";

    if (args.has("aim")) {
        // Rebuild every surface so the picture shows the current state, then write it scaled up.
        aim.rebuild_all(sim.maps());
        const int scale = 8, w = scene.atlas.width, h = scene.atlas.height;
        Image image(w * scale, h * scale);
        std::vector<float> lum;
        for (int y = 0; y < h * scale; ++y)
            for (int x = 0; x < w * scale; ++x) {
                // Atlas row 0 is at the bottom in GL; show it at the bottom of the picture too.
                const glm::vec3 c =
                    aim.radiance()[size_t(h - 1 - y / scale) * size_t(w) + size_t(x / scale)];
                image.set_rgb(x, y, c);
                if (c != glm::vec3(0.0f)) lum.push_back((c.x + c.y + c.z) / 3.0f);
            }
        float ev = float(args.get_double("exposure", 0.0));
        if (!args.has("exposure") && !lum.empty()) {
            std::nth_element(lum.begin(), lum.begin() + std::ptrdiff_t(lum.size() * 99 / 100),
                             lum.end());
            ev = std::log2(0.8f / std::max(1e-30f, lum[lum.size() * 99 / 100]));
        }
        write_image(image, args.get("aim"), ev);
        std::cerr << "afterglow photons: wrote " << args.get("aim") << "\n";
    }

    if (args.has("dump")) {
        nlohmann::json surfaces = nlohmann::json::array();
        for (int s = 0; s < int(scene.surfaces.size()); ++s) {
            const cpu::SurfaceHits& h = sim.maps().surface(s);
            surfaces.push_back(
                {{"surface", s},
                 {"object", scene.objects[size_t(scene.surfaces[size_t(s)].object)].name},
                 {"area", scene.surfaces[size_t(s)].area},
                 {"hits", h.hits.size()},
                 {"flux", {h.flux.x, h.flux.y, h.flux.z}},
                 {"delta_f", h.delta_f},
                 {"delta_i", h.delta_i}});
        }
        nlohmann::json lights = nlohmann::json::array();
        for (int l = 0; l < int(scene.lights.size()); ++l) {
            const cpu::LightGroupState st = sim.light_state(l);
            lights.push_back({{"light", scene.lights[size_t(l)].name},
                              {"groups_valid", st.valid},
                              {"groups_invalid", st.invalid},
                              {"groups_queued", st.queued},
                              {"invalidations", sim.invalidations(l)}});
        }
        const nlohmann::json dump = {{"scene", scene.path},
                                     {"frames", frame_log},
                                     {"surfaces", surfaces},
                                     {"lights", lights},
                                     {"photon_hits", sim.maps().hit_count()}};
        write_file_atomically(args.get("dump"), dump.dump(2) + "\n");
    }
    return 0;
}

static const Registration kRegistration(kPhotonsCommand, run_photons, 30);

}  // namespace ag::cli
