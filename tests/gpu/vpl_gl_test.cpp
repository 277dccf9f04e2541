// VPL shadow maps and the per-pixel VPL sum on GL (Barczak 2006 §4.2-4.3): visibility from the
// octahedral maps agrees with Embree rays on the Cornell box; octahedral maps leak nothing where
// paraboloid maps of a 25×25-vertex wall do (thesis Fig. 4-3).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cpu/photon_simulation.h"
#include "cpu/vpl_shading.h"
#include "cpu/vpl_source.h"
#include "cpu/vpl_visibility.h"
#include "gl_fixture.h"
#include "gpu/vpl_gather.h"
#include "gpu/vpl_shadow_maps.h"
#include "shared/camera.h"
#include "shared/charts.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/shapes.h"

namespace ag {
namespace {

// Points per pixel of a w × h view, rows bottom-first as GL stores them (zero normal: none).
struct Points {
    std::vector<glm::vec3> positions, normals;
    std::vector<cpu::SurfacePoint> cpu;
};

Points camera_points(const Scene& scene, const cpu::RayTracer& rays, int w, int h) {
    Points p;
    p.positions.assign(size_t(w) * size_t(h), glm::vec3(0.0f));
    p.normals = p.positions;
    p.cpu.resize(p.positions.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float px = (float(x) + 0.5f) * float(scene.camera.width) / float(w);
            const float py = (float(y) + 0.5f) * float(scene.camera.height) / float(h);
            const glm::vec3 dir = camera_ray_direction(scene.camera, px, py);
            const cpu::RayHit hit = rays.intersect({scene.camera.eye, dir});
            if (!hit.hit) continue;
            const size_t i = size_t(h - 1 - y) * size_t(w) + size_t(x);
            p.positions[i] = hit.position;
            p.normals[i] = glm::dot(dir, hit.normal) < 0.0f ? hit.normal : -hit.normal;
            p.cpu[i] = {p.positions[i], p.normals[i]};
        }
    return p;
}

std::vector<glm::vec3> cpu_sum(const cpu::RayTracer& rays, const Points& p,
                               const std::vector<Vpl>& vpls) {
    ThreadPool pool(2);
    std::vector<glm::vec3> e(p.cpu.size(), glm::vec3(0.0f));
    cpu::add_vpl_irradiance(rays, p.cpu, vpls.data(), vpls.size(), 0.0f, e.data(), pool);
    for (glm::vec3& v : e) v /= std::numbers::pi_v<float>;
    return e;
}

double rel_mse(const std::vector<glm::vec3>& x, const std::vector<glm::vec3>& y) {
    double sum = 0.0;
    for (size_t i = 0; i < x.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double d = double(x[i][c]) - double(y[i][c]);
            sum += d * d / (double(y[i][c]) * double(y[i][c]) + 0.01);
        }
    return sum / double(3 * x.size());
}

class VplGlTest : public test::GlTest {};

TEST_F(VplGlTest, OctahedralMapVisibilityMatchesEmbreeRaysOnCornell) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell.json");
    for (Object& o : scene.objects) o.material.type = MaterialType::diffuse;
    ThreadPool pool(2);
    cpu::PhotonSimulation sim(scene, pool);
    sim.trace_all();
    std::vector<Vpl> vpls;
    for (int g = 0; g < scene.settings.photons.groups; ++g)
        cpu::group_vpls(scene, sim.maps(), 0, g, 2, vpls);
    ASSERT_GT(vpls.size(), 200u);
    const int w = 64, h = 64;
    const Points points = camera_points(scene, sim.rays(), w, h);

    gpu::SceneMeshes meshes(scene);
    gpu::VplShadowMaps maps(scene, meshes, 256, gpu::VplMapKind::octahedral, 0.5f);
    maps.set_vpls(vpls);
    maps.render_all();
    gpu::VplGather gather(w, h);
    gather.set_points(points.positions, points.normals);
    // E/π on both sides (radiance-like values, as relMSE is meant for).
    gather.shade(maps, 0.0f, std::numbers::inv_pi_v<float>);
    const std::vector<glm::vec3> gl = gather.read_back();
    const std::vector<glm::vec3> exact = cpu_sum(sim.rays(), points, vpls);
    gather.shade(maps, 0.0f, std::numbers::inv_pi_v<float>, false);
    const std::vector<glm::vec3> unshadowed = gather.read_back();
    const double err = rel_mse(gl, exact), shadow_effect = rel_mse(unshadowed, exact);
    std::printf("%zu VPLs, 256² octahedral maps: relMSE against Embree %.5f (unshadowed %.4f)\n",
                vpls.size(), err, shadow_effect);
    EXPECT_LE(err, 0.005);
    EXPECT_GT(shadow_effect, 10.0 * err) << "the visibility must matter in this test";
    // Culling before the vertex stage transforms fewer vertices than every object for every
    // VPL and face (the naive pass, counted exactly).
    const uint64_t culled = maps.vertices_transformed();
    maps.set_culling(false);
    maps.render_all();
    const uint64_t naive = maps.vertices_transformed() - culled;
    EXPECT_EQ(naive, [&] {
        uint64_t v = 0;
        for (const Object& o : scene.objects) v += o.mesh.positions.size();
        return v * 4 * vpls.size();
    }());
    EXPECT_LT(culled, naive);
}

// Culling runs of triangles outside a face's octant before the vertex stage leaves every map
// as the naive pass draws it (the geometry shader would have dropped the same triangles), on
// cornell's photon VPLs and in the thesis's table room with the torus (a 0.8 m × 0.8 m quad
// light's photon VPLs), octahedral and paraboloid, and after the torus moves. Fails if a run
// is culled for a face that it reaches (a map then misses an occluder) or the instance list
// maps a draw to the wrong VPL or face.
TEST_F(VplGlTest, CullingBeforeTheVertexStageLeavesEveryMapAsTheNaivePassDrawsIt) {
    for (const char* name : {"cornell.json", "vpl_table_torus.json"}) {
        Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/" + name);
        for (Object& o : scene.objects) o.material.type = MaterialType::diffuse;
        ThreadPool pool(2);
        cpu::PhotonSimulation sim(scene, pool);
        sim.trace_all();
        std::vector<Vpl> vpls;
        for (int g = 0; g < scene.settings.photons.groups; g += 4)
            cpu::group_vpls(scene, sim.maps(), 0, g, 2, vpls);
        ASSERT_GT(vpls.size(), 40u) << name;
        gpu::SceneMeshes meshes(scene);
        for (gpu::VplMapKind kind : {gpu::VplMapKind::octahedral, gpu::VplMapKind::paraboloid}) {
            gpu::VplShadowMaps culled(scene, meshes, 64, kind, 1e-3f),
                naive(scene, meshes, 64, kind, 1e-3f);
            naive.set_culling(false);
            for (int move = 0; move < 2; ++move) {
                if (move) {
                    for (Object& o : scene.objects)
                        if (o.dynamic) o.transform.translation += glm::vec3(0.21f, 0.0f, 0.13f);
                }
                const uint64_t c0 = culled.vertices_transformed(),
                               n0 = naive.vertices_transformed();
                for (gpu::VplShadowMaps* m : {&culled, &naive}) {
                    m->set_vpls(vpls);
                    m->render_all();
                }
                size_t differ = 0;
                for (size_t i = 0; i < vpls.size(); ++i)
                    differ += culled.read_layer(int(i)) == naive.read_layer(int(i)) ? 0 : 1;
                const double share = double(culled.vertices_transformed() - c0) /
                                     double(naive.vertices_transformed() - n0);
                std::printf("%s, %s maps%s: %zu VPLs, vertices transformed %.3f of naive\n", name,
                            kind == gpu::VplMapKind::octahedral ? "octahedral" : "paraboloid",
                            move ? " (mover moved)" : "", vpls.size(), share);
                EXPECT_EQ(differ, 0u) << name;
                // The hemisphere alone culls little in a closed room; the octants do.
                if (kind == gpu::VplMapKind::octahedral) {
                    EXPECT_LT(share, 0.7) << name;
                } else {
                    EXPECT_LE(share, 1.0) << name;
                }
            }
        }
    }
}

// A VPL just above the floor facing up, a wall of 25×25 vertices standing 0.2 in front of it
// (reaching below its horizon), receivers on a wall behind: every receiver is occluded (Embree
// says so). The paraboloid map draws the wall's bent edges and its horizon clip as straight
// chords and leaks; the octahedral map's faces keep them straight and leak nothing.
TEST_F(VplGlTest, ParaboloidMapsLeakWhereOctahedralMapsDoNot) {
    auto leaks = [&](int wall_vertices, gpu::VplMapKind kind, int* occluded_by_rays) {
        Scene scene;
        scene.path = "leak_test";
        Object wall;
        wall.name = "wall";
        wall.mesh = make_bumpy_plane(10.0f, 5.5f, wall_vertices - 1, 0.0f, 1);
        wall.transform.rotation = glm::angleAxis(glm::radians(-90.0f), glm::vec3(1, 0, 0));
        wall.transform.translation = glm::vec3(0.0f, 2.25f, 0.2f);
        scene.objects.push_back(wall);
        Light l;
        l.position = glm::vec3(0.0f, 3.0f, -3.0f);
        l.intensity = glm::vec3(1.0f);
        scene.lights.push_back(l);
        init_versions(scene);
        make_surfaces_and_atlas(scene);
        cpu::RayTracer rays(scene);
        const Vpl vpl{{0.0f, 0.001f, 0.0f}, {0.0f, 1.0f, 0.0f}, glm::vec3(1.0f)};
        const int w = 48, h = 32;
        Points p;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const glm::vec3 at(-3.0f + 6.0f * (float(x) + 0.5f) / float(w),
                                   0.02f + 3.0f * std::pow((float(y) + 0.5f) / float(h), 2.0f),
                                   1.0f);
                p.positions.push_back(at);
                p.normals.emplace_back(0.0f, 0.0f, -1.0f);
                p.cpu.push_back({at, {0.0f, 0.0f, -1.0f}});
            }
        *occluded_by_rays = 0;
        for (const cpu::SurfacePoint& s : p.cpu)
            *occluded_by_rays += cpu::vpl_visible(rays, vpl, s.position, s.normal) ? 0 : 1;
        gpu::SceneMeshes meshes(scene);
        gpu::VplShadowMaps maps(scene, meshes, 256, kind, 1e-3f);
        maps.set_vpls({vpl});
        maps.render_all();
        gpu::VplGather gather(w, h);
        gather.set_points(p.positions, p.normals);
        gather.shade(maps, 0.0f, 1.0f);
        int lit = 0;
        for (const glm::vec3& e : gather.read_back()) lit += e.x > 0.0f ? 1 : 0;
        return lit;
    };
    int occluded = 0;
    const int octahedral = leaks(25, gpu::VplMapKind::octahedral, &occluded);
    EXPECT_EQ(occluded, 48 * 32) << "the wall hides every receiver from the VPL";
    const int paraboloid = leaks(25, gpu::VplMapKind::paraboloid, &occluded);
    const int paraboloid_fine = leaks(100, gpu::VplMapKind::paraboloid, &occluded);
    std::printf(
        "receivers lit through the wall (of %d): octahedral %d, paraboloid 25×25 %d, "
        "100×100 %d\n",
        48 * 32, octahedral, paraboloid, paraboloid_fine);
    EXPECT_EQ(octahedral, 0);
    EXPECT_GT(paraboloid, 0);
    EXPECT_LT(paraboloid_fine, paraboloid);
}

// Cutting the per-pixel sum: tile lists keep every VPL that can light a tile's point, so the
// sum is bit-identical to the full one; F/P/N labels in the lists leave out F pairs and the
// lookups of N pairs (what the maps would mostly say anyway); interleaved sampling with the
// geometry-aware filter changes the sum, by a bounded amount. Fails if a tile list drops a
// lit VPL, a label is wrong or the filter mixes surfaces or loses a class.
TEST_F(VplGlTest, TileListsLabelsAndInterleavingAgainstTheFullSum) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell.json");
    for (Object& o : scene.objects) o.material.type = MaterialType::diffuse;
    ThreadPool pool(2);
    cpu::PhotonSimulation sim(scene, pool);
    sim.trace_all();
    std::vector<Vpl> vpls;
    for (int g = 0; g < scene.settings.photons.groups; g += 2)
        cpu::group_vpls(scene, sim.maps(), 0, g, 2, vpls);
    ASSERT_GT(vpls.size(), 100u);
    const int w = 48, h = 48;
    const Points points = camera_points(scene, sim.rays(), w, h);
    gpu::SceneMeshes meshes(scene);
    gpu::VplShadowMaps maps(scene, meshes, 128, gpu::VplMapKind::octahedral, 0.5f);
    maps.set_vpls(vpls);
    maps.render_all();
    gpu::VplGather gather(w, h);
    gather.set_points(points.positions, points.normals);
    const float scale = std::numbers::inv_pi_v<float>;
    gather.shade(maps, 0.0f, scale);
    const std::vector<glm::vec3> full = gather.read_back();

    gather.set_tiles(vpls, 1);
    gather.shade(maps, 0.0f, scale);
    EXPECT_EQ(gather.read_back(), full) << "tile lists leave out only zero contributions";
    const gpu::VplGather::TileCounts plain = gather.tile_counts();
    EXPECT_LT(plain.entries, plain.pairs) << "cornell's walls face away from some VPLs";
    EXPECT_EQ(plain.lookups, plain.entries);

    // Patches: the database's leaf under each pixel (camera rays again, for the hits).
    const cpu::VisibilityDatabase db(scene, vpls, 2);
    std::vector<int> patch(points.positions.size(), 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec3 dir = camera_ray_direction(
                scene.camera, (float(x) + 0.5f) * float(scene.camera.width) / float(w),
                (float(y) + 0.5f) * float(scene.camera.height) / float(h));
            const cpu::RayHit hit = sim.rays().intersect({scene.camera.eye, dir});
            const int leaf = hit.hit ? db.leaf_at(hit.object, hit.triangle, hit.barycentric) : -1;
            patch[size_t(h - 1 - y) * size_t(w) + size_t(x)] =
                leaf < 0 ? int(db.nodes().size()) : leaf;
        }
    std::vector<uint32_t> labels((db.nodes().size() + 1) * vpls.size(), 1u);
    for (size_t node = 0; node < db.nodes().size(); ++node)
        for (size_t l = 0; l < vpls.size(); ++l)
            labels[node * vpls.size() + l] = uint32_t(db.state(int(node), int(l)));
    gather.set_points(points.positions, points.normals, patch);
    gather.set_tiles(vpls, 1, &labels);
    gather.shade(maps, 0.0f, scale);
    const double labelled = rel_mse(gather.read_back(), full);
    const gpu::VplGather::TileCounts fpn = gather.tile_counts();
    EXPECT_LE(fpn.entries, plain.entries);
    EXPECT_LT(fpn.lookups, fpn.entries) << "N pairs need no lookup";
    EXPECT_LE(labelled, 1e-4);

    double err[2] = {0.0, 0.0};
    for (int n : {2, 3}) {
        gather.set_tiles(vpls, n, &labels);
        gather.shade(maps, 0.0f, scale);
        const std::vector<glm::vec3> e = gather.read_back();
        err[n - 2] = rel_mse(e, full);
        double sum = 0.0, ref = 0.0;
        for (size_t i = 0; i < e.size(); ++i) {
            sum += double(e[i].x + e[i].y + e[i].z);
            ref += double(full[i].x + full[i].y + full[i].z);
        }
        std::printf("interleave %dx%d: relMSE %.2e against the full sum, mean %+.2f%%\n", n, n,
                    err[n - 2], 100.0 * (sum / ref - 1.0));
        EXPECT_GT(err[n - 2], 0.0) << "interleaving changes the sum";
        EXPECT_NEAR(sum / ref, 1.0, 0.02) << "each class is a share of the VPLs, scaled back";
    }
    std::printf("labels: relMSE %.2e; listed %llu of %llu pairs, %llu lookups (no labels %llu)\n",
                labelled, (unsigned long long)fpn.entries, (unsigned long long)plain.pairs,
                (unsigned long long)fpn.lookups, (unsigned long long)plain.lookups);
    EXPECT_LE(err[0], 0.03);  // measured 0.0175 (48², ~150 VPLs)
    EXPECT_LE(err[1], 0.08);  // measured 0.052
}

// More maps than the GL's array layers (GL_MAX_ARRAY_TEXTURE_LAYERS, 2048 on llvmpipe: the
// conference room's 4 lights × 128 groups × 4 photon VPLs with the method's room of half as many
// again need 3072) share layers as an atlas. The cornell photon VPLs, each copied c times at
// 1/c of its power so that the copies outnumber the layers, must give the same sum as the
// originals at one map a layer, and each copy's map the original's. Fails if a lookup reads the
// wrong tile or layer, a tile's clear or draw spills into its neighbours, or (as before the
// atlas) the array cannot be made ("framebuffer incomplete").
TEST_F(VplGlTest, MoreMapsThanArrayLayersShareLayersAsAnAtlas) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell.json");
    for (Object& o : scene.objects) o.material.type = MaterialType::diffuse;
    ThreadPool pool(2);
    cpu::PhotonSimulation sim(scene, pool);
    sim.trace_all();
    std::vector<Vpl> vpls;
    for (int g = 0; g < scene.settings.photons.groups; g += 2)
        cpu::group_vpls(scene, sim.maps(), 0, g, 2, vpls);
    ASSERT_GT(vpls.size(), 100u);
    const int w = 32, h = 32, size = 64;
    const Points points = camera_points(scene, sim.rays(), w, h);
    gpu::SceneMeshes meshes(scene);
    const float scale = std::numbers::inv_pi_v<float>;
    gpu::VplGather gather(w, h);
    gather.set_points(points.positions, points.normals);

    gpu::VplShadowMaps single(scene, meshes, size, gpu::VplMapKind::octahedral, 0.5f);
    single.set_vpls(vpls);
    single.render_all();
    ASSERT_EQ(single.layout().tiles, 1);
    gather.shade(single, 0.0f, scale);
    const std::vector<glm::vec3> reference = gather.read_back();
    const double exact = rel_mse(reference, cpu_sum(sim.rays(), points, vpls));
    EXPECT_LE(exact, 0.005) << "64² maps against Embree rays";

    const gpu::VplMapLimits gl = gpu::VplMapLimits::gl_limits();
    // The GL's own limits (copies past its layer count), then a tiny one (3 × 3 tiles a layer).
    for (const gpu::VplMapLimits& limits : {gl, gpu::VplMapLimits{20, gl.max_texture_size}}) {
        const int copies = std::max(1, limits.max_layers / int(vpls.size()) + 1);
        std::vector<Vpl> many;
        for (int c = 0; c < copies; ++c)
            for (const Vpl& v : vpls)
                many.push_back({v.position, v.normal, v.power / float(copies)});
        ASSERT_GT(int(many.size()), limits.max_layers);
        gpu::VplShadowMaps atlas(scene, meshes, size, gpu::VplMapKind::octahedral, 0.5f, limits);
        atlas.set_vpls(many);
        // Drawn in two halves, so that the second half's clears must keep the first's maps.
        atlas.render(0, int(many.size()) / 2);
        atlas.render(int(many.size()) / 2, int(many.size()));
        const gpu::VplMapLayout& layout = atlas.layout();
        EXPECT_GT(layout.tiles, 1);
        EXPECT_LE(layout.layers, limits.max_layers);
        gather.shade(atlas, 0.0f, scale);
        const double err = rel_mse(gather.read_back(), reference);
        std::printf(
            "%zu maps (limit %d layers): %d × %d tiles a layer, %d layers; relMSE against one "
            "map a layer %.2e (that against Embree %.5f)\n",
            many.size(), limits.max_layers, layout.tiles, layout.tiles, layout.layers, err, exact);
        EXPECT_LE(err, 1e-6);
        // Copies in other tiles and layers hold the original's map.
        for (size_t i : {size_t(0), vpls.size() - 1, many.size() - 1, many.size() / 2 + 1}) {
            const std::vector<float> map = atlas.read_layer(int(i));
            // The same texels up to interpolation rounding at another place in the viewport.
            const std::vector<float> original = single.read_layer(int(i % vpls.size()));
            double worst = 0.0;
            for (size_t t = 0; t < map.size(); ++t)
                worst = std::max(worst, std::abs(double(map[t]) - double(original[t])) /
                                            std::max(1e-6, double(original[t])));
            EXPECT_LE(worst, 1e-4) << "map " << i;  // the readers' depth bias is 1e-2
        }
    }
}

TEST(VplMapLayout, OneMapALayerWhileTheyFitThenTheFewestTilesThatDo) {
    const gpu::VplMapLimits llvmpipe{2048, 16384};
    EXPECT_EQ(gpu::vpl_map_layout(2048, 128, llvmpipe).tiles, 1);
    EXPECT_EQ(gpu::vpl_map_layout(2048, 128, llvmpipe).layers, 2048);
    // The conference room: 4 lights × 128 groups, room for 6 maps each (4 VPLs and half again).
    const gpu::VplMapLayout conference = gpu::vpl_map_layout(4 * 128 * 6, 128, llvmpipe);
    EXPECT_EQ(conference.tiles, 2);
    EXPECT_EQ(conference.layers, 768);
    EXPECT_EQ(conference.side(128), 256);
    EXPECT_EQ(gpu::vpl_map_layout(2048 * 9 + 1, 128, llvmpipe).tiles, 4);
    EXPECT_EQ(gpu::vpl_map_layout(0, 128, llvmpipe).layers, 1);
    // A map larger than a texture, or more maps than the largest atlas holds: a clear error.
    EXPECT_THROW(gpu::vpl_map_layout(1, 32768, llvmpipe), std::runtime_error);
    const gpu::VplMapLimits small{4, 256};
    EXPECT_EQ(gpu::vpl_map_layout(16, 128, small).tiles, 2);
    try {
        gpu::vpl_map_layout(17, 128, small);
        ADD_FAILURE() << "17 maps of 128² in 4 layers of 256²";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("vpl.map_size 128"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace ag
