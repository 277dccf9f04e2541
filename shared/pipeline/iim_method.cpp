#include "shared/pipeline/iim_method.h"

#include <chrono>

#include "gpu/gl.h"

namespace ag {

IimMethod::IimMethod(const Scene& scene, const gpu::SceneMeshes& meshes,
                     const gpu::LightmapTexture& aim_texture,
                     const std::vector<glm::vec3>& aim_values)
    : scene_(scene),
      iim_(scene),
      texture_(scene.atlas),
      gl_gather_(scene, meshes, 256, &aim_texture),
      cpu_gather_(scene, cpu_pool_, &aim_values) {
    backend_ = scene_.settings.gather.backend;
    if (backend_ == GatherBackend::automatic) choose_backend();
}

Gatherer& IimMethod::gatherer(GatherBackend backend) {
    if (backend == GatherBackend::cpu) return cpu_gather_;
    return gl_gather_;
}

void IimMethod::set_backend(GatherBackend backend) {
    if (backend != GatherBackend::automatic) backend_ = backend;
}

void IimMethod::choose_backend() {
    // A short measurement on up to 32 texels, each backend warmed up once. Only the gatherers
    // run: the IIM itself is not touched.
    std::vector<int> sample;
    for (size_t t = 0; t < scene_.atlas.texels.size() && sample.size() < 32; ++t)
        sample.push_back(int(t));
    if (sample.empty()) {
        backend_ = GatherBackend::gl;
        return;
    }
    auto time_us = [&](GatherBackend b) {
        gatherer(b).gather(sample);
        gpu::gl::Finish();
        const auto t = std::chrono::steady_clock::now();
        gatherer(b).gather(sample);
        gpu::gl::Finish();
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
        return 1000.0 * ms / double(sample.size());
    };
    gl_us_ = time_us(GatherBackend::gl);
    cpu_us_ = time_us(GatherBackend::cpu);
    backend_ = cpu_us_ < gl_us_ ? GatherBackend::cpu : GatherBackend::gl;
}

void IimMethod::update(const IndirectInputs& in, PipelineStats& stats) {
    if (in.aim_changed) iim_.aim_changed();
    const GatherSettings& g = scene_.settings.gather;
    const int budget = in.brute_force ? int(scene_.atlas.texels.size()) : g.texels_per_frame;
    const cpu::IimFrameStats s = iim_.gather(gatherer(backend_), budget, in.frame);
    stats.iim_texels_gathered = s.gathered;
    stats.iim_texels_invalid = s.invalid;
    texture_.update(iim_.shown(), iim_.blend(in.frame, in.brute_force ? 1 : g.blend_frames));
}

void IimMethod::hand_over(cpu::PhotonSimulation& photons, PipelineStats& stats) {
    iim_.schedule(photons.maps());
    stats.iim_texels_pending = iim_.pending();
}

gpu::IndirectTerm IimMethod::term() const {
    return gpu::IndirectTerm{texture_.id(), gpu::IndirectSpace::lightmap};
}

}  // namespace ag
