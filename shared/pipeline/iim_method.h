// The indirect term as Larsen computes it (ch. 8-11): IIM lightmaps gathered from the AIMs by
// either gather backend (GL hemi-planes or CPU rays, one ag::Gatherer interface), scheduled by Δi
// and blended in by cpu::Iim, uploaded to an atlas-sized texture the frame reads per surface point.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "cpu/cpu_gather.h"
#include "cpu/iim.h"
#include "gpu/hemi_plane_gather.h"
#include "gpu/lightmap_texture.h"
#include "gpu/scene_meshes.h"
#include "gpu/texel_coverage.h"
#include "shared/parallel.h"
#include "shared/pipeline/indirect_method.h"

namespace ag {

// What `gather.backend = automatic` resolves to under the current GL context: cpu on a software
// rasteriser (llvmpipe, softpipe, swrast), gl on anything else; `reason` (when given) says why.
GatherBackend automatic_gather_backend(std::string* reason = nullptr);

class IimMethod final : public IndirectMethod {
public:
    // `aim_texture` and `aim_values` (atlas-sized) are the AIMs as handed over to the GL thread;
    // the GL gather reads the first, the CPU gather the second. The backend comes from
    // settings.gather.backend; `automatic` measures both on a few texels and keeps the faster.
    // `width` × `height` is the frame's size: the selective schedule gathers first the texels
    // the camera sees (measured at a reduced size by gpu::TexelCoverage).
    IimMethod(const Scene& scene, const gpu::SceneMeshes& meshes,
              const gpu::LightmapTexture& aim_texture, const std::vector<glm::vec3>& aim_values,
              int width, int height, int gather_threads = 1);

    IndirectMethodKind kind() const override { return IndirectMethodKind::iim; }
    void update(const IndirectInputs& in, PipelineStats& stats) override;
    void hand_over(cpu::PhotonSimulation& photons, PipelineStats& stats) override;
    void invalidate_all() override { iim_.invalidate_all(); }
    void prime(cpu::PhotonSimulation& photons, uint64_t frame) override;
    gpu::IndirectTerm term() const override;
    bool settled() const override { return iim_.settled(); }
    uint64_t changes_seen() const override { return seen_sequence_; }

    const cpu::Iim& iim() const { return iim_; }
    // The texel records the last update() gathered (all its chunks).
    const std::vector<int>& last_gathered() const { return gathered_; }
    // Per texel record, the photons' indirect estimate as the AIMs now hold it (see
    // cpu::Iim::note_indirect_estimates); the selective schedule gathers the most stale first.
    void note_indirect_estimates(const std::vector<float>& estimates,
                                 const std::vector<float>& floors) {
        iim_.note_indirect_estimates(estimates, floors);
    }
    GLuint texture() const { return texture_.id(); }
    Gatherer& gatherer(GatherBackend backend);
    GatherBackend backend() const { return backend_; }
    // Switches the backend (gl or cpu; `automatic` is only resolved at construction).
    void set_backend(GatherBackend backend);
    // Why `automatic` chose the backend it did ("" when the settings named one).
    const std::string& backend_reason() const { return backend_reason_; }

private:
    void choose_backend();
    // With a frame-time target: the regions where moved objects change what gathers see (and,
    // into `objects`, which moved).
    std::vector<Bounds> moved_regions(std::vector<int>* objects = nullptr);
    static Bounds world_bounds(const Object& o);
    // Measures the texels' screen coverage again when the camera changed, or when objects moved
    // and the last measurement is `kCoverageFrames` frames old; hands it to the IIM.
    void update_coverage(bool objects_moved, uint64_t frame);
    static constexpr uint64_t kCoverageFrames = 8;
    // Gathers this frame's texels: `budget` at once, or with a time share in chunks (below).
    // `start`: when the frame's indirect work began (the screen coverage and the queueing of
    // moved regions count against the share, as they count in the frame).
    cpu::IimFrameStats gather(const IndirectInputs& in, int budget,
                              std::chrono::steady_clock::time_point start);
    // A chunk is at most one pass of the GL gather (its 256 layers).
    static constexpr int kChunkTexels = 256, kFirstChunkTexels = 8;
    std::vector<int> gathered_;     // texel records gathered in the last update()
    double texel_gather_ms_ = 0.0;  // of it, the time in the gatherers
    double gather_wait_ms_ = 0.0;   // of it, waiting for the workers' new AIMs

    const Scene& scene_;
    cpu::Iim iim_;
    gpu::LightmapTexture texture_;
    uint64_t revision_ = 1;  // IndirectTerm::revision: bumped whenever texture_ changes
    gpu::HemiPlaneGather gl_gather_;
    // The CPU gather runs beside the photon work on workers of its own, as many as the photon
    // work has (the pipeline's): once an edit's photons and AIMs are done, the gather has every
    // core (bumpy_133k_box after its box jump: 0.04 ms a texel on two, 0.07 on one).
    ThreadPool cpu_pool_;
    cpu::CpuGather cpu_gather_;
    SpecularRoutedGather routed_gather_{gl_gather_, cpu_gather_};
    GatherBackend backend_ = GatherBackend::gl;
    std::string backend_reason_;
    PipelineMode mode_ = PipelineMode::selective;  // of the last update()
    uint64_t seen_sequence_ = 0;                   // scene changes looked at
    std::vector<Bounds> placed_;                   // per object: world bounds when last seen
    gpu::TexelCoverage coverage_;
    Camera covered_camera_;       // the camera coverage_ was measured with
    uint64_t covered_frame_ = 0;  // the frame it was measured in; 0 = never
    bool moved_since_coverage_ = false;
};

}  // namespace ag
