// State of `afterglow view` shared by the main loop, the controls and the ImGui panel: plain data
// (no GL, no ImGui), so the panel's source never sees GL headers and the loop never sees ImGui.
#pragma once

#include <array>
#include <deque>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "shared/frame_terms.h"
#include "shared/settings.h"

namespace ag::cli {

// What the viewport shows: the composed frame, one term of eq. 13.2 (in FrameTerm order, named
// from kFrameTermNames), or a diagnostic view.
enum class ViewMode {
    frame,
    direct = 1 + kFrameTermDirect,
    indirect = 1 + kFrameTermIndirect,
    caustics = 1 + kFrameTermCaustics,
    specular = 1 + kFrameTermSpecular,
    volume = 1 + kFrameTermVolume,
    aim = 1 + kFrameTermCount,
    iim,
    surfaces,
    records,       // irradiance cache records and their zones (docs/irradiance_cache.md)
    photon_tiles,  // gpu_pm's photons per 8×8 screen tile (docs/gpu_pm.md)
    media,         // a slice of the media method's grids (docs/media.md)
    vpls           // the VPL sum with the VPLs as points (docs/vpl.md)
};
inline constexpr std::array kViewModeNames = {"frame",
                                              kFrameTermNames[0],
                                              kFrameTermNames[1],
                                              kFrameTermNames[2],
                                              kFrameTermNames[3],
                                              kFrameTermNames[4],
                                              "aim",
                                              "iim",
                                              "surfaces",
                                              "records",
                                              "photon_tiles",
                                              "media",
                                              "vpls"};
static_assert(kViewModeNames.size() == size_t(ViewMode::vpls) + 1);

struct Selection {
    enum class Kind { none, object, light };
    Kind kind = Kind::none;
    int index = -1;
    bool operator==(const Selection&) const = default;
};

// Points drawn over the view (best effort diagnostics, docs/viewer.md "Overlays").
struct Overlays {
    bool lights = true;            // light positions (grey when switched off)
    bool gather_centres = false;   // IIM texel centres: green gathered this frame, orange queued
    bool primary_photons = false;  // first hit of every photon of every light
    bool group_photons = false;    // every stored vertex of one photon group, coloured by bounce
    int group_light = 0, group = 0;
    float point_size = 3.0f;
};

struct FrameTimes {
    float frame_ms = 0, photon_ms = 0, aim_ms = 0, caustic_ms = 0, gather_ms = 0, draw_ms = 0,
          wait_ms = 0;
};

struct ViewStats {
    static constexpr int kHistory = 240;
    uint64_t frame = 0;
    double fps = 0.0;  // frames per second of the whole loop (pipeline, display, panel)
    FrameTimes last;
    std::vector<FrameTimes> history;  // ring of kHistory, oldest at history_next
    int history_next = 0;
    int groups_valid = 0, groups_invalid = 0, groups_queued = 0;  // all lights together
    int photons_retraced = 0, groups_invalidated = 0, aim_texels = 0;
    int texels_gathered = 0, texels_pending = 0, texels_repaired = 0, caustic_tiles = 0;
    bool converged = false;
    std::string renderer;
    GatherBackend backend = GatherBackend::gl;
    IndirectMethodKind indirect = IndirectMethodKind::iim;
};

struct ScriptStatus {
    std::string path;  // empty: no script
    bool playing = false;
    int frame = 0;      // next on_frame call's frame number
    std::string error;  // last failed call's message (kept until restart)
    int error_count = 0;
    int last_edit_frame = -1;  // viewer frame of the script's last edit
};

struct ViewState {
    ViewMode mode = ViewMode::frame;
    Overlays overlays;
    float exposure = 0.0f;  // stops
    bool fly = false;       // right-drag looks around (fly) instead of orbiting the target
    Selection selection;
    ViewStats stats;
    ScriptStatus script;
    std::deque<std::string> log;  // recent messages, newest last
    int panel_width = 400;        // window pixels right of the viewport
    int frame_width = 0, frame_height = 0;
    bool replaying = false;
    // The `media` view: which grid (MediaField), across which axis (0 x, 1 y, 2 z) and which
    // voxel layer (−1: the middle).
    int media_field = 2, media_axis = 2, media_layer = -1;

    void message(const std::string& text);  // to the log and stderr
};

// What the panel asked for during a frame; the loop applies it before the next frame, through
// scene_edit.h for scene edits.
struct ViewRequests {
    bool play = false, pause = false, step = false, restart = false;
    bool screenshot = false, window_shot = false;
    bool reset_camera = false, copy_camera = false;
    std::optional<Selection> select;
    std::optional<glm::vec3> albedo;  // for the selected object
    struct LightEdit {
        int light = -1;
        std::optional<glm::vec3> value;  // intensity or radiance
        std::optional<bool> enabled;
    };
    std::vector<LightEdit> lights;
    std::optional<Settings> settings;  // budgets changed in the panel
    std::optional<GatherBackend> backend;
    std::optional<IndirectMethodKind> indirect;  // rebuilds the pipeline
};

}  // namespace ag::cli
