// The progressive pipeline of one frame (DESIGN.md "The frame, as data flows through it"): scene
// edits → selective photon tracing and AIM rebuilds on worker threads, concurrently with the GL
// thread, which uploads the AIMs handed over by the last frame, brings the indirect term up to
// date (an IndirectMethod: IIM texels gathered by Δi under a budget, blended in), renders caustics
// and composes the frame (Larsen eq. 13.2). The two sides meet at the hand-over: between gather
// chunks or at the end of the frame once the workers are done. With a frame-time target a frame
// does not wait for them (the picture lags, not the frame rate): the work runs on into the next
// frame, which starts none of its own and takes it over when it is done. A scene edit waits for
// it (Scene::before_edit), since the workers read the scene.
#pragma once

#include <array>
#include <chrono>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include "cpu/aim.h"
#include "cpu/caustic_tracer.h"
#include "cpu/photon_simulation.h"
#include "gpu/caustics_renderer.h"
#include "gpu/frame_renderer.h"
#include "gpu/lightmap_texture.h"
#include "gpu/scene_meshes.h"
#include "shared/parallel.h"
#include "shared/pipeline/gpu_pm_method.h"
#include "shared/pipeline/iim_method.h"
#include "shared/pipeline/indirect_method.h"
#include "shared/pipeline/irradiance_cache_method.h"
#include "shared/pipeline/media_method.h"
#include "shared/pipeline/pipeline_stats.h"
#include "shared/pipeline/scheduler.h"
#include "shared/scene.h"
#include "shared/worker_thread.h"

namespace ag {

struct PipelineOptions {
    int width = 0, height = 0;  // frame size; 0 = the scene camera's
    int threads = -1;           // worker threads; −1 = settings.threads (0 = all cores)
    PipelineMode mode = PipelineMode::selective;
    // Instrumentation (tracing, tests): called on the worker when a frame's CPU work starts, and
    // on the GL thread once the frame is drawn, before the hand-over.
    std::function<void()> on_cpu_work_start, on_gl_drawn;
    // Pfeuti's method for the volume term of scenes with media (its width and height are the
    // frame's).
    MediaMethodSettings media;
};

// Makes the indirect method named by settings.indirect.method (screen-space methods render at
// width × height).
std::unique_ptr<IndirectMethod> make_indirect_method(const Scene& scene,
                                                     const gpu::SceneMeshes& meshes,
                                                     const gpu::LightmapTexture& aim_texture,
                                                     const std::vector<glm::vec3>& aim_values,
                                                     int width, int height, int gather_threads = 1);

class Pipeline {
public:
    // A GL context must be current. Edit the scene between frames through scene_edit.h (each edit
    // waits for the photon work in flight); anything else that writes the scene (settings)
    // calls sync() first.
    Pipeline(Scene& scene, const PipelineOptions& options);
    ~Pipeline();
    Pipeline(const Pipeline&) = delete;
    Pipeline& operator=(const Pipeline&) = delete;

    // One progressive frame; the scene may have been edited since the last call.
    PipelineStats frame();
    // Waits for the photon work in flight and takes it over (its counts go to the next frame's
    // stats).
    void sync();
    // Photon work is running on past the last frame (with a frame-time target).
    bool workers_busy() const { return cpu_work_.valid(); }
    // Untimed: brings everything to the converged state of the current scene at once (all
    // photons traced, every AIM and indirect texel computed and shown, caustics complete), so
    // that a benchmark measures an edit from where an interactive user would make it. Returns
    // the frames it ran after the bulk work (caustics and hand-overs), at most `max_frames`.
    int prime(int max_frames = 64);

    Scene& scene() { return scene_; }
    PipelineMode mode() const { return mode_; }
    uint64_t frame_index() const { return frame_; }
    const FrameScheduler& scheduler() const { return scheduler_; }
    gpu::FrameImages images() const { return renderer_->read_back(); }
    const gpu::FrameRenderer& renderer() const { return *renderer_; }
    const gpu::CausticsRenderer& caustics() const { return *caustics_; }
    const IndirectMethod& indirect() const { return *indirect_; }
    IndirectMethod& indirect() { return *indirect_; }
    // The IIM method when it is the active one, else null (for lightmap views and statistics).
    IimMethod* iim_method() { return dynamic_cast<IimMethod*>(indirect_.get()); }
    const IimMethod* iim_method() const { return dynamic_cast<const IimMethod*>(indirect_.get()); }
    GLuint aim_texture() const { return aim_texture_.id(); }
    GLuint iim_texture() const;  // 0 without the IIM method
    // Nothing queued, pending or blending anywhere, and the cube maps show the latest indirect
    // term.
    bool converged() const;

    // Gather backend of the IIM method (gl when there is none).
    GatherBackend gather_backend() const;
    void set_gather_backend(GatherBackend backend);
    std::string gather_backend_reason() const;  // why `automatic` chose it; "" otherwise

    // For the viewer's diagnostic views; read them between frames.
    const cpu::PhotonSimulation& photons() {
        sync();
        return *photons_;
    }
    const gpu::SceneMeshes& meshes() const { return *meshes_; }
    const std::vector<char>& texel_pending() const;  // per texel record; empty without IIM
    const std::vector<int>& last_gathered() const;   // texel records gathered last frame
    // Pfeuti's media method behind the `volume` term (grids, fluence) where the scene has media
    // and a light it can use; null otherwise.
    const MediaMethodResult* media() const { return media_.get(); }

private:
    void start_cpu_work(const FrameBudgets& budgets);
    // Waits for the CPU side, stages its results for the GL side and adds its counts to `stats`.
    void hand_over(PipelineStats& stats);
    // A frame waits for its photon work at the end: without a frame-time target (offline runs,
    // frame by frame deterministic), with settings.schedule.wait_for_workers, and in `full` mode
    // (everything every frame).
    bool waits_for_workers() const;
    // Between gather chunks: hand_over() if the workers have finished (never waits) and upload
    // the new AIM texels at once; true when AIMs changed.
    bool hand_over_if_done(PipelineStats& stats);
    // The volume term: the media method again when the scene changed, the view march alone when
    // only the camera moved (docs/media.md).
    void update_media();

    Scene& scene_;
    PipelineMode mode_;
    std::function<void()> on_cpu_work_start_, on_gl_drawn_;
    ThreadPool pool_;
    std::unique_ptr<cpu::PhotonSimulation> photons_;
    std::unique_ptr<cpu::Aim> aim_;
    std::unique_ptr<cpu::CausticTracer> caustic_tracer_;
    std::unique_ptr<gpu::SceneMeshes> meshes_;
    std::unique_ptr<gpu::FrameRenderer> renderer_;
    std::unique_ptr<gpu::CausticsRenderer> caustics_;
    gpu::LightmapTexture aim_texture_;
    std::unique_ptr<IndirectMethod> indirect_;
    bool uses_photon_maps_ = true;  // indirect_ reads the CPU photon maps and AIMs
    FrameScheduler scheduler_;

    // Results of the CPU side, written by the worker, read only after the hand-over.
    struct CpuWork {
        cpu::PhotonFrameStats photons;
        cpu::CausticStats caustics;
        double photon_ms = 0, aim_ms = 0, caustic_ms = 0;
    };
    std::future<CpuWork> cpu_work_;
    bool cpu_work_repairs_ = false;  // cpu_work_ repairs an edit (IndirectInputs::wait_hand_over)
    // Runs each frame's CPU side; declared after everything its tasks use, so it is joined first.
    WorkerThread cpu_thread_;
    // Staged at the hand-over for the next frame's GL work (no data race with the workers).
    std::vector<int> aim_dirty_;         // AIM texels changed by the last photon frame
    std::vector<glm::vec3> staged_aim_;  // atlas-sized AIM radiance as the GL side sees it
    std::vector<glm::vec3> caustic_positions_, caustic_powers_;
    uint64_t frame_ = 0;
    // Handed over outside a frame (sync()): reported with the next frame. Edits' waits for the
    // workers, counted into the next frame's time.
    PipelineStats carried_;
    double edit_wait_ms_ = 0.0;
    // Caustic photons are re-traced a slice a frame (ch. 12): they hold the current scene once
    // settings.caustics.frames frames have passed since it last changed, and are drawn a frame
    // after they are traced.
    uint64_t seen_version_ = 0;
    bool last_frame_edited_ = false;      // the last frame() saw a scene edit
    int caustic_slices_since_edit_ = 0;   // caustic slices handed over since the last edit
    int frames_since_edit_ = 0;           // frames since the last edit's, that one counted
    bool staged_caustics_drawn_ = false;  // the staged caustic photons were drawn
    bool edits_seen_ = false;           // a frame() saw a scene edit (the frames after it catch up)
    bool caustics_deferred_ = false;    // the last frame kept the caustics drawn before it
    bool caustics_drawn_last_ = false;  // the last frame drew the caustics anew
    std::unique_ptr<MediaMethodResult> media_;
    MediaMethodSettings media_settings_;
    uint64_t media_version_ = 0;
    Camera media_camera_;
    bool media_failed_ = false;  // the scene's media had no light the method can use
    std::string media_warning_;  // the last reason warned about
};

}  // namespace ag
