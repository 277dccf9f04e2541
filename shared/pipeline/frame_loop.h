// The one frame loop: scene edits (scripts, the viewer, callers) happen between frames through
// scene_edit.h, each after the photon work in flight has finished (with a frame-time target that
// work may run on past a frame: Pipeline); a script's clock is its own frame count at 30
// frames/s.
// Every command that runs frames (render, converge, view, bench, Python) goes through it.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "shared/pipeline/pipeline.h"
#include "shared/script.h"

namespace ag {

inline constexpr double kScriptFramesPerSecond = 30.0;

class FrameLoop {
public:
    // `script` (may be null) is started here: its on_start runs on the pipeline's scene.
    explicit FrameLoop(Pipeline& pipeline, Script* script = nullptr);

    // Replaces the script (null: none) and starts it; its clock starts again at frame 0.
    void start_script(Script* script);
    // Finishes the photon work in flight: the scene may be written directly (settings, not
    // only through scene_edit.h) until the next step().
    void begin_edits() { pipeline_.sync(); }
    // Runs the script's callback for its next frame; false if it failed
    // (its edits are rolled back, the error is reported and rendering goes on).
    bool run_script();
    // One frame: the script's next frame when `play`, then the pipeline frame.
    PipelineStats step(bool play = true);

    Pipeline& pipeline() { return pipeline_; }
    int frames() const { return frames_; }              // frames stepped so far
    int script_frame() const { return script_frame_; }  // the script's clock, in frames
    // The scene changed between the previous frame and the last one stepped (any source).
    bool edited() const { return edited_; }
    int script_errors() const { return script_errors_; }
    // Called with each script error (default: a warning on stderr for the first five).
    std::function<void(const std::string&)> on_script_error;

private:
    Pipeline& pipeline_;
    Script* script_ = nullptr;
    int frames_ = 0, script_frame_ = 0, script_errors_ = 0;
    uint64_t version_after_frame_ = 0;
    bool edited_ = false;
    // For methods that want the next frame's scene: a copy run by a second instance of the
    // script one frame ahead (Gautron's predefined animation).
    std::unique_ptr<Scene> lookahead_scene_;
    std::unique_ptr<Script> lookahead_script_;
    int lookahead_frame_ = 0;
};

struct FrameEvent {
    int frame = 0;        // 0-based, in this run
    bool edited = false;  // the scene changed before this frame
    const PipelineStats* stats = nullptr;
};

// Runs `frames` frames with `script` (may be null); calls `after` after each (may be empty).
// Returns the last frame's statistics.
PipelineStats run_frames(Pipeline& pipeline, Script* script, int frames,
                         const std::function<void(const FrameEvent&)>& after = {});

// Runs a script ahead on `scene` (a copy, no pipeline) for `frames` frames: the scene's state at
// the end of a run, e.g. to render its reference before the run.
void run_script_ahead(Script& script, Scene& scene, int frames);

}  // namespace ag
