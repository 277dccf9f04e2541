#include "tools/afterglow/view_input.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

#include "shared/input_error.h"
#include "shared/json_read.h"

namespace ag::cli {

namespace {

using Json = nlohmann::json;

// Named keys besides letters, digits and F1-F12.
const std::array<std::pair<const char*, int>, 17> kNamedKeys = {{
    {"space", GLFW_KEY_SPACE},
    {"escape", GLFW_KEY_ESCAPE},
    {"enter", GLFW_KEY_ENTER},
    {"tab", GLFW_KEY_TAB},
    {"backspace", GLFW_KEY_BACKSPACE},
    {"delete", GLFW_KEY_DELETE},
    {"home", GLFW_KEY_HOME},
    {"left", GLFW_KEY_LEFT},
    {"right", GLFW_KEY_RIGHT},
    {"up", GLFW_KEY_UP},
    {"down", GLFW_KEY_DOWN},
    {"page_up", GLFW_KEY_PAGE_UP},
    {"page_down", GLFW_KEY_PAGE_DOWN},
    {"period", GLFW_KEY_PERIOD},
    {"comma", GLFW_KEY_COMMA},
    {"left_shift", GLFW_KEY_LEFT_SHIFT},
    {"right_shift", GLFW_KEY_RIGHT_SHIFT},
}};

template <class Names>
int index_of(const Names& names, const std::string& s) {
    for (size_t i = 0; i < names.size(); ++i)
        if (s == names[i]) return int(i);
    return -1;
}

}  // namespace

int key_from_name(const std::string& name) {
    if (name.size() == 1 && name[0] >= 'A' && name[0] <= 'Z') return GLFW_KEY_A + (name[0] - 'A');
    if (name.size() == 1 && name[0] >= '0' && name[0] <= '9') return GLFW_KEY_0 + (name[0] - '0');
    if (name.size() >= 2 && name.size() <= 3 && name[0] == 'F') {
        int n = 0;
        for (size_t i = 1; i < name.size(); ++i) {
            if (name[i] < '0' || name[i] > '9') return -1;
            n = 10 * n + (name[i] - '0');
        }
        return n >= 1 && n <= 12 ? GLFW_KEY_F1 + n - 1 : -1;
    }
    for (const auto& [n, k] : kNamedKeys)
        if (name == n) return k;
    return -1;
}

std::string key_name(int key) {
    if (key >= GLFW_KEY_A && key <= GLFW_KEY_Z) return std::string(1, char('A' + key - GLFW_KEY_A));
    if (key >= GLFW_KEY_0 && key <= GLFW_KEY_9) return std::string(1, char('0' + key - GLFW_KEY_0));
    if (key >= GLFW_KEY_F1 && key <= GLFW_KEY_F12)
        return "F" + std::to_string(key - GLFW_KEY_F1 + 1);
    for (const auto& [n, k] : kNamedKeys)
        if (key == k) return n;
    return "";
}

std::string key_names_list() {
    std::string list = "A-Z, 0-9, F1-F12";
    for (const auto& nk : kNamedKeys) list += std::string(", ") + nk.first;
    return list;
}

std::vector<InputEvent> read_replay(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    if (!file) throw InputError(path + ": cannot open the replay file");
    std::stringstream text;
    text << file.rdbuf();
    Json root;
    try {
        root = Json::parse(text.str(), nullptr, true, /*ignore_comments=*/true);
    } catch (const Json::parse_error& e) {
        throw InputError(path + ": not valid JSON (byte " + std::to_string(e.byte) +
                         "): " + e.what());
    }
    const JsonInput in(path);
    in.object(root, "");
    in.check_keys(root, "", {"events"});
    const Json& list =
        in.array(in.require(root, "", "events", "an array of input events"), "/events");
    std::vector<InputEvent> events;
    for (size_t i = 0; i < list.size(); ++i) {
        const std::string at = JsonInput::child("/events", i);
        const Json& e = in.object(list[i], at);
        InputEvent ev;
        ev.frame = int(in.integer(in.require(e, at, "frame", "the frame number (from 0)"),
                                  JsonInput::child(at, "frame"), 0, 1'000'000'000));
        ev.type = InputType(in.choice(in.require(e, at, "type", "an event type"),
                                      JsonInput::child(at, "type"), kInputTypeNames));
        const bool mouse = ev.type == InputType::mouse_down || ev.type == InputType::mouse_up ||
                           ev.type == InputType::mouse_move;
        if (mouse) {
            in.check_keys(e, at, {"frame", "type", "x", "y", "button", "mods"});
            ev.x = float(
                in.number(in.require(e, at, "x", "x in frame pixels"), JsonInput::child(at, "x")));
            ev.y = float(
                in.number(in.require(e, at, "y", "y in frame pixels"), JsonInput::child(at, "y")));
            if (const Json* b = JsonInput::find(e, "button"))
                ev.button =
                    MouseButton(in.choice(*b, JsonInput::child(at, "button"), kMouseButtonNames));
        } else if (ev.type == InputType::scroll) {
            in.check_keys(e, at, {"frame", "type", "x", "y", "scroll", "mods"});
            ev.scroll = float(in.number(in.require(e, at, "scroll", "wheel steps"),
                                        JsonInput::child(at, "scroll")));
            if (const Json* x = JsonInput::find(e, "x"))
                ev.x = float(in.number(*x, JsonInput::child(at, "x")));
            if (const Json* y = JsonInput::find(e, "y"))
                ev.y = float(in.number(*y, JsonInput::child(at, "y")));
        } else {
            in.check_keys(e, at, {"frame", "type", "key", "mods"});
            const std::string key_at = JsonInput::child(at, "key");
            const std::string name = in.string(in.require(e, at, "key", "a key name"), key_at);
            ev.key = key_from_name(name);
            if (ev.key < 0)
                in.fail(key_at,
                        "expected a key name (" + key_names_list() + "), got \"" + name + "\"");
        }
        if (const Json* m = JsonInput::find(e, "mods")) {
            const std::string mods_at = JsonInput::child(at, "mods");
            const Json& mods = in.array(*m, mods_at);
            constexpr std::array kModNames = {"shift", "control", "alt"};
            for (size_t k = 0; k < mods.size(); ++k)
                ev.mods |= 1 << in.choice(mods[k], JsonInput::child(mods_at, k), kModNames);
        }
        events.push_back(ev);
    }
    std::stable_sort(events.begin(), events.end(),
                     [](const InputEvent& a, const InputEvent& b) { return a.frame < b.frame; });
    return events;
}

std::string replay_json(const std::vector<InputEvent>& events) {
    // One event per line, so recordings can be read and edited by hand.
    std::string out = "{\"events\": [\n";
    for (size_t i = 0; i < events.size(); ++i) {
        const InputEvent& e = events[i];
        nlohmann::ordered_json j = nlohmann::ordered_json::object();  // frame and type first
        j["frame"] = e.frame;
        j["type"] = kInputTypeNames[size_t(e.type)];
        switch (e.type) {
            case InputType::mouse_down:
            case InputType::mouse_up:
                j["button"] = kMouseButtonNames[size_t(e.button)];
                [[fallthrough]];
            case InputType::mouse_move:
                j["x"] = e.x;
                j["y"] = e.y;
                break;
            case InputType::scroll:
                j["x"] = e.x;
                j["y"] = e.y;
                j["scroll"] = e.scroll;
                break;
            default:
                j["key"] = key_name(e.key);
        }
        if (e.mods) {
            nlohmann::ordered_json mods = nlohmann::ordered_json::array();
            if (e.mods & kModShift) mods.push_back("shift");
            if (e.mods & kModControl) mods.push_back("control");
            if (e.mods & kModAlt) mods.push_back("alt");
            j["mods"] = mods;
        }
        out += "  " + j.dump() + (i + 1 < events.size() ? ",\n" : "\n");
    }
    return out + "]}\n";
}

}  // namespace ag::cli
