#include "tools/afterglow/view_controller.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/rotate_vector.hpp>

#include "shared/camera.h"
#include "shared/input_error.h"
#include "shared/scene_edit.h"

namespace ag::cli {

namespace {

constexpr float kDegreesPerPixel = 0.3f;
constexpr float kTurnDegrees = 15.0f;      // R / Shift+R
constexpr float kLightPickPixels = 10.0f;  // a click this close to a light's centre selects it
constexpr float kMinPolar = 5.0f;          // degrees kept between the view and the up axis

// The world axis closest to `v`: dragging on a tilted plane would lift objects off the floor.
glm::vec3 nearest_axis(const glm::vec3& v) {
    const glm::vec3 a = glm::abs(v);
    const int i = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    glm::vec3 axis(0.0f);
    axis[i] = v[i] < 0.0f ? -1.0f : 1.0f;
    return axis;
}

bool same_camera(const Camera& a, const Camera& b) {
    return a.eye == b.eye && a.target == b.target && a.up == b.up && a.fov_y == b.fov_y;
}

// Turns `v` about `axis` by `degrees`, keeping it at least kMinPolar from ±up when `up` is given.
glm::vec3 turned(const glm::vec3& v, float yaw, float pitch, const glm::vec3& up) {
    glm::vec3 r = glm::rotate(v, glm::radians(yaw), up);
    const glm::vec3 right = glm::normalize(glm::cross(r, up));
    const float polar =
        glm::degrees(std::acos(std::clamp(glm::dot(glm::normalize(r), up), -1.0f, 1.0f)));
    // Pitch moves the polar angle by −pitch about `right`; clamp the result into the allowed band.
    const float wanted = std::clamp(polar - pitch, kMinPolar, 180.0f - kMinPolar);
    return glm::rotate(r, glm::radians(polar - wanted), right);
}

}  // namespace

ViewController::ViewController(Scene& scene, int width, int height)
    : scene_(scene), width_(width), height_(height) {
    rays_ = std::make_unique<cpu::RayTracer>(scene_);
    home_ = scene_.camera;
    camera_ = scene_.camera;
    world_up_ = nearest_axis(glm::normalize(scene_.camera.up));
    Bounds b;
    for (const Object& o : scene_.objects)
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    scene_size_ = b.empty() ? 1.0f : std::max(1e-6f, glm::length(b.extent()));
}

ViewController::~ViewController() = default;

Camera ViewController::frame_camera() const {
    Camera c = camera_dirty_ ? camera_ : scene_.camera;
    c.width = width_;
    c.height = height_;
    return c;
}

Camera& ViewController::camera() {
    if (!camera_dirty_) camera_ = scene_.camera;  // a script may have moved it
    camera_dirty_ = true;
    return camera_;
}

void ViewController::reset_camera() { camera() = home_; }

void ViewController::orbit(float dx, float dy) {
    Camera& c = camera();
    const glm::vec3 offset = c.eye - c.target;
    c.eye = c.target + turned(offset, -dx * kDegreesPerPixel, dy * kDegreesPerPixel, world_up_);
}

void ViewController::pan(float dx, float dy) {
    Camera& c = camera();
    const glm::vec3 forward = glm::normalize(c.target - c.eye);
    const glm::vec3 right = glm::normalize(glm::cross(forward, c.up));
    const glm::vec3 up = glm::cross(right, forward);
    // One pixel at the target's distance, so the point under the cursor follows it.
    const float pixel = 2.0f * glm::length(c.target - c.eye) *
                        std::tan(glm::radians(c.fov_y) * 0.5f) / float(height_);
    const glm::vec3 move = (-dx * right + dy * up) * pixel;
    c.eye += move;
    c.target += move;
}

void ViewController::dolly(float steps) {
    Camera& c = camera();
    const glm::vec3 forward = glm::normalize(c.target - c.eye);
    const float distance =
        std::max(1e-3f * scene_size_, glm::length(c.target - c.eye) * std::pow(0.85f, steps));
    c.eye = c.target - forward * distance;
}

void ViewController::advance(double dt) {
    const float step = float(dt) * 0.5f * scene_size_ * speed_boost_;
    const float forward_amount = float(held_[0]) - float(held_[1]);
    const float right_amount = float(held_[3]) - float(held_[2]);
    const float up_amount = float(held_[4]) - float(held_[5]);
    if (forward_amount == 0.0f && right_amount == 0.0f && up_amount == 0.0f) return;
    Camera& c = camera();
    const glm::vec3 forward = glm::normalize(c.target - c.eye);
    const glm::vec3 right = glm::normalize(glm::cross(forward, c.up));
    const glm::vec3 move =
        step * (forward_amount * forward + right_amount * right + up_amount * world_up_);
    c.eye += move;
    c.target += move;
}

glm::vec3 ViewController::item_position(const Selection& s) const {
    if (s.kind == Selection::Kind::object)
        return scene_.objects[size_t(s.index)].transform.translation;
    if (s.kind == Selection::Kind::light) return scene_.lights[size_t(s.index)].center();
    return glm::vec3(0.0f);
}

Selection ViewController::pick(float x, float y) {
    const Camera c = frame_camera();
    // Lights first: they are points (or thin quads) that a ray would rarely hit.
    const glm::mat4 view_projection =
        projection_matrix(c, 1e-3f * scene_size_, 10.0f * scene_size_) * view_matrix(c);
    Selection best;
    float best_distance = kLightPickPixels;
    for (size_t l = 0; l < scene_.lights.size(); ++l) {
        const glm::vec4 clip = view_projection * glm::vec4(scene_.lights[l].center(), 1.0f);
        if (clip.w <= 0.0f) continue;
        const glm::vec2 pixel((clip.x / clip.w + 1.0f) * 0.5f * float(width_),
                              (1.0f - clip.y / clip.w) * 0.5f * float(height_));
        const float d = glm::length(pixel - glm::vec2(x, y));
        if (d <= best_distance) {
            best_distance = d;
            best = {Selection::Kind::light, int(l)};
        }
    }
    if (best.kind != Selection::Kind::none) return best;
    rays_->update(scene_);
    cpu::Ray ray;
    ray.origin = c.eye;
    ray.direction = camera_ray_direction(c, x, y);
    const cpu::RayHit hit = rays_->intersect(ray);
    if (hit.hit) return {Selection::Kind::object, hit.object};
    return {};
}

void ViewController::select(const Selection& selection, ViewState& state) {
    if (selection == state.selection) return;
    state.selection = selection;
    if (selection.kind == Selection::Kind::object)
        state.message("selected object '" + scene_.objects[size_t(selection.index)].name + "'");
    else if (selection.kind == Selection::Kind::light)
        state.message("selected light '" + scene_.lights[size_t(selection.index)].name + "'");
}

std::optional<glm::vec3> ViewController::on_plane(const Drag& d, float x, float y) const {
    const Camera c = frame_camera();
    const glm::vec3 dir = camera_ray_direction(c, x, y);
    const float denom = glm::dot(dir, d.plane_normal);
    if (std::abs(denom) < 1e-4f) return std::nullopt;
    const float t = glm::dot(d.plane_point - c.eye, d.plane_normal) / denom;
    if (t <= 0.0f) return std::nullopt;
    const glm::vec3 p = c.eye + t * dir;
    // Near the horizon a pixel spans a huge distance; keep the item within reach.
    if (glm::length(p - d.plane_point) > 2.0f * scene_size_) return std::nullopt;
    return p;
}

bool ViewController::handle(const InputEvent& e, ViewState& state) {
    const glm::vec2 mouse(e.x, e.y);
    switch (e.type) {
        case InputType::mouse_down: {
            last_mouse_ = mouse;
            if (e.button == MouseButton::right) right_down_ = true;
            if (e.button == MouseButton::middle) middle_down_ = true;
            if (e.button != MouseButton::left) return true;
            const Selection s = pick(e.x, e.y);
            select(s, state);
            if (s.kind == Selection::Kind::none) return true;
            if (s.kind == Selection::Kind::object && !scene_.objects[size_t(s.index)].dynamic) {
                state.message(
                    "'" + scene_.objects[size_t(s.index)].name +
                    "' is static: it can be recoloured but not moved (mark it \"dynamic\" in the "
                    "scene file)");
                return true;
            }
            Drag d;
            d.what = s;
            const Camera c = frame_camera();
            // Horizontal plane through the grabbed point; with Shift, the plane facing the camera.
            d.plane_normal = (e.mods & kModShift) ? glm::normalize(c.eye - c.target) : world_up_;
            if (s.kind == Selection::Kind::object) {
                cpu::Ray ray;
                ray.origin = c.eye;
                ray.direction = camera_ray_direction(c, e.x, e.y);
                const cpu::RayHit hit = rays_->intersect(ray);
                d.plane_point = hit.hit ? hit.position : item_position(s);
            } else {
                d.plane_point = item_position(s);
            }
            d.grab_offset = item_position(s) - d.plane_point;
            d.press = mouse;
            drag_ = d;
            return true;
        }
        case InputType::mouse_up:
            if (e.button == MouseButton::right) right_down_ = false;
            if (e.button == MouseButton::middle) middle_down_ = false;
            if (e.button == MouseButton::left && drag_) {
                if (mouse != drag_->press) drag_->moved = true;
                if (const auto p = on_plane(*drag_, e.x, e.y); p && drag_->moved)
                    pending_move_ = {{drag_->what, *p + drag_->grab_offset}};
                drag_.reset();
            }
            return true;
        case InputType::mouse_move: {
            const glm::vec2 delta = mouse - last_mouse_;
            last_mouse_ = mouse;
            if (drag_) {
                if (mouse != drag_->press) drag_->moved = true;
                if (const auto p = on_plane(*drag_, e.x, e.y); p && drag_->moved)
                    pending_move_ = {{drag_->what, *p + drag_->grab_offset}};
            } else if (right_down_ && !(e.mods & kModShift)) {
                if (state.fly) {
                    Camera& c = camera();
                    c.target = c.eye + turned(c.target - c.eye, -delta.x * kDegreesPerPixel,
                                              -delta.y * kDegreesPerPixel, world_up_);
                } else {
                    orbit(delta.x, delta.y);
                }
            } else if (middle_down_ || (right_down_ && (e.mods & kModShift))) {
                pan(delta.x, delta.y);
            }
            return true;
        }
        case InputType::scroll:
            dolly(e.scroll);
            return true;
        case InputType::key_down:
        case InputType::key_up: {
            const bool down = e.type == InputType::key_down;
            speed_boost_ = (e.mods & kModShift) ? 4.0f : 1.0f;
            constexpr std::array kFlyKeys = {GLFW_KEY_W, GLFW_KEY_S, GLFW_KEY_A,
                                             GLFW_KEY_D, GLFW_KEY_E, GLFW_KEY_Q};
            for (size_t k = 0; k < kFlyKeys.size(); ++k)
                if (e.key == kFlyKeys[k]) {
                    held_[k] = down;
                    return true;
                }
            if (!down)
                return e.key == GLFW_KEY_R || e.key == GLFW_KEY_HOME || e.key == GLFW_KEY_TAB;
            if (e.key == GLFW_KEY_R) {
                if (state.selection.kind == Selection::Kind::object &&
                    scene_.objects[size_t(state.selection.index)].dynamic) {
                    turn_target_ = state.selection;
                    turn_degrees_ += (e.mods & kModShift) ? -kTurnDegrees : kTurnDegrees;
                } else {
                    state.message("R turns the selected dynamic object: select one first");
                }
                return true;
            }
            if (e.key == GLFW_KEY_HOME) {
                reset_camera();
                return true;
            }
            if (e.key == GLFW_KEY_TAB) {
                state.fly = !state.fly;
                state.message(state.fly ? "camera: fly (right-drag looks around)"
                                        : "camera: orbit (right-drag orbits)");
                return true;
            }
            return false;
        }
        case InputType::key:
            return false;
    }
    return false;
}

int ViewController::apply(ViewState& state, int frame) {
    int edits = 0;
    try {
        if (camera_dirty_) {
            if (!same_camera(camera_, scene_.camera)) set_camera(scene_, camera_);
            camera_dirty_ = false;
        }
        if (pending_move_) {
            const auto [what, position] = *pending_move_;
            pending_move_.reset();
            if (what.kind == Selection::Kind::object) {
                Transform t = scene_.objects[size_t(what.index)].transform;
                if (t.translation != position) {
                    t.translation = position;
                    set_object_transform(scene_, what.index, t);
                    ++edits;
                }
            } else if (what.kind == Selection::Kind::light &&
                       scene_.lights[size_t(what.index)].center() != position) {
                set_light_position(scene_, what.index, position);
                ++edits;
            }
        }
        if (turn_degrees_ != 0.0f && turn_target_.kind == Selection::Kind::object) {
            rotate_object(scene_, turn_target_.index, world_up_, turn_degrees_);
            ++edits;
        }
    } catch (const InputError& e) {
        state.message(std::string("edit refused: ") + e.what());
    }
    turn_degrees_ = 0.0f;
    if (edits) {
        edits_ += edits;
        last_edit_frame_ = frame;
    }
    return edits;
}

}  // namespace ag::cli
