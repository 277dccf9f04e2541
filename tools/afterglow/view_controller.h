// Interaction of `afterglow view`: camera orbit/fly/pan/dolly, picking objects (a CPU ray cast
// through the shared camera model) and lights (their projected centres), dragging the selection
// on a plane and turning it. Input is collected during a frame; apply() turns it into at most one
// edit per item through scene_edit.h, between frames, so each frame sees one SceneChange per item.
#pragma once

#include <array>
#include <glm/glm.hpp>
#include <memory>
#include <optional>
#include <utility>

#include "cpu/ray_tracer.h"
#include "shared/scene.h"
#include "tools/afterglow/view_input.h"
#include "tools/afterglow/view_state.h"

namespace ag::cli {

class ViewController {
public:
    // `width`×`height` is the rendered frame (mouse positions are in its pixels).
    ViewController(Scene& scene, int width, int height);
    ~ViewController();

    // Mouse events and the navigation keys (W A S D Q E, R, Home, Tab). Returns false for keys it
    // does not handle. `state` gets selection changes and messages.
    bool handle(const InputEvent& event, ViewState& state);
    // Held keys move the camera by `dt` seconds' worth (fly speed: half the scene per second).
    void advance(double dt);
    // Turns the frame's input into edits (camera, drag, turns) before viewer frame `frame`.
    // Returns the number of object and light edits (camera moves not counted).
    int apply(ViewState& state, int frame);

    void reset_camera();  // back to the scene file's camera (applied by the next apply())
    void select(const Selection& selection, ViewState& state);
    Selection pick(float x, float y);  // what is under frame pixel (x, y)
    int edits() const { return edits_; }
    int last_edit_frame() const { return last_edit_frame_; }
    bool dragging() const { return drag_.has_value(); }

private:
    struct Drag {
        Selection what;
        glm::vec3 plane_point{0.0f}, plane_normal{0.0f};
        glm::vec3 grab_offset{0.0f};  // item position − grabbed point on the plane
        glm::vec2 press{0.0f};        // where the button went down, frame pixels
        bool moved = false;           // a click without motion moves nothing
    };

    Camera frame_camera() const;  // the camera being shown, at the frame's size
    Camera& camera();             // the camera to change (adopts script edits first)
    std::optional<glm::vec3> on_plane(const Drag& d, float x, float y) const;
    glm::vec3 item_position(const Selection& s) const;
    void orbit(float dx, float dy);
    void pan(float dx, float dy);
    void dolly(float steps);

    Scene& scene_;
    int width_, height_;
    std::unique_ptr<cpu::RayTracer> rays_;
    Camera home_;    // the scene file's camera
    Camera camera_;  // the wanted camera while camera_dirty_, until apply()
    glm::vec3 world_up_{0.0f, 1.0f, 0.0f};
    float scene_size_ = 1.0f;
    bool right_down_ = false, middle_down_ = false;
    glm::vec2 last_mouse_{0.0f};
    std::optional<Drag> drag_;
    std::array<bool, 6> held_{};  // W S A D E Q
    float speed_boost_ = 1.0f;
    float turn_degrees_ = 0.0f;  // R / Shift+R since the last apply()
    Selection turn_target_;
    int edits_ = 0;
    int last_edit_frame_ = -1;
    bool camera_dirty_ = false;
    std::optional<std::pair<Selection, glm::vec3>> pending_move_;
};

}  // namespace ag::cli
