// The composed frame (Larsen ch. 13): shadow volumes, the sum of the eq. 13.2 terms, and the
// light-sample limit.
#include <gtest/gtest.h>

#include <algorithm>
#include <numbers>

#include "../cpu/test_scenes.h"
#include "gl_fixture.h"
#include "gpu/frame_renderer.h"
#include "gpu/lightmap_texture.h"
#include "shared/camera.h"
#include "shared/charts.h"
#include "shared/input_error.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/shapes.h"

namespace ag::gpu {

namespace {

// A floor, a closed box hovering above it, a point light above the box, a camera looking down.
Scene occluder_scene() {
    Scene s;
    s.path = "frame_test";
    Object floor;
    floor.name = "floor";
    floor.mesh = make_quad(10.0f, 10.0f);
    s.objects.push_back(floor);
    Object box;
    box.name = "box";
    box.mesh = make_box(glm::vec3(1.0f));
    box.transform.translation = {0.0f, 2.0f, 0.0f};
    box.dynamic = true;
    s.objects.push_back(box);
    Light l;
    l.name = "lamp";
    l.position = {0.0f, 5.0f, 0.0f};
    l.intensity = glm::vec3(25.0f);
    s.lights.push_back(l);
    s.camera.eye = {0.0f, 9.0f, -6.0f};
    s.camera.target = {0.0f, 0.0f, 0.0f};
    s.camera.fov_y = 60.0f;
    s.camera.width = s.camera.height = 128;
    s.settings.lightmap.texel_size = 1.0f;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

// The pixel where world point p lands.
glm::ivec2 project(const Camera& c, const glm::vec3& p) {
    const glm::vec4 clip =
        projection_matrix(c, 0.01f, 100.0f) * view_matrix(c) * glm::vec4(p, 1.0f);
    const glm::vec2 ndc = glm::vec2(clip) / clip.w;
    return {int((ndc.x * 0.5f + 0.5f) * float(c.width)),
            int((0.5f - ndc.y * 0.5f) * float(c.height))};
}

}  // namespace

class FrameTest : public test::GlTest {};

TEST_F(FrameTest, PointUnderOccluderIsBlackInDirectAndBesideItIsLit) {
    const Scene scene = occluder_scene();
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    FrameRenderer renderer(scene, meshes, scene.camera.width, scene.camera.height);
    renderer.render(iim.id());
    const FrameImages images = renderer.read_back();
    const Image& direct = images.aov[size_t(FrameTerm::direct)];
    const glm::ivec2 under = project(scene.camera, {0.0f, 0.0f, 0.0f});
    const glm::ivec2 beside = project(scene.camera, {3.0f, 0.0f, 0.0f});
    EXPECT_EQ(direct.rgb(under.x, under.y), glm::vec3(0.0f))
        << "pixel " << under.x << "," << under.y;
    // Beside: ρ/π · I cosθ / d² with ρ = 0.75, d² = 9 + 25, cosθ = 5/√34.
    const float d2 = 34.0f,
                expected = 0.75f / std::numbers::pi_v<float> * 25.0f * (5.0f / std::sqrt(d2)) / d2;
    EXPECT_NEAR(direct.rgb(beside.x, beside.y).x, expected, 0.03f * expected);
    // Switching shadows off lights the point under the box too.
    Scene unshadowed = scene;
    unshadowed.settings.direct.shadows = false;
    FrameRenderer plain(unshadowed, meshes, scene.camera.width, scene.camera.height);
    plain.render(iim.id());
    EXPECT_GT(plain.read_back().aov[size_t(FrameTerm::direct)].rgb(under.x, under.y).x,
              0.1f * expected);
}

// The direct light is drawn deferred, one full-screen pass per light sample over the surface the
// G-buffer pass left; the forward passes (every object again per light, as the cube maps draw it)
// are the same arithmetic at the same fragments. Cornell (quad light samples, the glass sphere
// leaving its pixels unlit) with shadow volumes and with shadow maps, a sun beside them.
TEST_F(FrameTest, DeferredDirectLightMatchesTheForwardPasses) {
    for (DirectMethod method : {DirectMethod::shadow_volumes, DirectMethod::vpl}) {
        Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell.json");
        scene.settings.direct.method = method;
        Light sun;
        sun.name = "sun";
        sun.type = LightType::sun;
        sun.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
        sun.irradiance = glm::vec3(0.5f);
        scene.lights.push_back(sun);
        SceneMeshes meshes(scene);
        LightmapTexture iim(scene.atlas);
        auto direct = [&](bool forward) {
            FrameRenderer renderer(scene, meshes, 64, 64);
            renderer.set_direct_pass(forward ? FrameRenderer::DirectPass::forward
                                             : FrameRenderer::DirectPass::deferred);
            renderer.render(iim.id());
            return renderer.read_back().aov[size_t(FrameTerm::direct)];
        };
        const Image deferred = direct(false), forward = direct(true);
        double sum = 0.0;
        int lit = 0;
        for (size_t i = 0; i < deferred.pixels.size(); ++i) {
            ASSERT_NEAR(deferred.pixels[i], forward.pixels[i],
                        1e-5f * std::max(1.0f, forward.pixels[i]))
                << "value " << i << ", method " << int(method);
            sum += deferred.pixels[i];
            lit += deferred.pixels[i] > 0.0f;
        }
        EXPECT_GT(sum, 0.0);
        EXPECT_GT(lit, int(deferred.pixels.size() / 2));
    }
}

TEST_F(FrameTest, ComponentImagesSumToTheFrame) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell.json");
    scene.camera.width = scene.camera.height = 96;
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    std::vector<glm::vec3> values(size_t(scene.atlas.width) * size_t(scene.atlas.height),
                                  glm::vec3(0.2f, 0.1f, 0.05f));
    iim.update_all(values);
    FrameRenderer renderer(scene, meshes, 96, 96);
    renderer.render(iim.id());
    const FrameImages images = renderer.read_back();
    std::array<double, kFrameTermCount> terms{};
    for (size_t i = 0; i < images.frame.pixels.size(); ++i) {
        float sum = 0.0f;
        for (FrameTerm t : kFrameTerms) {
            sum += images.aov[size_t(t)].pixels[i];
            terms[size_t(t)] += images.aov[size_t(t)].pixels[i];
        }
        ASSERT_NEAR(images.frame.pixels[i], sum, 1e-5f * std::max(1.0f, sum))
            << "pixel value " << i;
    }
    EXPECT_GT(terms[size_t(FrameTerm::direct)], 0.0);
    EXPECT_GT(terms[size_t(FrameTerm::indirect)], 0.0);
    EXPECT_GT(terms[size_t(FrameTerm::specular)], 0.0);  // the glass sphere
    EXPECT_EQ(terms[size_t(FrameTerm::caustics)], 0.0);  // none passed to render()
}

// A quad light's samples move within their strata from frame to frame while nothing changes; the
// direct term is their running mean, kept once accumulate_frames are in, and restarted (frame 0's
// samples again) by any edit.
TEST_F(FrameTest, AreaLightSamplesMoveOverFramesAndRestartAfterAnEdit) {
    Scene scene = occluder_scene();
    scene.lights[0].type = LightType::quad;
    scene.lights[0].corners = {glm::vec3(-1, 5, -1), glm::vec3(1, 5, -1), glm::vec3(1, 5, 1),
                               glm::vec3(-1, 5, 1)};  // facing down
    scene.lights[0].radiance = glm::vec3(10.0f);
    scene.settings.direct.area_light_samples = 4;
    scene.settings.direct.accumulate_frames = 3;
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    FrameRenderer renderer(scene, meshes, scene.camera.width, scene.camera.height);
    auto direct = [&] {
        renderer.render(iim.id());
        return renderer.read_back().aov[size_t(FrameTerm::direct)].pixels;
    };
    const std::vector<float> first = direct();
    const std::vector<float> second = direct();
    size_t changed = 0;  // the penumbra's pixels: 2×2 samples moved
    for (size_t i = 0; i < first.size(); ++i) changed += first[i] != second[i] ? 1 : 0;
    EXPECT_GT(changed, first.size() / 100);
    const std::vector<float> third = direct();
    EXPECT_NE(third, second);
    EXPECT_EQ(direct(), third) << "3 frames are in: the mean is kept";
    set_camera(scene, scene.camera);  // an edit, even one that moves nothing, restarts the mean
    EXPECT_EQ(direct(), first);
    scene.settings.direct.accumulate_frames = 1;  // a fixed set: frame 0's every time
    EXPECT_EQ(direct(), first);
    EXPECT_EQ(direct(), first);
}

// While the indirect term changes every frame (an IIM converging), the frame is not accumulated,
// but the direct term still averages its area-light samples: penumbrae converge before the
// indirect term settles. Fails if any change of the frame restarts the direct term's mean.
TEST_F(FrameTest, AreaLightSamplesAccumulateWhileTheIndirectTermChanges) {
    Scene scene = occluder_scene();
    scene.lights[0].type = LightType::quad;
    scene.lights[0].corners = {glm::vec3(-1, 5, -1), glm::vec3(1, 5, -1), glm::vec3(1, 5, 1),
                               glm::vec3(-1, 5, 1)};  // facing down
    scene.lights[0].radiance = glm::vec3(10.0f);
    scene.settings.direct.area_light_samples = 4;
    scene.settings.direct.accumulate_frames = 3;
    scene.settings.frame.accumulate_frames = 64;
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    FrameRenderer renderer(scene, meshes, 48, 48);
    uint64_t revision = 0;
    auto direct = [&] {
        renderer.render(IndirectTerm{iim.id(), IndirectSpace::lightmap, ++revision});
        return renderer.read_back().aov[size_t(FrameTerm::direct)].pixels;
    };
    const std::vector<float> first = direct();
    const std::vector<float> second = direct();
    EXPECT_NE(second, first);
    const std::vector<float> third = direct();
    EXPECT_NE(third, second);
    EXPECT_EQ(direct(), third) << "3 frames are in: the direct term's mean is kept";
    EXPECT_FALSE(renderer.accumulation_complete()) << "the frame itself never stood still";
}

// Point lights give every frame the same samples: the first frame's direct term is kept (no light
// pass drawn) until an edit, and equals what drawing it again gives.
TEST_F(FrameTest, PointLightDirectTermIsKeptWhileNothingChanges) {
    Scene scene = occluder_scene();
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    FrameRenderer renderer(scene, meshes, scene.camera.width, scene.camera.height);
    auto direct = [&] {
        renderer.render(iim.id());
        return renderer.read_back().aov[size_t(FrameTerm::direct)].pixels;
    };
    const std::vector<float> first = direct();
    EXPECT_EQ(direct(), first);
    EXPECT_EQ(direct(), first);
    translate_object(scene, 1, glm::vec3(2.0f, 0.0f, 0.0f));  // the box moves: its shadow too
    const std::vector<float> moved = direct();
    EXPECT_NE(moved, first);
    EXPECT_EQ(direct(), moved);
}

// Progressive antialiasing: while nothing changes, each frame samples the pixels at another
// sub-pixel offset and every term is the running mean. An outline (the box against the floor,
// the shadow's edge) then converges to the box-filtered value that 8×8 samples per pixel give,
// where one sample at each centre is off by the whole contrast across the edge. Fails if the
// projection does not move, if a term is left out of the mean, or if the mean is not kept.
TEST_F(FrameTest, AccumulatedFrameConvergesToTheBoxFilteredOne) {
    Scene scene = occluder_scene();
    scene.settings.frame.accumulate_frames = 64;
    const int size = 48, factor = 8;
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    iim.update_all(std::vector<glm::vec3>(size_t(scene.atlas.width) * size_t(scene.atlas.height),
                                          glm::vec3(0.02f, 0.01f, 0.005f)));
    const IndirectTerm term{iim.id(), IndirectSpace::lightmap, 1};
    FrameRenderer renderer(scene, meshes, size, size);
    renderer.render(term);
    const FrameImages first = renderer.read_back();
    EXPECT_EQ(renderer.accumulated_frames(), 1);
    // Frame 1 is the first of the mean (the first after a change is drawn at the centres alone).
    for (int f = 1; f <= 64; ++f) renderer.render(term);
    EXPECT_EQ(renderer.accumulated_frames(), 64);
    EXPECT_TRUE(renderer.accumulation_complete());
    const FrameImages mean = renderer.read_back();

    // The references' pixel filter: 8×8 centre samples per pixel, box-filtered.
    Scene fine_scene = scene;
    fine_scene.settings.frame.accumulate_frames = 1;
    FrameRenderer fine(fine_scene, meshes, size * factor, size * factor);
    fine.render(term);
    FrameImages box = fine.read_back();
    box.frame = box_downsample(box.frame, factor);

    double error_first = 0.0, error_mean = 0.0, total = 0.0;
    for (size_t i = 0; i < box.frame.pixels.size(); ++i) {
        error_first += std::abs(first.frame.pixels[i] - box.frame.pixels[i]);
        error_mean += std::abs(mean.frame.pixels[i] - box.frame.pixels[i]);
        total += box.frame.pixels[i];
    }
    std::printf("mean |frame - box filter| / mean value: one sample %.4f, 64 frames %.4f\n",
                error_first / total, error_mean / total);
    EXPECT_GT(error_first / total, 0.01);  // the outlines are there to be filtered
    EXPECT_LT(error_mean, 0.15 * error_first);

    // The terms of the mean still sum to the displayed frame.
    for (size_t i = 0; i < mean.frame.pixels.size(); ++i) {
        float sum = 0.0f;
        for (FrameTerm t : kFrameTerms) sum += mean.aov[size_t(t)].pixels[i];
        ASSERT_NEAR(mean.frame.pixels[i], sum, 1e-6f * std::max(1.0f, sum)) << "value " << i;
    }
    // Kept: a later frame draws nothing and changes nothing.
    renderer.render(term);
    EXPECT_EQ(renderer.read_back().frame.pixels, mean.frame.pixels);

    // Deterministic: another renderer given the same frames shows the same mean.
    FrameRenderer again(scene, meshes, size, size);
    for (int f = 0; f <= 64; ++f) again.render(term);
    const FrameImages repeated = again.read_back();
    EXPECT_EQ(repeated.frame.pixels, mean.frame.pixels);
    for (FrameTerm t : kFrameTerms)
        EXPECT_EQ(repeated.aov[size_t(t)].pixels, mean.aov[size_t(t)].pixels) << frame_term_name(t);
}

// What restarts the mean: an edit (any: the scene version), a camera that moved without one, a
// new revision of the indirect term or of the caustics. After a restart the frame is frame 0
// again (one sample at each pixel's centre), exactly. An untracked term (revision 0) is never
// accumulated.
TEST_F(FrameTest, AccumulationRestartsWhenAnythingTheFrameShowsChanges) {
    Scene scene = occluder_scene();
    scene.settings.frame.accumulate_frames = 4;
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    FrameRenderer renderer(scene, meshes, 32, 32);
    auto frame = [&](uint64_t revision, GLuint caustics = 0, uint64_t caustics_revision = 0) {
        renderer.render(IndirectTerm{iim.id(), IndirectSpace::lightmap, revision}, caustics,
                        caustics_revision);
        return renderer.read_back().frame.pixels;
    };
    // The first frame after a change is drawn at the pixel centres; accumulation starts with the
    // next one, if nothing changed (its frame 0: the centres again).
    const std::vector<float> first = frame(1);
    EXPECT_EQ(frame(1), first);
    EXPECT_EQ(renderer.accumulated_frames(), 1);
    const std::vector<float> second = frame(1);
    EXPECT_NE(second, first);
    EXPECT_EQ(renderer.accumulated_frames(), 2);
    EXPECT_FALSE(renderer.accumulation_complete());
    frame(1);
    const std::vector<float> fourth = frame(1);
    EXPECT_TRUE(renderer.accumulation_complete());
    EXPECT_EQ(frame(1), fourth);
    EXPECT_EQ(renderer.accumulated_frames(), 4);

    EXPECT_EQ(frame(2), first) << "a new revision of the indirect term";
    EXPECT_EQ(frame(2), first);
    EXPECT_NE(frame(2), first);
    set_camera(scene, scene.camera);  // an edit, even one that moves nothing
    EXPECT_EQ(frame(2), first);
    EXPECT_EQ(frame(2), first);
    EXPECT_NE(frame(2), first);
    const glm::vec3 eye = scene.camera.eye;
    scene.camera.eye.x += 0.5f;  // moved without an edit (no version)
    const std::vector<float> moved = frame(2);
    EXPECT_NE(moved, first);
    EXPECT_EQ(renderer.accumulated_frames(), 1);
    scene.camera.eye = eye;
    EXPECT_EQ(frame(2), first);
    Texture caustics = make_float_texture(32, 32);
    const std::vector<float> with_caustics = frame(2, caustics.get(), 1);
    frame(2, caustics.get(), 1);
    EXPECT_EQ(renderer.accumulated_frames(), 1);
    frame(2, caustics.get(), 1);
    EXPECT_EQ(renderer.accumulated_frames(), 2);
    EXPECT_EQ(frame(2, caustics.get(), 2), with_caustics) << "new caustics";
    // Untracked: every frame is frame 0.
    EXPECT_EQ(frame(0), first);
    EXPECT_EQ(frame(0), first);
    EXPECT_EQ(frame(2, caustics.get(), 0), with_caustics);
    EXPECT_EQ(frame(2, caustics.get(), 0), with_caustics);
    // Off: every frame is frame 0.
    scene.settings.frame.accumulate_frames = 1;
    EXPECT_EQ(frame(3), first);
    EXPECT_EQ(frame(3), first);
}

// Settings changed after loading (flags, the viewer) may ask for more light samples than the frame
// holds: an InputError naming the scene, never a silently cut light list.
TEST_F(FrameTest, TooManyLightSamplesAreAnErrorNotACut) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/cornell.json");
    SceneMeshes meshes(scene);
    scene.lights.resize(1);
    scene.lights[0].type = LightType::quad;
    scene.lights[0].corners = {glm::vec3(0, 1, 0), glm::vec3(1, 1, 0), glm::vec3(1, 1, 1),
                               glm::vec3(0, 1, 1)};
    scene.settings.direct.area_light_samples = kMaxLightSamples;  // an 8×8 grid: just fits
    EXPECT_EQ(int(light_samples(scene).size()), kMaxLightSamples);
    scene.settings.direct.area_light_samples = 81;
    try {
        FrameRenderer renderer(scene, meshes, 8, 8);
        FAIL() << "81 light samples accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cornell.json: /lights: "), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(light_samples(scene), InputError);
}

// Every pixel of the room lies in the closed box's shadow volume, so the direct term is black
// exactly. The walls are open meshes and cast one prism per triangle; two walls meeting at a seam
// give two prisms sharing a side face, drawn once each way. Drawn from corners a few ulps apart and
// split along other diagonals, the pair rasterized a few pixels apart along the seams and left
// lit pixels there (10 at 96², up to 0.60; the sweep's 16² images missed them). Shared side faces
// are now left out (they cancel in the count), so nothing is drawn twice.
TEST_F(FrameTest, ALampInAClosedBoxLightsNoPixelAlongTheRoomsSeams) {
    Scene scene = test::room_with_lamp_in_box();
    scene.camera.width = scene.camera.height = 96;
    init_versions(scene);
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    FrameRenderer renderer(scene, meshes, scene.camera.width, scene.camera.height);
    renderer.render(iim.id());
    const FrameImages images = renderer.read_back();
    const Image& direct = images.aov[size_t(FrameTerm::direct)];
    int lit = 0;
    float brightest = 0.0f;
    for (int y = 0; y < direct.height; ++y)
        for (int x = 0; x < direct.width; ++x) {
            const glm::vec3 c = direct.rgb(x, y);
            lit += c != glm::vec3(0.0f) ? 1 : 0;
            brightest = std::max({brightest, c.r, c.g, c.b});
        }
    EXPECT_EQ(lit, 0) << "values in lit pixels up to " << brightest;
    // The same room with the box open at the bottom is lit: the test would see light.
    Scene open = scene;
    test::open_lamp_box_at_the_bottom(open);
    SceneMeshes open_meshes(open);
    FrameRenderer open_renderer(open, open_meshes, open.camera.width, open.camera.height);
    open_renderer.render(iim.id());
    const FrameImages open_images = open_renderer.read_back();
    double sum = 0.0;
    for (float v : open_images.aov[size_t(FrameTerm::direct)].pixels) sum += v;
    EXPECT_GT(sum, 1.0);
}

// The soup casters' weld is made again only when a soup caster (an open mesh: the room's walls)
// moves, not when a closed one (the box) does. The room of the seam test with its ceiling first
// 10 cm up (no corner shared with the walls), drawn, then back in place: the weld must be made
// again, or the ceiling's seams with the walls are drawn from both sides and crack (lit pixels,
// as before the weld). Then the box moves a centimetre (still round the lamp): the weld stays,
// and the direct term is a fresh renderer's, bit for bit.
TEST_F(FrameTest, ShadowVolumesFollowMovedWallsAndBoxes) {
    Scene scene = test::room_with_lamp_in_box();
    scene.camera.width = scene.camera.height = 96;
    scene.settings.frame.accumulate_frames = 1;
    init_versions(scene);
    const int ceiling = 1, box = int(scene.objects.size()) - 1;
    ASSERT_EQ(scene.objects[size_t(ceiling)].name, "ceiling");
    translate_object(scene, ceiling, glm::vec3(0.0f, 0.1f, 0.0f));
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    FrameRenderer renderer(scene, meshes, scene.camera.width, scene.camera.height);
    const auto direct = [&](FrameRenderer& r) {
        r.render(iim.id());
        return r.read_back().aov[size_t(FrameTerm::direct)].pixels;
    };
    const auto lit = [](const std::vector<float>& pixels) {
        return std::count_if(pixels.begin(), pixels.end(), [](float v) { return v != 0.0f; });
    };
    direct(renderer);  // (24 lit pixels with the ceiling apart from the walls: not looked into)
    translate_object(scene, ceiling, glm::vec3(0.0f, -0.1f, 0.0f));
    EXPECT_EQ(lit(direct(renderer)), 0)
        << "the ceiling's seams kept the weld made 10 cm up (15 then)";
    translate_object(scene, box, glm::vec3(0.01f, 0.0f, 0.0f));
    const std::vector<float> moved = direct(renderer);
    EXPECT_EQ(lit(moved), 0);
    SceneMeshes fresh_meshes(scene);
    FrameRenderer fresh(scene, fresh_meshes, scene.camera.width, scene.camera.height);
    EXPECT_EQ(moved, direct(fresh));
}
}  // namespace ag::gpu
