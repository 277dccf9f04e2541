// Scenes built in code for the CPU tests.
#pragma once

#include <string>

#include "shared/charts.h"
#include "shared/scene.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/shapes.h"

namespace ag::test {

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

}  // namespace ag::test
