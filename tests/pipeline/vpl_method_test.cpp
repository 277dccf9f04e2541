// The VPL indirect method (Barczak 2006) in the pipeline: photon-group VPLs follow an edit and
// are back at the settled image within ⌈N/K⌉ frames plus the photon hand-over frame; the thesis's
// static random-walk set stays wrong when a coloured object moves.
#include "shared/pipeline/vpl_method.h"

#include <gtest/gtest.h>

#include <cmath>

#include "../gpu/gl_fixture.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"

namespace ag {
namespace {

constexpr glm::vec3 kJump{254.5f, 0.0f, -59.0f};  // cornell_cube_jump.lua's step

// Cornell with a saturated blue cube (it bleeds colour) and the VPL method.
Scene blue_cube_cornell(VplSource source, bool jumped, VplBackend backend) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell.json");
    scene.settings.indirect.method = IndirectMethodKind::vpl;
    scene.settings.vpl.source = source;
    scene.settings.vpl.backend = backend;
    scene.settings.vpl.map_size = 48;  // small maps keep the GL backend quick on llvmpipe
    scene.settings.vpl.updates_per_frame = 200;
    scene.settings.vpl.resolution_divisor = 2;
    scene.settings.caustics.photons = 0;
    // The tests compare single frames of pipelines at different frame counts: no running mean of
    // sub-pixel offsets (its length would differ between them).
    scene.settings.frame.accumulate_frames = 1;
    const int cube = scene.find_object("cube");
    scene.objects[size_t(cube)].material.albedo = glm::vec3(0.05f, 0.1f, 0.9f);
    if (jumped) translate_object(scene, cube, kJump);
    return scene;
}

// Σ|a − b| / Σ|b| over the indirect term's pixels and channels.
double relative_l1(const Image& a, const Image& b) {
    double diff = 0.0, sum = 0.0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        diff += std::abs(double(a.pixels[i]) - double(b.pixels[i]));
        sum += std::abs(double(b.pixels[i]));
    }
    return diff / sum;
}

const Image& indirect(const gpu::FrameImages& f) { return f.aov[size_t(FrameTerm::indirect)]; }

class VplMethodTest : public test::GlTest, public ::testing::WithParamInterface<VplBackend> {};
class VplMethodCpuTest : public test::GlTest {};

TEST_P(VplMethodTest, PhotonVplsFollowAnEditWithinCeilNOverKFrames) {
    Scene fresh_scene = blue_cube_cornell(VplSource::photons, true, GetParam());
    Pipeline fresh(fresh_scene, PipelineOptions{64, 64});
    fresh.prime();
    const gpu::FrameImages settled = fresh.images();

    Scene scene = blue_cube_cornell(VplSource::photons, false, GetParam());
    Pipeline pipeline(scene, PipelineOptions{64, 64});
    FrameLoop loop(pipeline);
    pipeline.prime();
    const auto* vpl = dynamic_cast<const VplMethod*>(&pipeline.indirect());
    ASSERT_NE(vpl, nullptr);
    const int n = vpl->vpl_count();
    ASSERT_GT(n, 300);
    const double before = relative_l1(indirect(pipeline.images()), indirect(settled));
    EXPECT_GT(before, 0.05) << "the edit must change the indirect term";

    loop.begin_edits();
    translate_object(scene, scene.find_object("cube"), kJump);
    const int k = scene.settings.vpl.updates_per_frame;
    const int bound = (n + k - 1) / k + 1;  // + the frame the photon groups are handed over
    int frames = 0;
    double error = before;
    for (; frames < 4 * bound && error > 0.1 * before; ++frames) {
        const PipelineStats s = loop.step();
        EXPECT_LE(s.vpl_updated, k + 40) << "a frame re-shades about K VPLs (whole slots)";
        error = relative_l1(indirect(pipeline.images()), indirect(settled));
    }
    std::printf("N = %d VPLs, K = %d: error %.4f -> %.4f in %d frames (bound %d)\n", n, k, before,
                error, frames, bound);
    EXPECT_LE(error, 0.1 * before);
    EXPECT_LE(frames, bound);
    // Settled, it is where a pipeline started on the edited scene is.
    for (int f = 0; f < 4 * bound && !pipeline.indirect().settled(); ++f) loop.step();
    EXPECT_TRUE(pipeline.indirect().settled());
    EXPECT_LT(relative_l1(indirect(pipeline.images()), indirect(settled)), 1e-3);
}

// (CPU backend only: the GL backend's term is checked against it above, and its maps cost.)
// Barczak's VPLs are traced once (§6.3): when the blue cube moves, their visibility is updated but
// the light they carry still comes from where the cube was, and the term stays wrong.
TEST_F(VplMethodCpuTest, AStaticRandomWalkSetFailsWhenAColouredObjectMoves) {
    double residual[2] = {0.0, 0.0};
    for (VplSource source : {VplSource::photons, VplSource::random_walk}) {
        Scene fresh_scene = blue_cube_cornell(source, true, VplBackend::cpu);
        Pipeline fresh(fresh_scene, PipelineOptions{48, 48});
        fresh.prime();
        Scene scene = blue_cube_cornell(source, false, VplBackend::cpu);
        Pipeline pipeline(scene, PipelineOptions{48, 48});
        FrameLoop loop(pipeline);
        pipeline.prime();
        loop.begin_edits();
        translate_object(scene, scene.find_object("cube"), kJump);
        loop.step();
        for (int f = 0; f < 100 && !pipeline.indirect().settled(); ++f) loop.step();
        EXPECT_TRUE(pipeline.indirect().settled());
        residual[int(source)] = relative_l1(indirect(pipeline.images()), indirect(fresh.images()));
    }
    std::printf("settled after the move, against a fresh start: photons %.4f, random walk %.4f\n",
                residual[0], residual[1]);
    EXPECT_LT(residual[0], 1e-3);
    EXPECT_GT(residual[1], 0.02);  // measured 0.035 at 48×48
}

// GL backend: the tile lists (default) and the F/P/N labels in them cut the per-pixel sum but
// not its value: before and after the cube's jump the term is the full sum's. Fails if a list
// or a label drops light (or the lists are not rebuilt when the VPLs or points change).
TEST_F(VplMethodCpuTest, GlTileListsAndLabelsKeepTheFullSumThroughAnEdit) {
    auto run = [](bool tiles, bool labels, std::vector<Image>* out) {
        Scene scene = blue_cube_cornell(VplSource::photons, false, VplBackend::gl);
        scene.settings.vpl.tiles = tiles;
        scene.settings.vpl.labels = labels;
        Pipeline pipeline(scene, PipelineOptions{48, 48});
        FrameLoop loop(pipeline);
        pipeline.prime();
        out->push_back(indirect(pipeline.images()));
        loop.begin_edits();
        translate_object(scene, scene.find_object("cube"), kJump);
        loop.step();
        // Mid-update some maps still show the old cube; the labels, built on the scene now, may
        // then differ from them (measured 7e-4).
        out->push_back(indirect(pipeline.images()));
        for (int f = 0; f < 100 && !pipeline.indirect().settled(); ++f) loop.step();
        EXPECT_TRUE(pipeline.indirect().settled());
        out->push_back(indirect(pipeline.images()));
    };
    std::vector<Image> full, tiled, labelled;
    run(false, false, &full);
    run(true, false, &tiled);
    run(true, true, &labelled);
    for (size_t i = 0; i < full.size(); ++i) {
        const double t = relative_l1(tiled[i], full[i]), l = relative_l1(labelled[i], full[i]);
        std::printf("state %zu: tiles %.2e, tiles + labels %.2e (rel. L1 against the full sum)\n",
                    i, t, l);
        EXPECT_LT(t, 1e-5);
        EXPECT_LT(l, 2e-3);
    }
}

INSTANTIATE_TEST_SUITE_P(Backends, VplMethodTest,
                         ::testing::Values(VplBackend::cpu, VplBackend::gl),
                         [](const auto& p) { return kVplBackendNames[size_t(p.param)]; });

}  // namespace
}  // namespace ag
