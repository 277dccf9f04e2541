#include "tools/afterglow/pipeline.h"

#include <algorithm>

namespace ag::cli {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
constexpr float kInvalidBackFraction = 0.1f;  // a texel that sees more back faces is inside geometry
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
    const std::vector<gpu::GatherResult> results = gatherer_->gather(batch, aim_texture_->id());
    const int w = scene_.atlas.width;
    std::vector<char> invalid(batch.size(), 0);
    for (size_t k = 0; k < batch.size(); ++k) {
        const TexelRecord& t = scene_.atlas.texels[size_t(batch[k])];
        const size_t a = size_t(t.y) * size_t(w) + size_t(t.x);
        glm::vec3 value = results[k].iim;
        if (results[k].back_fraction > kInvalidBackFraction) {
            // Behind or inside geometry: take the chart's valid neighbours instead of leaking.
            invalid[k] = 1;
            ++stats.iim_texels_invalid;
            glm::vec3 sum(0.0f);
            int count = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = t.x + dx, ny = t.y + dy;
                    if (nx < 0 || ny < 0 || nx >= w || ny >= scene_.atlas.height || (dx == 0 && dy == 0)) continue;
                    const int r = scene_.atlas.texel_at(nx, ny);
                    if (r < 0 || scene_.atlas.texels[size_t(r)].chart != t.chart) continue;
                    sum += iim_to_[size_t(ny) * size_t(w) + size_t(nx)];
                    ++count;
                }
            value = count > 0 ? sum / float(count) : glm::vec3(0.0f);
        }
        iim_from_[a] = iim_shown_[a];
        iim_to_[a] = value;
        if (blend_start_[a] < 0) blending_.push_back(int(a));
        blend_start_[a] = int(frame_);
    }
    stats.iim_texels_gathered = int(batch.size());
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
