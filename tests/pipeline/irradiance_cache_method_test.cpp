// --indirect irradiance_cache (Gautron 2006) through the pipeline: after one frame every pixel
// that needs an indirect term is covered and the term is the splat of the records; records
// survive camera moves; with temporal caching and the look-ahead of the scene's script, far
// fewer records are made than by a new cache every frame, and the records a still scene keeps
// never expire before δt_max.
#include <gtest/gtest.h>

#include <optional>

#include "../gpu/gl_fixture.h"
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

}  // namespace ag
