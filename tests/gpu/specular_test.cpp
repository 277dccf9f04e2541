// The frame's specular term (Larsen ch. 13) against the path tracer: a glass ball lens in front of
// a backdrop of four coloured emitting quadrants refracts at both interfaces and shows them
// upside down and swapped, as pt does; a mirror ball shows its own contact shadow.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <glm/gtc/quaternion.hpp>

#include "cpu/reference/reference.h"
#include "gl_fixture.h"
#include "gpu/frame_renderer.h"
#include "gpu/lightmap_texture.h"
#include "shared/charts.h"
#include "shared/image.h"
#include "shared/scene_edit.h"
#include "shared/shapes.h"

namespace ag::gpu {

namespace {

Object emitter(const std::string& name, glm::vec3 centre, float size, float degrees_about_x,
               glm::vec3 emission) {
    Object o;
    o.name = name;
    o.mesh = make_quad(size, size);
    o.material.albedo = glm::vec3(0.0f);  // black: no light is scattered, only emitted
    o.material.emission = emission;
    o.transform.rotation = glm::angleAxis(glm::radians(degrees_about_x), glm::vec3(1, 0, 0));
    o.transform.translation = centre;
    return o;
}

// A glass ball (radius 1, n = 1.5) at the origin; 4 units behind it a backdrop of four emitting
// quadrants facing the camera (red top left, green top right, blue bottom left, grey bottom
// right as the camera sees them); a dim emitter behind the camera for the ball's reflection. No
// lights and black albedos: what the camera sees through the glass is emission only, so the
// frame's cube maps hold exactly what pt sees.
Scene lens_scene(int size) {
    Scene s;
    s.path = "specular_test";
    // The camera looks along +z; +x is to its left.
    s.objects.push_back(emitter("top_left", {2, 2, 4}, 4, -90, {4, 0.2f, 0.2f}));
    s.objects.push_back(emitter("top_right", {-2, 2, 4}, 4, -90, {0.2f, 4, 0.2f}));
    s.objects.push_back(emitter("bottom_left", {2, -2, 4}, 4, -90, {0.2f, 0.2f, 4}));
    s.objects.push_back(emitter("bottom_right", {-2, -2, 4}, 4, -90, {1, 1, 1}));
    s.objects.push_back(emitter("behind", {0, 0, -12}, 30, 90, {0.5f, 0.5f, 0.5f}));
    Object ball;
    ball.name = "ball";
    ball.mesh = make_sphere(1.0f, 4);
    ball.material.type = MaterialType::glass;
    ball.material.ior = 1.5f;
    ball.dynamic = true;
    s.objects.push_back(ball);
    s.camera.eye = {0.0f, 0.0f, -8.0f};
    s.camera.target = {0.0f, 0.0f, 0.0f};
    s.camera.fov_y = 18.0f;
    s.camera.width = s.camera.height = size;
    s.settings.lightmap.texel_size = 2.0f;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

// A mirror ball (radius 1) resting on a floor, a point light straight above, the camera level
// with the ball's centre: the ball's lower rim reflects the floor around the contact point, which
// lies in the ball's own shadow (radius 6·tan(asin(1/5)) ≈ 1.22 around it).
Scene mirror_scene(int size) {
    Scene s;
    s.path = "specular_test";
    Object floor;
    floor.name = "floor";
    floor.mesh = make_quad(30.0f, 30.0f);
    floor.material.albedo = glm::vec3(0.8f);
    s.objects.push_back(floor);
    Object ball;
    ball.name = "ball";
    ball.mesh = make_sphere(1.0f, 4);
    ball.material.type = MaterialType::mirror;
    ball.transform.translation = {0.0f, 1.0f, 0.0f};
    ball.dynamic = true;
    s.objects.push_back(ball);
    Light l;
    l.name = "lamp";
    l.position = {0.0f, 6.0f, 0.0f};
    l.intensity = glm::vec3(30.0f);
    s.lights.push_back(l);
    s.camera.eye = {0.0f, 1.0f, -8.0f};
    s.camera.target = {0.0f, 1.0f, 0.0f};
    s.camera.fov_y = 18.0f;
    s.camera.width = s.camera.height = size;
    s.settings.lightmap.texel_size = 4.0f;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

Image render_specular(const Scene& scene) {
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);  // zero: no indirect light
    FrameRenderer renderer(scene, meshes, scene.camera.width, scene.camera.height);
    renderer.render(iim.id());
    return renderer.read_back().aov[size_t(FrameTerm::specular)];
}

// Mean colour over pixels inside the disc of radius `r` (pixels) around the image centre,
// within the quadrant given by the signs of dx, dy (0: any).
glm::dvec3 disc_mean(const Image& img, double r, int sx, int sy, double below = -1e9) {
    glm::dvec3 sum(0.0);
    int n = 0;
    const double c = 0.5 * img.width;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const double dx = x + 0.5 - c, dy = y + 0.5 - c;
            if (dx * dx + dy * dy > r * r) continue;
            if (sx * dx < 0.0 || sy * dy < 0.0 || dy < below) continue;
            sum += glm::dvec3(img.rgb(x, y));
            ++n;
        }
    return n ? sum / double(n) : sum;
}

}  // namespace

class SpecularTest : public test::GlTest {};

// The ball's image, against pt: mean within 3% over the ball, and each quadrant of the ball shows
// the backdrop's diagonally opposite quadrant (a ball lens inverts), in both renderers.
TEST_F(SpecularTest, GlassBallInvertsTheBackdropAsPathTracingDoes) {
    const Scene scene = lens_scene(48);
    const Image frame = render_specular(scene);
    ThreadPool pool(2);
    cpu::ReferenceSettings settings;
    settings.spp = 64;
    const Image pt =
        cpu::render_reference(scene, settings, pool).components[size_t(FrameTerm::specular)];
    // The ball's radius in pixels: tan(asin(1/8)) / tan(9°) of the half height.
    const double r = 24.0 * std::tan(std::asin(1.0 / 8.0)) / std::tan(glm::radians(9.0));
    const glm::dvec3 f = disc_mean(frame, 0.97 * r, 0, 0), p = disc_mean(pt, 0.97 * r, 0, 0);
    if (const char* dir = std::getenv("AG_TEST_IMAGES")) {
        write_image(frame, std::string(dir) + "/lens_frame.png");
        write_image(pt, std::string(dir) + "/lens_pt.png");
    }
    std::printf("ball mean: frame %.4f %.4f %.4f, pt %.4f %.4f %.4f\n", f.x, f.y, f.z, p.x, p.y,
                p.z);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[c] / p[c], 1.0, 0.03) << "channel " << c;
    // Image rows go down and +x is on the left: the top-left quadrant of the picture (dx < 0,
    // dy < 0) must show the backdrop's bottom right (grey), the top right its bottom left
    // (blue), the bottom left its top right (green), the bottom right its top left (red).
    for (const Image* img : {&frame, &pt}) {
        const char* who = img == &frame ? "frame" : "pt";
        const glm::dvec3 tl = disc_mean(*img, 0.6 * r, -1, -1),
                         tr = disc_mean(*img, 0.6 * r, 1, -1), bl = disc_mean(*img, 0.6 * r, -1, 1),
                         br = disc_mean(*img, 0.6 * r, 1, 1);
        EXPECT_GT(tr.z, 2.0 * std::max(tr.x, tr.y)) << who << ": top right shows blue";
        EXPECT_GT(bl.y, 2.0 * std::max(bl.x, bl.z)) << who << ": bottom left shows green";
        EXPECT_GT(br.x, 2.0 * std::max(br.y, br.z)) << who << ": bottom right shows red";
        EXPECT_LT(std::abs(tl.x - tl.z), 0.3 * tl.x) << who << ": top left shows grey";
    }
    // Quadrant by quadrant (the whole disc: rims included), the sum of the channels within 5% of
    // pt (single channels of the dim colours depend on where the quadrants' edges fall).
    for (int sy : {-1, 1})
        for (int sx : {-1, 1}) {
            const glm::dvec3 a = disc_mean(frame, 0.97 * r, sx, sy),
                             b = disc_mean(pt, 0.97 * r, sx, sy);
            const double sa = a.x + a.y + a.z, sb = b.x + b.y + b.z;
            std::printf("quadrant %+d,%+d: frame %.4f, pt %.4f\n", sx, sy, sa, sb);
            EXPECT_NEAR(sa / sb, 1.0, 0.05) << "quadrant " << sx << "," << sy;
        }
}

}  // namespace ag::gpu

namespace ag::gpu {

// The cube map holds shadowed direct light: the ball's lower rim shows the contact shadow, as in
// pt (which adds a little light the frame has no IIM for here: the floor lit through the mirror).
TEST_F(SpecularTest, MirrorBallShowsItsOwnContactShadow) {
    const Scene scene = mirror_scene(48);
    const Image frame = render_specular(scene);
    Scene unshadowed = scene;
    unshadowed.settings.direct.shadows = false;
    const Image lit = render_specular(unshadowed);
    ThreadPool pool(2);
    cpu::ReferenceSettings settings;
    settings.spp = 64;
    const Image pt =
        cpu::render_reference(scene, settings, pool).components[size_t(FrameTerm::specular)];
    const double r = 24.0 * std::tan(std::asin(1.0 / 8.0)) / std::tan(glm::radians(9.0));
    // The rim below 0.6 r (image rows go down): the floor within ~0.3 of the contact point.
    const double f = disc_mean(frame, 0.95 * r, 0, 1, 0.6 * r).x,
                 p = disc_mean(pt, 0.95 * r, 0, 1, 0.6 * r).x,
                 u = disc_mean(lit, 0.95 * r, 0, 1, 0.6 * r).x;
    const double whole_f = disc_mean(frame, 0.95 * r, 0, 0).x,
                 whole_p = disc_mean(pt, 0.95 * r, 0, 0).x;
    std::printf("lower rim: frame %.4f, pt %.4f, unshadowed %.4f; ball: frame %.4f, pt %.4f\n", f,
                p, u, whole_f, whole_p);
    EXPECT_LT(f, 0.5 * u) << "the contact shadow is missing";
    EXPECT_NEAR(f, p, 0.1 * u);
    EXPECT_NEAR(whole_f / whole_p, 1.0, 0.05);
}

// The cube maps are kept while nothing they see changes, and rendered again when the scene (here
// the floor's albedo, seen in the mirror) or the indirect term's revision changes: the kept maps
// give exactly what a fresh renderer gives.
TEST_F(SpecularTest, CubeMapsAreKeptUntilWhatTheySeeChanges) {
    Scene scene = mirror_scene(32);
    // One sample per pixel centre: the frames compared are single frames, not running means.
    scene.settings.frame.accumulate_frames = 1;
    SceneMeshes meshes(scene);
    LightmapTexture iim(scene.atlas);
    FrameRenderer renderer(scene, meshes, 32, 32);
    auto mean = [](const Image& img) {
        double sum = 0.0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) sum += double(img.rgb(x, y).g);
        return sum;
    };
    auto specular = [&](FrameRenderer& r, uint64_t revision) {
        r.render(IndirectTerm{iim.id(), IndirectSpace::lightmap, revision});
        return mean(r.read_back().aov[size_t(FrameTerm::specular)]);
    };
    // Renders until the cube maps are current: within kIndirectRefreshFrames renders of a change
    // of the indirect term (a share of the faces a frame), within 6 / kRelitFacesPerFrame of an
    // edit (the faces re-lit one by one), not current before.
    auto settle = [&](FrameRenderer& r, uint64_t revision, size_t limit) {
        double seen = specular(r, revision);
        size_t renders = 1;
        while (!r.cube_maps_current() && renders < 2 * limit) {
            seen = specular(r, revision);
            ++renders;
        }
        EXPECT_TRUE(r.cube_maps_current());
        EXPECT_LE(renders, limit);
        return seen;
    };
    const size_t after_edit = 6 / FrameRenderer::kRelitFacesPerFrame;
    const size_t after_term = FrameRenderer::kIndirectRefreshFrames;
    const double before = specular(renderer, 1);
    EXPECT_TRUE(renderer.cube_maps_current());        // a new term texture: every face at once
    EXPECT_DOUBLE_EQ(specular(renderer, 1), before);  // kept
    set_albedo(scene, scene.find_object("floor"), glm::vec3(0.2f));
    // The edit's frame draws the direct light anew and leaves the faces to the frames after it.
    EXPECT_DOUBLE_EQ(specular(renderer, 1), before) << "the edit's frame renders no face";
    EXPECT_FALSE(renderer.cube_maps_current());
    EXPECT_LT(specular(renderer, 1), before) << "the frame after it renders a share";
    EXPECT_FALSE(renderer.cube_maps_current()) << "a share of the faces a frame";
    const double darker = settle(renderer, 1, after_edit - 1);
    EXPECT_LT(darker, 0.6 * before) << "the mirror must show the darker floor";
    FrameRenderer fresh(scene, meshes, 32, 32);
    EXPECT_DOUBLE_EQ(specular(fresh, 1), darker);
    // In a run of edits (an object moving every frame) only the first frame skips the faces.
    set_albedo(scene, scene.find_object("floor"), glm::vec3(0.3f));
    EXPECT_DOUBLE_EQ(specular(renderer, 1), darker);
    set_albedo(scene, scene.find_object("floor"), glm::vec3(0.4f));
    EXPECT_GT(specular(renderer, 1), darker) << "the second edit's frame renders its share";
    set_albedo(scene, scene.find_object("floor"), glm::vec3(0.2f));
    EXPECT_DOUBLE_EQ(settle(renderer, 1, after_edit), darker);
    // A new indirect term (non-zero now) reaches the mirror only through a new revision.
    std::vector<glm::vec3> lit(size_t(scene.atlas.width) * size_t(scene.atlas.height),
                               glm::vec3(5.0f));
    std::vector<int> all(lit.size());
    for (size_t a = 0; a < all.size(); ++a) all[a] = int(a);
    iim.update(lit, all);
    EXPECT_DOUBLE_EQ(specular(renderer, 1), darker);  // same revision: kept on purpose
    EXPECT_TRUE(renderer.cube_maps_current());
    specular(renderer, 2);
    EXPECT_FALSE(renderer.cube_maps_current());
    const double lit_up = settle(renderer, 2, after_term);
    EXPECT_GT(lit_up, darker);
    FrameRenderer fresh2(scene, meshes, 32, 32);
    EXPECT_DOUBLE_EQ(specular(fresh2, 2), lit_up);
    // A frame that has other drawing to catch up on (the pipeline's caustics) re-lights no face
    // (relit_faces 0): the faces wait, counted, for the next frame; each other frame re-lights
    // kRelitFacesPerFrame.
    set_albedo(scene, scene.find_object("floor"), glm::vec3(0.6f));
    specular(renderer, 2);  // the edit's frame
    EXPECT_EQ(renderer.faces_relit(), 0u);
    const size_t stale = renderer.faces_to_relight();
    EXPECT_EQ(stale, 6u);
    for (int f = 0; f < 3; ++f) {
        renderer.render(IndirectTerm{iim.id(), IndirectSpace::lightmap, 2}, 0, 0, 0);
        EXPECT_EQ(renderer.faces_relit(), 0u);
        EXPECT_EQ(renderer.faces_to_relight(), stale);
        EXPECT_EQ(renderer.cube_faces_ms(), 0.0);
    }
    specular(renderer, 2);
    EXPECT_EQ(renderer.faces_relit(), FrameRenderer::kRelitFacesPerFrame);
    EXPECT_EQ(renderer.faces_to_relight(), stale - FrameRenderer::kRelitFacesPerFrame);
    EXPECT_GT(renderer.cube_faces_ms(), 0.0);
}

}  // namespace ag::gpu
