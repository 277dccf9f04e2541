// afterglow view SCENE: the progressive pipeline in a GLFW window with an ImGui panel: camera
// navigation, picking and dragging objects and lights, script playback, term and diagnostic views,
// budgets, live statistics, screenshots, and --replay of recorded input for tests (docs/viewer.md).
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#if defined(__SANITIZE_ADDRESS__)
#include <dlfcn.h>
#include <link.h>
#endif
#include <optional>
#include <string>
#include <vector>

#include "gpu/gl_context.h"
#include "shared/image.h"
#include "shared/input_error.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/pipeline/vpl_method.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/script.h"
#include "tools/afterglow/commands.h"
#include "tools/afterglow/view_controller.h"
#include "tools/afterglow/view_input.h"
#include "tools/afterglow/view_renderer.h"
#include "tools/afterglow/view_state.h"
#include "tools/afterglow/view_ui.h"

namespace ag::cli {

const Command kViewCommand{
    "view",
    "SCENE [options]",
    "Open the progressive pipeline in a window with a control panel: orbit or fly the camera, "
    "click and drag objects and lights, recolour them, play a scene-edit script, show single "
    "terms or diagnostic views, change budgets and watch the frame-time breakdown. --replay feeds "
    "recorded input for tests; --frames, --shots and --exit-after-script make it run unattended.",
    {
        text("script", "S.lua",
             "scene-edit script (default: the scene's \"script\"); script frame time = frame / 30 "
             "s"),
        size_option(
            "frame size (default: the scene camera's resolution); the panel is added beside it"),
        integer("frames,n", "N", "exit after N frames (default: run until the window is closed)", 1,
                100000000),
        text("shots", "DIR",
             "write first.png and last.png there, and F12 screenshots (default for F12: beside the "
             "scene)"),
        flag("exit-after-script", "exit once the script has made no edit for --idle-frames frames"),
        integer("idle-frames", "N", "frames without script edits before --exit-after-script exits",
                1, 1000000, 30),
        text("replay", "EVENTS.json",
             "feed recorded mouse and key events, per frame (format: docs/viewer.md)"),
        text("record", "EVENTS.json",
             "write the session's input events in the --replay format on exit"),
        text("dump", "OUT.json",
             "on exit write final object and light positions, edits, IIM texels gathered and "
             "per-frame times as JSON"),
        choice("view", "MODE", "initial view:", {kViewModeNames.begin(), kViewModeNames.end()},
               kViewModeNames[0]),
        number("exposure", "EV", "display exposure in stops (radiance 1 is white at 0)", -100, 100,
               0),
        gl_option({gpu::GlBackend::window}, gpu::GlBackend::window),
        gather_option(),
        indirect_option(),
        frame_ms_option(),
        settings_option(),
        integer("threads", "N", "worker threads for photon work (default: settings.threads)", 0,
                1024),
        flag("quiet,q", "no messages on stderr except errors and the summary"),
    },
    1,
    1,
};

namespace {

using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;

bool g_quiet = false;
std::string g_glfw_error;  // GLFW's last error, to say why a window could not be made

// GLFW unloads the GL driver and the X libraries it opened (glfwTerminate) before LeakSanitizer
// looks at the heap at exit, so what they keep allocated shows up as "<unknown module>", which no
// suppression can name. Under AddressSanitizer every library loaded once the window exists stays
// loaded (RTLD_NODELETE on objects already there), so tests/lsan.supp can name the drivers.
void keep_libraries_loaded() {
#if defined(__SANITIZE_ADDRESS__)
    std::vector<std::string> names;
    dl_iterate_phdr(
        [](dl_phdr_info* info, size_t, void* out) {
            if (info->dlpi_name && info->dlpi_name[0])
                static_cast<std::vector<std::string>*>(out)->push_back(info->dlpi_name);
            return 0;
        },
        &names);
    for (const std::string& name : names)
        if (void* handle = dlopen(name.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE))
            dlclose(handle);
#endif
}

void on_glfw_error(int, const char* description) {
    g_glfw_error = description ? description : "unknown";
}

Json vec_json(const glm::vec3& v) { return Json::array({v.x, v.y, v.z}); }

// The camera as the scene file's "camera" block (docs/scene-format.md).
std::string camera_json(const Camera& c) {
    char text[512];
    std::snprintf(text, sizeof text,
                  "\"camera\": {\"eye\": [%.6g, %.6g, %.6g], \"target\": [%.6g, %.6g, %.6g], "
                  "\"up\": [%.6g, %.6g, "
                  "%.6g], \"fov_y\": %.6g, \"resolution\": [%d, %d]}",
                  c.eye.x, c.eye.y, c.eye.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y,
                  c.up.z, c.fov_y, c.width, c.height);
    return text;
}

// What a script restart goes back to: the editable state as loaded.
struct EditableState {
    std::vector<Transform> transforms;
    std::vector<glm::vec3> albedos;
    std::vector<Light> lights;
};

EditableState snapshot(const Scene& scene) {
    EditableState s;
    for (const Object& o : scene.objects) {
        s.transforms.push_back(o.transform);
        s.albedos.push_back(o.material.albedo);
    }
    s.lights = scene.lights;
    return s;
}

// Back to `s` through scene_edit.h, one edit per item that differs.
void restore(Scene& scene, const EditableState& s) {
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        const Transform& t = scene.objects[o].transform;
        if (t.translation != s.transforms[o].translation || t.rotation != s.transforms[o].rotation)
            set_object_transform(scene, int(o), s.transforms[o]);
        if (scene.objects[o].material.albedo != s.albedos[o])
            set_albedo(scene, int(o), s.albedos[o]);
    }
    for (size_t l = 0; l < scene.lights.size(); ++l) {
        const Light& now = scene.lights[l];
        const Light& then = s.lights[l];
        // A mesh light moves with its object (restored above); a sun has no position.
        if (now.center() != then.center() && now.type != LightType::mesh &&
            now.type != LightType::sun)
            set_light_position(scene, int(l), then.center());
        if (now.value() != then.value()) set_light_color(scene, int(l), then.value());
        if (now.enabled != then.enabled) set_light_enabled(scene, int(l), then.enabled);
    }
}

// Window and viewport geometry: the frame is shown scaled to fit left of the panel, centred.
struct Layout {
    int window_w = 1, window_h = 1, fb_w = 1, fb_h = 1;
    float x0 = 0, y0 = 0, scale = 1;  // window coordinates, top-left origin

    void update(GLFWwindow* w, int frame_w, int frame_h, int panel) {
        glfwGetWindowSize(w, &window_w, &window_h);
        glfwGetFramebufferSize(w, &fb_w, &fb_h);
        window_w = std::max(1, window_w);
        window_h = std::max(1, window_h);
        const float area_w = float(std::max(1, window_w - panel));
        scale =
            std::max(1e-3f, std::min(area_w / float(frame_w), float(window_h) / float(frame_h)));
        x0 = 0.5f * (area_w - scale * float(frame_w));
        y0 = 0.5f * (float(window_h) - scale * float(frame_h));
    }
    glm::vec2 to_frame(double x, double y) const {
        return {float((x - double(x0)) / double(scale)), float((y - double(y0)) / double(scale))};
    }
    bool in_viewport(double x, double y, int frame_w, int frame_h) const {
        const glm::vec2 p = to_frame(x, y);
        return p.x >= 0 && p.y >= 0 && p.x < float(frame_w) && p.y < float(frame_h);
    }
    ViewRect rect(int frame_w, int frame_h) const {
        const float rx = float(fb_w) / float(window_w), ry = float(fb_h) / float(window_h);
        const float h = scale * float(frame_h);
        return {int(std::lround(x0 * rx)), int(std::lround((float(window_h) - y0 - h) * ry)),
                std::max(1, int(std::lround(scale * float(frame_w) * rx))),
                std::max(1, int(std::lround(h * ry)))};
    }
};

// Live GLFW input, queued by the callbacks and handled at the start of the next frame.
struct LiveInput {
    Layout* layout = nullptr;
    ViewUi* ui = nullptr;
    int frame_w = 0, frame_h = 0;
    int frame = 0;
    double cursor_x = 0, cursor_y = 0;  // from the cursor callbacks, in event order
    std::vector<InputEvent> queue;
};

LiveInput& live(GLFWwindow* w) { return *static_cast<LiveInput*>(glfwGetWindowUserPointer(w)); }

void on_mouse_button(GLFWwindow* w, int button, int action, int mods) {
    LiveInput& in = live(w);
    if (button > GLFW_MOUSE_BUTTON_MIDDLE) return;
    // Where the cursor was when the button changed, not where it is by the time GLFW reports it.
    const double x = in.cursor_x, y = in.cursor_y;
    // Presses over the panel are the panel's; releases always count (a drag may end anywhere).
    if (action == GLFW_PRESS &&
        (!in.layout->in_viewport(x, y, in.frame_w, in.frame_h) || (in.ui && in.ui->wants_mouse())))
        return;
    InputEvent e;
    e.frame = in.frame;
    e.type = action == GLFW_PRESS ? InputType::mouse_down : InputType::mouse_up;
    e.button = button == GLFW_MOUSE_BUTTON_LEFT
                   ? MouseButton::left
                   : (button == GLFW_MOUSE_BUTTON_RIGHT ? MouseButton::right : MouseButton::middle);
    const glm::vec2 p = in.layout->to_frame(x, y);
    e.x = p.x;
    e.y = p.y;
    e.mods = mods & (kModShift | kModControl | kModAlt);
    in.queue.push_back(e);
}

void on_cursor(GLFWwindow* w, double x, double y) {
    LiveInput& in = live(w);
    in.cursor_x = x;
    in.cursor_y = y;
    InputEvent e;
    e.frame = in.frame;
    e.type = InputType::mouse_move;
    const glm::vec2 p = in.layout->to_frame(x, y);
    e.x = p.x;
    e.y = p.y;
    e.mods = (glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
              glfwGetKey(w, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS)
                 ? kModShift
                 : 0;
    // Consecutive moves in one frame: only the last position matters.
    if (!in.queue.empty() && in.queue.back().type == InputType::mouse_move)
        in.queue.back() = e;
    else
        in.queue.push_back(e);
}

void on_scroll(GLFWwindow* w, double, double dy) {
    LiveInput& in = live(w);
    const double x = in.cursor_x, y = in.cursor_y;
    if (!in.layout->in_viewport(x, y, in.frame_w, in.frame_h) || (in.ui && in.ui->wants_mouse()))
        return;
    InputEvent e;
    e.frame = in.frame;
    e.type = InputType::scroll;
    const glm::vec2 p = in.layout->to_frame(x, y);
    e.x = p.x;
    e.y = p.y;
    e.scroll = float(dy);
    in.queue.push_back(e);
}

void on_key(GLFWwindow* w, int key, int, int action, int mods) {
    LiveInput& in = live(w);
    // Typing into a panel field is not a viewer key; releases always pass, so no key stays held.
    if (action == GLFW_REPEAT || (action == GLFW_PRESS && in.ui && in.ui->wants_keyboard())) return;
    InputEvent e;
    e.frame = in.frame;
    e.type = action == GLFW_PRESS ? InputType::key_down : InputType::key_up;
    e.key = key;
    e.mods = mods & (kModShift | kModControl | kModAlt);
    in.queue.push_back(e);
}

struct FrameRecord {
    int frame = 0;
    FrameTimes times;
    float loop_ms = 0;
    int groups_queued = 0, groups_invalidated = 0, photons_retraced = 0, texels_pending = 0,
        texels_gathered = 0, edits = 0;
};

double percentile(std::vector<float> v, double q) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return double(v[std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5))]);
}

// Everything the viewer's loop owns; one frame at a time.
class Viewer {
public:
    Viewer(const Args& args, Scene& scene) : args_(args), scene_(scene) {}
    int run();

private:
    void handle_events(const std::vector<InputEvent>& events);
    bool handle_key(const InputEvent& e);
    void apply_requests();
    void make_pipeline();  // pipeline_, loop_ and renderer_ for the scene's settings
    void run_script(int frame);
    void restart_script();
    void update_stats(const PipelineStats& s, double loop_ms);
    void count_gathered();
    std::vector<ViewPoint> overlay_points() const;
    std::vector<ViewPoint> light_markers() const;
    void screenshot(const std::string& path, bool window);
    std::string shot_path(const std::string& name) const;
    void copy_camera();
    void write_dump(const std::string& path) const;

    const Args& args_;
    Scene& scene_;
    int width_ = 0, height_ = 0;
    gpu::Texture media_texture_;  // the `media` view's slice, frame-sized
    GLuint media_slice_texture();
    std::unique_ptr<gpu::GlContext> context_;
    GLFWwindow* window_ = nullptr;
    std::unique_ptr<Pipeline> pipeline_;
    std::unique_ptr<ViewRenderer> renderer_;
    std::unique_ptr<ViewController> controller_;
    std::unique_ptr<ViewUi> ui_;
    std::unique_ptr<FrameLoop> loop_;
    int threads_ = 0;  // the script clock; edits between frames
    std::optional<Script> script_;
    std::string script_path_;
    EditableState initial_;
    ViewState state_;
    ViewRequests requests_;
    Layout layout_;
    LiveInput live_;
    std::string shots_dir_;
    std::vector<InputEvent> recorded_;
    bool screenshot_pending_ = false, window_shot_pending_ = false;
    int frame_ = 0;
    int last_edit_frame_ = -1;  // any object, light or material edit (panel, mouse, script)
    int script_edits_ = 0, panel_edits_ = 0;
    long gathered_total_ = 0, gathered_after_edit_ = 0, gathered_near_after_edit_ = 0;
    std::vector<FrameRecord> records_;
};

std::string Viewer::shot_path(const std::string& name) const {
    if (!shots_dir_.empty()) return (std::filesystem::path(shots_dir_) / name).string();
    const std::filesystem::path scene_path(scene_.path);
    return (scene_path.parent_path() / (scene_path.stem().string() + "_" + name)).string();
}

void Viewer::screenshot(const std::string& path, bool window) {
    try {
        const Image image =
            window ? ViewRenderer::read_window(layout_.fb_w, layout_.fb_h) : renderer_->read_back();
        write_image(image, path, window ? 0.0f : state_.exposure);
        state_.message("wrote " + path);
    } catch (const std::exception& e) {
        state_.message(std::string("screenshot failed: ") + e.what());
    }
}

void Viewer::copy_camera() {
    Camera c = scene_.camera;
    const std::string text = camera_json(c);
    std::cout << text << std::endl;
    glfwSetClipboardString(window_, text.c_str());
    state_.message("camera copied to the clipboard (and printed on stdout)");
}

GLuint Viewer::media_slice_texture() {
    Image slice(width_, height_);
    if (const MediaMethodResult* media = pipeline_->media()) {
        const int axis = std::clamp(state_.media_axis, 0, 2);
        const int layer = state_.media_layer < 0 ? media->grids.size[axis] / 2 : state_.media_layer;
        slice =
            media_slice_view(*media, MediaField(state_.media_field), axis, layer, width_, height_);
    }
    std::vector<glm::vec4> rgba(size_t(width_) * size_t(height_));
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x)  // GL rows bottom-first
            rgba[size_t(height_ - 1 - y) * size_t(width_) + size_t(x)] =
                glm::vec4(slice.rgb(x, y), 1.0f);
    media_texture_ = gpu::make_float_texture(width_, height_, false, &rgba[0].x);
    return media_texture_.get();
}

bool Viewer::handle_key(const InputEvent& e) {
    if (e.type != InputType::key_down) return false;
    const bool shift = e.mods & kModShift;
    // 1 … 9 the first nine views, 0 the tenth; later views from the panel or --view (the key codes
    // after 9 are punctuation).
    if (e.key >= GLFW_KEY_1 && e.key <= GLFW_KEY_9) {
        state_.mode = ViewMode(e.key - GLFW_KEY_1);
        return true;
    }
    if (e.key == GLFW_KEY_0) {
        state_.mode = ViewMode(9);
        return true;
    }
    switch (e.key) {
        case GLFW_KEY_F12:
            (shift ? window_shot_pending_ : screenshot_pending_) = true;
            return true;
        case GLFW_KEY_SPACE:
            (state_.script.playing ? requests_.pause : requests_.play) = true;
            return true;
        case GLFW_KEY_N:
            requests_.step = true;
            return true;
        case GLFW_KEY_BACKSPACE:
            requests_.restart = true;
            return true;
        case GLFW_KEY_C:
            requests_.copy_camera = true;
            return true;
        case GLFW_KEY_ESCAPE:
            requests_.select = Selection{};
            return true;
        case GLFW_KEY_G:
            state_.overlays.gather_centres = !state_.overlays.gather_centres;
            return true;
        case GLFW_KEY_P:
            state_.overlays.primary_photons = !state_.overlays.primary_photons;
            return true;
        case GLFW_KEY_O:
            state_.overlays.group_photons = !state_.overlays.group_photons;
            return true;
        case GLFW_KEY_L:
            if (state_.selection.kind == Selection::Kind::light)
                requests_.lights.push_back(
                    {state_.selection.index, std::nullopt,
                     !scene_.lights[size_t(state_.selection.index)].enabled});
            else
                state_.message("L switches the selected light: click a light first");
            return true;
        default:
            return false;
    }
}

void Viewer::handle_events(const std::vector<InputEvent>& events) {
    for (const InputEvent& e : events) {
        if (e.type == InputType::key) {
            // A tap: down and up within the frame.
            InputEvent down = e, up = e;
            down.type = InputType::key_down;
            up.type = InputType::key_up;
            if (!controller_->handle(down, state_)) handle_key(down);
            controller_->handle(up, state_);
            continue;
        }
        if (!controller_->handle(e, state_)) handle_key(e);
    }
}

void Viewer::make_pipeline() {
    loop_.reset();
    renderer_.reset();
    pipeline_.reset();
    pipeline_ = std::make_unique<Pipeline>(scene_, PipelineOptions{width_, height_, threads_});
    loop_ = std::make_unique<FrameLoop>(*pipeline_);
    loop_->on_script_error = [this](const std::string& error) {
        ScriptStatus& s = state_.script;
        s.error = error;
        ++s.error_count;
        if (s.error_count <= 5) state_.message(error + " (edit skipped, rendering goes on)");
    };
    renderer_ = std::make_unique<ViewRenderer>(scene_, pipeline_->meshes(), width_, height_);
}

void Viewer::apply_requests() {
    ViewRequests r = std::move(requests_);
    requests_ = ViewRequests{};
    // Settings are written directly, not through scene_edit.h: the workers must be done first.
    if (r.settings || r.indirect || r.backend) loop_->begin_edits();
    if (r.select) controller_->select(*r.select, state_);
    if (r.settings) scene_.settings = *r.settings;
    if (r.indirect) {
        pipeline_->sync();
        scene_.settings.indirect.method = *r.indirect;
        make_pipeline();
        if (script_) restart_script();
        state_.message(std::string("indirect method ") + kIndirectMethodNames[size_t(*r.indirect)]);
    }
    if (r.backend) {
        pipeline_->set_gather_backend(*r.backend);
        state_.message(std::string("gather backend ") + kGatherBackendNames[size_t(*r.backend)]);
    }
    if (r.reset_camera) controller_->reset_camera();
    if (r.copy_camera) copy_camera();
    if (r.screenshot) screenshot_pending_ = true;
    if (r.window_shot) window_shot_pending_ = true;
    try {
        if (r.albedo && state_.selection.kind == Selection::Kind::object) {
            set_albedo(scene_, state_.selection.index, glm::clamp(*r.albedo, 0.0f, 1.0f));
            ++panel_edits_;
        }
        for (const ViewRequests::LightEdit& l : r.lights) {
            if (l.value) set_light_color(scene_, l.light, glm::max(*l.value, 0.0f));
            if (l.enabled) set_light_enabled(scene_, l.light, *l.enabled);
            ++panel_edits_;
        }
    } catch (const InputError& e) {
        state_.message(std::string("edit refused: ") + e.what());
    }
    if (r.albedo || !r.lights.empty()) last_edit_frame_ = frame_;
    if (script_) {
        if (r.play) state_.script.playing = true;
        if (r.pause) state_.script.playing = false;
        if (r.step) {
            state_.script.playing = false;
            run_script(frame_);
        }
        if (r.restart) restart_script();
    }
}

void Viewer::restart_script() {
    restore(scene_, initial_);
    try {
        script_.emplace(script_path_);
    } catch (const InputError& e) {
        state_.script.error = e.what();
        state_.message(std::string("script reload failed: ") + e.what());
        return;
    }
    state_.script = ScriptStatus{script_path_, true, 0, "", 0, frame_};
    loop_->start_script(&*script_);
    last_edit_frame_ = frame_;
    state_.message("script restarted");
}

void Viewer::run_script(int frame) {
    if (!script_) return;
    ScriptStatus& s = state_.script;
    const uint64_t before = scene_.version;
    loop_->run_script();  // errors reach on_script_error
    s.frame = loop_->script_frame();
    if (scene_.version != before) {
        s.last_edit_frame = frame;
        last_edit_frame_ = frame;
        ++script_edits_;
    }
}

void Viewer::update_stats(const PipelineStats& s, double loop_ms) {
    ViewStats& v = state_.stats;
    v.frame = s.frame;
    FrameTimes t;
    t.frame_ms = float(s.frame_ms);
    t.photon_ms = float(s.photon_ms);
    t.aim_ms = float(s.aim_ms);
    t.caustic_ms = float(s.caustic_ms);
    t.gather_ms = float(s.gather_ms);
    t.draw_ms = float(s.draw_ms);
    t.wait_ms = float(s.wait_ms);
    v.last = t;
    if (v.history.size() < size_t(ViewStats::kHistory)) {
        v.history.push_back(t);
    } else {
        v.history[size_t(v.history_next)] = t;
        v.history_next = (v.history_next + 1) % ViewStats::kHistory;
    }
    // fps of the whole loop, smoothed over about ten frames.
    const double fps = 1000.0 / std::max(1e-3, loop_ms);
    v.fps = v.fps == 0.0 ? fps : 0.9 * v.fps + 0.1 * fps;
    v.groups_valid = v.groups_invalid = v.groups_queued = 0;
    for (size_t l = 0; l < scene_.lights.size(); ++l) {
        const cpu::LightGroupState g = pipeline_->photons().light_state(int(l));
        v.groups_valid += g.valid;
        v.groups_invalid += g.invalid;
        v.groups_queued += g.queued;
    }
    v.photons_retraced = s.photons.photons_retraced;
    v.groups_invalidated = s.photons.groups_invalidated;
    v.aim_texels = s.photons.aim_texels_rebuilt;
    v.texels_gathered = s.iim_texels_gathered;
    v.texels_pending = s.iim_texels_pending;
    v.texels_repaired = s.iim_texels_invalid;
    v.caustic_tiles = s.caustic_tiles_filtered;
    v.converged = pipeline_->converged();
    v.backend = pipeline_->gather_backend();
    v.indirect = pipeline_->indirect().kind();
}

void Viewer::count_gathered() {
    const std::vector<int>& batch = pipeline_->last_gathered();
    gathered_total_ += long(batch.size());
    if (last_edit_frame_ < 0) return;
    gathered_after_edit_ += long(batch.size());
    // "Near" a moved object: within twice its bounding radius of its centre, on another object
    // (the light that object throws or blocks around it).
    for (int r : batch) {
        const TexelRecord& t = scene_.atlas.texels[size_t(r)];
        const glm::vec3 p = scene_.objects[size_t(t.object)].transform.apply_point(t.position);
        for (size_t o = 0; o < scene_.objects.size(); ++o) {
            if (int(o) == t.object) continue;
            const Object& obj = scene_.objects[o];
            if (obj.transform.translation == initial_.transforms[o].translation &&
                obj.transform.rotation == initial_.transforms[o].rotation)
                continue;
            const Bounds b = mesh_bounds(obj.mesh);
            if (glm::length(p - obj.transform.apply_point(b.center())) <= glm::length(b.extent())) {
                ++gathered_near_after_edit_;
                break;
            }
        }
    }
}

std::vector<ViewPoint> Viewer::overlay_points() const {
    std::vector<ViewPoint> points;
    const Overlays& o = state_.overlays;
    const cpu::PhotonMaps& maps = pipeline_->photons().maps();
    constexpr size_t kMaxPoints = 500000;
    if (state_.mode == ViewMode::vpls)
        if (const auto* vpl = dynamic_cast<const VplMethod*>(&pipeline_->indirect()))
            for (const Vpl& v : vpl->vpls()) {
                // The colour of its power; dimmer the later its bounce.
                const float peak = std::max({v.power.r, v.power.g, v.power.b, 1e-30f});
                const float dim = 1.0f / float(1 + v.bounce);
                points.push_back({v.position, (0.3f + 0.7f * dim) * v.power / peak});
            }
    if (o.primary_photons)
        for (size_t l = 0; l < scene_.lights.size(); ++l) {
            const glm::vec3 v = scene_.lights[l].value();
            const glm::vec3 colour = v / std::max({v.r, v.g, v.b, 1e-30f});
            for (int g = 0; g < scene_.settings.photons.groups && points.size() < kMaxPoints; ++g) {
                const cpu::PhotonGroup& group = maps.group(int(l), g);
                for (size_t p = 0; p + 1 < group.photon_begin.size(); ++p)
                    if (group.photon_begin[p] < group.photon_begin[p + 1])
                        points.push_back({group.vertices[group.photon_begin[p]].position, colour});
            }
        }
    if (o.group_photons && !scene_.lights.empty()) {
        const int l = std::clamp(o.group_light, 0, int(scene_.lights.size()) - 1);
        const int g = std::clamp(o.group, 0, scene_.settings.photons.groups - 1);
        const cpu::PhotonGroup& group = maps.group(l, g);
        const glm::vec3 by_bounce[4] = {
            {1.0f, 0.95f, 0.2f}, {1.0f, 0.55f, 0.1f}, {0.95f, 0.15f, 0.1f}, {0.9f, 0.2f, 0.9f}};
        for (size_t p = 0; p + 1 < group.photon_begin.size(); ++p)
            for (uint32_t v = group.photon_begin[p]; v < group.photon_begin[p + 1]; ++v)
                points.push_back({group.vertices[v].position,
                                  by_bounce[std::min<uint32_t>(3, v - group.photon_begin[p])]});
    }
    if (o.gather_centres) {
        const std::vector<char>& pending = pipeline_->texel_pending();
        std::vector<char> gathered(scene_.atlas.texels.size(), 0);
        for (int r : pipeline_->last_gathered()) gathered[size_t(r)] = 1;
        for (size_t r = 0; r < scene_.atlas.texels.size() && points.size() < kMaxPoints; ++r) {
            const TexelRecord& t = scene_.atlas.texels[r];
            const glm::vec3 colour = gathered[r] ? glm::vec3(0.2f, 1.0f, 0.2f)
                                                 : (pending[r] ? glm::vec3(1.0f, 0.5f, 0.0f)
                                                               : glm::vec3(0.25f, 0.35f, 0.9f));
            points.push_back(
                {scene_.objects[size_t(t.object)].transform.apply_point(t.position), colour});
        }
    }
    return points;
}

std::vector<ViewPoint> Viewer::light_markers() const {
    std::vector<ViewPoint> markers;
    for (size_t l = 0; l < scene_.lights.size(); ++l) {
        const Light& light = scene_.lights[l];
        const bool selected = state_.selection == Selection{Selection::Kind::light, int(l)};
        if (!state_.overlays.lights && !selected) continue;
        const glm::vec3 v = light.value();
        glm::vec3 colour = light.enabled ? v / std::max({v.r, v.g, v.b, 1e-30f}) : glm::vec3(0.3f);
        if (selected) colour = {1.0f, 0.75f, 0.1f};
        markers.push_back({light.center(), colour});
    }
    return markers;
}

void Viewer::write_dump(const std::string& path) const {
    Json j;
    j["scene"] = scene_.path;
    j["frames"] = frame_;
    j["frame_size"] = {width_, height_};
    j["renderer"] = state_.stats.renderer;
    j["gather_backend"] = kGatherBackendNames[size_t(pipeline_->gather_backend())];
    j["objects"] = Json::array();
    for (size_t o = 0; o < scene_.objects.size(); ++o) {
        const Object& obj = scene_.objects[o];
        const glm::quat q = obj.transform.rotation;
        j["objects"].push_back({{"name", obj.name},
                                {"position", vec_json(obj.transform.translation)},
                                {"start_position", vec_json(initial_.transforms[o].translation)},
                                {"rotation", {q.w, q.x, q.y, q.z}},
                                {"albedo", vec_json(obj.material.albedo)}});
    }
    j["lights"] = Json::array();
    for (const Light& l : scene_.lights)
        j["lights"].push_back({{"name", l.name},
                               {"position", vec_json(l.center())},
                               {"enabled", l.enabled},
                               {"value", vec_json(l.value())}});
    const Camera& c = scene_.camera;
    j["camera"] = {{"eye", vec_json(c.eye)},
                   {"target", vec_json(c.target)},
                   {"up", vec_json(c.up)},
                   {"fov_y", c.fov_y}};
    const Selection& s = state_.selection;
    j["selection"] =
        s.kind == Selection::Kind::object  ? Json{{"object", scene_.objects[size_t(s.index)].name}}
        : s.kind == Selection::Kind::light ? Json{{"light", scene_.lights[size_t(s.index)].name}}
                                           : Json::object();
    j["edits"] = {{"interactive", controller_->edits()},
                  {"panel", panel_edits_},
                  {"script", script_edits_},
                  {"last_edit_frame", last_edit_frame_}};
    j["iim_texels_gathered"] = {{"total", gathered_total_},
                                {"after_first_edit", gathered_after_edit_},
                                {"near_moved_objects_after_first_edit", gathered_near_after_edit_}};
    j["script"] = {{"path", script_path_},
                   {"frames_run", state_.script.frame},
                   {"errors", state_.script.error_count},
                   {"last_error", state_.script.error}};
    std::vector<float> frame_ms, loop_ms;
    Json per_frame = Json::array();
    for (const FrameRecord& r : records_) {
        frame_ms.push_back(r.times.frame_ms);
        loop_ms.push_back(r.loop_ms);
        per_frame.push_back({{"frame", r.frame},
                             {"frame_ms", r.times.frame_ms},
                             {"loop_ms", r.loop_ms},
                             {"photon_ms", r.times.photon_ms},
                             {"aim_ms", r.times.aim_ms},
                             {"caustic_ms", r.times.caustic_ms},
                             {"gather_ms", r.times.gather_ms},
                             {"draw_ms", r.times.draw_ms},
                             {"wait_ms", r.times.wait_ms},
                             {"groups_queued", r.groups_queued},
                             {"groups_invalidated", r.groups_invalidated},
                             {"photons_retraced", r.photons_retraced},
                             {"texels_gathered", r.texels_gathered},
                             {"texels_pending", r.texels_pending},
                             {"edits", r.edits}});
    }
    j["frame_ms"] = {{"median", percentile(frame_ms, 0.5)},
                     {"p95", percentile(frame_ms, 0.95)},
                     {"max", percentile(frame_ms, 1.0)}};
    j["loop_ms"] = {{"median", percentile(loop_ms, 0.5)},
                    {"p95", percentile(loop_ms, 0.95)},
                    {"max", percentile(loop_ms, 1.0)}};
    j["per_frame"] = per_frame;
    write_file_atomically(path, j.dump(1) + "\n");
}

int Viewer::run() {
    g_quiet = args_.has("quiet");
    width_ = scene_.camera.width;
    height_ = scene_.camera.height;
    args_.get_size("size", width_, height_);
    const int frames = args_.get_int("frames", 0);
    const bool exit_after_script = args_.has("exit-after-script");
    const int idle_frames = args_.get_int("idle-frames");
    const int threads = args_.get_int("threads", scene_.settings.threads);
    state_.mode = ViewMode(args_.get_choice("view"));
    state_.exposure = float(args_.get_double("exposure"));
    state_.frame_width = width_;
    state_.frame_height = height_;

    // Every user input is checked before the window opens.
    script_path_ = args_.get("script", scene_.script);
    if (!script_path_.empty()) script_.emplace(script_path_);  // InputError: exit 1
    if (exit_after_script && !script_)
        throw CliError("afterglow view: --exit-after-script needs a script (--script S.lua)");
    std::vector<InputEvent> replay;
    if (args_.has("replay")) replay = read_replay(args_.get("replay"));
    state_.replaying = !replay.empty();
    if (args_.has("shots")) {
        shots_dir_ = args_.get("shots");
        std::filesystem::create_directories(shots_dir_);
    }

    const int window_w = width_ + state_.panel_width, window_h = std::max(height_, 640);
    glfwSetErrorCallback(on_glfw_error);
    try {
        context_ = gpu::make_gl_context(gpu::GlBackend::window, window_w, window_h,
                                        "afterglow view: " + scene_.name);
    } catch (const gpu::GlError& e) {
        // GLFW's own reason says more than the backend's generic message (which suggests --gl
        // osmesa, no choice for a viewer).
        throw gpu::GlError(
            (g_glfw_error.empty() ? std::string(e.what()) : "window: GLFW: " + g_glfw_error) +
            ". afterglow view needs an X display with OpenGL 4.5 core; without one run it under "
            "`xvfb-run -a`, or use `afterglow render` for headless frames");
    }
    window_ = static_cast<GLFWwindow*>(context_->native_window());
    keep_libraries_loaded();
    glfwSwapInterval(0);  // the pipeline's frame rate, not the display's
    state_.stats.renderer = context_->renderer();
    live_.layout = &layout_;
    live_.frame_w = width_;
    live_.frame_h = height_;
    glfwGetCursorPos(window_, &live_.cursor_x, &live_.cursor_y);
    glfwSetWindowUserPointer(window_, &live_);
    glfwSetMouseButtonCallback(window_, on_mouse_button);
    glfwSetCursorPosCallback(window_, on_cursor);
    glfwSetScrollCallback(window_, on_scroll);
    glfwSetKeyCallback(window_, on_key);
    ui_ = std::make_unique<ViewUi>(window_);  // chains the callbacks above
    live_.ui = ui_.get();

    threads_ = threads;
    make_pipeline();
    controller_ = std::make_unique<ViewController>(scene_, width_, height_);
    initial_ = snapshot(scene_);
    if (scene_.settings.gather.backend == GatherBackend::automatic)
        state_.message(std::string("gather backend ") +
                       kGatherBackendNames[size_t(pipeline_->gather_backend())] + " (" +
                       pipeline_->gather_backend_reason() + ")");
    if (script_) {
        state_.script.path = script_path_;
        state_.script.playing = true;
        loop_->start_script(&*script_);
    }

    size_t next_replay = 0;
    Clock::time_point last = Clock::now();
    double loop_ms = 0.0;
    int script_start_frame = 0;
    for (frame_ = 0; !glfwWindowShouldClose(window_); ++frame_) {
        layout_.update(window_, width_, height_, state_.panel_width);
        live_.frame = frame_;
        glfwPollEvents();
        std::vector<InputEvent> events = std::move(live_.queue);
        live_.queue.clear();
        if (args_.has("record"))
            for (const InputEvent& e : events)
                if (e.type < InputType::key_down || !key_name(e.key).empty())
                    recorded_.push_back(e);
        while (next_replay < replay.size() && replay[next_replay].frame <= frame_)
            events.push_back(replay[next_replay++]);
        handle_events(events);
        controller_->advance(state_.replaying ? 1.0 / 30.0 : std::min(0.1, loop_ms / 1000.0));

        // Edits happen between frames, each after the photon work in flight (scene_edit.h
        // waits for it); a frame that edits nothing does not wait.
        const bool had_restart = requests_.restart;
        apply_requests();
        if (had_restart) script_start_frame = frame_;
        const int edits = controller_->apply(state_, frame_);
        if (edits) last_edit_frame_ = frame_;
        if (script_ && state_.script.playing) run_script(frame_);

        const PipelineStats stats = loop_->step(false);  // the script ran above, when playing
        count_gathered();

        GLuint source = 0;
        switch (state_.mode) {
            case ViewMode::frame:
                source = pipeline_->renderer().frame_texture();
                break;
            case ViewMode::direct:
                source = pipeline_->renderer().aov_texture(FrameTerm::direct);
                break;
            case ViewMode::indirect:
                source = pipeline_->renderer().aov_texture(FrameTerm::indirect);
                break;
            case ViewMode::caustics:
                source = pipeline_->renderer().aov_texture(FrameTerm::caustics);
                break;
            case ViewMode::specular:
                source = pipeline_->renderer().aov_texture(FrameTerm::specular);
                break;
            case ViewMode::volume:
                source = pipeline_->renderer().aov_texture(FrameTerm::volume);
                break;
            case ViewMode::aim:
                source = pipeline_->aim_texture();
                break;
            case ViewMode::iim:
                source = pipeline_->iim_texture();
                break;
            case ViewMode::surfaces:
                break;
            case ViewMode::records:
                if (auto* rc = dynamic_cast<IrradianceCacheMethod*>(&pipeline_->indirect()))
                    source = rc->render_record_view();
                break;
            case ViewMode::photon_tiles:
                if (auto* pm = dynamic_cast<GpuPmMethod*>(&pipeline_->indirect()))
                    source = pm->mapper().render_tile_view();
                break;
            case ViewMode::media:
                source = media_slice_texture();
                break;
            case ViewMode::vpls:  // the VPL sum; the VPLs are overlay points
                source = pipeline_->renderer().aov_texture(FrameTerm::indirect);
                break;
        }
        const int highlight =
            state_.selection.kind == Selection::Kind::object ? state_.selection.index : -1;
        renderer_->render(state_.mode, source, overlay_points(), light_markers(),
                          state_.overlays.point_size, highlight);
        gpu::gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
        gpu::gl::Viewport(0, 0, layout_.fb_w, layout_.fb_h);
        gpu::gl::ClearColor(0.08f, 0.08f, 0.09f, 1.0f);
        gpu::gl::Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
        renderer_->present(layout_.rect(width_, height_), state_.exposure);

        if (frame_ == 0 && !shots_dir_.empty()) screenshot(shot_path("first.png"), false);
        if (screenshot_pending_) {
            char name[64];
            std::snprintf(name, sizeof name, "shot_%05d.png", frame_);
            screenshot(shot_path(name), false);
            screenshot_pending_ = false;
        }
        ui_->draw(state_, scene_, requests_);
        if (window_shot_pending_) {
            char name[64];
            std::snprintf(name, sizeof name, "window_%05d.png", frame_);
            screenshot(shot_path(name), true);
            window_shot_pending_ = false;
        }
        context_->swap_buffers();

        const Clock::time_point now = Clock::now();
        loop_ms = std::chrono::duration<double, std::milli>(now - last).count();
        last = now;
        update_stats(stats, loop_ms);
        FrameRecord rec;
        rec.frame = frame_;
        rec.times = state_.stats.last;
        rec.loop_ms = float(loop_ms);
        rec.groups_queued = stats.photons.groups_queued;
        rec.groups_invalidated = stats.photons.groups_invalidated;
        rec.photons_retraced = stats.photons.photons_retraced;
        rec.texels_pending = stats.iim_texels_pending;
        rec.texels_gathered = stats.iim_texels_gathered;
        rec.edits = edits;
        records_.push_back(rec);

        const bool frames_done = frames > 0 && frame_ + 1 >= frames;
        const int quiet_since = std::max(state_.script.last_edit_frame, script_start_frame);
        const bool script_done =
            exit_after_script && state_.script.frame > 0 && frame_ - quiet_since >= idle_frames;
        if (frames_done || script_done) {
            if (script_done && !g_quiet)
                std::cerr << "afterglow view: the script made no edit for " << idle_frames
                          << " frames; exiting\n";
            ++frame_;
            break;
        }
    }
    pipeline_->sync();
    if (!shots_dir_.empty()) screenshot(shot_path("last.png"), false);
    if (args_.has("record")) {
        write_file_atomically(args_.get("record"), replay_json(recorded_));
        if (!g_quiet)
            std::cerr << "afterglow view: recorded " << recorded_.size() << " events to "
                      << args_.get("record") << "\n";
    }
    if (args_.has("dump")) write_dump(args_.get("dump"));

    std::vector<float> frame_ms, loop_list;
    for (const FrameRecord& r : records_) {
        frame_ms.push_back(r.times.frame_ms);
        loop_list.push_back(r.loop_ms);
    }
    std::fprintf(stderr,
                 "afterglow view: %d frames of %dx%d on %s; pipeline frame median %.1f ms (p95 "
                 "%.1f), whole loop median "
                 "%.1f ms; edits: %d interactive, %d panel, %d script; IIM texels gathered %ld "
                 "(%ld after the first "
                 "edit, %ld of them near moved objects)\n",
                 frame_, width_, height_, state_.stats.renderer.c_str(), percentile(frame_ms, 0.5),
                 percentile(frame_ms, 0.95), percentile(loop_list, 0.5), controller_->edits(),
                 panel_edits_, script_edits_, gathered_total_, gathered_after_edit_,
                 gathered_near_after_edit_);
    for (size_t o = 0; o < scene_.objects.size(); ++o) {
        const glm::vec3 p = scene_.objects[o].transform.translation,
                        p0 = initial_.transforms[o].translation;
        if (p != p0)
            std::fprintf(stderr,
                         "afterglow view: object '%s' at (%.1f, %.1f, %.1f), moved %.1f %s from "
                         "(%.1f, %.1f, %.1f)\n",
                         scene_.objects[o].name.c_str(), p.x, p.y, p.z, glm::length(p - p0),
                         scene_.length_unit.c_str(), p0.x, p0.y, p0.z);
    }
    // GL objects go before the context that owns them.
    ui_.reset();
    renderer_.reset();
    pipeline_.reset();
    return 0;
}

}  // namespace

void ViewState::message(const std::string& text) {
    log.push_back(text);
    while (log.size() > 8) log.pop_front();
    if (!g_quiet) std::cerr << "afterglow view: " << text << "\n";
}

int run_view(const Args& args) {
    Scene scene = load_scene(args.positionals()[0]);
    args.apply_settings(scene);
    Viewer viewer(args, scene);
    return viewer.run();
}

static const Registration kRegistration(kViewCommand, run_view, 6);

}  // namespace ag::cli
