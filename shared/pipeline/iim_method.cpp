#include "shared/pipeline/iim_method.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <string>

#include "gpu/gl.h"
#include "shared/scene_edit.h"

namespace ag {

namespace {
bool same_view(const Camera& a, const Camera& b) {
    return a.eye == b.eye && a.target == b.target && a.up == b.up && a.fov_y == b.fov_y &&
           a.width * b.height == b.width * a.height;
}
}  // namespace

IimMethod::IimMethod(const Scene& scene, const gpu::SceneMeshes& meshes,
                     const gpu::LightmapTexture& aim_texture,
                     const std::vector<glm::vec3>& aim_values, int width, int height,
                     int gather_threads)
    : scene_(scene),
      iim_(scene),
      texture_(scene.atlas),
      gl_gather_(scene, meshes, 256, &aim_texture),
      cpu_pool_(std::max(1, gather_threads)),
      cpu_gather_(scene, cpu_pool_, &aim_values),
      coverage_(scene, meshes, width, height) {
    backend_ = scene_.settings.gather.backend;
    if (backend_ == GatherBackend::automatic) choose_backend();
    if (!scene_.changes.empty()) seen_sequence_ = scene_.changes.back().sequence;
    for (const Object& o : scene_.objects) placed_.push_back(world_bounds(o));
}

Bounds IimMethod::world_bounds(const Object& o) {
    Bounds b;
    for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    return b;
}

std::vector<Bounds> IimMethod::moved_regions(std::vector<int>* objects) {
    std::vector<Bounds> regions;
    for (const SceneChange& c : changes_since(scene_, seen_sequence_)) {
        if (c.kind != ChangeKind::object_transform) continue;
        // Gathers within one object diagonal of its old or new place see it under a large
        // solid angle: their irradiance changes with the move itself, a frame before the
        // photons and AIMs catch up.
        const Bounds now = world_bounds(scene_.objects[size_t(c.index)]);
        for (Bounds b : {placed_[size_t(c.index)], now}) {
            const glm::vec3 grow(glm::length(b.extent()));
            b.min -= grow;
            b.max += grow;
            regions.push_back(b);
        }
        placed_[size_t(c.index)] = now;
        if (objects && std::find(objects->begin(), objects->end(), c.index) == objects->end())
            objects->push_back(c.index);
    }
    if (!scene_.changes.empty()) seen_sequence_ = scene_.changes.back().sequence;
    return regions;
}

Gatherer& IimMethod::gatherer(GatherBackend backend) {
    if (backend == GatherBackend::cpu) return cpu_gather_;
    // Texels that see mirrors or glass go to the rays, which follow the specular bounces.
    if (scene_.settings.gather.specular_bounces > 0) return routed_gather_;
    return gl_gather_;
}

void IimMethod::set_backend(GatherBackend backend) {
    if (backend != GatherBackend::automatic) backend_ = backend;
}

GatherBackend automatic_gather_backend(std::string* reason) {
    // By the GL renderer, not by timing. Until session 16 both backends were timed on 32 texels
    // at load and the faster kept: on a busy machine the timing could flip, so the same scene and
    // settings gave different images from one run to the next (a `full` baseline in `tools/run`
    // gathered by GL on llvmpipe at 2.2 ms a texel against the CPU's 0.25, and python.bindings'
    // comparison of the CLI with the module failed once under the sanitizers). A software
    // rasteriser (Mesa's llvmpipe, softpipe or swrast: OSMesa, or EGL without a GPU) gathers a
    // texel 10-60x slower than the CPU rays on this machine (`afterglow bench gather`); a GPU
    // rasterises the hemi-planes in parallel.
    const GLubyte* r = gpu::gl::GetString(GL_RENDERER);
    const std::string renderer = r ? reinterpret_cast<const char*>(r) : "";
    std::string lower = renderer;
    for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
    const bool software = lower.find("llvmpipe") != std::string::npos ||
                          lower.find("softpipe") != std::string::npos ||
                          lower.find("swrast") != std::string::npos ||
                          lower.find("software") != std::string::npos;
    if (reason)
        *reason = "automatic: the GL renderer '" + renderer + "' is " +
                  (software ? "a software rasteriser" : "not a software rasteriser");
    return software ? GatherBackend::cpu : GatherBackend::gl;
}

void IimMethod::choose_backend() { backend_ = automatic_gather_backend(&backend_reason_); }

void IimMethod::update_coverage(bool objects_moved, uint64_t frame) {
    moved_since_coverage_ = moved_since_coverage_ || objects_moved;
    const bool camera_moved = covered_frame_ == 0 || !same_view(covered_camera_, scene_.camera);
    if (!camera_moved && !(moved_since_coverage_ && frame >= covered_frame_ + kCoverageFrames))
        return;
    // Measured on the side the gather runs on: the one this machine does faster (rasterising
    // bumpy_133k_box's 131k triangles on llvmpipe took 18 ms of an edit's frame).
    if (backend_ == GatherBackend::cpu)
        iim_.set_coverage(cpu_gather_.texel_coverage(coverage_.width(), coverage_.height()));
    else
        iim_.set_coverage(coverage_.update());
    covered_camera_ = scene_.camera;
    covered_frame_ = std::max<uint64_t>(frame, 1);
    moved_since_coverage_ = false;
}

void IimMethod::update(const IndirectInputs& in, PipelineStats& stats) {
    const std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    mode_ = in.mode;
    // What the baselines recompute, they recompute: every gather ray traced.
    cpu_gather_.use_ray_cache(in.mode == PipelineMode::selective);
    if (in.aim_changed) iim_.aim_changed();
    const bool timed = scene_.settings.schedule.frame_ms > 0.0f;
    std::vector<int> moved_objects;
    const std::vector<Bounds> moved = moved_regions(&moved_objects);
    // The round-robin baselines know nothing of the screen.
    if (in.mode == PipelineMode::selective) update_coverage(!moved.empty(), in.frame);
    if (timed && in.mode == PipelineMode::selective && !moved.empty()) {
        iim_.queue_inside(moved);
        iim_.queue_moved(moved_objects);
    }
    int budget = in.budget;
    if (in.mode == PipelineMode::full) budget = int(scene_.atlas.texels.size());
    // Round robin through every texel, a new cycle when one ends.
    if (in.mode == PipelineMode::full_budget && iim_.pending() == 0) iim_.invalidate_all();
    const cpu::CpuGatherStats before = cpu_gather_.totals();
    const cpu::IimFrameStats s = gather(in, budget, start);
    stats.gather_rays = cpu_gather_.totals().rays - before.rays;
    stats.gather_rays_reused = cpu_gather_.totals().rays_reused - before.rays_reused;
    stats.iim_texels_gathered = s.gathered;
    stats.iim_texels_invalid = s.invalid;
    stats.texel_gather_ms = texel_gather_ms_;
    stats.gather_wait_ms = gather_wait_ms_;
    // New values fade in over blend_frames so the thesis's trickle of ≤ 20 texels a frame never
    // pops. With a frame-time target the scheduler updates as much as fits, by priority, and the
    // values show at once, as brute force shows them: the light follows the edit without lag.
    const bool blend = in.mode == PipelineMode::selective && !timed;
    const int blend_frames = blend ? scene_.settings.gather.blend_frames : 1;
    const std::vector<int>& changed = iim_.blend(in.frame, blend_frames);
    if (!changed.empty()) ++revision_;
    texture_.update(iim_.shown(), changed);
}

cpu::IimFrameStats IimMethod::gather(const IndirectInputs& in, int budget,
                                     std::chrono::steady_clock::time_point start) {
    using Clock = std::chrono::steady_clock;
    auto ms_since = [](Clock::time_point t) {
        return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
    };
    texel_gather_ms_ = gather_wait_ms_ = 0.0;
    if (in.work_ms <= 0.0 || in.mode == PipelineMode::full) {
        const Clock::time_point t = Clock::now();
        const cpu::IimFrameStats s = iim_.gather(gatherer(backend_), budget, in.frame);
        texel_gather_ms_ = ms_since(t);
        gathered_ = iim_.last_gathered();
        return s;
    }
    // By time: chunks of at most one GL pass, until the budget is spent or the share has run
    // out. A texel's cost varies with what its hemi-plane sees (on the conference room the
    // texels the camera sees cost about 3× the mean) and with what else runs on the cores, so
    // an estimate from other frames can be far off: after the first chunk (a third of the
    // plan), each is sized by what this frame's chunks cost, and the frame holds its target
    // anyway. Only running out of time stops the loop early, never a prediction: small
    // batches gather less efficiently, and stopping on predictions made from them shrank the
    // measured budget frame after frame. Between chunks the photon work is taken over as soon
    // as it is done, so the rest of the frame gathers with the new AIMs, a frame earlier.
    const Clock::time_point loop_start = Clock::now();
    cpu::IimFrameStats total;
    gathered_.clear();
    int chunk = std::min(budget, std::clamp(budget / 3, kFirstChunkTexels, kChunkTexels));
    iim_.defer_repairs();  // once for the frame, not per chunk (it scans every invalid texel)
    while (chunk > 0) {
        const Clock::time_point chunk_start = Clock::now();
        const cpu::IimFrameStats s = iim_.gather(gatherer(backend_), chunk, in.frame);
        texel_gather_ms_ += ms_since(chunk_start);
        total.gathered += s.gathered;
        total.invalid += s.invalid;
        total.relocated += s.relocated;
        total.refined += s.refined;
        total.pending = s.pending;
        gathered_.insert(gathered_.end(), iim_.last_gathered().begin(), iim_.last_gathered().end());
        const int left = budget - total.gathered;
        if (s.gathered < chunk) {
            // Nothing left to gather, refresh or refine. New AIMs bring texels to gather again:
            // taken over if the workers are done, or waited for with half of what the share has
            // left (the rest gathers what they bring). On bumpy_133k_box the box jump's AIM
            // rebuild (120-145 ms on the workers) ended during the gathering of the frame after
            // the edit's, whose queue ran out at 50-60 ms of a 150 ms share: its texels waited
            // a frame and 25 ms of drawing.
            const double remaining = in.work_ms - ms_since(start);
            if (left <= 0 || remaining <= 0.0) break;
            bool arrived = in.poll_hand_over && in.poll_hand_over();
            if (!arrived && in.wait_hand_over) {
                const Clock::time_point wait_start = Clock::now();
                arrived = in.wait_hand_over(0.5 * remaining);
                gather_wait_ms_ += ms_since(wait_start);
            }
            if (!arrived) break;
            iim_.aim_changed();
        } else if (in.poll_hand_over && in.poll_hand_over()) {
            iim_.aim_changed();
        }
        const double ms = ms_since(start);
        if (ms >= in.work_ms || left <= 0) break;
        const double per_texel = std::max(
            1e-6, (ms_since(loop_start) - gather_wait_ms_) / double(std::max(1, total.gathered)));
        const double fits = std::floor((in.work_ms - ms) / per_texel);
        chunk = int(std::clamp<double>(fits, double(std::min(left, kFirstChunkTexels)),
                                       double(std::min(left, kChunkTexels))));
    }
    iim_.repair_deferred(in.frame);
    return total;
}

void IimMethod::hand_over(cpu::PhotonSimulation& photons, PipelineStats& stats) {
    // The round-robin baseline does not look at what changed.
    if (mode_ != PipelineMode::full_budget) iim_.schedule(photons.maps());
    stats.iim_texels_pending = iim_.pending();
}

void IimMethod::prime(cpu::PhotonSimulation& photons, uint64_t frame) {
    iim_.aim_changed();
    iim_.schedule(photons.maps());  // consumes every surface's Δi
    iim_.invalidate_all();
    moved_regions();  // consumes the scene changes
    iim_.gather(gatherer(backend_), int(scene_.atlas.texels.size()), frame);
    gathered_ = iim_.last_gathered();
    texture_.update(iim_.shown(), iim_.blend(frame, 1));
    ++revision_;
}

gpu::IndirectTerm IimMethod::term() const {
    return gpu::IndirectTerm{texture_.id(), gpu::IndirectSpace::lightmap, revision_};
}

}  // namespace ag
