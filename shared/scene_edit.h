// The one API through which the scene changes (viewer, Lua scripts, tests). Each edit bumps the
// scene's and the item's version counters and records a SceneChange, so CPU and GPU consumers
// update only what an edit touched (Larsen ch. 9: invalidate the groups an edit can affect).
// Bad indices or non-finite values are user errors (they come from scripts): InputError.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <vector>

#include "shared/scene.h"

namespace ag {

// World-size limit (docs/scene-format.md, "Limits"): every coordinate that reaches Embree or GL —
// vertices as placed, light positions and corners, the camera — lies within ±kMaxCoordinate.
// float has a 24-bit mantissa, so at 1e7 units positions are still resolved to 1 unit and
// differences, squared lengths (≤ 1e15) and Embree's ray extents stay finite.
inline constexpr float kMaxCoordinate = 1e7f;
// Light values (intensity, radiance, emission) at most this, so that sums of photon powers and
// pixel values stay finite in float.
inline constexpr double kMaxLightValue = 1e15;
// Camera field of view where the projection is non-degenerate, degrees.
inline constexpr double kMinFovY = 0.1, kMaxFovY = 179.0;

// Checks shared by the scene loader and the edits: each returns "" when the value is fine, else
// what was expected and what it got.
std::string position_problem(const glm::vec3& p);
std::string light_value_problem(const glm::vec3& value);
// The object's vertices as placed by `t` within the world-size limit (checked through the
// object-space radius, so an edit need not transform every vertex).
std::string placement_problem(const Mesh& mesh, const Transform& t);
// The largest distance of a vertex from the object's origin.
float object_radius(const Mesh& mesh);
// Names the offending camera key ("eye", "target", "up", "fov_y", "resolution") in `key`.
std::string camera_problem(const Camera& camera, std::string& key);
// Unit vector along v, scaled first so that huge or tiny (but non-zero, finite) vectors
// normalise exactly; false for a zero or non-finite v.
bool safe_normalize(const glm::vec3& v, glm::vec3& unit);

// Scripts and the viewer move dynamic objects only (docs/scripting.md): InputError for a static
// one, naming it.
void check_movable(const Scene& scene, int object, const char* what);

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

// Drops the changes with sequence <= seen: whoever owns every consumer of the log (the pipeline)
// calls it with the oldest sequence any of them has yet to see, so the log stays as short as the
// edits no consumer has read, however long the program runs.
void trim_changes(Scene& scene, uint64_t seen);

// Called once after loading: sizes the version arrays.
void init_versions(Scene& scene);

}  // namespace ag
