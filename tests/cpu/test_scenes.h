// Scenes built in code for the CPU tests.
#pragma once

#include <glm/gtc/quaternion.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "shared/charts.h"
#include "shared/scene.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/shapes.h"

namespace ag::test {

// The uniform texel layout (one texel size per chart, no tiles) and one photon set: the settings
// a test calibrated on them states, so that it holds whatever the defaults. Set before the
// scene's atlas is made (or call settings_changed after).
inline void uniform_layout_one_set(Settings& s) {
    s.lightmap.refine_factor = 1;
    s.lightmap.refine_budget = 2.0f;
    s.lightmap.refine_tile = 0;
    s.lightmap.refine_reach = 0.0f;
    s.photons.refine_layers = 1;
}

inline std::string scene_path(const std::string& name) {
    return std::string(AG_SOURCE_DIR) + "/scenes/" + name;
}

// A closed cube of side `size` centred at the origin, all faces facing inwards, albedo ρ, one
// point light of intensity I at the centre.
inline Scene closed_box(float albedo, float intensity, int groups, int per_group) {
    Scene s;
    s.path = "closed_box";
    Object box;
    box.name = "box";
    box.mesh = make_box(glm::vec3(2.0f));
    for (glm::uvec3& t : box.mesh.triangles) std::swap(t.y, t.z);  // inward
    box.material.albedo = glm::vec3(albedo);
    s.objects.push_back(box);
    Light l;
    l.name = "lamp";
    l.position = glm::vec3(0.1f, 0.2f, -0.05f);
    l.intensity = glm::vec3(intensity);
    s.lights.push_back(l);
    s.settings.photons.groups = groups;
    s.settings.photons.photons_per_group = per_group;
    s.settings.photons.max_bounces = 2000;
    s.settings.lightmap.texel_size = 0.5f;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

// A large diffuse plane (normal +Y) under a point light at height h.
inline Scene plane_under_light(float half_size, float height, float intensity, float albedo) {
    Scene s;
    s.path = "plane_under_light";
    Object plane;
    plane.name = "plane";
    plane.mesh = make_quad(2.0f * half_size, 2.0f * half_size);
    plane.material.albedo = glm::vec3(albedo);
    s.objects.push_back(plane);
    Light l;
    l.name = "lamp";
    l.position = glm::vec3(0.0f, height, 0.0f);
    l.intensity = glm::vec3(intensity);
    s.lights.push_back(l);
    init_versions(s);
    return s;
}

// A ceiling quad at height `ceiling_y` facing down and a closed box of side 0.3 (faces outwards)
// whose top lies at y = 1, in the ceiling's plane by default (the robustness sweep's
// light_in_box_coplanar case): the box static or dynamic. Objects: 0 ceiling, 1 box.
inline constexpr glm::vec3 kBoxUnderCeilingCentre(0.5f, 0.85f, 0.5f);
inline Scene box_under_ceiling(bool dynamic_box, float ceiling_y = 1.0f) {
    Scene s;
    s.path = "box_under_ceiling";
    Object ceiling;
    ceiling.name = "ceiling";
    ceiling.mesh = make_quad(1.0f, 1.0f);
    ceiling.transform.translation = glm::vec3(0.5f, ceiling_y, 0.5f);
    ceiling.transform.rotation =
        glm::angleAxis(std::numbers::pi_v<float>, glm::vec3(1.0f, 0.0f, 0.0f));
    s.objects.push_back(ceiling);
    Object box;
    box.name = "box";
    box.mesh = make_box(glm::vec3(0.3f));
    box.transform.translation = kBoxUnderCeilingCentre;
    box.dynamic = dynamic_box;
    s.objects.push_back(box);
    init_versions(s);
    return s;
}

// Rays from four lamp positions inside that box up through a 24 × 24 grid of points on its top
// (the lamp's photons): {origin, direction}.
struct TestRay {
    glm::vec3 origin, direction;
};
inline std::vector<TestRay> rays_up_through_the_box_top() {
    std::vector<TestRay> rays;
    for (const glm::vec3 lamp : {glm::vec3(0.5f, 0.946f, 0.5f), glm::vec3(0.41f, 0.8f, 0.57f),
                                 glm::vec3(0.6f, 0.99f, 0.43f), glm::vec3(0.5f, 0.71f, 0.5f)})
        for (int i = 0; i < 24; ++i)
            for (int j = 0; j < 24; ++j) {
                const glm::vec3 to(0.36f + 0.28f * (float(i) + 0.5f) / 24.0f, 1.0f,
                                   0.36f + 0.28f * (float(j) + 0.5f) / 24.0f);
                rays.push_back({lamp, to - lamp});
            }
    return rays;
}

// The robustness sweep's one-unit Cornell room (five quads, each turned into place, so the corners
// two walls share differ in their last bits), its lamp inside the closed box of side 0.3 turned by
// −17° whose top lies at `box_top` (1: in the ceiling's plane, light_in_box_coplanar). No light
// can leave the box: pt renders every term black. Objects: floor, ceiling, back, left and right
// walls, box. A 16² camera looks in through the open front.
inline Scene room_with_lamp_in_box(float box_top = 1.0f) {
    Scene s;
    s.path = "room_with_lamp_in_box";
    const auto wall = [&](const char* name, glm::vec3 at, glm::vec3 axis, float degrees) {
        Object o;
        o.name = name;
        o.mesh = make_quad(1.0f, 1.0f);
        o.transform.translation = at;
        if (degrees != 0.0f) o.transform.rotation = glm::angleAxis(glm::radians(degrees), axis);
        s.objects.push_back(o);
    };
    wall("floor", {0.5f, 0.0f, 0.5f}, {1, 0, 0}, 0.0f);
    wall("ceiling", {0.5f, 1.0f, 0.5f}, {1, 0, 0}, 180.0f);
    wall("back_wall", {0.5f, 0.5f, 1.0f}, {1, 0, 0}, -90.0f);
    wall("left_wall", {1.0f, 0.5f, 0.5f}, {0, 0, 1}, 90.0f);
    wall("right_wall", {0.0f, 0.5f, 0.5f}, {0, 0, 1}, -90.0f);
    Object box;
    box.name = "box";
    box.mesh = make_box(glm::vec3(0.3f));
    box.transform.translation = {0.5f, box_top - 0.15f, 0.5f};
    box.transform.rotation = glm::angleAxis(glm::radians(-17.0f), glm::vec3(0, 1, 0));
    s.objects.push_back(box);
    Light l;
    l.name = "lamp";
    l.position = {0.5f, box_top - 0.054f, 0.5f};
    l.intensity = glm::vec3(1.3f, 1.1f, 0.8f);
    s.lights.push_back(l);
    s.camera.eye = {0.5f, 0.5f, -1.44f};
    s.camera.target = {0.5f, 0.5f, 0.0f};
    s.camera.fov_y = 39.3f;
    s.camera.width = s.camera.height = 16;
    s.settings.lightmap.texel_size = 0.2f;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

// The same box opened at the bottom (its faces below y = -0.1 in its own frame removed): the
// lamp then lights the room, so a test that expects black can show that it would see light.
inline void open_lamp_box_at_the_bottom(Scene& s) {
    Mesh& m = s.objects.back().mesh;
    std::erase_if(m.triangles, [&](const glm::uvec3& t) {
        return m.positions[t.x].y < -0.1f && m.positions[t.y].y < -0.1f &&
               m.positions[t.z].y < -0.1f;
    });
    init_versions(s);
}

}  // namespace ag::test
