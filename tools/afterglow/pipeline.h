// The progressive pipeline of one frame (DESIGN.md "The frame, as data flows through it"): scene
// edits → selective photon tracing and AIM rebuilds on worker threads, concurrently with the GL
// thread's gathering and drawing, which use the previous frame's AIM (double buffering) →
// IIM texels scheduled by Δi under a budget, blended in over several frames → the composed frame.
#pragma once

#include <chrono>
#include <deque>
#include <future>
#include <memory>
#include <vector>

#include "cpu/aim.h"
#include "cpu/caustic_tracer.h"
#include "cpu/cpu_gather.h"
#include "cpu/photon_simulation.h"
#include "gpu/caustics_renderer.h"
#include "gpu/frame_renderer.h"
#include "gpu/hemi_plane_gather.h"
#include "gpu/lightmap_texture.h"
#include "gpu/scene_meshes.h"
#include "shared/parallel.h"
#include "shared/scene.h"

namespace ag::cli {

struct PipelineStats {
    uint64_t frame = 0;
    cpu::PhotonFrameStats photons;
    cpu::CausticStats caustics;
    int caustic_tiles_filtered = 0;
    int iim_texels_gathered = 0;
    int iim_texels_pending = 0;
    int iim_texels_invalid = 0;  // back-face texels repaired from neighbours
    // photon_ms and aim_ms run on the workers, overlapped with gather_ms and draw_ms on the GL
    // thread; wait_ms is what the GL thread then waited for them.
    double photon_ms = 0, aim_ms = 0, caustic_ms = 0, gather_ms = 0, draw_ms = 0, wait_ms = 0, frame_ms = 0;
};

class Pipeline {
public:
    // A GL context must be current. `width`×`height` is the frame size. The gather backend comes
    // from scene.settings.gather.backend; `automatic` measures both on a few texels and keeps the
    // faster.
    Pipeline(Scene& scene, int width, int height, int threads);
    ~Pipeline();

    // One progressive frame; the scene may have been edited since the last call.
    PipelineStats frame();
    // Waits for the photon work in flight (call before editing the scene).
    void sync();

    gpu::FrameImages images() const { return renderer_->read_back(); }
    const gpu::FrameRenderer& renderer() const { return *renderer_; }
    GLuint iim_texture() const { return iim_texture_->id(); }
    GLuint aim_texture() const { return aim_texture_->id(); }
    bool converged() const;  // nothing queued, pending or blending
    GatherBackend gather_backend() const { return backend_; }
    // Per-texel gather cost measured when choosing the backend (µs; 0 if not measured).
    double gl_gather_us() const { return gl_us_; }
    double cpu_gather_us() const { return cpu_us_; }
    // Switches the IIM gather backend (gl or cpu; `automatic` is only measured at construction)
    // from the next frame on.
    void set_gather_backend(GatherBackend backend) {
        if (backend != GatherBackend::automatic) backend_ = backend;
    }

    // For the viewer's diagnostic views and statistics; read them between frames (after frame()
    // returns no photon work is in flight).
    const cpu::PhotonSimulation& photons() const { return *photons_; }
    const gpu::SceneMeshes& meshes() const { return *meshes_; }
    const std::vector<char>& texel_pending() const { return is_pending_; }  // per texel record
    const std::vector<int>& last_gathered() const { return last_gathered_; }  // records, last frame

private:
    void schedule_from_deltas();
    void gather(PipelineStats& stats);
    void gather_batch(const std::vector<int>& batch, GatherBackend backend);
    void choose_backend();
    void blend(PipelineStats& stats);

    Scene& scene_;
    ThreadPool pool_;
    std::unique_ptr<cpu::PhotonSimulation> photons_;
    std::unique_ptr<cpu::Aim> aim_;
    std::unique_ptr<cpu::CausticTracer> caustic_tracer_;
    std::unique_ptr<gpu::CausticsRenderer> caustics_;
    std::vector<glm::vec3> caustic_positions_, caustic_powers_;  // staged at the hand-over
    cpu::CausticStats caustic_stats_;
    std::unique_ptr<gpu::SceneMeshes> meshes_;
    std::unique_ptr<gpu::HemiPlaneGather> gatherer_;
    ThreadPool gather_pool_{1};  // the CPU gather runs beside the photon work, on its own worker
    std::unique_ptr<cpu::RayTracer> gather_rays_;
    std::unique_ptr<cpu::CpuGather> cpu_gather_;
    GatherBackend backend_ = GatherBackend::gl;
    double gl_us_ = 0.0, cpu_us_ = 0.0;
    std::vector<glm::vec3> iim_raw_;     // latest gathered (and repaired) values, atlas-sized
    std::vector<char> texel_valid_;      // per record: last gather saw few enough back faces
    std::unique_ptr<gpu::FrameRenderer> renderer_;
    std::unique_ptr<gpu::LightmapTexture> aim_texture_, iim_texture_;
    std::future<cpu::PhotonFrameStats> photon_work_;
    std::vector<int> aim_dirty_;  // AIM texels changed by the last photon frame, to upload
    std::vector<glm::vec3> staged_aim_;  // their values, copied at the hand-over (no data race)

    // IIM: texels waiting for a gather (FIFO, each once), and the blend from old to new values.
    std::deque<int> pending_;          // texel record indices
    std::vector<char> is_pending_;
    std::vector<int> last_gathered_;   // texel records gathered in the last frame
    std::vector<glm::vec3> iim_from_, iim_to_, iim_shown_;  // atlas-sized
    std::vector<int> blend_start_;     // per atlas texel: frame the new value arrived, −1 = done
    std::vector<int> blending_;        // atlas texels currently blending
    // AIM generations: a texel gathered before the latest AIM upload is stale. Δi picks what is
    // re-gathered first (Larsen ch. 11); a round-robin sweep then refreshes stale texels with the
    // rest of the budget, so the IIM settles on the final AIMs once edits stop.
    int aim_generation_ = 0;
    std::vector<int> texel_generation_;  // per texel record; -1 = never gathered
    size_t sweep_ = 0;
    bool has_stale() const;
    uint64_t frame_ = 0;
    double photon_cpu_ms_ = 0, aim_cpu_ms_ = 0, caustic_cpu_ms_ = 0;  // written by the worker, read after get()
};

}  // namespace ag::cli
