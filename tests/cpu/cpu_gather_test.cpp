// CPU final gather (Larsen ch. 11) against analytic form factors, atlas sampling without bleeding
// across charts, back-face repair, colour bleeding in the Cornell box, thread-count independence.
#include "cpu/cpu_gather.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <numeric>
#include <random>

#include "cpu/aim.h"
#include "cpu/iim.h"
#include "cpu/photon_simulation.h"
#include "gather_scenes.h"
#include "shared/lightmap_sample.h"
#include "shared/media.h"
#include "shared/shapes.h"
#include "test_scenes.h"

namespace ag::cpu {

namespace {

using test::all_texels;
using test::atlas_index;
using test::atlas_values;
using test::finish;
using test::kFacingDown;
using test::quad_object;
using test::square_form_factor;
using test::world_position;

// Photons traced and AIMs built for a scene file, ready to gather.
struct Simulated {
    Scene scene;
    ThreadPool pool{2};
    std::unique_ptr<PhotonSimulation> sim;
    std::unique_ptr<Aim> aim;

    explicit Simulated(const std::string& file, void (*tweak)(Scene&) = nullptr)
        : scene(load_scene(test::scene_path(file))) {
        if (tweak) tweak(scene);
        sim = std::make_unique<PhotonSimulation>(scene, pool);
        sim->trace_all();
        aim = std::make_unique<Aim>(scene, pool);
        aim->rebuild_all(sim->maps());
    }
};

// Texels of a quad of side `receiver` at the origin under a parallel square of half-width a at
// height 1 whose AIM is uniformly `radiance`: per texel, the gathered iim and the analytic L · F.
struct FacingResult {
    std::vector<glm::vec3> got;
    std::vector<double> form_factor;
    uint64_t rays_cast = 0, rays_counted = 0;
    bool all_valid = true;
};

// Gathers `records` the way the pipeline does: through cpu::Iim, which judges each result's
// validity and repairs invalid texels from their chart's valid neighbours.
struct Gathered {
    std::vector<glm::vec3> iim;  // atlas-sized
    std::vector<char> valid;     // per texel record
    int invalid = 0;             // repaired from neighbours
    int relocated = 0;           // gathered at a point of their footprint
};
Gathered gather_records(const Scene& scene, Gatherer& gatherer, const std::vector<int>& records) {
    Iim map(scene);
    const IimFrameStats stats = map.gather_records(gatherer, records, 0);
    return {map.gathered(), map.texel_valid(), stats.invalid, stats.relocated};
}

FacingResult gather_under_square(float receiver, float a, float texel_size, int rays_per_texel,
                                 glm::vec3 radiance) {
    Scene s;
    s.path = "facing squares";
    s.objects.push_back(quad_object("receiver", receiver, glm::vec3(0.0f)));
    s.objects.push_back(quad_object("emitter", 2.0f * a, glm::vec3(0.0f, 1.0f, 0.0f), kFacingDown));
    s.settings.gather.cpu_rays = rays_per_texel;
    const Scene scene = finish(s, texel_size);
    std::vector<glm::vec3> aim = atlas_values(scene);
    std::vector<int> receivers;
    for (int r = 0; r < int(scene.atlas.texels.size()); ++r) {
        const TexelRecord& t = scene.atlas.texels[size_t(r)];
        if (t.object == 1)
            aim[atlas_index(scene.atlas, t)] = radiance;
        else
            receivers.push_back(r);
    }
    ThreadPool pool(2);
    RayTracer rays(scene);
    CpuGather gather(scene, rays, pool, &aim);
    const Gathered g = gather_records(scene, gather, receivers);
    const std::vector<glm::vec3>& iim = g.iim;
    FacingResult out;
    for (int r : receivers) {
        const TexelRecord& t = scene.atlas.texels[size_t(r)];
        const glm::vec3 p = world_position(scene, t);
        out.got.push_back(iim[atlas_index(scene.atlas, t)]);
        out.form_factor.push_back(square_form_factor(p.x, p.z, a, 1.0));
        out.all_valid = out.all_valid && g.valid[size_t(r)];
    }
    out.rays_cast = rays.rays_cast();
    out.rays_counted = gather.last_stats().rays;
    return out;
}

}  // namespace

TEST(LightmapSample, UvAtCornersIsTheCornerUv) {
    const Scene scene = load_scene(test::scene_path("cornell.json"));
    const LightmapAtlas& atlas = scene.atlas;
    for (const Chart& chart : atlas.charts)
        for (int t : chart.triangles) {
            const glm::vec2* c = &atlas.corner_uvs[size_t(chart.object)][3 * size_t(t)];
            EXPECT_EQ(lightmap_uv(atlas, chart.object, t, {0.0f, 0.0f}), c[0]);
            EXPECT_EQ(lightmap_uv(atlas, chart.object, t, {1.0f, 0.0f}), c[1]);
            EXPECT_EQ(lightmap_uv(atlas, chart.object, t, {0.0f, 1.0f}), c[2]);
        }
}

// Constant values per chart come back unchanged anywhere on the chart's triangles, corners and
// edges included, with gutters and with charts packed edge to edge (gutter 0), where only the
// chart test keeps a neighbour's texels out.
TEST(LightmapSample, ConstantPerChartValuesDoNotBleed) {
    for (int gutter : {1, 0}) {
        Scene scene = load_scene(test::scene_path("cornell.json"));
        scene.settings.lightmap.gutter = gutter;
        make_surfaces_and_atlas(scene);
        const LightmapAtlas& atlas = scene.atlas;
        auto chart_value = [](int c) { return glm::vec3(float(c + 1), 100.0f - float(c), 7.0f); };
        std::vector<glm::vec3> values = atlas_values(scene);
        for (const TexelRecord& t : atlas.texels)
            values[atlas_index(atlas, t)] = chart_value(t.chart);

        std::mt19937 rng(5);
        std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
        int samples = 0;
        for (int c = 0; c < int(atlas.charts.size()); ++c) {
            const Chart& chart = atlas.charts[size_t(c)];
            for (int t : chart.triangles) {
                ASSERT_EQ(triangle_chart(atlas, chart.object, t), c);
                std::vector<glm::vec2> bary = {{0, 0},
                                               {1, 0},
                                               {0, 1},
                                               {0.5f, 0},
                                               {0, 0.5f},
                                               {0.5f, 0.5f},
                                               {1.0f / 3, 1.0f / 3}};
                for (int k = 0; k < 20; ++k) {
                    const float u = uniform(rng), v = uniform(rng);
                    bary.push_back(u + v > 1.0f ? glm::vec2(1.0f - u, 1.0f - v) : glm::vec2(u, v));
                }
                for (glm::vec2 b : bary) {
                    const glm::vec3 got = sample_lightmap(atlas, values, chart.object, t, b);
                    const glm::vec3 want = chart_value(c);
                    for (int i = 0; i < 3; ++i)
                        ASSERT_NEAR(got[i], want[i], 1e-5f * want[i])
                            << "gutter " << gutter << ", chart " << c << ", triangle " << t;
                    ++samples;
                }
            }
        }
        EXPECT_GT(samples, 500);
        // Glass has no charts: nothing to read.
        const int sphere = scene.find_object("sphere");
        ASSERT_GE(sphere, 0);
        EXPECT_EQ(triangle_chart(atlas, sphere, 0), -1);
        EXPECT_EQ(sample_lightmap(atlas, values, sphere, 0, {0.2f, 0.3f}), glm::vec3(0.0f));
    }
}

// Bilinear interpolation reproduces a function linear in the atlas coordinates wherever the
// four surrounding texels exist: between two texel centres it is linear.
TEST(LightmapSample, BilinearReproducesLinearValues) {
    Scene s;
    s.path = "quad";
    s.objects.push_back(quad_object("quad", 2.0f, glm::vec3(0.0f)));
    const Scene scene = finish(s, 0.1f);
    const LightmapAtlas& atlas = scene.atlas;
    auto linear = [](glm::vec2 uv) {
        return glm::vec3(1.0f + 0.5f * uv.x - 0.25f * uv.y, uv.x, uv.y);
    };
    std::vector<glm::vec3> values = atlas_values(scene);
    for (const TexelRecord& t : atlas.texels)
        values[atlas_index(atlas, t)] = linear({float(t.x) + 0.5f, float(t.y) + 0.5f});

    std::mt19937 rng(9);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    int interior = 0;
    for (int k = 0; k < 2000; ++k) {
        const int t = k % 2;
        const float u = uniform(rng), v = uniform(rng);
        const glm::vec2 b = u + v > 1.0f ? glm::vec2(1.0f - u, 1.0f - v) : glm::vec2(u, v);
        const glm::vec2 uv = lightmap_uv(atlas, 0, t, b);
        const int x0 = int(std::floor(uv.x - 0.5f)), y0 = int(std::floor(uv.y - 0.5f));
        bool all = true;
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) all = all && atlas.texel_at(x0 + dx, y0 + dy) >= 0;
        if (!all) continue;
        const glm::vec3 got = sample_lightmap(atlas, values, 0, t, b), want = linear(uv);
        for (int i = 0; i < 3; ++i) ASSERT_NEAR(got[i], want[i], 1e-4f) << uv.x << ", " << uv.y;
        ++interior;
    }
    EXPECT_GT(interior, 1500);
}

// Invalid texels take the mean of their valid 8-neighbours, islands fill layer by layer, a chart
// without valid texels becomes 0, other charts are untouched, and the targeted form writes
// only its targets.
TEST(LightmapRepair, FillsFromValidNeighboursOfTheSameChart) {
    Scene s;
    s.path = "two quads";
    s.objects.push_back(quad_object("a", 2.0f, glm::vec3(0.0f)));
    s.objects.push_back(quad_object("b", 1.0f, glm::vec3(0.0f, 1.0f, 0.0f), kFacingDown));
    const Scene scene = finish(s, 0.2f);
    const LightmapAtlas& atlas = scene.atlas;
    ASSERT_EQ(atlas.charts.size(), 2u);
    const int big = atlas.charts[0].width >= atlas.charts[1].width ? 0 : 1;
    const Chart& chart = atlas.charts[size_t(big)];
    ASSERT_GE(chart.width, 8);

    std::vector<glm::vec3> values = atlas_values(scene);
    std::vector<char> valid(atlas.texels.size(), 1);
    const int cx = chart.x + chart.width / 2, cy = chart.y + chart.height / 2;
    for (size_t r = 0; r < atlas.texels.size(); ++r) {
        const TexelRecord& t = atlas.texels[r];
        values[atlas_index(atlas, t)] = glm::vec3(float(t.x), float(t.y), 1.0f);
        // A 5×5 island in the big chart; the whole small chart.
        const bool island = t.chart == big && std::abs(t.x - cx) <= 2 && std::abs(t.y - cy) <= 2;
        if (island || t.chart != big) {
            valid[r] = 0;
            values[atlas_index(atlas, t)] = glm::vec3(999.0f);
        }
    }
    const std::vector<glm::vec3> before = values;

    // Targeted: only the island's centre is written, yet it is filled through the ring.
    const int centre = atlas.texel_at(cx, cy);
    std::vector<glm::vec3> targeted = values;
    repair_invalid_texels(atlas, targeted, valid, std::vector<int>{centre});
    for (size_t i = 0; i < values.size(); ++i) {
        if (i == size_t(cy) * size_t(atlas.width) + size_t(cx)) continue;
        EXPECT_EQ(targeted[i], values[i]);
    }

    repair_invalid_texels(atlas, values, valid);
    for (size_t r = 0; r < atlas.texels.size(); ++r) {
        const TexelRecord& t = atlas.texels[r];
        const glm::vec3 got = values[atlas_index(atlas, t)];
        if (valid[r]) {
            EXPECT_EQ(got, before[atlas_index(atlas, t)]);
        } else if (t.chart != big) {
            EXPECT_EQ(got, glm::vec3(0.0f));
        } else if (std::max(std::abs(t.x - cx), std::abs(t.y - cy)) == 2) {
            // Outer ring of the island: the mean of its valid neighbours.
            glm::vec3 sum(0.0f);
            int n = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nr = atlas.texel_at(t.x + dx, t.y + dy);
                    if ((dx || dy) && nr >= 0 && valid[size_t(nr)]) {
                        sum += before[atlas_index(atlas, atlas.texels[size_t(nr)])];
                        ++n;
                    }
                }
            ASSERT_GT(n, 0);
            for (int i = 0; i < 3; ++i) EXPECT_NEAR(got[i], sum[i] / float(n), 1e-4f);
        } else {
            // Inner texels: means of means of the valid texels around the island.
            EXPECT_GE(got.x, float(cx - 3));
            EXPECT_LE(got.x, float(cx + 3));
            EXPECT_GE(got.y, float(cy - 3));
            EXPECT_LE(got.y, float(cy + 3));
            EXPECT_NEAR(got.z, 1.0f, 1e-5f);
        }
    }
    EXPECT_EQ(targeted[size_t(cy) * size_t(atlas.width) + size_t(cx)],
              values[size_t(cy) * size_t(atlas.width) + size_t(cx)]);
}

// A point under a parallel square of uniform radiance L gathers L · F, F the form factor of the
// square (a = 2: F = 0.83 at the centre); F → 1 as the square grows (Larsen's hemi-plane
// coverage, DESIGN.md). Scrambled QMC is unbiased: at 256 rays the error averages out over
// texels and stays near N^(-3/4) per texel; at 1024 rays every texel is within 1%.
TEST(CpuGather, FacingSquareMatchesFormFactor) {
    const glm::vec3 radiance(2.0f, 1.0f, 0.5f);
    for (int rays : {256, 1024}) {
        const FacingResult r = gather_under_square(0.5f, 2.0f, 0.1f, rays, radiance);
        ASSERT_GE(r.got.size(), 25u);
        EXPECT_TRUE(r.all_valid);
        EXPECT_EQ(r.rays_counted, uint64_t(rays) * r.got.size());
        EXPECT_EQ(r.rays_cast, r.rays_counted);
        double mean = 0.0, squares = 0.0, worst = 0.0;
        for (size_t i = 0; i < r.got.size(); ++i) {
            for (int c = 1; c < 3; ++c)
                EXPECT_FLOAT_EQ(r.got[i][c] / radiance[c], r.got[i].x / radiance.x);
            const double error = r.got[i].x / (radiance.x * r.form_factor[i]) - 1.0;
            mean += error;
            squares += error * error;
            worst = std::max(worst, std::abs(error));
            if (rays == 1024) {
                EXPECT_LT(std::abs(error), 0.01) << "texel " << i;
            }
        }
        mean /= double(r.got.size());
        const double rms = std::sqrt(squares / double(r.got.size()));
        std::printf(
            "%d rays, %zu texels, F %.4f..%.4f: mean error %+.4f, rms %.4f, worst %.4f\n", rays,
            r.got.size(), *std::min_element(r.form_factor.begin(), r.form_factor.end()),
            *std::max_element(r.form_factor.begin(), r.form_factor.end()), mean, rms, worst);
        EXPECT_LT(std::abs(mean), 0.003);
        EXPECT_LT(rms, rays == 256 ? 0.012 : 0.005);
    }
    // A plane much larger than its distance: nearly the whole hemisphere, iim → L.
    const FacingResult big = gather_under_square(0.1f, 20.0f, 0.25f, 256, radiance);
    ASSERT_EQ(big.got.size(), 1u);
    EXPECT_GT(big.form_factor[0], 0.997);
    EXPECT_NEAR(big.got[0].x, radiance.x * big.form_factor[0], 0.01 * radiance.x);
    EXPECT_GT(big.got[0].x, 0.98f * radiance.x);
}

// Light reaching a texel off a mirror or through glass counts (issue #12): the gather follows
// the specular bounces to the diffuse surface behind them. A receiver between a large mirror
// above and a large emitting floor below sees the floor's mirror image; under a glass slab with an
// emitter above, it gets the slab's transmittance, (1 − F)/(1 + F) per polarisation for a
// lossless slab, averaged over the cosine-weighted hemisphere. With no bounces both are black.
TEST(CpuGather, LightOffMirrorsAndThroughGlassCounts) {
    const glm::vec3 radiance(1.0f, 0.5f, 0.25f);
    // Coarse texels: the receiver is one texel, the large quads stay small atlases.
    auto gather_centre = [&](Scene s, int bounces, const std::string& lit) {
        s.path = "specular";
        s.settings.gather.cpu_rays = 4096;
        s.settings.gather.specular_bounces = bounces;
        const Scene scene = finish(s, 4.0f);
        std::vector<glm::vec3> aim = atlas_values(scene);
        std::vector<int> receivers;
        for (int r = 0; r < int(scene.atlas.texels.size()); ++r) {
            const TexelRecord& t = scene.atlas.texels[size_t(r)];
            if (scene.objects[size_t(t.object)].name == lit)
                aim[atlas_index(scene.atlas, t)] = radiance;
            if (scene.objects[size_t(t.object)].name == "receiver") receivers.push_back(r);
        }
        ThreadPool pool(2);
        RayTracer rays(scene);
        CpuGather gather(scene, rays, pool);
        double sum = 0.0;
        for (const GatherResult& g : gather.gather(receivers, aim)) sum += g.iim.x;
        return sum / double(receivers.size()) / radiance.x;
    };

    Scene mirror;
    mirror.objects.push_back(quad_object("receiver", 0.1f, glm::vec3(0.0f)));
    mirror.objects.push_back(quad_object("floor", 40.0f, glm::vec3(0.0f, -0.01f, 0.0f)));
    mirror.objects.push_back(
        quad_object("mirror", 40.0f, glm::vec3(0.0f, 1.0f, 0.0f), kFacingDown));
    mirror.objects.back().material.type = MaterialType::mirror;
    const double seen = gather_centre(mirror, 4, "floor");
    // The floor's image lies 2 below the mirror; a square of half-width 20 at distance ~2 covers
    // 99% of the cosine-weighted hemisphere.
    EXPECT_GT(seen, 0.985);
    EXPECT_LT(seen, 1.0001);
    EXPECT_LT(gather_centre(mirror, 0, "floor"), 1e-6);

    Scene glass;
    glass.objects.push_back(quad_object("receiver", 0.1f, glm::vec3(0.0f)));
    glass.objects.push_back(
        quad_object("emitter", 400.0f, glm::vec3(0.0f, 2.0f, 0.0f), kFacingDown));
    Object slab;
    slab.name = "slab";
    slab.mesh = make_box(glm::vec3(200.0f, 0.2f, 200.0f));
    slab.transform.translation = glm::vec3(0.0f, 1.0f, 0.0f);
    slab.material.type = MaterialType::glass;
    slab.material.ior = 1.5f;
    glass.objects.push_back(slab);
    // Expected: ∫ T(θ) 2 cosθ sinθ dθ with T the mean over both polarisations of (1 − F)/(1 + F).
    double expected = 0.0;
    constexpr int kSteps = 20000;
    for (int k = 0; k < kSteps; ++k) {
        const double theta = (k + 0.5) * (std::numbers::pi / 2) / kSteps;
        const double ci = std::cos(theta), eta = 1.0 / 1.5;
        const double ct = std::sqrt(1.0 - eta * eta * (1.0 - ci * ci));
        const double rs = std::pow((eta * ci - ct) / (eta * ci + ct), 2);
        const double rp = std::pow((ci - eta * ct) / (ci + eta * ct), 2);
        const double t = 0.5 * ((1 - rs) / (1 + rs) + (1 - rp) / (1 + rp));
        expected += t * 2.0 * ci * std::sin(theta) * (std::numbers::pi / 2) / kSteps;
    }
    const double through = gather_centre(glass, 8, "emitter");
    std::printf("mirror: %.4f of the floor's radiance; glass slab: %.4f (lossless slab %.4f)\n",
                seen, through, expected);
    // Branches under 1% of a ray's weight are dropped (most of the slab's inner reflections).
    EXPECT_NEAR(through, expected, 0.015);
    EXPECT_LT(gather_centre(glass, 0, "emitter"), 1e-6);
}

// A floor that passes through a closed cube: the texels inside see only the cube's back faces,
// are marked invalid, and take their values from the valid floor texels around them instead of
// going dark or reporting the cube's (outside) radiance.
TEST(CpuGather, TexelsInsideGeometryAreRepairedFromNeighbours) {
    Scene s;
    s.path = "floor through a cube";
    s.objects.push_back(quad_object("floor", 4.0f, glm::vec3(0.0f)));
    s.objects.push_back(quad_object("ceiling", 4.0f, glm::vec3(0.0f, 2.0f, 0.0f), kFacingDown));
    Object cube;
    cube.name = "cube";
    cube.mesh = make_box(glm::vec3(1.5f));
    cube.transform.translation = glm::vec3(0.5f, -0.4f, 0.5f);  // x, z in [-0.25, 1.25]
    s.objects.push_back(cube);
    const Scene scene = finish(s, 0.25f);
    const float cube_radiance = 50.0f;

    std::vector<glm::vec3> aim = atlas_values(scene);
    std::vector<int> floor;
    for (int r = 0; r < int(scene.atlas.texels.size()); ++r) {
        const TexelRecord& t = scene.atlas.texels[size_t(r)];
        if (t.object == 0) floor.push_back(r);
        aim[atlas_index(scene.atlas, t)] = glm::vec3(t.object == 1   ? 1.0f
                                                     : t.object == 2 ? cube_radiance
                                                                     : 0.0f);
    }
    ThreadPool pool(2);
    RayTracer rays(scene);
    CpuGather gather(scene, rays, pool, &aim);
    const Gathered g = gather_records(scene, gather, floor);
    const std::vector<glm::vec3>& iim = g.iim;
    const std::vector<char>& valid = g.valid;

    const LightmapAtlas& atlas = scene.atlas;
    auto value = [&](int r) { return iim[atlas_index(atlas, atlas.texels[size_t(r)])].x; };
    float valid_min = 1e30f, valid_max = 0.0f;
    for (int r : floor) {
        if (!valid[size_t(r)]) continue;
        valid_min = std::min(valid_min, value(r));
        valid_max = std::max(valid_max, value(r));
    }
    EXPECT_GT(valid_min, 0.0f);
    int inside = 0, outside = 0, invalid = 0, ring = 0;
    for (int r : floor) {
        const TexelRecord& t = atlas.texels[size_t(r)];
        const glm::vec3 p = world_position(scene, t);
        const float d = std::max(std::abs(p.x - 0.5f), std::abs(p.z - 0.5f));
        if (d > 0.76f) {
            EXPECT_TRUE(valid[size_t(r)]) << p.x << ", " << p.z;
            ++outside;
        } else if (d < 0.74f) {
            EXPECT_FALSE(valid[size_t(r)]) << p.x << ", " << p.z;
            ++inside;
        }
        if (valid[size_t(r)]) continue;
        ++invalid;
        const float got = value(r);
        EXPECT_GE(got, valid_min) << p.x << ", " << p.z;
        EXPECT_LE(got, valid_max) << p.x << ", " << p.z;
        EXPECT_LT(got, 0.8f * cube_radiance) << p.x << ", " << p.z;
        // Next to valid texels: exactly their mean.
        float sum = 0.0f;
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int nr = atlas.texel_at(t.x + dx, t.y + dy);
                if ((dx || dy) && nr >= 0 && valid[size_t(nr)]) sum += value(nr), ++n;
            }
        if (n > 0) {
            EXPECT_NEAR(got, sum / float(n), 1e-5f * got) << p.x << ", " << p.z;
            ++ring;
        }
    }
    EXPECT_GE(inside, 16);
    EXPECT_GE(ring, 8);
    EXPECT_GT(invalid, ring);  // some only reachable through other invalid texels
    EXPECT_GE(outside, 100);
    EXPECT_EQ(g.invalid, invalid);
    // Texels whose centre is inside the cube but part of whose footprint is not are gathered
    // there (cpu::Iim relocates them); the rest are repaired.
    EXPECT_GT(g.relocated, 0);
    EXPECT_EQ(gather.last_stats().invalid, invalid + g.relocated);
}

// End to end in the Cornell box: every floor texel receives indirect light, and the walls'
// colours bleed: near the red wall (x = 555) the floor and back wall are redder than near the
// green wall (x = 0).
TEST(CpuGather, CornellColourBleeding) {
    Simulated s("cornell.json");
    const Scene& scene = s.scene;
    ASSERT_EQ(scene.objects[size_t(scene.find_object("left_wall"))].material.name, "red");
    ASSERT_EQ(scene.objects[size_t(scene.find_object("right_wall"))].material.name, "green");
    CpuGather gather(scene, s.sim->rays(), s.pool, &s.aim->radiance());
    const Gathered g = gather_records(scene, gather, all_texels(scene));
    const std::vector<glm::vec3>& iim = g.iim;
    // The floor under the cube: at 111 mm every such texel reaches out from under the cube and is
    // gathered at a point of its footprint.
    EXPECT_GT(g.invalid + g.relocated, 0);

    auto nearest = [&](const std::string& object, glm::vec3 target) {
        const int o = scene.find_object(object);
        int best = -1;
        float best_d = 1e30f;
        for (int r = 0; r < int(scene.atlas.texels.size()); ++r) {
            const TexelRecord& t = scene.atlas.texels[size_t(r)];
            if (t.object != o) continue;
            const float d = glm::length(world_position(scene, t) - target);
            if (d < best_d) best_d = d, best = r;
        }
        return iim[atlas_index(scene.atlas, scene.atlas.texels[size_t(best)])];
    };
    // Every floor texel but those wholly under the cube, which no one sees: with finer texels at
    // the contact (lightmap.refine_tile) a few of them have no open neighbour on their chart to
    // be repaired from, and stay 0 (4 of 1,425 on #12's layout).
    const int floor = scene.find_object("floor");
    const Object& cube = scene.objects[size_t(scene.find_object("cube"))];
    const auto under_cube = [&](const glm::vec3& p) {
        const glm::vec3 local =
            glm::inverse(cube.transform.rotation) * (p - cube.transform.translation);
        return std::abs(local.x) < 82.5f && std::abs(local.z) < 82.5f;
    };
    for (size_t r = 0; r < scene.atlas.texels.size(); ++r) {
        const TexelRecord& t = scene.atlas.texels[r];
        if (t.object != floor) continue;
        if (!g.valid[r] && under_cube(world_position(scene, t))) continue;
        for (int i = 0; i < 3; ++i) EXPECT_GT(iim[atlas_index(scene.atlas, t)][i], 0.0f);
    }
    for (const char* object : {"floor", "back_wall"}) {
        const float y = std::string(object) == "floor" ? 0.0f : 277.5f;
        const float z = std::string(object) == "floor" ? 277.5f : 555.0f;
        const glm::vec3 red = nearest(object, {555.0f, y, z}),
                        green = nearest(object, {0.0f, y, z});
        std::printf("%s: near red wall %.4g %.4g %.4g, near green wall %.4g %.4g %.4g\n", object,
                    red.x, red.y, red.z, green.x, green.y, green.z);
        EXPECT_GT(red.x / red.y, green.x / green.y) << object;
        EXPECT_GT(red.x / red.y, 1.1f * green.x / green.y) << object;
    }
}

TEST(CpuGather, SameResultForAnyThreadCount) {
    Simulated s("cornell.json");
    const Scene& scene = s.scene;
    ThreadPool pool1(1), pool3(3);
    CpuGather gather1(scene, s.sim->rays(), pool1, &s.aim->radiance()),
        gather3(scene, s.sim->rays(), pool3, &s.aim->radiance());
    const std::vector<GatherResult> raw1 = gather1.gather(all_texels(scene)),
                                    raw3 = gather3.gather(all_texels(scene));
    ASSERT_EQ(raw1.size(), raw3.size());
    for (size_t i = 0; i < raw1.size(); ++i) {
        ASSERT_EQ(raw1[i].iim, raw3[i].iim) << "record " << i;
        ASSERT_EQ(raw1[i].back_fraction, raw3[i].back_fraction) << "record " << i;
    }
    const Gathered one = gather_records(scene, gather1, all_texels(scene)),
                   three = gather_records(scene, gather3, all_texels(scene));
    for (size_t i = 0; i < one.iim.size(); ++i)
        ASSERT_EQ(one.iim[i], three.iim[i]) << "atlas texel " << i;
    EXPECT_EQ(one.valid, three.valid);
    // Batches: gathering in pieces gives the same as all at once (repairs read earlier batches).
    CpuGather gather2(scene, s.sim->rays(), s.pool, &s.aim->radiance());
    std::vector<int> ids = all_texels(scene), valid_first, invalid_then;
    for (int r : ids) (one.valid[size_t(r)] ? valid_first : invalid_then).push_back(r);
    Iim pieces(scene);
    pieces.gather_records(gather2, valid_first, 0);
    pieces.gather_records(gather2, invalid_then, 0);
    for (size_t i = 0; i < one.iim.size(); ++i)
        ASSERT_EQ(one.iim[i], pieces.gathered()[i]) << "atlas texel " << i;
}

// The ray cache (gather.ray_cache_mb) re-reads a texel's first hits instead of tracing them
// while nothing they crossed has moved: after a move, an albedo edit and a mirror made of a
// diffuse object, every texel is what a gatherer without a cache gives, to the bit, and the
// cache was used (most rays re-read) but not blindly (the rays the cube's move touched were
// traced again). Fails if a move does not invalidate the rays that hit the cube or cross its new
// place, or if a cached hit is read where a ray now meets a mirror.
TEST(CpuGather, TheRayCacheGivesWhatTracingGives) {
    Simulated s("cornell.json");
    Scene& scene = s.scene;
    scene.settings.gather.cpu_rays = 64;
    const std::vector<int> all = all_texels(scene);
    // Both see every edit (a tracer brought up to date after a move can differ from a new one
    // in the last bits: that is the tracer's, not the cache's).
    Scene traced_scene = scene;
    traced_scene.settings.gather.ray_cache_mb = 0;
    CpuGather cached(scene, s.pool, &s.aim->radiance());
    CpuGather traced(traced_scene, s.pool, &s.aim->radiance());
    const uint64_t rays = uint64_t(all.size()) * 64;
    auto expect_as_traced = [&](const char* what, double min_reused, double max_reused) {
        traced_scene.objects = scene.objects;
        const std::vector<GatherResult> got = cached.gather(all);
        const uint64_t reused = cached.last_stats().rays_reused;
        const std::vector<GatherResult> want = traced.gather(all);
        EXPECT_EQ(traced.last_stats().rays_reused, 0u) << what;
        size_t differ = 0, first = all.size();
        for (size_t i = 0; i < all.size(); ++i)
            if (got[i].iim != want[i].iim || got[i].back_fraction != want[i].back_fraction) {
                ++differ;
                first = std::min(first, i);
            }
        EXPECT_EQ(differ, 0u) << what << ": first at record " << first;
        const double share = double(reused) / double(rays);
        EXPECT_GE(share, min_reused) << what;
        EXPECT_LE(share, max_reused) << what;
        return share;
    };
    expect_as_traced("first gather", 0.0, 0.0);
    // Nothing moved: every ray but those meeting the glass sphere (followed anew) is re-read.
    const double still = expect_as_traced("nothing changed", 0.9, 1.0);
    const int cube = scene.find_object("cube");
    ASSERT_GE(cube, 0);
    scene.objects[size_t(cube)].transform.translation += glm::vec3(-120.0f, 0.0f, 90.0f);
    expect_as_traced("the cube moved", 0.3, still - 0.05);
    // An albedo edit changes no ray: the cache holds, and the values follow the AIM.
    scene.objects[size_t(scene.find_object("left_wall"))].material.albedo = glm::vec3(0.2f);
    expect_as_traced("an albedo edit", still - 1e-9, 1.0);
    // The cube becomes a mirror: rays that met it follow the bounce now.
    scene.objects[size_t(cube)].material.type = MaterialType::mirror;
    expect_as_traced("the cube a mirror", 0.3, still - 0.01);
    // Fog in the lower half of the box: a re-read hit is dimmed along its ray as a traced one.
    Medium fog;
    fog.bounds.add(glm::vec3(-10.0f, -10.0f, -10.0f));
    fog.bounds.add(glm::vec3(560.0f, 250.0f, 560.0f));
    fog.sigma_s = 1e-3f;
    fog.sigma_a = 1e-3f;
    scene.media.push_back(fog);
    traced_scene.media = scene.media;
    expect_as_traced("fog added", 0.3, still);
}

}  // namespace ag::cpu

namespace ag::cpu {

namespace {
// The Cornell box simulated, a cheap CPU gather of its AIMs and an empty IIM, for the scheduling
// tests (refinement off: complete() then means gathered, not refined).
struct ScheduleCase {
    Simulated s{"cornell.json", [](Scene& scene) {
                    scene.settings.gather.cpu_rays = 16;
                    scene.settings.gather.refine_passes = 1;
                }};
    CpuGather gather{s.scene, s.sim->rays(), s.pool, &s.aim->radiance()};
    Iim map{s.scene};
};
}  // namespace

// An object edited every frame keeps its surfaces' Δi high; the texels it queues must not starve
// the ones never gathered (they show no indirect light at all), so with a budget of B texels a
// frame every texel is gathered once within ⌈texels / B⌉ frames.
TEST(IimSchedule, TexelsNeverGatheredAreNotStarvedByRepeatedEdits) {
    ScheduleCase c;
    Simulated& s = c.s;
    CpuGather& gather = c.gather;
    Iim& map = c.map;
    PhotonMaps& maps = s.sim->maps();
    // The surface with the most texels plays the edited one.
    std::vector<int> per_surface(maps.surface_count(), 0);
    for (const TexelRecord& t : s.scene.atlas.texels)
        if (t.surface >= 0 && size_t(t.surface) < per_surface.size())
            ++per_surface[size_t(t.surface)];
    const int edited =
        int(std::max_element(per_surface.begin(), per_surface.end()) - per_surface.begin());
    const int texels = int(s.scene.atlas.texels.size());
    const int budget = std::max(1, per_surface[size_t(edited)]);
    ASSERT_LT(budget, texels);
    std::vector<char> seen(size_t(texels), 0);
    const int frames = (texels + budget - 1) / budget;
    for (int frame = 0; frame < frames; ++frame) {
        maps.surface(edited).delta_i = 1e9;
        map.schedule(maps);
        map.gather(gather, budget, uint64_t(frame));
        for (int r : map.last_gathered()) seen[size_t(r)] = 1;
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), texels)
        << "after " << frames << " frames of " << budget << " texels";
}

}  // namespace ag::cpu

namespace ag::cpu {

// With screen coverage known, the texels the camera sees are gathered before the others of their
// class: first when never gathered, then again when a new AIM makes every texel stale.
TEST(IimSchedule, TexelsTheCameraSeesGoFirst) {
    ScheduleCase c;
    Simulated& s = c.s;
    CpuGather& gather = c.gather;
    Iim& map = c.map;
    const int texels = int(s.scene.atlas.texels.size());
    std::vector<float> coverage(size_t(texels), 0.0f);
    int seen = 0;
    for (int r = 0; r < texels; r += 3, ++seen) coverage[size_t(r)] = 1e-3f;
    map.set_coverage(coverage);
    map.schedule(s.sim->maps());
    map.gather(gather, seen, 0);
    ASSERT_EQ(int(map.last_gathered().size()), seen);
    for (int r : map.last_gathered()) EXPECT_GT(coverage[size_t(r)], 0.0f) << "record " << r;
    map.gather(gather, texels, 1);  // the rest
    EXPECT_TRUE(map.complete());
    // A new AIM: the stale sweep refreshes the seen texels first.
    map.aim_changed();
    map.gather(gather, seen, 2);
    ASSERT_EQ(int(map.last_gathered().size()), seen);
    for (int r : map.last_gathered()) EXPECT_GT(coverage[size_t(r)], 0.0f) << "record " << r;
}

}  // namespace ag::cpu

namespace ag::cpu {

// Among the texels of surfaces whose indirect hits changed, those whose own indirect estimate
// moved most since they were last gathered go first; one whose estimate is not known keeps its
// surface's place (first). Staleness is measured from the last gather, so a texel that drifts a
// little every frame of a continuous move overtakes one that jumped once by less in all: ordering
// by each rebuild's own change (as before) put the one-time jump first.
TEST(IimSchedule, MostStaleTexelsFirst) {
    ScheduleCase c;
    Simulated& s = c.s;
    CpuGather& gather = c.gather;
    Iim& map = c.map;
    const int texels = int(s.scene.atlas.texels.size());
    ASSERT_GT(texels, 10);
    const std::vector<float> floors(size_t(texels), 0.0f);
    std::vector<float> estimate(size_t(texels), 1.0f);
    map.note_indirect_estimates(estimate, floors);
    map.gather(gather, texels, 0);  // everything gathered once, at estimate 1
    ASSERT_TRUE(map.complete());
    for (int r = 0; r < texels; ++r) EXPECT_EQ(map.staleness(r), 0.0f) << "record " << r;
    PhotonMaps& maps = s.sim->maps();

    // Ten frames of a move: every fifth record drifts by d/10 a frame to 1 + d (d distinct,
    // growing with the record); record 3 jumps once, in the last frame, to 1.3.
    std::vector<int> drifting;
    for (int r = 0; r < texels; r += 5) drifting.push_back(r);
    auto drift = [&](int r) { return 0.5f + float(r) / float(texels); };
    for (int frame = 1; frame <= 10; ++frame) {
        for (int r : drifting) estimate[size_t(r)] = 1.0f + drift(r) * float(frame) / 10.0f;
        if (frame == 10) {
            estimate[3] = 1.3f;
            estimate[1] = -1.0f;  // not known
        }
        map.note_indirect_estimates(estimate, floors);
        for (int surface = 0; surface < int(maps.surface_count()); ++surface)
            maps.surface(surface).delta_i = 1e9;
        map.schedule(maps);
    }
    EXPECT_NEAR(map.staleness(3), 0.3f / 2.3f, 1e-6f);
    EXPECT_NEAR(map.staleness(0), drift(0) / (2.0f + drift(0)), 1e-6f);
    EXPECT_EQ(map.staleness(1), std::numeric_limits<float>::infinity());
    EXPECT_EQ(map.staleness(2), 0.0f);

    map.gather(gather, int(drifting.size()) + 2, 11);
    const std::vector<int> got = map.last_gathered();
    ASSERT_EQ(got.size(), drifting.size() + 2);
    EXPECT_EQ(got.front(), 1);
    for (size_t k = 1; k < drifting.size(); ++k)  // the drifting ones, most stale first
        EXPECT_EQ(got[k], drifting[drifting.size() - k]) << "position " << k;
    EXPECT_EQ(got[drifting.size()], 0);
    EXPECT_EQ(got.back(), 3);  // the one-time jump: less stale than any drifting record
    // Gathering resets staleness.
    for (int r : got) {
        if (r == 1) continue;
        EXPECT_EQ(map.staleness(r), 0.0f) << "record " << r;
    }
}

}  // namespace ag::cpu

namespace ag::cpu {

// With screen coverage known, the changed texels the camera sees are ordered by staleness² ×
// pixels covered (their share of the image's relative squared error), not by staleness alone: a
// texel filling many pixels goes before a staler one seen in a single pixel, and one seen in no
// pixel at all goes after every seen one, however stale.
TEST(IimSchedule, ChangedTexelsByStalenessSquaredTimesPixels) {
    ScheduleCase c;
    Simulated& s = c.s;
    CpuGather& gather = c.gather;
    Iim& map = c.map;
    const int texels = int(s.scene.atlas.texels.size());
    ASSERT_GT(texels, 10);
    std::vector<float> coverage(size_t(texels), 1.0f);
    coverage[4] = 50.0f;  // large on screen, a little stale
    coverage[7] = 0.0f;   // not seen, the stalest
    map.set_coverage(coverage);
    const std::vector<float> floors(size_t(texels), 0.0f);
    std::vector<float> estimate(size_t(texels), 1.0f);
    map.note_indirect_estimates(estimate, floors);
    map.gather(gather, texels, 0);
    ASSERT_TRUE(map.complete());
    estimate[4] = 1.2f;  // staleness 0.2 / 2.2 = 0.091: 0.0083 x 50 pixels = 0.41
    estimate[5] = 1.6f;  // 0.6 / 2.6 = 0.23: 0.053 x 1 pixel
    estimate[6] = 1.1f;  // 0.1 / 2.1 = 0.048: 0.0023 x 1 pixel
    estimate[7] = 3.0f;  // 0.5, not seen
    map.note_indirect_estimates(estimate, floors);
    PhotonMaps& maps = s.sim->maps();
    for (int surface = 0; surface < int(maps.surface_count()); ++surface)
        maps.surface(surface).delta_i = 1e9;
    map.schedule(maps);
    map.gather(gather, 3, 1);
    const std::vector<int> got = map.last_gathered();
    ASSERT_EQ(got.size(), 3u);
    EXPECT_EQ(got[0], 4);  // by staleness alone it would come after 5
    EXPECT_EQ(got[1], 5);
    EXPECT_EQ(got[2], 6);
    map.gather(gather, texels, 2);
    // The unseen one was gathered last among the changed: after every seen texel of its class.
    const std::vector<int> rest = map.last_gathered();
    const auto at7 = std::find(rest.begin(), rest.end(), 7);
    ASSERT_NE(at7, rest.end());
    for (auto it = at7 + 1; it != rest.end(); ++it) EXPECT_EQ(coverage[size_t(*it)], 0.0f);
}

// The error a stale texel shows is relative to the value it will have: a texel whose light falls
// to a third (a lamp switched off) shows 200% too bright until it is gathered, one whose light
// rises by half 33% too dark. The falling one goes first though it covers a tenth of the pixels:
// by the symmetric staleness (0.5² × 0.2 = 0.05 against 0.2² × 2 = 0.08) it would go second, and
// the conference room's chairs beside the lamp stayed 3× too bright for four frames.
TEST(IimSchedule, ChangedTexelsByTheirErrorRelativeToTheNewValue) {
    ScheduleCase c;
    Simulated& s = c.s;
    Iim& map = c.map;
    const int texels = int(s.scene.atlas.texels.size());
    ASSERT_GT(texels, 10);
    std::vector<float> coverage(size_t(texels), 0.0f);
    coverage[3] = 2.0f;  // on a wall, its light up by half
    coverage[8] = 0.2f;  // on a chair, its light down to a third
    map.set_coverage(coverage);
    const std::vector<float> floors(size_t(texels), 0.0f);
    std::vector<float> estimate(size_t(texels), 1.0f);
    estimate[8] = 3.0f;
    map.note_indirect_estimates(estimate, floors);
    map.gather(c.gather, texels, 0);
    ASSERT_TRUE(map.complete());
    estimate[3] = 1.5f;
    estimate[8] = 1.0f;
    map.note_indirect_estimates(estimate, floors);
    PhotonMaps& maps = s.sim->maps();
    for (int surface = 0; surface < int(maps.surface_count()); ++surface)
        maps.surface(surface).delta_i = 1e9;
    map.schedule(maps);
    map.gather(c.gather, 2, 1);
    const std::vector<int> got = map.last_gathered();
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0], 8);
    EXPECT_EQ(got[1], 3);
}

}  // namespace ag::cpu

namespace ag::cpu {

// A moved object's texels were gathered from another place: the photons' estimates (here
// unchanged) cannot say how far off they are. queue_moved ranks them as wholly wrong (relative
// error 1 × pixels): the one covering most pixels goes first, ahead of the changed texels of
// smaller error × pixels and behind larger ones, and they keep that rank through schedule() until
// gathered; texels of objects that did not move are not queued.
TEST(IimSchedule, TexelsOfAMovedObjectRankAsWhollyWrongByThePixelsTheyCover) {
    ScheduleCase c;
    Simulated& s = c.s;
    Iim& map = c.map;
    const int texels = int(s.scene.atlas.texels.size());
    const int cube = s.scene.find_object("cube");
    ASSERT_GE(cube, 0);
    std::vector<int> on_cube, elsewhere;
    for (int t = 0; t < texels; ++t)
        (s.scene.atlas.texels[size_t(t)].object == cube ? on_cube : elsewhere).push_back(t);
    ASSERT_GT(on_cube.size(), 3u);
    ASSERT_GT(elsewhere.size(), 3u);
    std::vector<float> coverage(size_t(texels), 1.0f);
    coverage[size_t(on_cube[2])] = 30.0f;
    coverage[size_t(elsewhere[0])] = 50.0f;   // changed: (0.5 / 1)² × 50 = 12.5
    coverage[size_t(elsewhere[1])] = 200.0f;  // changed: (0.5 / 1)² × 200 = 50
    map.set_coverage(coverage);
    const std::vector<float> floors(size_t(texels), 0.0f);
    std::vector<float> estimate(size_t(texels), 1.0f);
    map.note_indirect_estimates(estimate, floors);
    map.gather(c.gather, texels, 0);
    ASSERT_TRUE(map.complete());
    map.queue_moved({cube});
    EXPECT_EQ(map.pending(), int(on_cube.size()));
    estimate[size_t(elsewhere[0])] = 2.0f;  // the light doubles: 50% too dark until gathered
    estimate[size_t(elsewhere[1])] = 2.0f;
    map.note_indirect_estimates(estimate, floors);
    PhotonMaps& maps = s.sim->maps();
    for (int surface = 0; surface < int(maps.surface_count()); ++surface)
        maps.surface(surface).delta_i = 1e9;
    map.schedule(maps);
    map.gather(c.gather, 3, 1);
    const std::vector<int> got = map.last_gathered();
    ASSERT_EQ(got.size(), 3u);
    EXPECT_EQ(got[0], elsewhere[1]);  // 50
    EXPECT_EQ(got[1], on_cube[2]);    // 30: by the photons' estimates (unchanged) it would be last
    EXPECT_EQ(got[2], elsewhere[0]);  // 12.5
    // The rest of the cube before the unchanged texels of the other surfaces.
    map.gather(c.gather, int(on_cube.size()) - 1, 2);
    for (int t : map.last_gathered())
        EXPECT_EQ(s.scene.atlas.texels[size_t(t)].object, cube) << "texel " << t;
}

}  // namespace ag::cpu
