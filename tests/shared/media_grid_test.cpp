// Media grids (shared/media_grid.h): the Gaussian smoothing, the photon plane's geometry.
#include "shared/media_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "shared/qmc.h"

namespace ag {
namespace {

TEST(MediaGrid, GaussianKeepsConstantsAndSums) {
    const glm::ivec3 size(12, 9, 7);
    std::vector<float> flat(size_t(size.x * size.y * size.z), 1.5f);
    gaussian_smooth(flat, size, 9, 1.5f);
    for (float v : flat) EXPECT_NEAR(v, 1.5f, 1e-5f);
    // A spike in the middle spreads but keeps its sum (far from the borders).
    std::vector<float> spike(flat.size(), 0.0f);
    Bounds b;
    b.min = glm::vec3(0.0f);
    b.max = glm::vec3(1.0f);
    MediaGrid g = make_media_grid(b, {21, 21, 21});
    g.n.assign(g.voxel_count(), 0.0f);
    g.n[g.index(10, 10, 10)] = 1.0f;
    gaussian_smooth(g.n, g.size, 9, 1.5f);
    double sum = 0.0;
    for (float v : g.n) sum += v;
    EXPECT_NEAR(sum, 1.0, 1e-5);
    EXPECT_NEAR(g.n[g.index(11, 10, 10)] / g.n[g.index(10, 10, 10)], std::exp(-0.5 / 2.25), 1e-4);
}

TEST(MediaGrid, BoxSolidAngle) {
    Bounds b;
    b.min = glm::vec3(0.0f);
    b.max = glm::vec3(1.0f);
    // One face from where the cube's centre would see it: a sixth of the sphere.
    EXPECT_NEAR(box_solid_angle(b, {0.5f, 0.5f, -0.5f}), 4.0 * std::numbers::pi / 6.0, 1e-6);
    // Far away: the projected area over d², one face (1 at 999.5) or three (√3 along the
    // diagonal, at distance √3 · 500).
    EXPECT_NEAR(box_solid_angle(b, {0.5f, 1000.5f, 0.5f}), 1.0 / (999.5 * 999.5), 1e-11);
    EXPECT_NEAR(box_solid_angle(b, glm::vec3(500.5f)), std::sqrt(3.0) / (3.0 * 500.0 * 500.0),
                1e-3 * std::sqrt(3.0) / (3.0 * 500.0 * 500.0));
}

// A point light on the grid's boundary (a face, an edge, a corner; found by the renderer
// robustness sweep, docs/robustness.md) gets the sphere source like one inside: strictly outside
// it has grid corners level with it, which no photon plane in front of it covers, and the media
// method threw ("the light must lie outside the grid") and the pipeline dropped the volume term.
// Its photons carry the light's whole flux 4πI.
TEST(MediaGrid, LightOnTheGridBoundaryGetsTheSphereSource) {
    Bounds b;
    b.min = glm::vec3(0.0f);
    b.max = glm::vec3(1.0f);
    for (const glm::vec3 light : {glm::vec3(0.0f, 0.5f, 0.5f), glm::vec3(1.0f, 0.5f, 0.5f),
                                  glm::vec3(0.5f, 1.0f, 0.0f), glm::vec3(1.0f, 0.0f, 1.0f)}) {
        EXPECT_TRUE(light_in_grid(light, b));
        PhotonSource source;
        ASSERT_NO_THROW(source = photon_source(light, 2.0f, b));
        EXPECT_EQ(source.kind, PhotonSource::Kind::sphere);
        double power = 0.0;
        for (const MediaPhoton& p : sphere_photons(light, 2.0f, 1000)) power += p.power;
        EXPECT_NEAR(power, 4.0 * std::numbers::pi * 2.0, 1e-3);
    }
    // Just outside a face the plane still covers every corner.
    EXPECT_FALSE(light_in_grid(glm::vec3(-1e-3f, 0.5f, 0.5f), b));
    EXPECT_EQ(photon_source(glm::vec3(-1e-3f, 0.5f, 0.5f), 2.0f, b).kind,
              PhotonSource::Kind::plane);
}

// His importance-distributed photons (ch. 3.2.3): Hammersley points through the two-stage
// inversion land in each cell in proportion to its density, and the weights 1/(N p) sum to the
// area where p > 0 (what keeps the importance-sampled photons' power unbiased; 63/64 here, one
// cell being empty, which is why the pipeline adds a background density everywhere). A sampler that
// ignored the rows' conditionals or a pdf off by a cell would fail both.
TEST(MediaGrid, PhotonDensitySamplesItsCells) {
    const int side = 8;
    std::vector<float> cells(size_t(side * side), 0.2f);
    cells[size_t(3 * side + 5)] = 6.0f;  // a hot cell
    cells[size_t(6 * side + 1)] = 2.0f;
    cells[size_t(0)] = 0.0f;  // an empty one: never sampled
    const PhotonDensity density(side, cells);
    double mean = 0.0;
    for (double p : density.cells()) mean += p;
    EXPECT_NEAR(mean / (side * side), 1.0, 1e-12);
    const int count = 1 << 16;
    std::vector<int> hits(cells.size(), 0);
    double weight = 0.0;
    for (int i = 0; i < count; ++i) {
        const glm::vec2 uv = density.sample(hammersley(i, count, glm::vec2(0.0f)));
        ASSERT_TRUE(uv.x >= 0.0f && uv.x < 1.0f && uv.y >= 0.0f && uv.y < 1.0f);
        const int x = int(uv.x * side), y = int(uv.y * side);
        ++hits[size_t(y * side + x)];
        weight += 1.0 / (double(count) * density.pdf(uv));
    }
    EXPECT_NEAR(weight, 63.0 / 64.0, 1e-3);
    EXPECT_EQ(hits[0], 0);
    for (size_t c = 0; c < cells.size(); ++c) {
        const double expected = density.cells()[c] * count / double(side * side);
        EXPECT_NEAR(hits[c], expected, 0.02 * expected + 2.0) << "cell " << c;
    }
    // A Cranley–Patterson rotation keeps the points uniform: the weights still sum to 1.
    weight = 0.0;
    for (int i = 0; i < count; ++i) {
        const glm::vec2 uv = density.sample(hammersley(i, count, glm::vec2(0.37f, 0.81f)));
        weight += 1.0 / (double(count) * density.pdf(uv));
    }
    EXPECT_NEAR(weight, 63.0 / 64.0, 1e-3);
    EXPECT_THROW(PhotonDensity(2, {0.0f, 0.0f, 0.0f, 0.0f}), std::invalid_argument);
    EXPECT_THROW(PhotonDensity(2, {1.0f}), std::invalid_argument);
}

// The bilinear density (docs/media.md "Session 15"): the same integral as its cells, sampled in
// proportion to itself — Hammersley points through it land in each quarter cell in proportion to
// the density's integral there (by a fine midpoint sum), the weights 1/(N p) sum to 1 — and
// continuous across the cell edges, where the piecewise-constant density jumps. A sampler that
// inverted the cells (not the interpolant), or a pdf that did not match what it samples, fails.
TEST(MediaGrid, BilinearPhotonDensitySamplesItself) {
    const int side = 8;
    std::vector<float> cells(size_t(side * side), 0.2f);
    cells[size_t(3 * side + 5)] = 6.0f;
    cells[size_t(6 * side + 1)] = 2.0f;
    cells[size_t(7 * side + 7)] = 3.0f;  // a corner: the outer half cells hold it constant
    const PhotonDensity density(side, cells, true);
    const PhotonDensity constant(side, cells);
    ASSERT_TRUE(density.bilinear());
    // Continuous at a cell edge beside the hot cell; the cells' density jumps 30× there.
    const glm::vec2 left(5.0f / side - 1e-4f, 3.5f / side), right(5.0f / side + 1e-4f, 3.5f / side);
    EXPECT_NEAR(density.pdf(left), density.pdf(right), 1e-2 * density.pdf(right));
    EXPECT_GT(constant.pdf(right) / constant.pdf(left), 20.0);
    // At a centre it is the cell's value; its integral is 1.
    EXPECT_NEAR(density.pdf({5.5f / side, 3.5f / side}), density.cells()[3 * side + 5], 1e-5);
    const int fine = 8 * side;
    std::vector<double> expected(size_t(4 * side * side), 0.0);
    double integral = 0.0;
    for (int y = 0; y < fine; ++y)
        for (int x = 0; x < fine; ++x) {
            const double p = density.pdf({(x + 0.5f) / fine, (y + 0.5f) / fine}) / (fine * fine);
            expected[size_t((y / 4) * 2 * side + x / 4)] += p;
            integral += p;
        }
    EXPECT_NEAR(integral, 1.0, 1e-3);
    const int count = 1 << 17;
    std::vector<int> hits(expected.size(), 0);
    double weight = 0.0;
    for (int i = 0; i < count; ++i) {
        const glm::vec2 uv = density.sample(hammersley(i, count, glm::vec2(0.37f, 0.81f)));
        ASSERT_TRUE(uv.x >= 0.0f && uv.x < 1.0f && uv.y >= 0.0f && uv.y < 1.0f);
        ++hits[size_t(int(uv.y * 2 * side) * 2 * side + int(uv.x * 2 * side))];
        weight += 1.0 / (double(count) * density.pdf(uv));
    }
    EXPECT_NEAR(weight, 1.0, 1e-3);
    for (size_t c = 0; c < hits.size(); ++c)
        EXPECT_NEAR(hits[c], expected[c] * count, 0.02 * expected[c] * count + 3.0)
            << "quarter cell " << c;
}

// Why the pipeline reads its density bilinearly (docs/media.md "Session 15"): Hammersley points
// drawn through a density and weighted by 1/(N p) integrate a smooth field (a lit blob, as a
// photon plane's flux towards a dense medium) whose smooth density they follow. Through the
// cells, every weight jumps at every cell edge and the points lose the low discrepancy they had
// over the smooth field; through the bilinear density the weights change continuously. Both are
// unbiased (the mean over rotations is the integral); the error over 16 rotations falls by a
// factor of several. A bilinear pdf that disagreed with its sampler would be biased and fail.
TEST(MediaGrid, BilinearDensityKeepsTheQuasiMonteCarloAdvantage) {
    const int side = 16;
    const auto blob = [](glm::vec2 p, glm::vec2 centre, float width) {
        const glm::vec2 d = p - centre;
        return std::exp(-glm::dot(d, d) / width);
    };
    std::vector<float> cells(size_t(side * side));
    for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x)
            cells[size_t(y * side + x)] =
                0.1f + blob({(x + 0.5f) / side, (y + 0.5f) / side}, {0.5f, 0.45f}, 0.02f);
    const auto field = [&](glm::vec2 p) { return 0.2 + 3.0 * blob(p, {0.52f, 0.47f}, 0.03f); };
    const int fine = 1024;
    double integral = 0.0;
    for (int y = 0; y < fine; ++y)
        for (int x = 0; x < fine; ++x)
            integral += field({(x + 0.5f) / fine, (y + 0.5f) / fine}) / (double(fine) * fine);
    const int count = 4096, rotations = 16;
    double error[2] = {0.0, 0.0}, mean[2] = {0.0, 0.0};
    for (int k = 0; k < 2; ++k) {
        const PhotonDensity density(side, cells, k == 1);
        for (int r = 0; r < rotations; ++r) {
            const glm::vec2 shift(std::fmod(0.6180339f * (r + 1), 1.0f),
                                  std::fmod(0.7548777f * (r + 1), 1.0f));
            double sum = 0.0;
            for (int i = 0; i < count; ++i) {
                const glm::vec2 uv = density.sample(hammersley(i, count, shift));
                sum += field(uv) / (double(count) * density.pdf(uv));
            }
            error[k] += (sum - integral) * (sum - integral) / rotations;
            mean[k] += sum / rotations;
        }
        error[k] = std::sqrt(error[k]) / integral;
    }
    std::printf(
        "relative RMS error over %d rotations: cells %.2e, bilinear %.2e (means %+.1e, %+.1e)\n",
        rotations, error[0], error[1], mean[0] / integral - 1.0, mean[1] / integral - 1.0);
    EXPECT_LT(error[1], 0.3 * error[0]);
    EXPECT_NEAR(mean[1] / integral, 1.0, 3.0 * error[1] / std::sqrt(double(rotations)) + 1e-5);
}

// The significance stop (docs/media.md, "The filter beside a caustic's focus"): a bright line
// (a caustic's focus, 10 over a field of 1) with many photons a voxel. His filter alone lets the
// voxels beside the line climb (their differences shrink after the first level) and read the
// blurred line; with the stop, the step from 1 to that blur is many standard errors at 1,000
// crossings, so they keep level 0 and the field exactly. Noise with one crossing a voxel is still
// filtered (its steps are within its errors). A stop that never fired, or fired on noise, fails.
TEST(MediaGrid, SignificanceStopKeepsAFocusSharpAndFiltersNoise) {
    const glm::ivec3 size(32, 32, 32);
    const size_t voxels = size_t(size.x) * size.y * size.z;
    const auto index = [&](int x, int y, int z) { return (size_t(z) * size.y + y) * size.x + x; };
    std::vector<float> line(voxels, 1.0f), many(voxels, 1000.0f), ones(voxels, 1.0f);
    for (int z = 0; z < size.z; ++z) line[index(16, 16, z)] = 10.0f;
    std::vector<glm::vec3> flow(voxels, glm::vec3(0.0f));
    const std::vector<float> heavy(voxels, 1.0f);
    const MediaReconstruction his = reconstruct_adaptive(size, line, flow, many, heavy, 0.1f, 4);
    const MediaReconstruction stopped =
        reconstruct_adaptive(size, line, flow, many, heavy, 0.1f, 4, 3.0f);
    // The stop accepts a step within 3 standard errors (1/√1000 ≈ 3.2% each level): no voxel
    // off by more than 10%, the line and the voxels beside it exact.
    int his_blurred = 0;
    float worst = 0.0f;
    for (int y = 8; y <= 24; ++y)
        for (int x = 8; x <= 24; ++x) {
            const size_t i = index(x, y, 16);
            if (std::abs(his.fluence[i] - line[i]) > 0.1f * line[i]) ++his_blurred;
            worst = std::max(worst, std::abs(stopped.fluence[i] - line[i]) / line[i]);
            if (std::abs(x - 16) <= 1 && std::abs(y - 16) <= 1) {
                EXPECT_EQ(stopped.level[i], 0) << x << " " << y;
                EXPECT_EQ(stopped.fluence[i], line[i]) << x << " " << y;
            }
        }
    std::printf(
        "significance stop: his filter reads %d of 289 voxels around the line more than "
        "10%% off, ours at most %.1f%%\n",
        his_blurred, 100.0f * worst);
    EXPECT_LT(worst, 0.1f);
    EXPECT_GT(his_blurred, 4);  // the test's premise: his filter alone blurs the focus
    // Noise (±50%, one crossing a voxel): filtered as by his filter alone.
    std::vector<float> noisy(voxels);
    double error_in = 0.0, error_out = 0.0;
    for (size_t i = 0; i < voxels; ++i) {
        const float u = float(hash_u32(uint32_t(i)) >> 8) / float(1 << 24);
        noisy[i] = 2.0f * (0.5f + u);
    }
    const MediaReconstruction r =
        reconstruct_adaptive(size, noisy, flow, ones, heavy, 0.1f, 4, 3.0f);
    for (size_t i = 0; i < voxels; ++i) {
        error_in += (noisy[i] - 2.0) * (noisy[i] - 2.0);
        error_out += (r.fluence[i] - 2.0) * (r.fluence[i] - 2.0);
    }
    std::printf("significance stop on noise: squared error %.1f -> %.1f\n", error_in, error_out);
    EXPECT_LT(error_out, 0.05 * error_in);
}

// The fractional weight level (session 14, docs/media.md): noise (±50%, one crossing a voxel,
// the stop on) under a uniform photon weight w from 0.2 to 2 Δweight. His ⌊w / Δweight⌋ reads
// the same level 1 everywhere from Δweight to just below 2 Δweight (the error flat, then a
// cliff at 2 Δweight: where fog_sphere_point's uniform set sat at 50,000 photons, 0.62 of
// uniform's photons); w / Δweight read continuously filters more at every step of w, with no
// jump. A rule that truncated the level, or ignored w, fails.
TEST(MediaGrid, FractionalWeightLevelHasNoCliff) {
    const glm::ivec3 size(32, 32, 32);
    const size_t voxels = size_t(size.x) * size.y * size.z;
    std::vector<float> noisy(voxels), ones(voxels, 1.0f);
    const std::vector<glm::vec3> flow(voxels, glm::vec3(0.0f));
    for (size_t i = 0; i < voxels; ++i) {
        const float u = float(hash_u32(uint32_t(i) + 7u) >> 8) / float(1 << 24);
        noisy[i] = 2.0f * (0.5f + u);
    }
    const float delta = 0.1f;
    const auto error = [&](float w, bool fractional) {
        const std::vector<float> weight(voxels, w * delta);
        const MediaReconstruction r =
            reconstruct_adaptive(size, noisy, flow, ones, weight, delta, 4, 3.0f, fractional);
        double e = 0.0;
        for (float f : r.fluence) e += (f - 2.0) * (f - 2.0);
        return e;
    };
    std::printf("fractional weight level, squared error at w / dweight:");
    double last_fractional = 1e30;
    for (int k = 2; k <= 20; ++k) {
        const float w = 0.1f * float(k);
        const double his = error(w, false), ours = error(w, true);
        std::printf(" %.1f: %.0f/%.0f", double(w), his, ours);
        EXPECT_LT(ours, 0.97 * last_fractional) << "w " << w;  // more filtering at every step
        if (k % 10 != 0) {
            EXPECT_LT(ours, 0.97 * his) << "w " << w;
        }
        last_fractional = ours;
    }
    std::printf("\n");
    // His rule: flat from Δweight to just below 2 Δweight, then a cliff; ours continuous there.
    EXPECT_EQ(error(1.1f, false), error(1.9f, false));
    EXPECT_GT(error(1.99f, false), 1.5 * error(2.01f, false));
    EXPECT_LT(error(1.99f, true), 1.05 * error(2.01f, true));
    // At whole multiples of Δweight both rules read the same level.
    EXPECT_EQ(error(1.0f, true), error(1.0f, false));
}

// Pfeuti's reconstruction (ch. 3.2.4): a constant field comes back unchanged at any level; light
// weights (dense photons) keep level 0 and the field exactly; heavy weights over noise pick higher
// levels and cut the noise, but the centre-surround filter picks lower levels beside an edge than
// away from it (a weight-only filter would read the top level everywhere).
TEST(MediaGrid, ReconstructionFiltersNoiseNotEdges) {
    const glm::ivec3 size(32, 32, 32);
    const size_t voxels = size_t(size.x) * size.y * size.z;
    std::vector<float> constant(voxels, 2.5f), ones(voxels, 1.0f);
    std::vector<glm::vec3> flow(voxels, glm::vec3(0.0f, -2.5f, 0.0f));
    const std::vector<float> heavy(voxels, 1.0f), light(voxels, 1e-6f);
    MediaReconstruction r = reconstruct_adaptive(size, constant, flow, ones, heavy, 0.1f, 4);
    EXPECT_EQ(r.max_level, 4);
    for (size_t i = 0; i < voxels; ++i) ASSERT_NEAR(r.fluence[i], 2.5f, 1e-4f);
    // Noise: a step along x (1 | 3) with ±50% hashed noise on every voxel.
    std::vector<float> noisy(voxels);
    for (int z = 0; z < size.z; ++z)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x) {
                const size_t i = (size_t(z) * size.y + y) * size.x + x;
                const float u = float(hash_u32(uint32_t(i)) >> 8) / float(1 << 24);
                noisy[i] = (x < 16 ? 1.0f : 3.0f) * (0.5f + u);
            }
    r = reconstruct_adaptive(size, noisy, flow, ones, light, 0.1f, 4);
    for (size_t i = 0; i < voxels; ++i) {
        ASSERT_EQ(r.level[i], 0);
        ASSERT_EQ(r.fluence[i], noisy[i]);
    }
    r = reconstruct_adaptive(size, noisy, flow, ones, heavy, 0.1f, 4);
    double error_in = 0.0, error_out = 0.0;
    for (int z = 0; z < size.z; ++z)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x) {
                const size_t i = (size_t(z) * size.y + y) * size.x + x;
                const float truth = x < 16 ? 1.0f : 3.0f;
                error_in += (noisy[i] - truth) * (noisy[i] - truth);
                error_out += (r.fluence[i] - truth) * (r.fluence[i] - truth);
            }
    std::printf("reconstruction: squared error %.1f -> %.1f\n", error_in, error_out);
    EXPECT_LT(error_out, 0.25 * error_in);
    // The step without noise: the centre-surround filter climbs while the levels agree and stops
    // before the filter reaches the edge, so levels rise with the distance from it and nothing
    // beside it blurs. The two voxels at the edge itself climb (their first difference is the
    // largest, Listing B.3): there the weight filter has to hold the level down.
    std::vector<float> step(voxels);
    for (size_t i = 0; i < voxels; ++i) step[i] = i % size_t(size.x) < 16 ? 1.0f : 3.0f;
    r = reconstruct_adaptive(size, step, flow, ones, heavy, 0.1f, 4);
    for (int x = 0; x < size.x; ++x) {
        const size_t i = (size_t(16) * size.y + 16) * size.x + size_t(x);
        const int distance = x < 16 ? 15 - x : x - 16;  // voxels between x and the edge
        if (distance >= 1 && distance <= 5) {
            EXPECT_EQ(r.level[i], 0) << x;
            EXPECT_EQ(r.fluence[i], step[i]) << x;
        }
        if (distance >= 12) {
            EXPECT_EQ(r.level[i], 2) << x;
        }
        if (distance >= 1) {
            EXPECT_NEAR(r.fluence[i], step[i], 1e-5f) << x;
        }
    }
}

}  // namespace
}  // namespace ag
