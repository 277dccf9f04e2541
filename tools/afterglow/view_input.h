// Input of `afterglow view`: one stream of mouse and key events for live GLFW input and for
// --replay files, so a recorded session drives picking, dragging and keys exactly as a user does.
// The replay file format is in docs/viewer.md.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace ag::cli {

enum class InputType { mouse_down, mouse_up, mouse_move, scroll, key_down, key_up, key };
// "key" is a press and a release in the same frame (a tap: F12, a view key).
inline constexpr std::array kInputTypeNames = {"mouse_down", "mouse_up", "mouse_move", "scroll",
                                               "key_down",   "key_up",   "key"};

enum class MouseButton { left, right, middle };
inline constexpr std::array kMouseButtonNames = {"left", "right", "middle"};

// Modifier bits, equal to GLFW's.
inline constexpr int kModShift = 0x1, kModControl = 0x2, kModAlt = 0x4;

struct InputEvent {
    int frame = 0;  // viewer frame before which the event is handled (counting from 0)
    InputType type = InputType::mouse_move;
    // Mouse events: position in frame pixels (the rendered image, x right, y down from its
    // top-left corner; x + 0.5 is a pixel centre), independent of window size and panel.
    float x = 0.0f, y = 0.0f;
    float scroll = 0.0f;  // scroll: wheel steps, positive = away from the user (zoom in)
    MouseButton button = MouseButton::left;
    int key = -1;  // GLFW key code (key events)
    int mods = 0;  // kModShift | kModControl | kModAlt
};

// Reads a replay file: {"events": [{"frame": 3, "type": "mouse_down", "x": 120, "y": 190}, ...]}.
// Bad files are InputErrors naming the file, the event's JSON pointer and what was expected.
// Events come back sorted by frame (stable).
std::vector<InputEvent> read_replay(const std::string& path);
// The same format, for --record.
std::string replay_json(const std::vector<InputEvent>& events);

// Key names of the replay format ("A".."Z", "0".."9", "F1".."F12", "space", "escape", ...).
// key_from_name returns -1 for an unknown name; key_name returns "" for a key without one.
int key_from_name(const std::string& name);
std::string key_name(int key);
std::string key_names_list();  // for error messages

}  // namespace ag::cli
