// IIM refinement (cpu::Iim, docs/fidelity.md): settled texels are gathered again at other points
// of their footprint with other ray sets and averaged; the noise falls, the settled mean does not
// depend on batch sizes, thread counts or order, and any re-gather starts the mean again.
#include "cpu/iim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "cpu/aim.h"
#include "cpu/cpu_gather.h"
#include "cpu/photon_simulation.h"
#include "shared/metrics.h"
#include "test_scenes.h"

namespace ag::cpu {
namespace {

struct Cornell {
    Scene scene;
    ThreadPool pool{2};
    std::unique_ptr<PhotonSimulation> sim;
    std::unique_ptr<Aim> aim;

    explicit Cornell(int refine_passes, uint32_t seed = 1)
        : scene(load_scene(test::scene_path("cornell.json"))) {
        scene.settings.gather.refine_passes = refine_passes;
        sim = std::make_unique<PhotonSimulation>(scene, pool);
        sim->trace_all();
        aim = std::make_unique<Aim>(scene, pool);
        aim->rebuild_all(sim->maps());
        scene.settings.seed = seed;  // the gather's ray sets only: photons and AIMs are the same
    }
};

// Gathers every texel, then refines with `budget` texels a call until complete.
std::vector<glm::vec3> settle(Iim& map, Gatherer& gatherer, int budget, int* calls = nullptr) {
    uint64_t frame = 0;
    while (!map.complete() && frame < 100000) map.gather(gatherer, budget, frame++);
    if (calls) *calls = int(frame);
    EXPECT_TRUE(map.complete());
    EXPECT_EQ(map.pending(), 0);
    return map.gathered();
}

TEST(IimRefinement, NoiseFallsWithPasses) {
    // Two gathers of the same AIMs that differ only in their ray sets (the seed): their
    // difference is the gather's noise. Averaging 16 passes should divide it by about 4.
    double rms[2] = {0.0, 0.0};
    int count = 0;
    for (int variant = 0; variant < 2; ++variant) {
        const int passes = variant == 0 ? 1 : 16;
        Cornell a(passes, 1), b(passes, 2);
        CpuGather ga(a.scene, a.sim->rays(), a.pool, &a.aim->radiance());
        CpuGather gb(b.scene, b.sim->rays(), b.pool, &b.aim->radiance());
        Iim ma(a.scene), mb(b.scene);
        const int records = int(a.scene.atlas.texels.size());
        const std::vector<glm::vec3> va = settle(ma, ga, records), vb = settle(mb, gb, records);
        double sum = 0.0;
        count = 0;
        for (int r = 0; r < records; ++r) {
            if (!ma.texel_valid()[size_t(r)] || !mb.texel_valid()[size_t(r)]) continue;
            EXPECT_EQ(ma.texel_passes()[size_t(r)], passes);
            const TexelRecord& t = a.scene.atlas.texels[size_t(r)];
            const size_t i = size_t(t.y) * size_t(a.scene.atlas.width) + size_t(t.x);
            const double x = luminance(va[i]), y = luminance(vb[i]);
            if (x + y <= 0.0) continue;
            sum += ((x - y) / (0.5 * (x + y))) * ((x - y) / (0.5 * (x + y)));
            ++count;
        }
        rms[variant] = std::sqrt(sum / std::max(1, count));
    }
    std::printf("seed-to-seed RMS difference per texel: 1 pass %.4f, 16 passes %.4f (%d texels)\n",
                rms[0], rms[1], count);
    ASSERT_GT(count, 100);
    EXPECT_GT(rms[0], 0.02);  // there is noise to remove
    EXPECT_LT(rms[1], 0.5 * rms[0]);
}

TEST(IimRefinement, SettledMeanDoesNotDependOnBatchesOrThreads) {
    Cornell c(6);
    const int records = int(c.scene.atlas.texels.size());
    ThreadPool pool1(1), pool3(3);
    CpuGather g1(c.scene, c.sim->rays(), pool1, &c.aim->radiance());
    CpuGather g3(c.scene, c.sim->rays(), pool3, &c.aim->radiance());
    Iim all_at_once(c.scene), in_pieces(c.scene);
    int calls_all = 0, calls_pieces = 0;
    const std::vector<glm::vec3> a = settle(all_at_once, g1, records, &calls_all);
    const std::vector<glm::vec3> b = settle(in_pieces, g3, 97, &calls_pieces);
    EXPECT_GT(calls_pieces, calls_all);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "atlas texel " << i;
    EXPECT_EQ(all_at_once.texel_passes(), in_pieces.texel_passes());
}

TEST(IimRefinement, ARegatherStartsTheMeanAgainAndEndsWhereItDid) {
    Cornell c(4);
    const int records = int(c.scene.atlas.texels.size());
    CpuGather g(c.scene, c.sim->rays(), c.pool, &c.aim->radiance());
    Iim map(c.scene);
    const std::vector<glm::vec3> settled = settle(map, g, records);

    // A new AIM (the same values here): every texel is stale, re-gathered once, then refined
    // again; nothing refines before the stale texels are done.
    map.aim_changed();
    EXPECT_FALSE(map.complete());
    const IimFrameStats first = map.gather(g, records / 2, 1000);
    EXPECT_EQ(first.refined, 0);
    EXPECT_EQ(first.gathered, records / 2);
    for (int r : map.last_gathered()) EXPECT_EQ(map.texel_passes()[size_t(r)], 1);
    // A single gather of a texel with several valid passes differs from its mean.
    Iim single(c.scene);
    single.gather_records(g, map.last_gathered(), 0);
    int differ = 0;
    for (int r : map.last_gathered()) {
        if (!map.texel_valid()[size_t(r)]) continue;  // repaired from other neighbours
        const TexelRecord& t = c.scene.atlas.texels[size_t(r)];
        const size_t i = size_t(t.y) * size_t(c.scene.atlas.width) + size_t(t.x);
        EXPECT_EQ(map.gathered()[i], single.gathered()[i]);
        differ += map.gathered()[i] != settled[i];
    }
    EXPECT_GT(differ, 0);
    const std::vector<glm::vec3> again = settle(map, g, records);
    for (size_t i = 0; i < again.size(); ++i) ASSERT_EQ(again[i], settled[i]) << "texel " << i;
}

TEST(IimRefinement, OnePassMeansNoRefinement) {
    Cornell c(1);
    const int records = int(c.scene.atlas.texels.size());
    CpuGather g(c.scene, c.sim->rays(), c.pool, &c.aim->radiance());
    Iim map(c.scene);
    map.gather(g, records, 0);
    EXPECT_TRUE(map.complete());
    EXPECT_EQ(map.gather(g, records, 1).gathered, 0);
}

TEST(IimRefinement, OffsetsCoverTheFootprint) {
    EXPECT_EQ(Iim::refine_offset(0), glm::vec2(0.0f));
    glm::vec2 sum(0.0f);
    for (int k = 0; k < 64; ++k) {
        const glm::vec2 o = Iim::refine_offset(k);
        EXPECT_GE(o.x, -0.5f);
        EXPECT_LT(o.x, 0.5f);
        EXPECT_GE(o.y, -0.5f);
        EXPECT_LT(o.y, 0.5f);
        sum += o;
    }
    EXPECT_LT(std::abs(sum.x / 64.0f), 0.02f);  // centred on the texel
    EXPECT_LT(std::abs(sum.y / 64.0f), 0.02f);
}

}  // namespace
}  // namespace ag::cpu
