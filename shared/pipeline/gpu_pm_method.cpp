#include "shared/pipeline/gpu_pm_method.h"

#include "shared/scene_edit.h"

namespace ag {

GpuPmMethod::GpuPmMethod(const Scene& scene, const gpu::SceneMeshes& meshes, int width, int height)
    : scene_(scene), g_buffer_(scene, meshes, width, height), mapper_(scene, g_buffer_) {
    const std::vector<SceneChange> changes = changes_since(scene, 0);
    seen_sequence_ = changes.empty() ? 0 : changes.back().sequence;
}

void GpuPmMethod::update(const IndirectInputs& in, PipelineStats&) {
    // Photons live in world space: a camera move keeps them; every other edit restarts them.
    for (const SceneChange& c : changes_since(scene_, seen_sequence_)) {
        if (c.kind != ChangeKind::camera) restart_ = true;
        seen_sequence_ = c.sequence;
    }
    if (in.mode == PipelineMode::full) restart_ = true;
    if (restart_) {
        mapper_.reset();
        restart_ = false;
        ++restarts_;
    }
    const bool traced = !mapper_.settled();
    mapper_.trace();
    g_buffer_.render();
    mapper_.render();
    const glm::mat4& vp = g_buffer_.last_view().view_projection;
    if (traced || vp != last_view_projection_) ++revision_;
    last_view_projection_ = vp;
}

void GpuPmMethod::prime(cpu::PhotonSimulation&, uint64_t) {
    for (const SceneChange& c : changes_since(scene_, seen_sequence_)) seen_sequence_ = c.sequence;
    mapper_.reset();
    while (!mapper_.settled()) mapper_.trace();
    g_buffer_.render();
    mapper_.render();
    ++revision_;
}

gpu::IndirectTerm GpuPmMethod::term() const {
    return {mapper_.texture(), gpu::IndirectSpace::screen, revision_};
}

}  // namespace ag
