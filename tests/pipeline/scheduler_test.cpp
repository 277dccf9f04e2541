// Scheduling by time (DESIGN.md): budgets from measured costs, counted not timed; and the
// round-robin baseline, which trusts nothing and re-traces everything in turn.
#include "shared/pipeline/scheduler.h"

#include <gtest/gtest.h>

#include "../gpu/gl_fixture.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/scene_file.h"

namespace ag {
namespace {

PipelineStats measured(double draw_ms, int texels, double gather_ms, int photons, double photon_ms,
                       int aim_texels, double aim_ms, bool direct = false) {
    PipelineStats s;
    s.draw_ms = draw_ms;
    s.drawn_direct = direct;
    s.iim_texels_gathered = texels;
    s.gather_ms = gather_ms;
    s.photons.photons_retraced = photons;
    s.photon_ms = photon_ms;
    s.photons.aim_texels_rebuilt = aim_texels;
    s.aim_ms = aim_ms;
    s.caustic_ms = 1.0;
    s.hand_overs = 1;  // the frame took its photon work over
    return s;
}

TEST(FrameScheduler, WithoutATargetTheFixedCountsHold) {
    Settings settings;
    FrameScheduler scheduler;
    scheduler.measure(measured(10.0, 20, 2.0, 1000, 5.0, 100, 1.0));
    const FrameBudgets b = scheduler.budgets(settings, 1000);
    EXPECT_EQ(b.iim_texels, settings.gather.texels_per_frame);
    EXPECT_EQ(b.retrace_photons, settings.photons.retrace_budget);
    EXPECT_EQ(b.aim_surfaces, settings.aim.surfaces_per_frame);
    EXPECT_EQ(scheduler.aim_texels_left(settings, 0.0), FrameBudgets::kUnlimited);
}

// One slow frame (an edit's first gather) must not starve a budget for good: a small batch
// cannot measure the unit cost (its fixed costs dominate), but one cheaper than the estimate
// proves the estimate too high.
TEST(FrameScheduler, ABudgetShrunkByASlowFrameGrowsBack) {
    Settings settings;
    settings.schedule.frame_ms = 33.0f;
    FrameScheduler scheduler;
    scheduler.measure(measured(10.0, 20, 500.0, 1000, 5.0, 100, 1.0));  // 25 ms a texel
    EXPECT_EQ(scheduler.budgets(settings, 1000).iim_texels, 1);
    for (int f = 0; f < 30; ++f) {
        const int texels = scheduler.budgets(settings, 1000).iim_texels;
        scheduler.measure(measured(10.0, texels, 0.5 + 0.1 * texels, 1000, 5.0, 100, 1.0));
    }
    // 0.5 ms a batch + 0.1 ms a texel: the budget is back near (33 − 10 − 0.5) / 0.1.
    EXPECT_GT(scheduler.budgets(settings, 1000).iim_texels, 150);
}

// The frames after an edit's frame draw more than the running estimate (caustics traced again
// and drawn every other frame, cube-map faces re-lit): they plan for the larger of the last two
// frames' drawing where that is larger; other frames for the estimate.
TEST(FrameScheduler, FramesCatchingUpAfterAnEditPlanForTheLastFramesDrawing) {
    Settings settings;
    settings.schedule.frame_ms = 33.0f;
    FrameScheduler scheduler;
    for (int f = 0; f < 20; ++f) scheduler.measure(measured(10.0, 100, 10.0, 1000, 5.0, 100, 1.0));
    scheduler.measure(measured(20.0, 100, 10.0, 1000, 5.0, 100, 1.0));  // a heavy frame
    const FrameBudgets plain = scheduler.budgets(settings, 100000);
    const FrameBudgets catching_up = scheduler.budgets(settings, 100000, false, true);
    EXPECT_NEAR(catching_up.gather_ms, 33.0 - 20.0, 1e-9);
    EXPECT_GT(plain.gather_ms, catching_up.gather_ms + 2.0);  // the estimate moved 30% of the way
    EXPECT_LT(catching_up.iim_texels, plain.iim_texels);
    // A light frame after it: the heavy one is still one of the last two.
    scheduler.measure(measured(5.0, 100, 10.0, 1000, 5.0, 100, 1.0));
    EXPECT_NEAR(scheduler.budgets(settings, 100000, false, true).gather_ms, 33.0 - 20.0, 1e-9);
    // Two light frames: the estimate is larger than both, and is kept.
    scheduler.measure(measured(5.0, 100, 10.0, 1000, 5.0, 100, 1.0));
    EXPECT_DOUBLE_EQ(scheduler.budgets(settings, 100000, false, true).gather_ms,
                     scheduler.budgets(settings, 100000).gather_ms);
}

// The caustics' drawing and the cube-map faces that draw their direct light again come in some
// frames only: learnt apart from the frame's own drawing, they are planned for where a frame is
// to draw them and nowhere else. A frame that has drawn already gathers with what is left.
TEST(FrameScheduler, CausticsAndReLitFacesArePlannedForApart) {
    Settings settings;
    settings.schedule.frame_ms = 33.0f;
    FrameScheduler scheduler;
    for (int f = 0; f < 20; ++f) {
        PipelineStats s = measured(10.0, 100, 10.0, 1000, 5.0, 100, 1.0);  // 0.1 ms a texel
        if (f % 2 == 0) {  // every other frame draws the caustics (6 ms of its 16)
            s.draw_ms += 6.0;
            s.caustics_drawn = true;
            s.caustics_draw_ms = 6.0;
        } else {  // the others re-lit two faces (8 ms of their 18)
            s.draw_ms += 8.0;
            s.cube_faces_relit = 2;
            s.cube_faces_ms = 8.0;
        }
        scheduler.measure(s);
    }
    EXPECT_NEAR(scheduler.draw_ms().value(), 10.0, 1e-9) << "the frame's own drawing";
    EXPECT_NEAR(scheduler.caustics_draw_ms().value(), 6.0, 1e-9);
    EXPECT_NEAR(scheduler.relit_face_ms().value(), 4.0, 1e-9);
    EXPECT_NEAR(scheduler.budgets(settings, 100000).gather_ms, 33.0 - 10.0, 1e-9);
    EXPECT_NEAR(scheduler.budgets(settings, 100000, false, false, true).gather_ms, 33.0 - 16.0,
                1e-9);
    EXPECT_NEAR(scheduler.budgets(settings, 100000, false, false, false, 1).gather_ms, 33.0 - 14.0,
                1e-9);
    EXPECT_NEAR(scheduler.budgets(settings, 100000, false, false, true).iim_texels, 170, 1);
    // Drawn already, 20 ms into the frame: 13 ms are left; 40 ms into it, the least share.
    const FrameBudgets after = scheduler.after_drawing(settings, 100000, 20.0);
    EXPECT_NEAR(after.gather_ms, 13.0, 1e-9);
    EXPECT_NEAR(after.iim_texels, 130, 1);
    EXPECT_NEAR(scheduler.after_drawing(settings, 100000, 40.0).gather_ms,
                FrameScheduler::kMinGatherShare * 33.0, 1e-9);
}

TEST(FrameScheduler, ATargetIsFilledByMeasuredCost) {
    Settings settings;
    settings.schedule.frame_ms = 33.0f;
    FrameScheduler scheduler;
    // Drawing 10 ms, 0.1 ms a texel, 0.005 ms a photon, 0.01 ms an AIM texel, caustics 1 ms.
    scheduler.measure(measured(10.0, 20, 2.0, 1000, 5.0, 100, 1.0));
    FrameBudgets b = scheduler.budgets(settings, 100000);
    EXPECT_EQ(b.iim_texels, 230);                               // (33 − 10) / 0.1
    EXPECT_EQ(b.retrace_photons, int((0.8 * 33 - 1) / 0.005));  // workers: 80% of the frame
    EXPECT_EQ(b.aim_surfaces, FrameBudgets::kUnlimited);
    EXPECT_EQ(scheduler.aim_texels_left(settings, 10.0), int((0.8 * 33 - 1 - 10) / 0.01));
    // A frame the workers ran on through (no hand-over) measures no caustic work: without the
    // guard its 0 ms would lower the caustics' estimate and raise the photon budget.
    PipelineStats ran_on = measured(10.0, 20, 2.0, 0, 0.0, 0, 0.0);
    ran_on.caustic_ms = 0.0;
    ran_on.hand_overs = 0;
    for (int f = 0; f < 20; ++f) scheduler.measure(ran_on);
    EXPECT_EQ(scheduler.budgets(settings, 100000).retrace_photons, int((0.8 * 33 - 1) / 0.005));
    // The frame of an edit draws the direct light anew, and moved geometry besides. Until a
    // frame that drew the direct light anew is measured, it leaves twice the usual drawing time:
    // (33 − 20) / 0.1.
    EXPECT_EQ(scheduler.budgets(settings, 100000, true).iim_texels, 130);
    EXPECT_NEAR(scheduler.budgets(settings, 100000, true).gather_ms, 13.0, 1e-9);
    // Then what such a frame cost where that is more (the conference room: 154 ms against 50 ms
    // for a settled frame; twice the estimate left its edit frame at 268 ms of a 200 ms target):
    // drawing the direct light anew 24 ms, (33 − 24) / 0.1 texels, while other frames keep their
    // share.
    FrameScheduler edits;
    edits.measure(measured(24.0, 20, 2.0, 1000, 5.0, 100, 1.0, true));
    for (int f = 0; f < 40; ++f) edits.measure(measured(10.0, 20, 2.0, 1000, 5.0, 100, 1.0));
    EXPECT_NEAR(edits.budgets(settings, 100000).iim_texels, 230, 1);
    EXPECT_NEAR(edits.budgets(settings, 100000, true).gather_ms, 9.0, 1e-6);
    // Where it is less, twice the usual drawing still holds (moved geometry: two_rooms' door
    // drew in 16–27 ms where a frame drawing the direct light anew took 12 ms).
    FrameScheduler cheap;
    cheap.measure(measured(12.0, 20, 2.0, 1000, 5.0, 100, 1.0, true));
    for (int f = 0; f < 40; ++f) cheap.measure(measured(10.0, 20, 2.0, 1000, 5.0, 100, 1.0));
    EXPECT_NEAR(cheap.budgets(settings, 100000, true).gather_ms, 13.0, 1e-3);
    // A pipeline's first frame compiles the shaders (llvmpipe: bumpy_133k_box drew in 156 ms,
    // later frames that drew the direct light anew in 27-48 ms): it teaches nothing about
    // drawing, unless nothing else has.
    FrameScheduler first;
    PipelineStats compiling = measured(150.0, 20, 2.0, 1000, 5.0, 100, 1.0, true);
    compiling.frame = 1;
    first.measure(compiling);
    EXPECT_FALSE(first.direct_draw_ms().known());
    EXPECT_NEAR(first.draw_ms().value(), 150.0, 1e-9);  // the only measurement yet
    PipelineStats second = measured(12.0, 20, 2.0, 1000, 5.0, 100, 1.0, true);
    second.frame = 2;
    first.measure(second);
    EXPECT_NEAR(first.direct_draw_ms().value(), 12.0, 1e-9);
    EXPECT_LT(first.draw_ms().value(), 150.0);
    // Where drawing the direct light is most of the frame, gathering keeps a quarter of it.
    FrameScheduler busy;
    busy.measure(measured(30.0, 20, 2.0, 1000, 5.0, 100, 1.0, true));
    EXPECT_EQ(busy.budgets(settings, 100000, true).iim_texels, int(0.25 * 33 / 0.1));
    // Never more texels than there are, never none.
    EXPECT_EQ(scheduler.budgets(settings, 50).iim_texels, 50);
    // Drawing alone overruns the target: gathering keeps a quarter of it.
    FrameScheduler slow;
    slow.measure(measured(40.0, 20, 2.0, 1000, 5.0, 100, 1.0));
    EXPECT_EQ(slow.budgets(settings, 1000).iim_texels, int(0.25 * 33 / 0.1));
    // With counts_cap the fixed counts are upper limits.
    settings.schedule.counts_cap = true;
    b = scheduler.budgets(settings, 100000);
    EXPECT_EQ(b.iim_texels, settings.gather.texels_per_frame);
    EXPECT_EQ(b.retrace_photons, settings.photons.retrace_budget);
    EXPECT_EQ(b.aim_surfaces, settings.aim.surfaces_per_frame);
}

// An edit's frame spends much of its gathering share on other things: the screen coverage, the
// AIM uploads, the repairs. A texel's cost comes from the time in the gatherers where the method
// tells it apart (texel_gather_ms), and the rest counts as drawing.
TEST(FrameScheduler, ATexelCostsWhatTheGatherersTook) {
    Settings settings;
    settings.schedule.frame_ms = 100.0f;
    FrameScheduler told, untold;
    PipelineStats s = measured(20.0, 100, 30.0, 1000, 5.0, 100, 1.0);
    untold.measure(s);
    s.texel_gather_ms = 10.0;  // 20 ms of the 30 were the coverage pass and uploads
    told.measure(s);
    EXPECT_NEAR(untold.gather_ms_per_texel().value(), 0.3, 1e-9);
    EXPECT_NEAR(told.gather_ms_per_texel().value(), 0.1, 1e-9);
    EXPECT_NEAR(told.draw_ms().value(), 40.0, 1e-9);
    EXPECT_EQ(told.budgets(settings, 100000).iim_texels, 600);  // (100 − 40) / 0.1
}

TEST(FrameScheduler, HalfTheCostTwiceTheWork) {
    Settings settings;
    settings.schedule.frame_ms = 40.0f;
    FrameScheduler a, b;
    a.measure(measured(8.0, 40, 8.0, 2000, 8.0, 100, 1.0));
    b.measure(measured(8.0, 40, 4.0, 2000, 4.0, 100, 1.0));
    EXPECT_NEAR(double(b.budgets(settings, 100000).iim_texels),
                2.0 * a.budgets(settings, 100000).iim_texels, 1.0);
    EXPECT_NEAR(double(b.budgets(settings, 100000).retrace_photons),
                2.0 * a.budgets(settings, 100000).retrace_photons, 1.0);
}

class FullBudgetTest : public test::GlTest {};

// The round-robin baseline verifies nothing and re-traces every group once per cycle under the
// budget: two_rooms has 4 lights × 77 groups of 40 photons; 4,000 photons a frame make a cycle of
// four frames (100 + 100 + 100 + 8 groups).
TEST_F(FullBudgetTest, EveryGroupOncePerCycleNothingVerified) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/two_rooms.json");
    scene.settings.gather.backend = GatherBackend::cpu;
    ASSERT_EQ(scene.settings.photons.retrace_budget, 4000);
    ASSERT_EQ(scene.settings.photons.photons_per_group, 40);
    const int groups = scene.settings.photons.groups * int(scene.lights.size());
    ASSERT_EQ(groups, 308);
    Pipeline pipeline(scene, PipelineOptions{32, 32, -1, PipelineMode::full_budget});
    FrameLoop loop(pipeline);
    int retraced = 0;
    std::vector<int> per_frame;
    for (int f = 0; f < 8; ++f) {
        const PipelineStats s = loop.step();
        EXPECT_EQ(s.photons.photons_verified, 0);
        retraced += s.photons.photons_retraced;
        per_frame.push_back(s.photons.groups_retraced);
    }
    EXPECT_EQ(per_frame, (std::vector<int>{100, 100, 100, 8, 100, 100, 100, 8}));
    EXPECT_EQ(retraced, 2 * groups * 40);
    // The IIM too: every texel once per cycle, at the fixed count a frame.
    const int texels = int(scene.atlas.texels.size());
    const int per = scene.settings.gather.texels_per_frame;
    int gathered = 0;
    for (int f = 0; f < (texels + per - 1) / per; ++f) gathered += loop.step().iim_texels_gathered;
    EXPECT_GE(gathered, texels - per);
}

}  // namespace
}  // namespace ag
