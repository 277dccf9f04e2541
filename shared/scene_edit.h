// The one API through which the scene changes (viewer, Lua scripts, tests). Each edit bumps the
// scene's and the item's version counters and records a SceneChange, so CPU and GPU consumers
// update only what an edit touched (Larsen ch. 9: invalidate the groups an edit can affect).
// Bad indices or non-finite values are user errors (they come from scripts): InputError.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <vector>

#include "shared/scene.h"

namespace ag {

void set_object_transform(Scene& scene, int object, const Transform& transform);
void translate_object(Scene& scene, int object, const glm::vec3& offset);
// Rotates about the object's own origin (its translation), by `degrees` around world `axis`.
void rotate_object(Scene& scene, int object, const glm::vec3& axis, float degrees);
void set_albedo(Scene& scene, int object, const glm::vec3& albedo);

void set_light_position(Scene& scene, int light,
                        const glm::vec3& position);                     // quads: moves the centre
void set_light_color(Scene& scene, int light, const glm::vec3& value);  // intensity or radiance
void set_light_enabled(Scene& scene, int light, bool enabled);

void set_camera(Scene& scene, const Camera& camera);

// Changes with sequence > since, oldest first.
std::vector<SceneChange> changes_since(const Scene& scene, uint64_t since);

// Called once after loading: sizes the version arrays.
void init_versions(Scene& scene);

}  // namespace ag
