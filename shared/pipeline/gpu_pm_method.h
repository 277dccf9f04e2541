// GPU photon mapping (Jimenez Kwast 2016) as the pipeline's indirect method: a screen-space term
// from gpu::GpuPhotonMapper over its own G-buffer. It needs no CPU photon maps, AIMs or rays: the
// pipeline skips that work (uses_photon_maps() is false), and nothing is read back per frame.
// Photons accumulate while the scene is static; any edit but a camera move restarts them.
#pragma once

#include <memory>

#include "gpu/g_buffer.h"
#include "gpu/gpu_photon_mapper.h"
#include "gpu/scene_meshes.h"
#include "shared/pipeline/indirect_method.h"

namespace ag {

class GpuPmMethod final : public IndirectMethod {
public:
    GpuPmMethod(const Scene& scene, const gpu::SceneMeshes& meshes, int width, int height);

    IndirectMethodKind kind() const override { return IndirectMethodKind::gpu_pm; }
    void update(const IndirectInputs& in, PipelineStats& stats) override;
    void hand_over(cpu::PhotonSimulation&, PipelineStats&) override {}
    void invalidate_all() override { restart_ = true; }
    void prime(cpu::PhotonSimulation& photons, uint64_t frame) override;
    gpu::IndirectTerm term() const override;
    bool settled() const override { return mapper_.settled(); }
    uint64_t changes_seen() const override { return seen_sequence_; }
    bool uses_photon_maps() const override { return false; }

    const gpu::GpuPhotonMapper& mapper() const { return mapper_; }
    gpu::GpuPhotonMapper& mapper() { return mapper_; }
    const gpu::GBuffer& g_buffer() const { return g_buffer_; }
    int restarts() const { return restarts_; }

private:
    const Scene& scene_;
    gpu::GBuffer g_buffer_;
    gpu::GpuPhotonMapper mapper_;
    uint64_t seen_sequence_ = 0, revision_ = 1;
    glm::mat4 last_view_projection_{0.0f};
    bool restart_ = false;
    int restarts_ = 0;
};

}  // namespace ag
