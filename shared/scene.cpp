#include "shared/scene.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/quaternion.hpp>
#include <numbers>
#include <string>

#include "shared/input_error.h"

namespace ag {

glm::mat4 Transform::matrix() const {
    glm::mat4 m = glm::mat4_cast(rotation);
    m[3] = glm::vec4(translation, 1.0f);
    return m;
}

glm::vec3 Light::quad_normal() const {
    return glm::normalize(glm::cross(corners[1] - corners[0], corners[3] - corners[0]));
}

float Light::quad_area() const {
    return glm::length(glm::cross(corners[1] - corners[0], corners[3] - corners[0]));
}

glm::vec3 Light::center() const {
    if (type == LightType::point) return position;
    return 0.25f * (corners[0] + corners[1] + corners[2] + corners[3]);
}

glm::vec3 Light::power() const {
    if (type == LightType::point) return 4.0f * std::numbers::pi_v<float> * intensity;
    return std::numbers::pi_v<float> * quad_area() * radiance;  // Lambertian emitter: Φ = π L A
}

int Scene::find_object(const std::string& object_name) const {
    for (int i = 0; i < int(objects.size()); ++i)
        if (objects[size_t(i)].name == object_name) return i;
    return -1;
}

int Scene::find_light(const std::string& light_name) const {
    for (int i = 0; i < int(lights.size()); ++i)
        if (lights[size_t(i)].name == light_name) return i;
    return -1;
}

Bounds Scene::world_bounds() const {
    Bounds b;
    for (const Object& o : objects)
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    return b;
}

float Scene::diagonal() const {
    const Bounds b = world_bounds();
    return b.empty() ? 1.0f : glm::length(b.extent());
}

size_t Scene::triangle_count() const {
    size_t n = 0;
    for (const Object& o : objects) n += o.mesh.triangles.size();
    return n;
}

int quad_light_grid(const Settings& settings) {
    return std::max(1, int(std::lround(std::sqrt(double(settings.direct.area_light_samples)))));
}

int light_sample_count(const Scene& scene) {
    const int grid = quad_light_grid(scene.settings);
    int count = 0;
    for (const Light& l : scene.lights) count += l.type == LightType::point ? 1 : grid * grid;
    return count;
}

void check_light_samples(const Scene& scene) {
    const int count = light_sample_count(scene);
    if (count <= kMaxLightSamples) return;
    int quads = 0;
    for (const Light& l : scene.lights) quads += l.type == LightType::quad ? 1 : 0;
    const int grid = quad_light_grid(scene.settings);
    throw_input_error(
        scene.path, "/lights",
        std::to_string(scene.lights.size() - size_t(quads)) + " point lights and " +
            std::to_string(quads) + " quad lights of " + std::to_string(grid) + "×" +
            std::to_string(grid) + " samples (settings/direct/area_light_samples = " +
            std::to_string(scene.settings.direct.area_light_samples) + ") make " +
            std::to_string(count) + " light samples; expected at most " +
            std::to_string(kMaxLightSamples) +
            ", what the GPU frame holds (use fewer lights or fewer area_light_samples)");
}

void check_photon_budget(const Scene& scene) {
    const int64_t lights = std::max<int64_t>(1, int64_t(scene.lights.size()));
    const PhotonSettings& p = scene.settings.photons;
    const int64_t photons = int64_t(p.groups) * p.photons_per_group * lights;
    if (photons > kMaxScenePhotons)
        throw_input_error(scene.path, "/settings/photons",
                          "groups (" + std::to_string(p.groups) + ") × photons_per_group (" +
                              std::to_string(p.photons_per_group) + ") × lights (" +
                              std::to_string(lights) + ") = " + std::to_string(photons) +
                              " photons; expected at most " + std::to_string(kMaxScenePhotons));
    const int64_t caustic = int64_t(scene.settings.caustics.photons) * lights;
    if (caustic > kMaxScenePhotons)
        throw_input_error(scene.path, "/settings/caustics/photons",
                          std::to_string(scene.settings.caustics.photons) + " × lights (" +
                              std::to_string(lights) + ") = " + std::to_string(caustic) +
                              " caustic photons; expected at most " +
                              std::to_string(kMaxScenePhotons));
}

}  // namespace ag
