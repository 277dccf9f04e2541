// --indirect irradiance_cache (Gautron 2006) through the pipeline: after one frame every pixel
// that needs an indirect term is covered and the term is the splat of the records; records
// survive camera moves; with temporal caching and the look-ahead of the scene's script, far
// fewer records are made than by a new cache every frame, and the records a still scene keeps
// never expire before δt_max.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "../gpu/gl_fixture.h"
#include "cpu/aim.h"
#include "cpu/irradiance_gather.h"
#include "cpu/photon_simulation.h"
#include "gpu/hemi_plane_gather.h"
#include "gpu/lightmap_texture.h"
#include "gpu/scene_meshes.h"
#include "shared/charts.h"
#include "shared/input_error.h"
#include "shared/metrics.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/script.h"

namespace ag {

namespace {

class IrradianceCacheMethodTest : public test::GlTest {};

Scene load(const std::string& name) {
    Scene s = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/" + name);
    s.settings.indirect.method = IndirectMethodKind::irradiance_cache;
    s.settings.rc.theta_strata = 4;  // cheap records: the test counts, it does not look
    s.settings.rc.phi_strata = 16;
    s.settings.rc.records_per_frame = 1 << 30;
    return s;
}

IrradianceCacheMethod& method_of(Pipeline& p) {
    return dynamic_cast<IrradianceCacheMethod&>(p.indirect());
}

}  // namespace

TEST_F(IrradianceCacheMethodTest, OneFrameCoversEveryPixelAndTheTermIsTheSplat) {
    Scene scene = load("cornell.json");
    // Direct-light records: the AIMs still change in the first frames and would retire them.
    scene.settings.rc.source = RcSource::direct;
    Pipeline pipeline(scene, PipelineOptions{48, 40});
    FrameLoop loop(pipeline);
    loop.step();
    pipeline.sync();
    IrradianceCacheMethod& m = method_of(pipeline);
    EXPECT_TRUE(m.settled());
    ASSERT_GT(m.records().size(), 10u);
    const std::vector<SplatPixel> px = m.splat().read_gbuffer();
    std::vector<glm::vec4> sums;
    splat_records(m.records(), px, scene.settings.rc.accuracy, 0, sums);
    const std::vector<glm::vec3> want = normalise_splat(sums);
    const std::vector<glm::vec3> got = m.splat().read_term();
    int covered = 0;
    for (size_t i = 0; i < px.size(); ++i) {
        if (!px[i].covered) continue;
        ++covered;
        ASSERT_GE(sums[i].a, scene.settings.rc.accuracy * (1.0f - 1e-5f)) << "pixel " << i;
        EXPECT_NEAR(got[i].g, want[i].g, 1e-4f * std::max(1.0f, want[i].g));
    }
    EXPECT_GT(covered, int(px.size()) / 2);
    // The camera moves: records are view-independent, only new pixels get new ones.
    const size_t before = m.records().size();
    loop.begin_edits();
    Camera c = scene.camera;
    c.eye.x += 20.0f;
    set_camera(scene, c);
    loop.step();
    pipeline.sync();
    EXPECT_GE(m.records().size(), before);
    EXPECT_LT(m.last_stats().added, int(before) / 2);
    EXPECT_EQ(m.last_stats().replaced, 0);
}

TEST_F(IrradianceCacheMethodTest, TemporalCachingMakesFarFewerRecordsThanPerFrame) {
    auto records_made = [](PipelineMode mode, int lifespan) {
        Scene scene = load("cube_in_a_box.json");
        scene.settings.rc.max_lifespan = lifespan;
        PipelineOptions o{32, 32};
        o.mode = mode;
        Pipeline pipeline(scene, o);
        Script script(scene.script);
        FrameLoop loop(pipeline, &script);
        uint64_t made = 0;
        for (int f = 0; f < 24; ++f) {
            loop.step();
            pipeline.sync();
            const IrradianceCacheStats& s = method_of(pipeline).last_stats();
            made += uint64_t(s.added + s.replaced);
            EXPECT_FALSE(s.uncovered_left);
        }
        return made;
    };
    const uint64_t per_frame = records_made(PipelineMode::full, 20);
    const uint64_t temporal = records_made(PipelineMode::selective, 20);
    const uint64_t every_frame_in_place = records_made(PipelineMode::selective, 1);
    EXPECT_GT(per_frame, 5 * temporal);
    // δt_max = 1: every record replaced every frame, as many as per-frame recomputation makes.
    EXPECT_GT(every_frame_in_place, per_frame / 2);
}

// Records from the GL hemi-plane (rc.gather gl): E from the plane, R_k from its distance output
// (Σ w / Σ w/d), against the stratified rays of the CPU records at 20 points on Cornell's walls
// and ceiling, both reading the same AIMs. A wide plane (a = 16, 256²) leaves out only 0.3% of
// the cosine-weighted hemisphere, so what is compared is the distance output and the sums.
// Measured: E RMS 0.88%, worst 1.42%; R_k RMS 0.53%, worst 1.62% (held to 3% / 5% RMS, 5% / 10%
// per point). At the default plane (a = 2, 32²; printed) E RMS 3.5% (the stretched border's own
// error, Table 4.1), R_k RMS 1.6%.
TEST_F(IrradianceCacheMethodTest, GlHemiPlaneRecordsAgreeWithTheRays) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell.json");
    scene.settings.lightmap.texel_size = 111.0f;
    scene.settings.gather.plane_resolution = 256;
    scene.settings.gather.plane_half_width = 16.0f;
    scene.settings.gather.specular_bounces = 0;  // glass black to both
    make_surfaces_and_atlas(scene);
    ThreadPool pool(2);
    cpu::PhotonSimulation sim(scene, pool);
    sim.trace_all();
    cpu::Aim aim(scene, pool);
    aim.rebuild_all(sim.maps());

    std::vector<GatherPoint> points;
    for (float u : {150.0f, 400.0f})
        for (float v : {250.0f, 450.0f}) {
            points.push_back({{u, v, 555.0f}, {0, 0, -1}});  // back wall
            points.push_back({{555.0f, v, u}, {-1, 0, 0}});  // left wall
            points.push_back({{0.0f, v, u}, {1, 0, 0}});     // right wall
            points.push_back({{u, 555.0f, v}, {0, -1, 0}});  // ceiling
            points.push_back({{u, 555.0f, v - 100.0f}, {0, -1, 0}});
        }
    for (size_t k = 0; k < points.size(); ++k) points[k].key = uint32_t(k);

    const cpu::RayTracer rays(scene);
    cpu::IrradianceGather gather(scene, rays, pool);
    cpu::RecordGatherOptions options;
    options.theta = 32;
    options.phi = 128;
    const std::vector<IrradianceRecord> want =
        gather.gather(points, cpu::aim_radiance_source(scene, aim.radiance()), options);

    gpu::SceneMeshes meshes(scene);
    gpu::LightmapTexture texture(scene.atlas);
    texture.update_all(aim.radiance());
    gpu::HemiPlaneGather plane(scene, meshes, 8, &texture, true);
    const std::vector<GatherResult> got = plane.gather_points(points);
    {
        // The default plane (a = 2, 32², stretched border), what rc.gather gl uses: printed only.
        Scene coarse = scene;
        coarse.settings.gather.plane_resolution = Settings{}.gather.plane_resolution;
        coarse.settings.gather.plane_half_width = Settings{}.gather.plane_half_width;
        gpu::HemiPlaneGather small(coarse, meshes, 8, &texture, true);
        const std::vector<GatherResult> g = small.gather_points(points);
        double e_sq = 0.0, r_sq = 0.0;
        for (size_t k = 0; k < points.size(); ++k) {
            const double e = luminance(g[k].iim) / luminance(want[k].iim) - 1.0;
            const double r = g[k].harmonic_distance / want[k].harmonic_distance - 1.0;
            e_sq += e * e;
            r_sq += r * r;
        }
        std::printf("default plane (a = 2, 32²): E RMS %.2f%%, R_k RMS %.2f%%\n",
                    100.0 * std::sqrt(e_sq / double(points.size())),
                    100.0 * std::sqrt(r_sq / double(points.size())));
    }

    double e_sq = 0.0, r_sq = 0.0, e_worst = 0.0, r_worst = 0.0;
    for (size_t k = 0; k < points.size(); ++k) {
        const float le = luminance(want[k].iim), lg = luminance(got[k].iim);
        const double e = std::abs(lg - le) / le;
        const double r = std::abs(got[k].harmonic_distance - want[k].harmonic_distance) /
                         want[k].harmonic_distance;
        e_sq += e * e;
        r_sq += r * r;
        e_worst = std::max(e_worst, e);
        r_worst = std::max(r_worst, r);
        EXPECT_LT(e, 0.05) << "point " << k << ": E/pi gl " << lg << " rays " << le;
        EXPECT_LT(r, 0.10) << "point " << k << ": R_k gl " << got[k].harmonic_distance << " rays "
                           << want[k].harmonic_distance;
    }
    const double n = double(points.size());
    std::printf(
        "GL hemi-plane records vs rays on %zu points: E RMS %.2f%% (worst %.2f%%), R_k RMS "
        "%.2f%% (worst %.2f%%)\n",
        points.size(), 100.0 * std::sqrt(e_sq / n), 100.0 * e_worst, 100.0 * std::sqrt(r_sq / n),
        100.0 * r_worst);
    EXPECT_LT(std::sqrt(e_sq / n), 0.03);
    EXPECT_LT(std::sqrt(r_sq / n), 0.05);
}

// rc.gather gl in the pipeline: one frame covers every pixel with records whose R_k came from the
// plane.
// GL records read the AIM texture: with direct light as the source there is none, and the
// pipeline refuses to be built, naming both settings; the process goes on.
TEST_F(IrradianceCacheMethodTest, GlGatherWithDirectSourceIsRefused) {
    Scene scene = load("cornell.json");
    scene.settings.rc.gather = RcGather::gl;
    scene.settings.rc.source = RcSource::direct;
    try {
        Pipeline pipeline(scene, PipelineOptions{48, 40});
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("rc.source"), std::string::npos) << e.what();
    }
    scene.settings.rc.source = RcSource::aim;
    Pipeline pipeline(scene, PipelineOptions{48, 40});
    pipeline.frame();
}

TEST_F(IrradianceCacheMethodTest, GlGatherRecordsCoverTheFrame) {
    Scene scene = load("cornell.json");
    scene.settings.rc.gather = RcGather::gl;
    Pipeline pipeline(scene, PipelineOptions{48, 40});
    FrameLoop loop(pipeline);
    loop.step();
    pipeline.sync();
    IrradianceCacheMethod& m = method_of(pipeline);
    ASSERT_GT(m.records().size(), 10u);
    const std::vector<SplatPixel> px = m.splat().read_gbuffer();
    std::vector<glm::vec4> sums;
    splat_records(m.records(), px, scene.settings.rc.accuracy, 0, sums);
    for (size_t i = 0; i < px.size(); ++i) {
        if (!px[i].covered) continue;
        ASSERT_GE(sums[i].a, scene.settings.rc.accuracy * (1.0f - 1e-5f)) << "pixel " << i;
    }
    const float lo = scene.settings.rc.min_radius * scene.diagonal(),
                hi = scene.settings.rc.max_radius * scene.diagonal();
    int inside = 0;
    for (const IrradianceRecord& r : m.records()) {
        EXPECT_GE(r.harmonic_distance, lo);
        EXPECT_LE(r.harmonic_distance, hi);
        inside += r.harmonic_distance > lo && r.harmonic_distance < hi;
    }
    EXPECT_GT(inside, int(m.records().size()) / 2);  // measured, not the clamp
}

}  // namespace ag
