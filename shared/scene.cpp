#include "shared/scene.h"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/quaternion.hpp>

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
    constexpr float kPi = 3.14159265358979f;
    if (type == LightType::point) return 4.0f * kPi * intensity;
    return kPi * quad_area() * radiance;  // Lambertian emitter: Φ = π L A
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

}  // namespace ag
