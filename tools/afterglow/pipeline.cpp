#include "tools/afterglow/pipeline.h"

#include <algorithm>

#include "shared/lightmap_sample.h"

namespace ag::cli {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
}  // namespace

Pipeline::Pipeline(Scene& scene, int width, int height, int threads) : scene_(scene), pool_(threads) {
    photons_ = std::make_unique<cpu::PhotonSimulation>(scene_, pool_);
    aim_ = std::make_unique<cpu::Aim>(scene_, pool_);
    meshes_ = std::make_unique<gpu::SceneMeshes>(scene_);
    gatherer_ = std::make_unique<gpu::HemiPlaneGather>(scene_, *meshes_);
    renderer_ = std::make_unique<gpu::FrameRenderer>(scene_, *meshes_, width, height);
    caustic_tracer_ = std::make_unique<cpu::CausticTracer>(scene_, pool_);
    caustics_ = std::make_unique<gpu::CausticsRenderer>(scene_, *meshes_, width, height);
    aim_texture_ = std::make_unique<gpu::LightmapTexture>(scene_.atlas);
    iim_texture_ = std::make_unique<gpu::LightmapTexture>(scene_.atlas);
    const size_t n = size_t(scene_.atlas.width) * size_t(scene_.atlas.height);
    iim_from_.assign(n, glm::vec3(0.0f));
    iim_to_.assign(n, glm::vec3(0.0f));
    iim_shown_.assign(n, glm::vec3(0.0f));
    staged_aim_.assign(n, glm::vec3(0.0f));
    blend_start_.assign(n, -1);
    is_pending_.assign(scene_.atlas.texels.size(), 1);
    texel_generation_.assign(scene_.atlas.texels.size(), -1);
    iim_raw_.assign(n, glm::vec3(0.0f));
    texel_valid_.assign(scene_.atlas.texels.size(), 0);
    gather_rays_ = std::make_unique<cpu::RayTracer>(scene_);
    cpu_gather_ = std::make_unique<cpu::CpuGather>(scene_, *gather_rays_, gather_pool_);
    backend_ = scene_.settings.gather.backend;
    if (backend_ == GatherBackend::automatic) choose_backend();
    for (int t = 0; t < int(scene_.atlas.texels.size()); ++t) pending_.push_back(t);
}

Pipeline::~Pipeline() { sync(); }

void Pipeline::sync() {
    if (photon_work_.valid()) photon_work_.wait();
}

void Pipeline::schedule_from_deltas() {
    // Larsen ch. 11: re-gather the texels of surfaces whose indirect photon hits changed most.
    std::vector<int> surfaces;
    for (int s = 0; s < int(photons_->maps().surface_count()); ++s) {
        cpu::SurfaceHits& h = photons_->maps().surface(s);
        const double flux = std::abs(cpu::energy(h.flux));
        if (h.delta_i <= 0.0 || (flux > 0.0 && h.delta_i / flux <= double(scene_.settings.aim.delta_threshold))) continue;
        surfaces.push_back(s);
    }
    std::stable_sort(surfaces.begin(), surfaces.end(), [&](int a, int b) {
        return photons_->maps().surface(a).delta_i > photons_->maps().surface(b).delta_i;
    });
    for (int s : surfaces) {
        photons_->maps().surface(s).delta_i = 0.0;
        for (int t = 0; t < int(scene_.atlas.texels.size()); ++t)
            if (scene_.atlas.texels[size_t(t)].surface == s && !is_pending_[size_t(t)]) {
                is_pending_[size_t(t)] = 1;
                pending_.push_back(t);
            }
    }
}

void Pipeline::gather(PipelineStats& stats) {
    last_gathered_.clear();
    std::vector<int> batch;
    while (!pending_.empty() && int(batch.size()) < scene_.settings.gather.texels_per_frame) {
        batch.push_back(pending_.front());
        is_pending_[size_t(pending_.front())] = 0;
        pending_.pop_front();
    }
    // The rest of the budget refreshes texels gathered with older AIMs, round robin.
    const size_t n = texel_generation_.size();
    for (size_t visited = 0; visited < n && int(batch.size()) < scene_.settings.gather.texels_per_frame; ++visited) {
        const size_t t = sweep_;
        sweep_ = (sweep_ + 1) % n;
        if (!is_pending_[t] && texel_generation_[t] < aim_generation_ &&
            std::find(batch.begin(), batch.end(), int(t)) == batch.end())
            batch.push_back(int(t));
    }
    if (batch.empty()) return;
    for (int t : batch) texel_generation_[size_t(t)] = aim_generation_;
    gather_batch(batch, backend_);
    const int w = scene_.atlas.width;
    for (int r : batch) {
        const TexelRecord& t = scene_.atlas.texels[size_t(r)];
        const size_t a = size_t(t.y) * size_t(w) + size_t(t.x);
        stats.iim_texels_invalid += texel_valid_[size_t(r)] ? 0 : 1;
        iim_from_[a] = iim_shown_[a];
        iim_to_[a] = iim_raw_[a];
        if (blend_start_[a] < 0) blending_.push_back(int(a));
        blend_start_[a] = int(frame_);
    }
    stats.iim_texels_gathered = int(batch.size());
    last_gathered_ = batch;
}

void Pipeline::gather_batch(const std::vector<int>& batch, GatherBackend backend) {
    if (backend == GatherBackend::cpu) {
        gather_rays_->update(scene_);
        cpu_gather_->gather(batch, staged_aim_, iim_raw_);  // repairs its invalid texels itself
        for (int r : batch) texel_valid_[size_t(r)] = cpu_gather_->valid()[size_t(r)];
        return;
    }
    const std::vector<gpu::GatherResult> results = gatherer_->gather(batch, aim_texture_->id(), aim_texture_->charts());
    const int w = scene_.atlas.width;
    std::vector<int> invalid;
    for (size_t k = 0; k < batch.size(); ++k) {
        const TexelRecord& t = scene_.atlas.texels[size_t(batch[k])];
        iim_raw_[size_t(t.y) * size_t(w) + size_t(t.x)] = results[k].iim;
        // Behind or inside geometry: take the chart's valid neighbours instead of leaking.
        const bool valid = results[k].back_fraction <= kBackFaceInvalidFraction;
        texel_valid_[size_t(batch[k])] = valid;
        if (!valid) invalid.push_back(batch[k]);
    }
    if (!invalid.empty()) repair_invalid_texels(scene_.atlas, iim_raw_, texel_valid_, invalid);
}

void Pipeline::choose_backend() {
    // A short measurement on up to 32 texels, each backend warmed up once.
    std::vector<int> sample;
    for (size_t t = 0; t < scene_.atlas.texels.size() && sample.size() < 32; ++t) sample.push_back(int(t));
    if (sample.empty()) {
        backend_ = GatherBackend::gl;
        return;
    }
    auto time_us = [&](GatherBackend b) {
        gather_batch(sample, b);
        gpu::gl::Finish();
        const Clock::time_point t = Clock::now();
        gather_batch(sample, b);
        gpu::gl::Finish();
        return 1000.0 * ms_since(t) / double(sample.size());
    };
    gl_us_ = time_us(GatherBackend::gl);
    cpu_us_ = time_us(GatherBackend::cpu);
    backend_ = cpu_us_ < gl_us_ ? GatherBackend::cpu : GatherBackend::gl;
    std::fill(texel_valid_.begin(), texel_valid_.end(), 0);
    std::fill(iim_raw_.begin(), iim_raw_.end(), glm::vec3(0.0f));
}

void Pipeline::blend(PipelineStats&) {
    // Two IIM buffers, blended over `blend_frames` so new gathers never pop.
    const int frames = scene_.settings.gather.blend_frames;
    std::vector<int> still;
    for (int a : blending_) {
        const float t = std::min(1.0f, float(int(frame_) - blend_start_[size_t(a)] + 1) / float(frames));
        iim_shown_[size_t(a)] = glm::mix(iim_from_[size_t(a)], iim_to_[size_t(a)], t);
        if (t < 1.0f) still.push_back(a);
        else blend_start_[size_t(a)] = -1;
    }
    iim_texture_->update(iim_shown_, blending_);
    blending_.swap(still);
}

PipelineStats Pipeline::frame() {
    const Clock::time_point start = Clock::now();
    PipelineStats stats;
    stats.frame = ++frame_;
    sync();
    // CPU: photons and AIMs for this frame's scene, on the workers, while GL works below.
    photon_work_ = std::async(std::launch::async, [this] {
        const Clock::time_point t0 = Clock::now();
        cpu::PhotonFrameStats st = photons_->frame();
        const Clock::time_point t1 = Clock::now();
        st.aim_texels_rebuilt = aim_->update(photons_->maps(), &st.aim_surfaces_rebuilt);
        const Clock::time_point t2 = Clock::now();
        caustic_stats_ = caustic_tracer_->frame();
        photon_cpu_ms_ = std::chrono::duration<double, std::milli>(t1 - t0).count();
        aim_cpu_ms_ = std::chrono::duration<double, std::milli>(t2 - t1).count();
        caustic_cpu_ms_ = ms_since(t2);
        return st;
    });
    // GL: last frame's AIM texels, then gathers and the frame.
    Clock::time_point t = Clock::now();
    if (!aim_dirty_.empty()) ++aim_generation_;
    aim_texture_->update(staged_aim_, aim_dirty_);
    aim_dirty_.clear();
    gather(stats);
    stats.gather_ms = ms_since(t);
    t = Clock::now();
    blend(stats);
    caustics_->render(caustic_positions_, caustic_powers_);
    stats.caustic_tiles_filtered = caustics_->tiles_filtered();
    renderer_->render(iim_texture_->id(), caustics_->texture());
    gpu::gl::Finish();
    stats.draw_ms = ms_since(t);
    // Hand-over: wait for the CPU side, stage its AIM texels for the next frame's upload.
    t = Clock::now();
    stats.photons = photon_work_.get();
    stats.wait_ms = ms_since(t);
    stats.photon_ms = photon_cpu_ms_;
    stats.aim_ms = aim_cpu_ms_;
    stats.caustic_ms = caustic_cpu_ms_;
    stats.caustics = caustic_stats_;
    caustic_positions_.clear();
    caustic_powers_.clear();
    for (const cpu::CausticPhoton& p : caustic_tracer_->photons())
        if (p.power != glm::vec3(0.0f)) {
            caustic_positions_.push_back(p.position);
            caustic_powers_.push_back(p.power);
        }
    aim_dirty_ = aim_->take_dirty_texels();
    for (int a : aim_dirty_) staged_aim_[size_t(a)] = aim_->radiance()[size_t(a)];
    schedule_from_deltas();
    stats.iim_texels_pending = int(pending_.size());
    stats.frame_ms = ms_since(start);
    return stats;
}

bool Pipeline::has_stale() const {
    for (int g : texel_generation_)
        if (g < aim_generation_) return true;
    return false;
}

bool Pipeline::converged() const {
    return photons_->settled() && pending_.empty() && blending_.empty() && aim_dirty_.empty() && !has_stale();
}

}  // namespace ag::cli
