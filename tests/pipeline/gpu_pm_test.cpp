// GPU photon mapping (Jimenez Kwast 2016) as an indirect method: photon energy against Embree for
// every light type, tile lists against the thesis's brute-force binning, no CPU rays and no
// read-back per frame, restart after an edit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "../cpu/test_scenes.h"
#include "../gpu/gl_fixture.h"
#include "cpu/ray_tracer.h"
#include "cpu/sampling.h"
#include "gpu/g_buffer.h"
#include "gpu/gpu_photon_mapper.h"
#include "shared/photon_sampling.h"
#include "shared/pipeline/gpu_pm_method.h"
#include "shared/pipeline/pipeline.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/texture.h"

namespace ag {

namespace {

Scene cornell() { return load_scene(AG_SOURCE_DIR "/scenes/cornell.json"); }

// The cornell scene with its light replaced by one of another type near the ceiling.
Scene cornell_with(LightType type) {
    Scene s = cornell();
    Light& l = s.lights.at(0);
    const glm::vec3 c = l.position;
    l.type = type;
    if (type == LightType::quad) {
        l.corners = {c + glm::vec3(-60, -1, -60), c + glm::vec3(60, -1, -60),
                     c + glm::vec3(60, -1, 60), c + glm::vec3(-60, -1, 60)};
        if (glm::dot(l.quad_normal(), glm::vec3(0, 1, 0)) > 0.0f)
            std::swap(l.corners[1], l.corners[3]);
        l.radiance = glm::vec3(20.0f);
    } else if (type == LightType::spot) {
        l.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
        l.cone_inner = 25.0f;
        l.cone_outer = 50.0f;
    } else if (type == LightType::sun) {
        l.direction = glm::normalize(glm::vec3(0.2f, -1.0f, 0.9f));  // through the open front
        l.irradiance = glm::vec3(5.0f);
        update_sun_discs(s);
    }
    init_versions(s);
    return s;
}

// Paths out of `n` that reach a second diffuse vertex (its front, every diffuse vertex's: a back
// face absorbs, as in the CPU tracers), with Embree and the CPU's own emission
// (cpu::emission_ray), cosine bounce and mirror/glass bounce (cpu::specular_bounce, Fresnel), and
// independent random numbers. Mirrors and glass carry a path on (at most 8 of them in a row, as
// the trace); with `end_at_specular` they end it instead (gpu_pm before specular bounces).
double embree_second_hit_fraction(const Scene& scene, int n, bool end_at_specular = false) {
    cpu::RayTracer rays(scene);
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int second = 0;
    double weight_sum = 0.0;
    for (int i = 0; i < n; ++i) {
        const cpu::EmissionRay e = cpu::emission_ray(scene, scene.lights[0], {u(rng), u(rng)},
                                                     {u(rng), u(rng)}, rays.epsilon());
        weight_sum += e.weight;
        cpu::Ray ray = e.ray;
        int diffuse = 0, specular = 0;
        while (true) {
            const cpu::RayHit h = rays.intersect(ray);
            if (!h.hit) break;
            const Material& m = scene.objects[size_t(h.object)].material;
            if (m.type != MaterialType::diffuse) {
                if (end_at_specular || ++specular > 8) break;
                ray = cpu::specular_bounce(m, h, ray.direction, u(rng), rays.epsilon());
                continue;
            }
            if (glm::dot(ray.direction, h.normal) >= 0.0f) break;  // a back face absorbs
            if (++diffuse == 2) {
                second += 1;
                break;
            }
            glm::vec3 nrm = h.normal;
            if (glm::dot(nrm, ray.direction) > 0.0f) nrm = -nrm;
            ray = {h.position + rays.epsilon() * nrm,
                   photon::cosine_direction({u(rng), u(rng)}, nrm)};
        }
    }
    EXPECT_NEAR(weight_sum / n, 1.0, 0.05);  // emission weights average 1 (spot)
    return double(second) / n;
}

}  // namespace

class GpuPmTest : public test::GlTest {};

TEST_F(GpuPmTest, StoredOverEmittedMatchesEmbreesHitFractionForEveryLightType) {
    for (const LightType type :
         {LightType::point, LightType::quad, LightType::spot, LightType::sun}) {
        Scene scene = cornell_with(type);
        scene.settings.gpu_pm.paths = 200000;
        scene.settings.gpu_pm.frames = 1;
        gpu::SceneMeshes meshes(scene);
        gpu::GBuffer g(scene, meshes, 16, 16);
        gpu::GpuPhotonMapper m(scene, g);
        m.trace();
        const double gpu = double(m.stored_photons()) / double(m.paths_traced());
        const double embree = embree_second_hit_fraction(scene, 200000);
        EXPECT_NEAR(gpu / embree, 1.0, 0.02)
            << "light type " << int(type) << ": gpu " << gpu << " embree " << embree;
        EXPECT_GT(gpu, 0.05);
        std::printf("light type %d: stored/emitted %.4f, Embree %.4f\n", int(type), gpu, embree);
    }
}

// Mirrors and glass carry photons on (pt's single-bounce indirect term counts L S* D S* D
// paths): in cornell with its back and left walls turned into mirrors (and its glass sphere), the
// stored fraction matches Embree's paths through the same specular bounces within 2%, and is far
// above what ending paths at the first mirror or glass stores (which fails it).
TEST_F(GpuPmTest, PhotonsContinueThroughMirrorsAndGlass) {
    Scene scene = cornell();
    for (const char* wall : {"back_wall", "left_wall"})
        scene.objects[size_t(scene.find_object(wall))].material.type = MaterialType::mirror;
    init_versions(scene);
    scene.settings.gpu_pm.paths = 200000;
    scene.settings.gpu_pm.frames = 1;
    gpu::SceneMeshes meshes(scene);
    gpu::GBuffer g(scene, meshes, 16, 16);
    gpu::GpuPhotonMapper m(scene, g);
    m.trace();
    const double gpu = double(m.stored_photons()) / double(m.paths_traced());
    const double through = embree_second_hit_fraction(scene, 200000);
    const double ending = embree_second_hit_fraction(scene, 200000, true);
    std::printf("stored/emitted %.4f, Embree through specular %.4f, ending at it %.4f\n", gpu,
                through, ending);
    EXPECT_NEAR(gpu / through, 1.0, 0.02);
    EXPECT_GT(through, 1.2 * ending);
}

TEST_F(GpuPmTest, StoredPowerIsEmittedPowerTimesTheBounce) {
    // Single bounce: every stored photon carries Φ_light/N × albedo of the surface it left, so
    // Σ power ≤ Φ · max albedo and ≥ 0; with a grey box the ratio is stored fraction × albedo.
    Scene scene = cornell();
    for (Object& o : scene.objects) o.material.albedo = glm::vec3(0.5f);
    scene.settings.gpu_pm.paths = 20000;
    scene.settings.gpu_pm.frames = 1;
    gpu::SceneMeshes meshes(scene);
    gpu::GBuffer g(scene, meshes, 16, 16);
    gpu::GpuPhotonMapper m(scene, g);
    m.trace();
    glm::dvec3 sum(0.0);
    const auto photons = m.read_photons();
    for (const auto& p : photons) sum += glm::dvec3(p.power);
    const glm::dvec3 expected = glm::dvec3(scene.lights[0].power()) * 0.5 *
                                (double(photons.size()) / double(m.paths_traced()));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c] / expected[c], 1.0, 1e-4);
    // estimator: kwast carries his code's ×100 at emission and 1/π at the bounce (same paths).
    scene.settings.gpu_pm.estimator = GpuPmEstimator::kwast;
    gpu::GpuPhotonMapper kwast(scene, g);
    kwast.trace();
    glm::dvec3 kwast_sum(0.0);
    for (const auto& p : kwast.read_photons()) kwast_sum += glm::dvec3(p.power);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(kwast_sum[c] / sum[c], 100.0 / M_PI, 1e-3);
}

// A photon leaving a textured surface carries the texel's albedo where it landed: a floor whose two
// triangles read a red and a green texel sends on purely red or purely green photons (its mean,
// or the white base albedo, would send yellow or white ones); grey walls send the light's colour.
TEST_F(GpuPmTest, PhotonsBounceWithTheTexelAlbedo) {
    Scene scene = cornell();
    for (Object& o : scene.objects) o.material.albedo = glm::vec3(0.5f);
    Object& floor = scene.objects[size_t(scene.find_object("floor"))];
    auto texture = std::make_shared<Texture>();
    texture->width = 2;
    texture->height = 1;
    texture->texels = {glm::vec3(0.8f, 0.0f, 0.0f), glm::vec3(0.0f, 0.8f, 0.0f)};
    texture->mean = glm::vec3(0.4f, 0.4f, 0.0f);
    floor.material.albedo = glm::vec3(1.0f);
    floor.material.albedo_map = texture;
    floor.mesh.texcoords.clear();
    for (size_t t = 0; t < floor.mesh.triangles.size(); ++t)  // a texel centre: no blending
        floor.mesh.texcoords.insert(floor.mesh.texcoords.end(), 3,
                                    glm::vec2(t % 2 == 0 ? 0.25f : 0.75f, 0.5f));
    scene.settings.gpu_pm.paths = 20000;
    scene.settings.gpu_pm.frames = 1;
    gpu::SceneMeshes meshes(scene);
    gpu::GBuffer g(scene, meshes, 16, 16);
    gpu::GpuPhotonMapper m(scene, g);
    m.trace();
    size_t red = 0, green = 0, grey = 0, other = 0;
    for (const auto& p : m.read_photons()) {
        const glm::vec3 c =
            glm::vec3(p.power) / scene.lights[0].power();  // the light's colour taken out
        const float most = std::max({c.r, c.g, c.b});
        if (std::abs(c.r - c.g) <= 1e-4f * most && std::abs(c.g - c.b) <= 1e-4f * most)
            ++grey;
        else if (c.g <= 1e-3f * c.r && c.b == 0.0f)
            ++red;
        else if (c.r <= 1e-3f * c.g && c.b == 0.0f)
            ++green;
        else
            ++other;
    }
    EXPECT_EQ(other, 0u);
    EXPECT_GT(red, 200u);
    EXPECT_GT(green, 200u);
    EXPECT_GT(grey, red);
}

TEST_F(GpuPmTest, TileListsEqualTheBruteForceBinning) {
    Scene scene = cornell();
    scene.settings.gpu_pm.paths = 3000;
    scene.settings.gpu_pm.frames = 1;
    gpu::SceneMeshes meshes(scene);
    gpu::GBuffer g(scene, meshes, 100, 76);  // partial tiles on both edges
    gpu::GpuPhotonMapper m(scene, g);
    m.trace();
    g.render();
    scene.settings.gpu_pm.binning = GpuPmBinning::scatter;
    m.render();
    const auto scatter = m.read_tile_lists();
    EXPECT_FALSE(m.index_overflow());
    scene.settings.gpu_pm.binning = GpuPmBinning::brute;
    m.render();
    const auto brute = m.read_tile_lists();
    ASSERT_EQ(scatter.size(), size_t(m.tiles_x() * m.tiles_y()));
    size_t entries = 0, empty = 0;
    for (size_t t = 0; t < brute.size(); ++t) {
        EXPECT_EQ(scatter[t], brute[t]) << "tile " << t;
        entries += brute[t].size();
        empty += brute[t].empty() ? 1 : 0;
    }
    EXPECT_GT(entries, 3000u);           // photons reach several tiles each
    EXPECT_LT(empty, brute.size() / 2);  // and most tiles hold some
}

static std::vector<float> read_texture(GLuint texture, int width, int height) {
    std::vector<float> rgba(size_t(width) * size_t(height) * 4);
    gpu::gl::BindTexture(GL_TEXTURE_2D, texture);
    gpu::gl::GetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, rgba.data());
    gpu::gl::BindTexture(GL_TEXTURE_2D, 0);
    return rgba;
}

// The estimate sums in fixed point, so the order of a tile's list (chosen by GPU atomics: scatter
// and brute-force binning fill the lists in different orders, and runs differ) does not change a
// bit. A float sum differs in the last bits between the two binnings; so would two runs.
TEST_F(GpuPmTest, TheEstimateHasTheSameBitsWhateverTheOrderOfTheTileLists) {
    Scene scene = cornell();
    scene.settings.gpu_pm.paths = 3000;
    scene.settings.gpu_pm.frames = 2;
    gpu::SceneMeshes meshes(scene);
    gpu::GBuffer g(scene, meshes, 48, 40);
    auto render = [&](GpuPmBinning binning) {
        gpu::GpuPhotonMapper m(scene, g);
        m.trace();
        m.trace();
        g.render();
        scene.settings.gpu_pm.binning = binning;
        m.render();
        EXPECT_FALSE(m.index_overflow());
        return read_texture(m.texture(), 48, 40);
    };
    const std::vector<float> scatter = render(GpuPmBinning::scatter);
    const std::vector<float> brute = render(GpuPmBinning::brute);
    const std::vector<float> again = render(GpuPmBinning::scatter);
    size_t lit = 0;
    for (size_t i = 0; i < scatter.size(); ++i) {
        ASSERT_EQ(std::memcmp(&scatter[i], &brute[i], sizeof(float)), 0)
            << "value " << i << ": " << scatter[i] << " vs " << brute[i];
        ASSERT_EQ(std::memcmp(&scatter[i], &again[i], sizeof(float)), 0) << "value " << i;
        lit += (i % 4 != 3 && scatter[i] > 0.0f) ? 1 : 0;
    }
    EXPECT_GT(lit, scatter.size() / 2);  // most of the picture has indirect light
}

// The viewer's tile view: every pixel carries its tile's list length (a) and a colour that is
// black only for tiles without photons.
TEST_F(GpuPmTest, TheTileViewShowsEachTilesPhotonCount) {
    Scene scene = cornell();
    scene.settings.gpu_pm.paths = 2000;
    scene.settings.gpu_pm.frames = 1;
    gpu::SceneMeshes meshes(scene);
    gpu::GBuffer g(scene, meshes, 44, 36);  // partial tiles
    gpu::GpuPhotonMapper m(scene, g);
    m.trace();
    g.render();
    m.render();
    const auto lists = m.read_tile_lists();
    const std::vector<float> view = read_texture(m.render_tile_view(), 44, 36);
    size_t distinct_counts = 0;
    float last = -1.0f;
    for (int y = 0; y < 36; ++y)
        for (int x = 0; x < 44; ++x) {
            const float* p = &view[(size_t(y) * 44 + size_t(x)) * 4];
            const size_t n = lists[size_t((y / 8) * m.tiles_x() + x / 8)].size();
            ASSERT_EQ(p[3], float(n)) << x << "," << y;
            if (n > 0) {
                EXPECT_GT(p[0] + p[1] + p[2], 0.0f) << x << "," << y;
            }
            if (n > 0 && p[3] != last) ++distinct_counts;
            last = p[3];
        }
    EXPECT_GT(distinct_counts, 5u);
    // Tile edges are drawn darker than the tile's inside.
    const float* edge = &view[(size_t(8) * 44 + 12) * 4];
    const float* inside = &view[(size_t(11) * 44 + 12) * 4];
    if (edge[3] > 0.0f) {
        EXPECT_LT(edge[0] + edge[1] + edge[2], inside[0] + inside[1] + inside[2]);
    }
}

TEST_F(GpuPmTest, NoCpuRaysAndNoReadBackPerFrame) {
    Scene scene = cornell();
    scene.settings.indirect.method = IndirectMethodKind::gpu_pm;
    scene.settings.gpu_pm.paths = 500;
    scene.settings.gpu_pm.frames = 4;
    Pipeline pipeline(scene, PipelineOptions{32, 32});
    const uint64_t rays = pipeline.photons().rays().rays_cast();
    const uint64_t readbacks = gpu::readback_count();
    for (int f = 0; f < 6; ++f) pipeline.frame();
    EXPECT_EQ(pipeline.photons().rays().rays_cast(), rays);  // no CPU photon ray for the term
    EXPECT_EQ(gpu::readback_count(), readbacks);
    const auto* method = dynamic_cast<const GpuPmMethod*>(&pipeline.indirect());
    ASSERT_NE(method, nullptr);
    EXPECT_EQ(method->mapper().frames_accumulated(), 4);  // accumulated, then settled
    EXPECT_TRUE(method->settled());
    EXPECT_GT(method->mapper().stored_photons(), 1000u);
}

TEST_F(GpuPmTest, AnEditRestartsTheAccumulationACameraMoveDoesNot) {
    Scene scene = cornell();
    scene.settings.indirect.method = IndirectMethodKind::gpu_pm;
    scene.settings.gpu_pm.paths = 200;
    scene.settings.gpu_pm.frames = 3;
    Pipeline pipeline(scene, PipelineOptions{32, 32});
    for (int f = 0; f < 3; ++f) pipeline.frame();
    const auto* method = dynamic_cast<const GpuPmMethod*>(&pipeline.indirect());
    ASSERT_NE(method, nullptr);
    EXPECT_TRUE(method->settled());
    pipeline.sync();
    Camera camera = scene.camera;
    camera.eye.x += 10.0f;
    set_camera(scene, camera);
    pipeline.frame();
    EXPECT_TRUE(method->settled());
    EXPECT_EQ(method->restarts(), 0);
    pipeline.sync();
    set_albedo(scene, 1, glm::vec3(0.2f));
    pipeline.frame();
    EXPECT_EQ(method->restarts(), 1);
    EXPECT_EQ(method->mapper().frames_accumulated(), 1);
}

// A lamp inside a closed box (the sweep's light_in_box_coplanar, and the box 5 cm lower, nothing
// coplanar): every photon meets the box's inside, a back face, and is absorbed, as in the CPU
// tracers, so nothing is stored and the term is black exactly, as pt's. gpu_pm stored photons on
// the back faces and lit the room along the box's edges (mean 0.047 at 128² after 30 frames): the
// cone filter's sphere reaches through the zero-thickness walls. The box open at its bottom
// stores photons and lights the room (the test can see light).
TEST_F(GpuPmTest, ALampInAClosedBoxStoresNothingAndLightsNothing) {
    for (const float top : {1.0f, 0.95f})
        for (const bool open : {false, true}) {
            Scene scene = test::room_with_lamp_in_box(top);
            if (open) test::open_lamp_box_at_the_bottom(scene);
            scene.settings.gpu_pm.paths = 20000;
            scene.settings.gpu_pm.frames = 1;
            gpu::SceneMeshes meshes(scene);
            gpu::GBuffer g(scene, meshes, 48, 48);
            gpu::GpuPhotonMapper m(scene, g);
            m.trace();
            g.render();
            m.render();
            const std::vector<float> rgba = read_texture(m.texture(), 48, 48);
            double sum = 0.0;
            int lit = 0;
            for (size_t i = 0; i < rgba.size(); ++i)
                if (i % 4 != 3) {
                    sum += rgba[i];
                    lit += rgba[i] != 0.0f ? 1 : 0;
                }
            if (open) {
                EXPECT_GT(m.stored_photons(), 1000u) << "top " << top;
                EXPECT_GT(sum, 1.0) << "top " << top;
            } else {
                EXPECT_EQ(m.stored_photons(), 0u) << "top " << top;
                EXPECT_EQ(lit, 0) << "top " << top << ": sum " << sum;
            }
        }
}

// Photons lose Beer–Lambert through the media boxes on their way, their paths unchanged, as the
// CPU photon tracer's do: the lamp in its box open at the bottom, the room filled with fog of
// σ_t 1. The same paths store photons at the same places with and without the fog (matched by
// position); each carries at most exp(−σ_t · its straight distance from the lamp) of its clear
// power (a path is no shorter than that), and some share of it. And a lamp inside a small box of
// dense fog (σ_t 1100 over at least 5 cm: e^−55) lights nothing. gpu_pm ignored the media: every
// ratio was 1, and the dense fog's room was lit as without it (mean 0.21 at 16², pt 0).
TEST_F(GpuPmTest, PhotonsThroughFogLoseBeerLambertAlongTheirPaths) {
    const auto traced = [](bool fog, glm::vec3 lo, glm::vec3 hi, float sigma_t) {
        Scene scene = test::room_with_lamp_in_box();
        test::open_lamp_box_at_the_bottom(scene);
        if (fog) {
            Medium m;
            m.bounds.min = lo;
            m.bounds.max = hi;
            m.sigma_s = m.sigma_a = 0.5f * sigma_t;
            scene.media.push_back(m);
        }
        scene.settings.gpu_pm.paths = 20000;
        scene.settings.gpu_pm.frames = 1;
        gpu::SceneMeshes meshes(scene);
        gpu::GBuffer g(scene, meshes, 16, 16);
        gpu::GpuPhotonMapper m(scene, g);
        m.trace();
        std::vector<gpu::GpuPhotonMapper::Photon> photons = m.read_photons();
        std::sort(photons.begin(), photons.end(), [](const auto& a, const auto& b) {
            return std::lexicographical_compare(&a.position.x, &a.position.x + 4, &b.position.x,
                                                &b.position.x + 4);
        });
        return photons;
    };
    const glm::vec3 lamp = test::room_with_lamp_in_box().lights[0].position;
    const auto clear = traced(false, {}, {}, 0.0f);
    const auto foggy = traced(true, glm::vec3(-0.5f), glm::vec3(1.5f), 1.0f);
    ASSERT_EQ(clear.size(), foggy.size());
    ASSERT_GT(clear.size(), 1000u);
    double worst_excess = 0.0, clear_sum = 0.0, fog_sum = 0.0;
    for (size_t i = 0; i < clear.size(); ++i) {
        ASSERT_EQ(clear[i].position, foggy[i].position) << "photon " << i;
        const double bound = std::exp(-double(glm::length(glm::vec3(clear[i].position) - lamp)));
        const double ratio = double(foggy[i].power.g) / double(clear[i].power.g);
        worst_excess = std::max(worst_excess, ratio / bound - 1.0);
        EXPECT_GT(ratio, 0.0) << "photon " << i;
        clear_sum += double(clear[i].power.g);
        fog_sum += double(foggy[i].power.g);
    }
    std::printf(
        "%zu photons through fog: stored power %.3f of clear, worst ratio over the bound "
        "%+.2g\n",
        clear.size(), fog_sum / clear_sum, worst_excess);
    EXPECT_LT(worst_excess, 1e-4);
    const auto dense =
        traced(true, glm::vec3(0.4f, 0.8f, 0.4f), glm::vec3(0.6f, 0.99f, 0.6f), 1100.0f);
    double dense_sum = 0.0;
    for (const auto& p : dense) dense_sum += double(p.power.g);
    EXPECT_LT(dense_sum, 1e-12 * clear_sum);
}

}  // namespace ag
