// direct.method vpl (Barczak 2006 §4.2): each light sample shadowed by its hemispherical
// octahedral shadow map, against the same samples shadowed by stencil shadow volumes (exact per
// sample), on a quad light (one map per sample) and a point light (two maps back to back).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "../cpu/test_scenes.h"
#include "gl_fixture.h"
#include "gpu/frame_renderer.h"
#include "gpu/lightmap_texture.h"
#include "shared/metrics.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"

namespace ag::gpu {

namespace {

class DirectVplTest : public test::GlTest {};

constexpr int kSize = 48;

// The direct term of one frame of one fixed sample set (no accumulation), no indirect light.
Image direct_term(Scene& scene, DirectMethod method, bool shadows) {
    scene.settings.direct.method = method;
    scene.settings.direct.shadows = shadows;
    scene.settings.direct.accumulate_frames = 1;
    scene.settings.frame.accumulate_frames = 1;
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    iim.update_all(std::vector<glm::vec3>(size_t(scene.atlas.width) * size_t(scene.atlas.height),
                                          glm::vec3(0.0f)));
    FrameRenderer renderer(scene, meshes, kSize, kSize);
    renderer.render(iim.id());
    return renderer.read_back().aov[size_t(FrameTerm::direct)];
}

Scene load(const char* name) {
    Scene scene = load_scene(std::string(AG_SOURCE_DIR) + "/scenes/" + name);
    scene.camera.width = scene.camera.height = kSize;
    return scene;
}

// relMSE of the shadow-mapped direct term against the shadow volumes' and, to show the check can
// fail, of the unshadowed one.
struct Errors {
    double mapped = 0.0, unshadowed = 0.0;
};
Errors errors(Scene& scene) {
    const Image volumes = direct_term(scene, DirectMethod::shadow_volumes, true);
    const Image mapped = direct_term(scene, DirectMethod::vpl, true);
    const Image open = direct_term(scene, DirectMethod::vpl, false);
    return {compare_images(mapped, volumes).rel_mse, compare_images(open, volumes).rel_mse};
}

}  // namespace

// The cube's and the block's soft shadows under compare.json's quad light (16 one-sided
// samples). Fails if the maps are not read (visibility ignored: relMSE 0.13 here), read at the
// wrong layer or side, or leak or self-shadow beyond a texel's worth of edge pixels.
TEST_F(DirectVplTest, QuadLightSamplesShadowedByMapsMatchShadowVolumes) {
    Scene scene = load("compare.json");
    const Errors e = errors(scene);
    EXPECT_LT(e.mapped, 0.005) << "unshadowed: " << e.unshadowed;
    EXPECT_GT(e.unshadowed, 0.05);
}

// cornell.json's point light lights the box all round (two maps per sample); the glass ball and
// the block cast the shadows.
TEST_F(DirectVplTest, PointLightShadowedByTwoHemisphericalMapsMatchesShadowVolumes) {
    Scene scene = load("cornell.json");
    const Errors e = errors(scene);
    EXPECT_LT(e.mapped, 0.005) << "unshadowed: " << e.unshadowed;
    EXPECT_GT(e.unshadowed, 0.05);
}

// The maps follow an edit: after the cube moves, the frame's maps are rendered again (a stale map
// keeps the old shadow where the cube was).
TEST_F(DirectVplTest, MapsFollowAMovedObject) {
    Scene scene = load("compare.json");
    scene.settings.direct.method = DirectMethod::vpl;
    scene.settings.direct.accumulate_frames = 1;
    scene.settings.frame.accumulate_frames = 1;
    int cube = -1;
    for (size_t o = 0; o < scene.objects.size(); ++o)
        if (scene.objects[o].dynamic) cube = int(o);
    ASSERT_GE(cube, 0) << "compare.json has a movable object";
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    iim.update_all(std::vector<glm::vec3>(size_t(scene.atlas.width) * size_t(scene.atlas.height),
                                          glm::vec3(0.0f)));
    FrameRenderer renderer(scene, meshes, kSize, kSize);
    renderer.render(iim.id());
    const Image before = renderer.read_back().aov[size_t(FrameTerm::direct)];
    translate_object(scene, cube, glm::vec3(0.0f, 150.0f, 0.0f));  // lifted: its shadow spreads
    renderer.render(iim.id());
    const Image after = renderer.read_back().aov[size_t(FrameTerm::direct)];
    scene.settings.direct.method = DirectMethod::shadow_volumes;
    set_camera(scene, scene.camera);  // an edit: the mean restarts
    renderer.render(iim.id());
    const Image volumes = renderer.read_back().aov[size_t(FrameTerm::direct)];
    EXPECT_GT(compare_images(before, volumes).rel_mse, 0.01) << "the cube moved far enough";
    EXPECT_LT(compare_images(after, volumes).rel_mse, 0.005);
}

// The sweep's lamp in a closed box (light_in_box_coplanar, and the box 5 cm lower: nothing can
// light the room; pt renders it black) with maps 8 texels across, the sweep's base. The normal
// offset is a quarter of the distance there: it carried ceiling points 5 cm above the lamp below
// the map's horizon, out of the map, where they count as seen, and lit the ceiling beyond 20 cm
// from the lamp (269 and 163 of 2,304 pixels lit at 48² before). The offset is now cut to stay
// above the horizon. What remains is the maps' resolution: a few ceiling pixels next to the box's
// top corners, where a texel's centre sees a corner of the box farther than the receiver (1 and 5
// pixels at 48²; 0 at 16² and 32²). The same box open at the bottom shows the test sees light.
TEST_F(DirectVplTest, ALampInAClosedBoxLightsNoCeilingThroughMapsEightTexelsAcross) {
    for (const float top : {1.0f, 0.95f}) {
        Scene scene = test::room_with_lamp_in_box(top);
        scene.settings.direct.map_size = 8;
        scene.camera.width = scene.camera.height = kSize;
        const Image closed = direct_term(scene, DirectMethod::vpl, true);
        test::open_lamp_box_at_the_bottom(scene);
        const Image open = direct_term(scene, DirectMethod::vpl, true);
        double sum = 0.0, open_sum = 0.0;
        int lit = 0;
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const glm::vec3 c = closed.rgb(x, y);
                sum += double(c.r + c.g + c.b);
                lit += c != glm::vec3(0.0f) ? 1 : 0;
                const glm::vec3 o = open.rgb(x, y);
                open_sum += double(o.r + o.g + o.b);
            }
        std::printf("box top %.2f: %d of %d pixels lit (sum %.3g; the open box %.3g)\n", top, lit,
                    kSize * kSize, sum, open_sum);
        EXPECT_GT(open_sum, 1.0) << "box top " << top;
        EXPECT_LE(lit, kSize * kSize / 200) << "box top " << top;
    }
}

}  // namespace ag::gpu
