#include "tools/afterglow/view_ui.h"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>
#include <cfloat>
#include <string>
#include <vector>

#include "shared/media_grid.h"

namespace ag::cli {

namespace {

const ImVec4 kErrorColour(1.0f, 0.45f, 0.4f, 1.0f);
const ImVec4 kDimColour(0.65f, 0.65f, 0.65f, 1.0f);

bool edit_int(const char* label, int& value, int min, int max, const char* help) {
    const bool changed = ImGui::DragInt(label, &value, std::max(1.0f, float(value) * 0.02f), min,
                                        max, "%d", ImGuiSliderFlags_AlwaysClamp);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", help);
    return changed;
}

void plot(const char* label, const std::vector<FrameTimes>& ring, int next,
          float FrameTimes::*member, float height) {
    if (ring.empty()) return;
    std::vector<float> values;
    values.reserve(ring.size());
    float peak = 1.0f, sum = 0.0f;
    for (size_t k = 0; k < ring.size(); ++k) {
        const float v = ring[(size_t(next) + k) % ring.size()].*member;
        values.push_back(v);
        peak = std::max(peak, v);
        sum += v;
    }
    char overlay[64];
    std::snprintf(overlay, sizeof overlay, "%s: avg %.1f, max %.1f ms", label,
                  sum / float(values.size()), peak);
    ImGui::PlotLines(label, values.data(), int(values.size()), 0, overlay, 0.0f, peak * 1.1f,
                     ImVec2(ImGui::GetContentRegionAvail().x, height));
}

void stats_section(const ViewState& state) {
    const ViewStats& s = state.stats;
    ImGui::Text("frame %llu  %.1f fps  %dx%d", static_cast<unsigned long long>(s.frame), s.fps,
                state.frame_width, state.frame_height);
    ImGui::TextColored(kDimColour, "%s, gather %s", s.renderer.c_str(),
                       kGatherBackendNames[size_t(s.backend)]);
    const FrameTimes& t = s.last;
    ImGui::Text("pipeline %.1f ms: gather %.1f, draw %.1f, waited %.1f", t.frame_ms, t.gather_ms,
                t.draw_ms, t.wait_ms);
    ImGui::Text("workers: photons %.1f, AIM %.1f, caustics %.1f ms", t.photon_ms, t.aim_ms,
                t.caustic_ms);
    ImGui::Text("groups %d valid, %d invalid, %d queued", s.groups_valid, s.groups_invalid,
                s.groups_queued);
    ImGui::Text("retraced %d photons, invalidated %d groups", s.photons_retraced,
                s.groups_invalidated);
    ImGui::Text("AIM texels %d; IIM gathered %d, pending %d", s.aim_texels, s.texels_gathered,
                s.texels_pending);
    ImGui::Text("caustic tiles %d; %s", s.caustic_tiles, s.converged ? "converged" : "converging");
    plot("frame", s.history, s.history_next, &FrameTimes::frame_ms, 50.0f);
    plot("wait", s.history, s.history_next, &FrameTimes::wait_ms, 30.0f);
    plot("gather", s.history, s.history_next, &FrameTimes::gather_ms, 30.0f);
}

void view_section(ViewState& state, const Scene& scene) {
    for (size_t m = 0; m < kViewModeNames.size(); ++m) {
        const std::string label = std::to_string(m + 1) + " " + kViewModeNames[m];
        if (ImGui::RadioButton(label.c_str(), state.mode == ViewMode(m))) state.mode = ViewMode(m);
        if (m % 4 != 3) ImGui::SameLine();
    }
    ImGui::SliderFloat("exposure", &state.exposure, -8.0f, 8.0f, "%+.1f EV");
    if (state.mode == ViewMode::media) {
        ImGui::Combo("grid", &state.media_field, kMediaFieldNames,
                     int(std::size(kMediaFieldNames)));
        ImGui::RadioButton("x", &state.media_axis, 0);
        ImGui::SameLine();
        ImGui::RadioButton("y", &state.media_axis, 1);
        ImGui::SameLine();
        ImGui::RadioButton("z", &state.media_axis, 2);
        ImGui::SliderInt("layer (-1 middle)", &state.media_layer, -1, 511);
    }
    Overlays& o = state.overlays;
    ImGui::Checkbox("lights", &o.lights);
    ImGui::SameLine();
    ImGui::Checkbox("gather centres (G)", &o.gather_centres);
    ImGui::Checkbox("primary photons (P)", &o.primary_photons);
    ImGui::SameLine();
    ImGui::Checkbox("one group (O)", &o.group_photons);
    if (o.group_photons && !scene.lights.empty()) {
        ImGui::SliderInt("light", &o.group_light, 0, int(scene.lights.size()) - 1);
        ImGui::SliderInt("group", &o.group, 0, std::max(0, scene.settings.photons.groups - 1));
    }
    ImGui::SliderFloat("point size", &o.point_size, 1.0f, 8.0f, "%.0f px");
    bool fly = state.fly;
    if (ImGui::Checkbox("fly camera (Tab)", &fly)) state.fly = fly;
}

void script_section(ViewState& state, ViewRequests& requests) {
    ScriptStatus& s = state.script;
    if (s.path.empty()) {
        ImGui::TextColored(kDimColour, "no script (--script S.lua)");
        return;
    }
    ImGui::TextWrapped("%s", s.path.c_str());
    ImGui::Text("%s, next frame %d", s.playing ? "playing" : "paused", s.frame);
    if (ImGui::Button(s.playing ? "pause (space)" : "play (space)"))
        (s.playing ? requests.pause : requests.play) = true;
    ImGui::SameLine();
    if (ImGui::Button("step (N)")) requests.step = true;
    ImGui::SameLine();
    if (ImGui::Button("restart (Backspace)")) requests.restart = true;
    if (!s.error.empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, kErrorColour);
        ImGui::TextWrapped("%d failed call%s; last: %s", s.error_count,
                           s.error_count == 1 ? "" : "s", s.error.c_str());
        ImGui::PopStyleColor();
    }
}

// A light's value (intensity or radiance) as a colour and a strength, so both can be dragged.
bool edit_light_value(const char* id, glm::vec3& value) {
    float strength = std::max({value.r, value.g, value.b});
    glm::vec3 colour = strength > 0.0f ? value / strength : glm::vec3(1.0f);
    ImGui::PushID(id);
    bool changed = ImGui::ColorEdit3("colour", &colour.r, ImGuiColorEditFlags_NoInputs);
    ImGui::SameLine();
    ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x * 0.6f);
    changed |= ImGui::DragFloat("strength", &strength, std::max(1e-3f, strength * 0.01f), 0.0f,
                                FLT_MAX, "%.4g", ImGuiSliderFlags_AlwaysClamp);
    ImGui::PopID();
    if (changed) value = colour * strength;
    return changed;
}

void selection_section(ViewState& state, const Scene& scene, ViewRequests& requests) {
    const Selection& s = state.selection;
    if (s.kind == Selection::Kind::none) {
        ImGui::TextColored(kDimColour, "click an object or a light");
        return;
    }
    if (s.kind == Selection::Kind::object) {
        const Object& o = scene.objects[size_t(s.index)];
        const glm::vec3 p = o.transform.translation;
        ImGui::Text("object '%s' (%s)", o.name.c_str(), o.dynamic ? "dynamic" : "static");
        ImGui::Text("at %.1f %.1f %.1f %s", p.x, p.y, p.z, scene.length_unit.c_str());
        if (o.material.type == MaterialType::diffuse) {
            glm::vec3 albedo = o.material.albedo;
            if (ImGui::ColorEdit3("albedo", &albedo.r)) requests.albedo = albedo;
        } else {
            ImGui::TextColored(kDimColour, "%s: no albedo",
                               kMaterialTypeNames[size_t(o.material.type)]);
        }
        if (o.dynamic) {
            ImGui::PushStyleColor(ImGuiCol_Text, kDimColour);
            ImGui::TextWrapped(
                "drag: move on the horizontal plane (Shift: the plane facing the camera); R, "
                "Shift+R: turn");
            ImGui::PopStyleColor();
        }
    } else {
        const Light& l = scene.lights[size_t(s.index)];
        const glm::vec3 p = l.center();
        ImGui::Text("light '%s' (%s) at %.1f %.1f %.1f", l.name.c_str(),
                    kLightTypeNames[size_t(l.type)], p.x, p.y, p.z);
    }
    if (ImGui::Button("deselect (Esc)")) requests.select = Selection{};
}

void lights_section(const Scene& scene, ViewRequests& requests) {
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& l = scene.lights[i];
        ImGui::PushID(int(i));
        bool on = l.enabled;
        if (ImGui::Checkbox(l.name.c_str(), &on))
            requests.lights.push_back({int(i), std::nullopt, on});
        ImGui::SameLine();
        ImGui::TextColored(kDimColour, l.type == LightType::point || l.type == LightType::spot
                                           ? "I (W/sr)"
                                       : l.type == LightType::sun ? "E"
                                                                  : "L");
        glm::vec3 value = l.value();
        if (edit_light_value("value", value))
            requests.lights.push_back({int(i), value, std::nullopt});
        ImGui::PopID();
    }
}

void budgets_section(const ViewState& state, const Scene& scene, ViewRequests& requests) {
    Settings s = scene.settings;
    bool changed = false;
    changed |= edit_int("retrace budget", s.photons.retrace_budget, 1, 1000000,
                        "photons.retrace_budget: photons re-traced per frame for invalid groups");
    changed |=
        edit_int("verify / group", s.photons.verify_per_frame, 0, s.photons.photons_per_group,
                 "photons.verify_per_frame: photons per group re-traced and compared each frame");
    changed |=
        edit_int("AIM surfaces", s.aim.surfaces_per_frame, 1, 100000,
                 "aim.surfaces_per_frame: AIM rebuilds per frame, largest delta_f / area first");
    changed |= edit_int("IIM texels", s.gather.texels_per_frame, 1, 100000,
                        "gather.texels_per_frame: IIM texels gathered per frame (thesis: <= 20)");
    changed |= edit_int("caustic frames", s.caustics.frames, 1, 1000,
                        "caustics.frames: all caustic photons re-traced over this many frames");
    changed |= edit_int("blend frames", s.gather.blend_frames, 1, 1000,
                        "gather.blend_frames: frames over which a new IIM value fades in");
    if (changed) requests.settings = s;
    int backend = state.stats.backend == GatherBackend::cpu ? 1 : 0;
    const char* names[] = {"gl", "cpu"};
    if (ImGui::Combo("gather backend", &backend, names, 2))
        requests.backend = backend == 1 ? GatherBackend::cpu : GatherBackend::gl;
    // Every indirect method the pipeline knows (settings.indirect.method, --indirect).
    int method = int(state.stats.indirect);
    if (ImGui::Combo("indirect method", &method, kIndirectMethodNames.data(),
                     int(kIndirectMethodNames.size())) &&
        method != int(state.stats.indirect))
        requests.indirect = IndirectMethodKind(method);
}

void help_section() {
    ImGui::TextWrapped(
        "Left click: select an object or light; drag: move it on the horizontal plane through the "
        "grabbed point (Shift: the plane facing the camera). R / Shift+R: turn the object 15 deg.\n"
        "Right drag: orbit (fly mode: look); Shift+right or middle drag: pan; wheel: dolly. "
        "W A S D Q E: fly (Shift: faster). Home: reset camera. C: print and copy the camera. "
        "Tab: orbit/fly.\n"
        "1-8: views. G, P, O: gather centres, primary photons, one group. L: switch the selected "
        "light. Space: play/pause script; N: step; "
        "Backspace: restart. F12: screenshot of the view; Shift+F12: of the window. Esc: "
        "deselect.");
}

}  // namespace

ViewUi::ViewUi(void* glfw_window) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;  // no imgui.ini left in the working directory
    ImGui::StyleColorsDark();
    ImGui::GetStyle().WindowRounding = 0.0f;
    ImGui_ImplGlfw_InitForOpenGL(static_cast<GLFWwindow*>(glfw_window), true);
    ImGui_ImplOpenGL3_Init("#version 450 core");
}

ViewUi::~ViewUi() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
}

bool ViewUi::wants_keyboard() const { return ImGui::GetIO().WantTextInput; }
bool ViewUi::wants_mouse() const { return ImGui::GetIO().WantCaptureMouse; }

void ViewUi::draw(ViewState& state, const Scene& scene, ViewRequests& requests) {
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    const ImVec2 display = ImGui::GetIO().DisplaySize;
    ImGui::SetNextWindowPos(ImVec2(display.x - float(state.panel_width), 0.0f));
    ImGui::SetNextWindowSize(ImVec2(float(state.panel_width), display.y));
    ImGui::Begin(("afterglow view: " + scene.name).c_str(), nullptr,
                 ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
    ImGui::PushItemWidth(ImGui::GetContentRegionAvail().x * 0.55f);
    stats_section(state);
    if (ImGui::CollapsingHeader("view", ImGuiTreeNodeFlags_DefaultOpen)) view_section(state, scene);
    if (ImGui::CollapsingHeader("script", ImGuiTreeNodeFlags_DefaultOpen))
        script_section(state, requests);
    if (ImGui::CollapsingHeader("selection", ImGuiTreeNodeFlags_DefaultOpen))
        selection_section(state, scene, requests);
    if (ImGui::CollapsingHeader("camera")) {
        if (ImGui::Button("reset (Home)")) requests.reset_camera = true;
        ImGui::SameLine();
        if (ImGui::Button("print + copy JSON (C)")) requests.copy_camera = true;
        const glm::vec3 e = scene.camera.eye, t = scene.camera.target;
        ImGui::TextColored(kDimColour, "eye %.1f %.1f %.1f", e.x, e.y, e.z);
        ImGui::TextColored(kDimColour, "target %.1f %.1f %.1f", t.x, t.y, t.z);
    }
    if (ImGui::CollapsingHeader("lights")) lights_section(scene, requests);
    if (ImGui::CollapsingHeader("budgets")) budgets_section(state, scene, requests);
    if (ImGui::CollapsingHeader("log", ImGuiTreeNodeFlags_DefaultOpen))
        for (const std::string& line : state.log) ImGui::TextWrapped("%s", line.c_str());
    if (ImGui::CollapsingHeader("help")) help_section();
    if (ImGui::Button("screenshot (F12)")) requests.screenshot = true;
    ImGui::SameLine();
    if (ImGui::Button("window (Shift+F12)")) requests.window_shot = true;
    ImGui::PopItemWidth();
    ImGui::End();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace ag::cli
