#include "shared/scene_edit.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/quaternion.hpp>
#include <string>

#include "shared/input_error.h"
#include "shared/json_read.h"

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

std::string format_vec(const glm::vec3& v) {
    return "[" + JsonInput::format_number(v.x) + ", " + JsonInput::format_number(v.y) + ", " +
           JsonInput::format_number(v.z) + "]";
}

float max_abs(const glm::vec3& v) {
    return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z)));
}

const std::string kLimitText = JsonInput::format_number(kMaxCoordinate);

}  // namespace

bool safe_normalize(const glm::vec3& v, glm::vec3& unit) {
    const float m = max_abs(v);
    if (!finite(v) || !(m > 0.0f)) return false;
    unit = glm::normalize(v / m);
    return true;
}

std::string position_problem(const glm::vec3& p) {
    if (finite(p) && max_abs(p) <= kMaxCoordinate) return "";
    return "expected coordinates within ±" + kLimitText + " (the world-size limit), got " +
           format_vec(p);
}

std::string light_value_problem(const glm::vec3& value) {
    if (finite(value) && glm::all(glm::greaterThanEqual(value, glm::vec3(0.0f))) &&
        max_abs(value) <= kMaxLightValue)
        return "";
    return "expected components in [0, " + JsonInput::format_number(kMaxLightValue) + "], got " +
           format_vec(value);
}

float object_radius(const Mesh& mesh) {
    float radius = 0.0f;
    for (const glm::vec3& p : mesh.positions) radius = std::max(radius, glm::length(p));
    return radius;
}

std::string placement_problem(const Mesh& mesh, const Transform& t) {
    const float radius = object_radius(mesh);
    if (finite(t.translation) && double(max_abs(t.translation)) + radius <= kMaxCoordinate)
        return "";
    return "expected the placed object within ±" + kLimitText +
           " (the world-size limit), got translation " + format_vec(t.translation) +
           " for an object reaching " + JsonInput::format_number(radius) + " from its origin";
}

std::string camera_problem(const Camera& c, std::string& key) {
    for (const auto& [name, p] : {std::pair{"eye", c.eye}, std::pair{"target", c.target}})
        if (std::string problem = position_problem(p); !problem.empty()) {
            key = name;
            return problem;
        }
    // The view must stay resolvable in float next to the coordinates' own rounding.
    const glm::vec3 view = c.target - c.eye;
    const float scale = std::max(1.0f, std::max(max_abs(c.eye), max_abs(c.target)));
    if (!(max_abs(view) > 1e-5f * scale)) {
        key = "target";
        return "expected a target different from the eye " + format_vec(c.eye) + ", got " +
               format_vec(c.target);
    }
    glm::vec3 forward, up;
    safe_normalize(view, forward);
    if (!safe_normalize(c.up, up) || glm::length(glm::cross(forward, up)) < 1e-4f) {
        key = "up";
        return "expected an up vector not parallel to the view direction " + format_vec(view) +
               ", got " + format_vec(c.up);
    }
    if (!(c.fov_y >= kMinFovY && c.fov_y <= kMaxFovY)) {
        key = "fov_y";
        return "expected a number in [" + JsonInput::format_number(kMinFovY) + ", " +
               JsonInput::format_number(kMaxFovY) + "], got " + JsonInput::format_number(c.fov_y);
    }
    if (c.width <= 0 || c.height <= 0) {
        key = "resolution";
        return "expected a positive resolution, got " + std::to_string(c.width) + "x" +
               std::to_string(c.height);
    }
    return "";
}

void check_movable(const Scene& scene, int object, const char* what) {
    check_object(scene, object, what);
    const Object& o = scene.objects[size_t(object)];
    if (!o.dynamic)
        throw_input_error(
            scene.path, what,
            "object '" + o.name + "' is static; mark it \"dynamic\": true in the scene to move it");
}

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
    const Transform placed{transform.translation, glm::normalize(q)};
    if (std::string problem = placement_problem(o.mesh, placed); !problem.empty())
        throw_input_error(scene.path, "set_object_transform",
                          "object '" + o.name + "': " + problem);
    scene.before_edit();
    o.transform = placed;
    record(scene, ChangeKind::object_transform, object);
    // A mesh light moves with its object: its photons leave from the new place.
    update_mesh_light_positions(scene, object);
    for (size_t l = 0; l < scene.lights.size(); ++l)
        if (scene.lights[l].type == LightType::mesh && scene.lights[l].object == object)
            record(scene, ChangeKind::light_position, int(l));
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
    glm::vec3 unit;
    if (!std::isfinite(degrees) || !safe_normalize(axis, unit))
        throw_input_error(scene.path, "rotate_object",
                          "expected a non-zero axis and finite degrees");
    Transform t = scene.objects[size_t(object)].transform;
    t.rotation = glm::angleAxis(glm::radians(degrees), unit) * t.rotation;
    set_object_transform(scene, object, t);
}

void set_albedo(Scene& scene, int object, const glm::vec3& albedo) {
    check_object(scene, object, "set_albedo");
    check_finite(scene, albedo, "set_albedo");
    if (glm::any(glm::lessThan(albedo, glm::vec3(0.0f))) ||
        glm::any(glm::greaterThan(albedo, glm::vec3(1.0f))))
        throw_input_error(scene.path, "set_albedo", "expected albedo components in [0, 1]");
    scene.before_edit();
    scene.objects[size_t(object)].material.albedo = albedo;
    record(scene, ChangeKind::object_material, object);
}

void set_light_position(Scene& scene, int light, const glm::vec3& position) {
    check_light(scene, light, "set_light_position");
    check_finite(scene, position, "set_light_position");
    Light& l = scene.lights[size_t(light)];
    if (l.type == LightType::mesh)
        throw_input_error(
            scene.path, "set_light_position",
            "light '" + l.name + "' is a mesh light; expected an edit of its object's transform");
    if (l.type == LightType::sun)
        throw_input_error(scene.path, "set_light_position",
                          "light '" + l.name + "' is a sun; it has a direction, not a position");
    Light moved = l;
    if (l.type == LightType::point || l.type == LightType::spot) {
        moved.position = position;
        if (std::string problem = position_problem(position); !problem.empty())
            throw_input_error(scene.path, "set_light_position", problem);
    } else {
        const glm::vec3 offset = position - l.center();
        for (glm::vec3& c : moved.corners) {
            c += offset;
            if (std::string problem = position_problem(c); !problem.empty())
                throw_input_error(scene.path, "set_light_position", "corner: " + problem);
        }
    }
    scene.before_edit();
    l = moved;
    record(scene, ChangeKind::light_position, light);
}

void set_light_color(Scene& scene, int light, const glm::vec3& value) {
    check_light(scene, light, "set_light_color");
    check_finite(scene, value, "set_light_color");
    if (glm::any(glm::lessThan(value, glm::vec3(0.0f))))
        throw_input_error(scene.path, "set_light_color", "expected non-negative intensity");
    if (std::string problem = light_value_problem(value); !problem.empty())
        throw_input_error(scene.path, "set_light_color", problem);
    scene.before_edit();
    Light& l = scene.lights[size_t(light)];
    l.value() = value;
    // A mesh light's radiance is its object's emission: both are seen and lit by the same value.
    if (l.type == LightType::mesh) scene.objects[size_t(l.object)].material.emission = value;
    record(scene, ChangeKind::light_power, light);
}

void set_light_enabled(Scene& scene, int light, bool enabled) {
    check_light(scene, light, "set_light_enabled");
    scene.before_edit();
    scene.lights[size_t(light)].enabled = enabled;
    record(scene, ChangeKind::light_enabled, light);
}

void set_camera(Scene& scene, const Camera& camera) {
    check_finite(scene, camera.eye, "set_camera");
    check_finite(scene, camera.target, "set_camera");
    check_finite(scene, camera.up, "set_camera");
    std::string key;
    if (std::string problem = camera_problem(camera, key); !problem.empty())
        throw_input_error(scene.path, "set_camera", key + ": " + problem);
    // The workers never read the camera, but the change log they read grows here.
    scene.before_edit();
    scene.camera = camera;
    record(scene, ChangeKind::camera, -1);
}

void trim_changes(Scene& scene, uint64_t seen) {
    std::erase_if(scene.changes, [seen](const SceneChange& c) { return c.sequence <= seen; });
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
