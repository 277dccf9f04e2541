#include "shared/pipeline/frame_loop.h"

#include "shared/input_error.h"

namespace ag {

FrameLoop::FrameLoop(Pipeline& pipeline, Script* script) : pipeline_(pipeline) {
    on_script_error = [this](const std::string& message) {
        if (script_errors_ <= 5) warn(message + " (edit skipped, rendering goes on)");
    };
    version_after_frame_ = pipeline_.scene().version;
    start_script(script);
}

void FrameLoop::start_script(Script* script) {
    script_ = script;
    script_frame_ = 0;
    lookahead_scene_.reset();
    lookahead_script_.reset();
    lookahead_frame_ = 0;
    pipeline_.indirect().set_lookahead(nullptr);
    if (!script_) return;
    begin_edits();
    if (pipeline_.indirect().wants_lookahead()) {
        try {
            lookahead_script_ = std::make_unique<Script>(script_->path());
            lookahead_scene_ = std::make_unique<Scene>(pipeline_.scene());
            lookahead_script_->on_start(*lookahead_scene_);
        } catch (const std::exception&) {
            // A script made from text has no file to load twice: no look-ahead, records near
            // edits then expire at once.
            lookahead_script_.reset();
            lookahead_scene_.reset();
        }
    }
    if (!script_->on_start(pipeline_.scene())) {
        ++script_errors_;
        on_script_error(*script_->last_error());
    }
}

bool FrameLoop::run_script() {
    if (!script_) return true;
    const bool ok =
        script_->on_frame(pipeline_.scene(), script_frame_, script_frame_ / kScriptFramesPerSecond);
    ++script_frame_;
    if (!ok) {
        ++script_errors_;
        on_script_error(*script_->last_error());
    }
    return ok;
}

PipelineStats FrameLoop::step(bool play) {
    // No begin_edits(): the photon work of the last frame may run on (a frame-time target); the
    // script's edits wait for it through the scene (Scene::before_edit) only when it edits.
    if (play) run_script();
    if (lookahead_script_) {
        // The copy runs the frame after the one just run: the scene as the next frame sees it.
        while (lookahead_frame_ <= script_frame_) {
            lookahead_script_->on_frame(*lookahead_scene_, lookahead_frame_,
                                        lookahead_frame_ / kScriptFramesPerSecond);
            ++lookahead_frame_;
        }
        pipeline_.indirect().set_lookahead(lookahead_scene_.get());
    }
    edited_ = pipeline_.scene().version != version_after_frame_;
    const PipelineStats stats = pipeline_.frame();
    version_after_frame_ = pipeline_.scene().version;
    ++frames_;
    return stats;
}

PipelineStats run_frames(Pipeline& pipeline, Script* script, int frames,
                         const std::function<void(const FrameEvent&)>& after) {
    FrameLoop loop(pipeline, script);
    PipelineStats last;
    for (int f = 0; f < frames; ++f) {
        last = loop.step();
        if (after) after(FrameEvent{f, loop.edited(), &last});
    }
    pipeline.sync();
    return last;
}

void run_script_ahead(Script& script, Scene& scene, int frames) {
    script.on_start(scene);
    for (int f = 0; f < frames; ++f) script.on_frame(scene, f, f / kScriptFramesPerSecond);
}

}  // namespace ag
