// The side panel of `afterglow view` (Dear ImGui on GLFW and OpenGL 3): live statistics with a
// frame-time plot, views and overlays, script playback, the selection's albedo, lights, budgets
// and the gather backend. The only viewer file that includes ImGui; it never includes gpu/gl.h
// (the ImGui OpenGL backend loads its own GL entry points).
#pragma once

#include "shared/scene.h"
#include "tools/afterglow/view_state.h"

namespace ag::cli {

class ViewUi {
public:
    // Starts ImGui on the GLFW window (a GLFWwindow*) whose GL context is current. Callbacks the
    // viewer installed before are kept and called first.
    explicit ViewUi(void* glfw_window);
    ~ViewUi();
    ViewUi(const ViewUi&) = delete;
    ViewUi& operator=(const ViewUi&) = delete;

    // Builds the panel (right `state.panel_width` pixels of the window) and draws it into the
    // window's back buffer. Scene edits and commands go to `requests`; view settings (mode,
    // overlays, exposure) are changed in `state` directly.
    void draw(ViewState& state, const Scene& scene, ViewRequests& requests);
    // True while a text field has the keyboard (viewer keys are then ignored).
    bool wants_keyboard() const;
    // True while the mouse is over the panel or one of its pop-ups, or a panel widget is held.
    bool wants_mouse() const;
};

}  // namespace ag::cli
