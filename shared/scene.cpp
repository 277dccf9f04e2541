#include "shared/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/quaternion.hpp>
#include <limits>
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

float Light::area() const {
    if (type == LightType::quad) return quad_area();
    if (type == LightType::mesh) return mesh_area;
    return 0.0f;
}

glm::vec3 Light::center() const {
    if (type != LightType::quad) return position;
    return 0.25f * (corners[0] + corners[1] + corners[2] + corners[3]);
}

float Light::cos_outer() const { return std::cos(glm::radians(cone_outer)); }
float Light::cos_inner() const { return std::cos(glm::radians(std::min(cone_inner, cone_outer))); }

float Light::spot_factor(float cos_theta) const {
    if (type != LightType::spot) return 1.0f;
    const float co = cos_outer(), ci = cos_inner();
    if (cos_theta >= ci) return 1.0f;
    if (!(ci > co)) return 0.0f;
    return std::clamp((cos_theta - co) / (ci - co), 0.0f, 1.0f);
}

glm::vec3 Light::power() const {
    constexpr float kPi = std::numbers::pi_v<float>;
    switch (type) {
        case LightType::point:
            return 4.0f * kPi * intensity;
        case LightType::spot: {
            // ∫ f dω = 2π [(1 − cos_i) + (cos_i − cos_o)/2] for f linear in cosθ between the cones.
            const float co = cos_outer(), ci = cos_inner();
            return 2.0f * kPi * ((1.0f - ci) + 0.5f * (ci - co)) * intensity;
        }
        case LightType::sun:
            return kPi * sun_radius * sun_radius * irradiance;  // E through the disc
        default:
            return kPi * area() * radiance;  // Lambertian emitter: Φ = π L A
    }
}

void update_sun_discs(Scene& scene) {
    const Bounds b = scene.world_bounds();
    for (Light& l : scene.lights)
        if (l.type == LightType::sun) {
            l.sun_center = b.empty() ? glm::vec3(0.0f) : b.center();
            l.sun_radius = b.empty() ? 1.0f : 0.505f * glm::length(b.extent());
            l.position = l.sun_center - 2.0f * l.sun_radius * l.direction;  // for display only
        }
}

LightPoint sample_area_light(const Scene& scene, const Light& light, float u, float v) {
    if (light.type == LightType::quad) {
        const glm::vec3 e1 = light.corners[1] - light.corners[0];
        const glm::vec3 e3 = light.corners[3] - light.corners[0];
        return {light.corners[0] + u * e1 + v * e3, light.quad_normal()};
    }
    const Object& o = scene.objects[size_t(light.object)];
    const std::vector<float>& cdf = light.triangle_cdf;
    const size_t t = size_t(std::min<ptrdiff_t>(
        std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin(), ptrdiff_t(cdf.size()) - 1));
    const float lo = t == 0 ? 0.0f : cdf[t - 1];
    const float w = cdf[t] > lo ? std::clamp((u - lo) / (cdf[t] - lo), 0.0f, 1.0f) : 0.5f;
    // Uniform in the triangle: p = (1-√w) a + √w (1-v) b + √w v c.
    const glm::uvec3 tri = o.mesh.triangles[t];
    const float r = std::sqrt(w);
    const glm::vec3 p = (1.0f - r) * o.mesh.positions[tri.x] +
                        r * (1.0f - v) * o.mesh.positions[tri.y] + r * v * o.mesh.positions[tri.z];
    return {o.transform.apply_point(p), o.transform.apply_vector(triangle_normal(o.mesh, int(t)))};
}

void update_mesh_light_positions(Scene& scene, int object) {
    for (Light& l : scene.lights)
        if (l.type == LightType::mesh && l.object == object) {
            const Object& o = scene.objects[size_t(object)];
            l.position = o.transform.apply_point(mesh_bounds(o.mesh).center());
        }
}

void add_mesh_lights(Scene& scene) {
    for (int i = 0; i < int(scene.objects.size()); ++i) {
        const Object& o = scene.objects[size_t(i)];
        const Material& m = o.material;
        if (!m.emits_light || !(std::max({m.emission.x, m.emission.y, m.emission.z}) > 0.0f))
            continue;
        if (scene.find_light(o.name) >= 0)
            throw_input_error(scene.path, "/objects",
                              "object \"" + o.name +
                                  "\" emits light and becomes a mesh light of its name; expected "
                                  "no light named \"" +
                                  o.name + "\" in /lights");
        Light l;
        l.name = o.name;
        l.type = LightType::mesh;
        l.object = i;
        l.radiance = m.emission;
        double total = 0.0;
        l.triangle_cdf.resize(o.mesh.triangles.size());
        for (size_t t = 0; t < o.mesh.triangles.size(); ++t) {
            total += double(triangle_area(o.mesh, int(t)));
            l.triangle_cdf[t] = float(total);
        }
        for (float& c : l.triangle_cdf) c = float(double(c) / total);
        l.triangle_cdf.back() = 1.0f;
        l.mesh_area = float(total);
        scene.lights.push_back(std::move(l));
        update_mesh_light_positions(scene, i);
    }
}

std::vector<int> object_lights(const Scene& scene) {
    std::vector<int> out(scene.objects.size(), -1);
    for (size_t l = 0; l < scene.lights.size(); ++l)
        if (scene.lights[l].type == LightType::mesh) out[size_t(scene.lights[l].object)] = int(l);
    return out;
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

void warn_about_scale(const Scene& scene) {
    const auto num = [](float v) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.3g", double(v));
        return std::string(buf);
    };
    const float diagonal = scene.diagonal();
    const float near_plane = kNearPlanePerDiagonal * diagonal;
    const float offset = kRayOffsetPerDiagonal * diagonal;
    // The nearest vertex, not the nearest point: no false alarm, and it finds a part of the scene
    // far smaller than the whole.
    float nearest = std::numeric_limits<float>::infinity();
    std::string nearest_object, small;
    int small_count = 0;
    for (const Object& o : scene.objects) {
        Bounds b;
        for (const glm::vec3& p : o.mesh.positions) {
            const glm::vec3 w = o.transform.apply_point(p);
            b.add(w);
            const float d = glm::length(w - scene.camera.eye);
            if (d < nearest) {
                nearest = d;
                nearest_object = o.name;
            }
        }
        if (!b.empty() && glm::length(b.extent()) < 10.0f * offset && ++small_count <= 3)
            small +=
                (small.empty() ? "'" : ", '") + o.name + "' (" + num(glm::length(b.extent())) + ")";
    }
    const std::string where =
        scene.path + ": the scene is " + num(diagonal) + " across (its bounds' diagonal); ";
    if (nearest < near_plane)
        warn(where + "object '" + nearest_object + "' has a vertex " + num(nearest) +
             " from the camera, nearer than the frame's near plane (" + num(near_plane) +
             ", 1e-3 of the diagonal): geometry that near is clipped from the frame");
    if (small_count > 0)
        warn(where + std::to_string(small_count) + " object" + (small_count > 1 ? "s are" : " is") +
             " smaller than ten ray offsets (" + num(10.0f * offset) +
             ", the offset 1e-5 of the diagonal), and rays may step over them: " + small +
             (small_count > 3 ? ", ..." : ""));
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
    for (const Light& l : scene.lights) count += l.is_area() ? grid * grid : 1;
    return count;
}

void check_light_samples(const Scene& scene) {
    const int count = light_sample_count(scene);
    if (count <= kMaxLightSamples) return;
    int quads = 0;
    for (const Light& l : scene.lights) quads += l.is_area() ? 1 : 0;
    const int grid = quad_light_grid(scene.settings);
    throw_input_error(
        scene.path, "/lights",
        std::to_string(scene.lights.size() - size_t(quads)) + " point lights and " +
            std::to_string(quads) + " quad or mesh lights of " + std::to_string(grid) + "×" +
            std::to_string(grid) + " samples (settings/direct/area_light_samples = " +
            std::to_string(scene.settings.direct.area_light_samples) + ") make " +
            std::to_string(count) + " light samples; expected at most " +
            std::to_string(kMaxLightSamples) +
            ", what the GPU frame holds (use fewer lights or fewer area_light_samples)");
}

void check_photon_budget(const Scene& scene) {
    const int64_t lights = std::max<int64_t>(1, int64_t(scene.lights.size()));
    const PhotonSettings& p = scene.settings.photons;
    const int64_t photons =
        int64_t(p.groups) * p.photons_per_group * lights * std::max(1, p.refine_layers);
    if (photons > kMaxScenePhotons)
        throw_input_error(
            scene.path, "/settings/photons",
            "groups (" + std::to_string(p.groups) + ") × photons_per_group (" +
                std::to_string(p.photons_per_group) + ") × lights (" + std::to_string(lights) +
                ")" +
                (p.refine_layers > 1 ? " × refine_layers (" + std::to_string(p.refine_layers) + ")"
                                     : std::string()) +
                " = " + std::to_string(photons) + " photons; expected at most " +
                std::to_string(kMaxScenePhotons));
    const int64_t caustic = int64_t(scene.settings.caustics.photons) * lights;
    if (caustic > kMaxScenePhotons)
        throw_input_error(scene.path, "/settings/caustics/photons",
                          std::to_string(scene.settings.caustics.photons) + " × lights (" +
                              std::to_string(lights) + ") = " + std::to_string(caustic) +
                              " caustic photons; expected at most " +
                              std::to_string(kMaxScenePhotons));
}

}  // namespace ag
