#include "shared/scene_edit.h"

#include <cmath>
#include <glm/gtc/quaternion.hpp>
#include <string>

#include "shared/input_error.h"

namespace ag {

namespace {

bool finite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void check_object(const Scene& scene, int object, const char* what) {
    if (object < 0 || object >= int(scene.objects.size()))
        throw_input_error(scene.path, what, "no object with index " + std::to_string(object));
}

void check_light(const Scene& scene, int light, const char* what) {
    if (light < 0 || light >= int(scene.lights.size()))
        throw_input_error(scene.path, what, "no light with index " + std::to_string(light));
}

void check_finite(const Scene& scene, const glm::vec3& v, const char* what) {
    if (!finite(v)) throw_input_error(scene.path, what, "expected finite numbers");
}

void record(Scene& scene, ChangeKind kind, int index) {
    ++scene.version;
    if (kind == ChangeKind::object_transform || kind == ChangeKind::object_material)
        scene.object_versions[size_t(index)] = scene.version;
    else if (kind == ChangeKind::camera)
        scene.camera_version = scene.version;
    else
        scene.light_versions[size_t(index)] = scene.version;
    // Coalesce repeated edits of the same thing between two consumer reads is up to the
    // consumer; the log stays complete and ordered.
    scene.changes.push_back(SceneChange{scene.version, kind, index});
}

}  // namespace

void init_versions(Scene& scene) {
    scene.object_versions.assign(scene.objects.size(), 0);
    scene.light_versions.assign(scene.lights.size(), 0);
}

void set_object_transform(Scene& scene, int object, const Transform& transform) {
    check_object(scene, object, "set_object_transform");
    check_finite(scene, transform.translation, "set_object_transform");
    const glm::quat q = transform.rotation;
    if (!std::isfinite(q.w) || !finite(glm::vec3(q.x, q.y, q.z)) || glm::length(q) < 1e-6f)
        throw_input_error(scene.path, "set_object_transform",
                          "expected a finite non-zero rotation");
    Object& o = scene.objects[size_t(object)];
    o.transform.translation = transform.translation;
    o.transform.rotation = glm::normalize(q);
    record(scene, ChangeKind::object_transform, object);
}

void translate_object(Scene& scene, int object, const glm::vec3& offset) {
    check_object(scene, object, "translate_object");
    Transform t = scene.objects[size_t(object)].transform;
    t.translation += offset;
    set_object_transform(scene, object, t);
}

void rotate_object(Scene& scene, int object, const glm::vec3& axis, float degrees) {
    check_object(scene, object, "rotate_object");
    check_finite(scene, axis, "rotate_object");
    if (!std::isfinite(degrees) || glm::length(axis) < 1e-12f)
        throw_input_error(scene.path, "rotate_object",
                          "expected a non-zero axis and finite degrees");
    Transform t = scene.objects[size_t(object)].transform;
    t.rotation = glm::angleAxis(glm::radians(degrees), glm::normalize(axis)) * t.rotation;
    set_object_transform(scene, object, t);
}

void set_albedo(Scene& scene, int object, const glm::vec3& albedo) {
    check_object(scene, object, "set_albedo");
    check_finite(scene, albedo, "set_albedo");
    if (glm::any(glm::lessThan(albedo, glm::vec3(0.0f))) ||
        glm::any(glm::greaterThan(albedo, glm::vec3(1.0f))))
        throw_input_error(scene.path, "set_albedo", "expected albedo components in [0, 1]");
    scene.objects[size_t(object)].material.albedo = albedo;
    record(scene, ChangeKind::object_material, object);
}

void set_light_position(Scene& scene, int light, const glm::vec3& position) {
    check_light(scene, light, "set_light_position");
    check_finite(scene, position, "set_light_position");
    Light& l = scene.lights[size_t(light)];
    if (l.type == LightType::point) {
        l.position = position;
    } else {
        const glm::vec3 offset = position - l.center();
        for (glm::vec3& c : l.corners) c += offset;
    }
    record(scene, ChangeKind::light_position, light);
}

void set_light_color(Scene& scene, int light, const glm::vec3& value) {
    check_light(scene, light, "set_light_color");
    check_finite(scene, value, "set_light_color");
    if (glm::any(glm::lessThan(value, glm::vec3(0.0f))))
        throw_input_error(scene.path, "set_light_color", "expected non-negative intensity");
    Light& l = scene.lights[size_t(light)];
    l.value() = value;
    record(scene, ChangeKind::light_power, light);
}

void set_light_enabled(Scene& scene, int light, bool enabled) {
    check_light(scene, light, "set_light_enabled");
    scene.lights[size_t(light)].enabled = enabled;
    record(scene, ChangeKind::light_enabled, light);
}

void set_camera(Scene& scene, const Camera& camera) {
    check_finite(scene, camera.eye, "set_camera");
    check_finite(scene, camera.target, "set_camera");
    check_finite(scene, camera.up, "set_camera");
    if (glm::length(camera.target - camera.eye) <= 0.0f ||
        glm::length(glm::cross(camera.target - camera.eye, camera.up)) <= 0.0f)
        throw_input_error(scene.path, "set_camera",
                          "expected eye ≠ target and up not parallel to the view");
    if (!(camera.fov_y > 0.0f && camera.fov_y < 180.0f) || camera.width <= 0 || camera.height <= 0)
        throw_input_error(scene.path, "set_camera",
                          "expected 0 < fov_y < 180 and a positive resolution");
    scene.camera = camera;
    record(scene, ChangeKind::camera, -1);
}

std::vector<SceneChange> changes_since(const Scene& scene, uint64_t since) {
    std::vector<SceneChange> out;
    // The log is ordered by sequence; find the first newer one from the back.
    size_t i = scene.changes.size();
    while (i > 0 && scene.changes[i - 1].sequence > since) --i;
    out.assign(scene.changes.begin() + std::ptrdiff_t(i), scene.changes.end());
    return out;
}

}  // namespace ag
