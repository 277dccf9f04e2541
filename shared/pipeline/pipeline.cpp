#include "shared/pipeline/pipeline.h"

#include <algorithm>
#include <stdexcept>

#include "gpu/gl.h"
#include "shared/input_error.h"
#include "shared/pipeline/vpl_method.h"
#include "shared/scene_edit.h"

namespace ag {

namespace {
using Clock = std::chrono::steady_clock;
double ms_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}
double ms_since(Clock::time_point t) { return ms_between(t, Clock::now()); }
const std::vector<char> kNoPending;
const std::vector<int> kNoneGathered;

void add(cpu::PhotonFrameStats& a, const cpu::PhotonFrameStats& b) {
    a.frame = b.frame;
    a.photons_verified += b.photons_verified;
    a.groups_invalidated += b.groups_invalidated;
    a.groups_invalidated_by_query += b.groups_invalidated_by_query;
    a.objects_moved += b.objects_moved;
    a.query_segments_tested += b.query_segments_tested;
    a.query_ms += b.query_ms;
    a.photons_retraced += b.photons_retraced;
    a.groups_retraced += b.groups_retraced;
    a.groups_queued = b.groups_queued;
    a.photons_grown += b.photons_grown;
    a.layers = b.layers;
    a.aim_texels_rebuilt += b.aim_texels_rebuilt;
    a.aim_surfaces_rebuilt += b.aim_surfaces_rebuilt;
}

// The workers' part of `from` (photon frames handed over) added to `into`.
void add_worker_results(PipelineStats& into, const PipelineStats& from) {
    if (from.hand_overs == 0) return;
    add(into.photons, from.photons);
    into.caustics.traced += from.caustics.traced;
    into.caustics.hit_specular += from.caustics.hit_specular;
    into.caustics.stored += from.caustics.stored;
    into.photon_ms += from.photon_ms;
    into.aim_ms += from.aim_ms;
    into.caustic_ms += from.caustic_ms;
    into.iim_texels_pending = from.iim_texels_pending;
    into.hand_overs += from.hand_overs;
}
}  // namespace

std::unique_ptr<IndirectMethod> make_indirect_method(const Scene& scene,
                                                     const gpu::SceneMeshes& meshes,
                                                     const gpu::LightmapTexture& aim_texture,
                                                     const std::vector<glm::vec3>& aim_values,
                                                     int width, int height, int gather_threads) {
    switch (scene.settings.indirect.method) {
        case IndirectMethodKind::iim:
            return std::make_unique<IimMethod>(scene, meshes, aim_texture, aim_values, width,
                                               height, gather_threads);
        case IndirectMethodKind::gpu_pm:
            return std::make_unique<GpuPmMethod>(scene, meshes, width, height);
        case IndirectMethodKind::vpl:
            return std::make_unique<VplMethod>(scene, meshes, width, height);
        case IndirectMethodKind::irradiance_cache:
            return std::make_unique<IrradianceCacheMethod>(scene, meshes, aim_values, width,
                                                           height);
    }
    return nullptr;
}

Pipeline::Pipeline(Scene& scene, const PipelineOptions& options)
    : scene_(scene),
      mode_(options.mode),
      on_cpu_work_start_(options.on_cpu_work_start),
      on_gl_drawn_(options.on_gl_drawn),
      pool_(options.threads >= 0 ? options.threads : scene.settings.threads),
      aim_texture_(scene.atlas) {
    const int width = options.width > 0 ? options.width : scene_.camera.width;
    const int height = options.height > 0 ? options.height : scene_.camera.height;
    media_settings_ = options.media;
    media_settings_.width = width;
    media_settings_.height = height;
    photons_ = std::make_unique<cpu::PhotonSimulation>(scene_, pool_);
    aim_ = std::make_unique<cpu::Aim>(scene_, pool_);
    caustic_tracer_ = std::make_unique<cpu::CausticTracer>(scene_, pool_);
    meshes_ = std::make_unique<gpu::SceneMeshes>(scene_);
    renderer_ = std::make_unique<gpu::FrameRenderer>(scene_, *meshes_, width, height);
    caustics_ = std::make_unique<gpu::CausticsRenderer>(scene_, *meshes_, width, height);
    staged_aim_.assign(size_t(scene_.atlas.width) * size_t(scene_.atlas.height), glm::vec3(0.0f));
    indirect_ = make_indirect_method(scene_, *meshes_, aim_texture_, staged_aim_, width, height,
                                     pool_.size());
    uses_photon_maps_ = indirect_->uses_photon_maps();
    // Progressive photon refinement feeds the AIMs, which the IIM method gathers; the baselines
    // (full, full_budget) keep the photon budget they are measured with.
    photons_->set_growth(mode_ == PipelineMode::selective && iim_method() != nullptr);
    if (mode_ == PipelineMode::full_budget) {
        // The baseline knows nothing of what changed: no verification, no moved-object query.
        photons_->set_verification(false);
        photons_->set_query_invalidation(false);
    }
    scene_.before_edit.owner = this;
    scene_.before_edit.wait = [this] {
        if (!cpu_work_.valid()) return;
        const Clock::time_point t = Clock::now();
        cpu_work_.wait();
        edit_wait_ms_ += ms_since(t);
    };
}

Pipeline::~Pipeline() {
    if (cpu_work_.valid()) cpu_work_.wait();
    // A viewer makes the next pipeline on the scene before this one goes: its wait stays.
    if (scene_.before_edit.owner == this) {
        scene_.before_edit.wait = nullptr;
        scene_.before_edit.owner = nullptr;
    }
}

bool Pipeline::waits_for_workers() const {
    return mode_ == PipelineMode::full || !(scene_.settings.schedule.frame_ms > 0.0f) ||
           scene_.settings.schedule.wait_for_workers;
}

void Pipeline::update_media() {
    const bool scene_changed = !media_ || scene_.version != media_version_;
    if (scene_changed && media_failed_ && scene_.version == media_version_) return;
    const Camera& c = media_camera_;
    const Camera& now = scene_.camera;
    const bool camera_moved =
        c.eye != now.eye || c.target != now.target || c.up != now.up || c.fov_y != now.fov_y;
    if (!scene_changed && !camera_moved) return;
    media_version_ = scene_.version;
    media_camera_ = now;
    Camera camera = now;
    camera.width = media_settings_.width;
    camera.height = media_settings_.height;
    try {
        if (scene_changed) {
            media_ = std::make_unique<MediaMethodResult>(render_media(scene_, media_settings_));
        } else {
            media_->volume =
                view_media(scene_, *media_, camera, media_settings_, &media_->transmittance);
            media_->indirect = view_fog_on_surfaces(scene_, *media_, camera, media_settings_);
            if (media_settings_.through_glass)
                media_->specular =
                    view_through_glass(scene_, *media_, camera, media_settings_, &media_->glass);
        }
        media_failed_ = false;
        renderer_->set_volume(media_->volume, media_->transmittance);
        renderer_->set_media_indirect(media_->indirect);
        renderer_->set_specular_through_glass(media_->specular, media_->glass);
    } catch (const std::invalid_argument& e) {
        // Media without a light the method can use (a light switched off in the viewer): no
        // volume term until the scene changes again. Said once per reason, not silently: a
        // light the method wrongly refused (one on the medium's boundary) once went unseen.
        media_.reset();
        media_failed_ = true;
        renderer_->set_volume(Image());
        renderer_->set_media_indirect(Image());
        renderer_->set_specular_through_glass(Image(), {});
        if (e.what() != media_warning_) {
            media_warning_ = e.what();
            warn("no volume term: " + media_warning_);
        }
    }
}

void Pipeline::sync() {
    if (cpu_work_.valid()) hand_over(carried_);
}

void Pipeline::start_cpu_work(const FrameBudgets& budgets) {
    // Photons, AIMs and caustic photons for this frame's scene, on the workers: invalid photon
    // groups first, AIM texels with what the frame has left.
    cpu_work_ = cpu_thread_.submit([this, budgets] {
        CpuWork w;
        if (on_cpu_work_start_) on_cpu_work_start_();
        const Clock::time_point t0 = Clock::now();
        cpu::PhotonMaps& maps = photons_->maps();
        if (uses_photon_maps_) switch (mode_) {
                case PipelineMode::full:
                    w.photons = photons_->frame(1 << 30);
                    break;
                case PipelineMode::full_budget:
                    // Round robin through every group, trusting nothing: a new cycle when one ends.
                    if (photons_->queued_photons() == 0) photons_->invalidate_all();
                    w.photons = photons_->frame(budgets.retrace_photons);
                    break;
                case PipelineMode::selective:
                    // Refinement layers grow with what the repairs leave of the budget.
                    w.photons = photons_->frame(budgets.retrace_photons);
                    break;
            }
        const Clock::time_point t1 = Clock::now();
        const int aim_texels = scheduler_.aim_texels_left(scene_.settings, ms_between(t0, t1));
        cpu::PhotonFrameStats& p = w.photons;
        if (uses_photon_maps_) switch (mode_) {
                case PipelineMode::full:
                    p.aim_texels_rebuilt = aim_->rebuild_all(maps);
                    p.aim_surfaces_rebuilt = int(maps.surface_count());
                    break;
                case PipelineMode::full_budget:
                    p.aim_texels_rebuilt =
                        aim_->rebuild_round_robin(maps, aim_texels, &p.aim_surfaces_rebuilt);
                    break;
                case PipelineMode::selective:
                    p.aim_texels_rebuilt = aim_->update(maps, budgets.aim_surfaces, aim_texels,
                                                        &p.aim_surfaces_rebuilt);
                    break;
            }
        const Clock::time_point t2 = Clock::now();
        w.caustics = caustic_tracer_->frame();
        w.photon_ms = ms_between(t0, t1);
        w.aim_ms = ms_between(t1, t2);
        w.caustic_ms = ms_since(t2);
        return w;
    });
}

PipelineStats Pipeline::frame() {
    const Clock::time_point start = Clock::now();
    PipelineStats stats;
    stats.frame = ++frame_;
    add_worker_results(stats, carried_);
    const double carried_wait_ms = edit_wait_ms_;
    carried_ = PipelineStats{};
    edit_wait_ms_ = 0.0;
    // Photon work that ran on past the last frame: taken over if it is done (its AIM texels are
    // uploaded below); otherwise it goes on, and this frame starts none.
    bool workers_busy = false;
    if (cpu_work_.valid()) {
        if (cpu_work_.wait_for(std::chrono::seconds(0)) == std::future_status::ready)
            hand_over(stats);
        else
            workers_busy = true;
    }
    const bool edited = scene_.version != seen_version_ && frame_ > 1;
    // The first edit after frames without one brings costs the running estimates do not hold
    // yet; in a run of edits they are part of every frame, and measured.
    const bool first_edit = edited && !last_frame_edited_;
    last_frame_edited_ = edited;
    if (edited || frame_ == 1) caustic_slices_since_edit_ = frames_since_edit_ = 0;
    ++frames_since_edit_;
    seen_version_ = scene_.version;
    int invalidated = 0;
    if (mode_ == PipelineMode::full) {
        if (uses_photon_maps_) invalidated = photons_->invalidate_all();
        indirect_->invalidate_all();
    }
    // After an edit the caustic photons are traced again, a slice a hand-over, each drawn after
    // it arrives, and the cube-map faces re-lit one a frame: drawing catches up until the last
    // slice is drawn and the last face re-lit. Counted by what is left, not by frames: the
    // workers may hand over later than a slice a frame, and the frame that drew the last slice
    // with a re-lit face, planned as a settled frame, ran to 41-48 ms on two_rooms' door.
    const bool catching_up = !edited && edits_seen_ &&
                             (caustic_slices_since_edit_ < scene_.settings.caustics.frames ||
                              !staged_caustics_drawn_ || renderer_->faces_to_relight() > 0);
    edits_seen_ = edits_seen_ || edited;
    // With a frame-time target, drawing the caustics again waits a frame in the edit's frame
    // (its photons are still the old ones; the new scene's first slice arrives with the next
    // frame) and in every other frame while they catch up (a slice re-traced each frame): on
    // two_rooms at 96² a drawing costs 9-12 ms of the 33. The term lags by at most a frame.
    // Decided before the budgets, which plan for a drawing where one is expected.
    const bool timed = scene_.settings.schedule.frame_ms > 0.0f && mode_ != PipelineMode::full;
    caustics_deferred_ = timed && (first_edit || (catching_up && caustics_drawn_last_));
    // The caustics are drawn again when the staged photons are new: staged since their last
    // drawing, or handed over during this frame's gathering (selective takes the photon work
    // over between chunks) while the slices still hold photons of before the last edit. Planning
    // only for the first, selective's frames during cornell's continuous move drew caustics
    // they had not planned for, ran long, and its error lagged the move more than full-budget's.
    // While drawing catches up after an edit, a frame that draws them leaves the cube-map faces'
    // direct light to the next (each costs about as much as the caustics: 10-12 ms of
    // two_rooms' frame at 96²), so no frame pays for both.
    const bool caustics_expected =
        !caustics_deferred_ &&
        (!staged_caustics_drawn_ || caustic_slices_since_edit_ < scene_.settings.caustics.frames);
    const int relit_expected =
        first_edit || (timed && catching_up && caustics_expected)
            ? 0
            : int(std::min(gpu::FrameRenderer::kRelitFacesPerFrame, renderer_->faces_to_relight()));
    // The scheduler's hedge for the frames after an edit (planning for the last frames'
    // drawing where it was larger than the estimate: the AIM rebuild on the workers slows the
    // GL thread's passes) covers the first caustics.frames + 1 of them; the caustics and
    // re-lit faces that come later are planned for by their own costs. Hedging for all of
    // catching up held gathering at its least share up to 16 frames after an edit, and
    // selective's error lagged cornell's continuous move more than full-budget's.
    const bool hedge = catching_up && frames_since_edit_ <= scene_.settings.caustics.frames + 1;
    const FrameBudgets budgets =
        scheduler_.budgets(scene_.settings, int(scene_.atlas.texels.size()), first_edit, hedge,
                           caustics_expected, relit_expected);
    if (!workers_busy) {
        // Repair work (an edit's, or invalid groups still queued) may be waited for mid-gather;
        // verification and refinement alone never are.
        cpu_work_repairs_ = edited || photons_->queued_photons() > 0;
        start_cpu_work(budgets);
    }

    // GL: the AIM texels handed over by the last frame, the indirect term, then the frame.
    Clock::time_point t = Clock::now();
    const bool aim_changed = !aim_dirty_.empty();
    aim_texture_.update(staged_aim_, aim_dirty_);
    aim_dirty_.clear();
    auto update_indirect = [&](int texels, double work_ms, bool may_wait) {
        const Clock::time_point t0 = Clock::now();
        IndirectInputs in{frame_, aim_changed, mode_, texels};
        in.work_ms = work_ms;
        // Selective takes the photon work over the moment it is done; the baselines at the end
        // of the frame, as brute force does.
        if (mode_ == PipelineMode::selective && work_ms > 0.0) {
            in.poll_hand_over = [this, &stats] { return hand_over_if_done(stats); };
            // Not after drawing: what the edit's frame gathers then shows a frame later, and
            // the next frame takes the new AIMs over as they arrive. A run whose frames wait for
            // their photon work at the end keeps doing so.
            if (may_wait && !waits_for_workers())
                in.wait_hand_over = [this, &stats](double ms) {
                    if (!cpu_work_.valid() || !cpu_work_repairs_ || ms <= 0.0) return false;
                    if (cpu_work_.wait_for(std::chrono::duration<double, std::milli>(ms)) !=
                        std::future_status::ready)
                        return false;
                    return hand_over_if_done(stats);
                };
        }
        indirect_->update(in, stats);
        stats.gather_ms = ms_since(t0);
    };
    // The edit's frame of the IIM method draws first and gathers with what the drawing left of
    // the target: its drawing (every light's shadows anew, the moved geometry) is the frame's
    // least predictable (two_rooms' door at 96²: 22-29 ms against 9-12 ms a settled frame, so
    // the frame ran to 41-45 ms), and what it gathers reads the AIMs of before the edit anyway
    // (the workers have just started on it): its texels show a frame later.
    const bool draw_first =
        timed && first_edit && iim_method() != nullptr && budgets.gather_ms > 0.0;
    if (!draw_first) update_indirect(budgets.iim_texels, budgets.gather_ms, true);
    t = Clock::now();
    caustics_drawn_last_ = false;
    if (!caustics_deferred_) {
        const uint64_t revision = caustics_->revision();
        caustics_->render(caustic_positions_, caustic_powers_);
        caustics_drawn_last_ = caustics_->revision() != revision;
        staged_caustics_drawn_ = true;
        stats.caustic_tiles_filtered = caustics_->tiles_filtered();
        if (caustics_drawn_last_) {
            gpu::gl::Finish();
            stats.caustics_draw_ms = ms_since(t);
        }
    }
    stats.caustics_drawn = caustics_drawn_last_;
    if (!scene_.media.empty()) update_media();
    const size_t relit_faces =
        timed && catching_up && caustics_drawn_last_ ? 0 : gpu::FrameRenderer::kRelitFacesPerFrame;
    renderer_->render(indirect_->term(), caustics_->texture(), caustics_->revision(), relit_faces);
    gpu::gl::Finish();
    stats.draw_ms = ms_since(t);
    stats.cube_faces_relit = int(renderer_->faces_relit());
    stats.cube_faces_ms = renderer_->cube_faces_ms();
    FrameBudgets planned = budgets;
    if (draw_first) {
        planned = scheduler_.after_drawing(scene_.settings, int(scene_.atlas.texels.size()),
                                           ms_since(start));
        update_indirect(planned.iim_texels, planned.gather_ms, false);
    }
    stats.drawn = renderer_->drew();
    stats.drawn_direct = renderer_->drew_direct();
    if (on_gl_drawn_) on_gl_drawn_();

    t = Clock::now();
    if (cpu_work_.valid() && (waits_for_workers() || cpu_work_.wait_for(std::chrono::seconds(0)) ==
                                                         std::future_status::ready))
        hand_over(stats);
    stats.workers_behind = cpu_work_.valid();
    stats.photons.groups_invalidated += invalidated;
    // An edit's wait for the workers came before this frame, on its behalf.
    stats.wait_ms = ms_since(t) + carried_wait_ms;
    stats.frame_ms = ms_since(start) + carried_wait_ms;
    stats.budget_iim_texels = planned.iim_texels;
    stats.budget_photons = budgets.retrace_photons;
    stats.budget_gather_ms = planned.gather_ms;
    scheduler_.measure(stats);
    return stats;
}

void Pipeline::hand_over(PipelineStats& stats) {
    // Wait for the CPU side, then stage its results for the next frame's GL work.
    const CpuWork w = cpu_work_.get();
    PipelineStats work;
    work.photons = w.photons;
    work.caustics = w.caustics;
    work.photon_ms = w.photon_ms;
    work.aim_ms = w.aim_ms;
    work.caustic_ms = w.caustic_ms;
    work.hand_overs = 1;
    add_worker_results(stats, work);
    // One slice of caustic photons a hand-over (the workers may run past several frames, so
    // frames do not count slices); photons other than those staged wait for a drawing.
    ++caustic_slices_since_edit_;
    std::vector<glm::vec3> positions, powers;
    for (const cpu::CausticPhoton& p : caustic_tracer_->photons())
        if (p.power != glm::vec3(0.0f)) {
            positions.push_back(p.position);
            powers.push_back(p.power);
        }
    if (positions != caustic_positions_ || powers != caustic_powers_) {
        caustic_positions_ = std::move(positions);
        caustic_powers_ = std::move(powers);
        staged_caustics_drawn_ = false;
    }
    aim_dirty_ = aim_->take_dirty_texels();
    for (int a : aim_dirty_) staged_aim_[size_t(a)] = aim_->radiance()[size_t(a)];
    if (IimMethod* m = iim_method(); m && mode_ == PipelineMode::selective)
        m->note_indirect_estimates(aim_->indirect_estimates(), aim_->indirect_floors());
    indirect_->hand_over(*photons_, stats);
    // Both readers of the change log have seen this frame's edits: without trimming, the log
    // grows by every edit for as long as the program runs.
    trim_changes(scene_, std::min(photons_->changes_seen(), indirect_->changes_seen()));
}

bool Pipeline::hand_over_if_done(PipelineStats& stats) {
    if (!cpu_work_.valid() ||
        cpu_work_.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
        return false;
    hand_over(stats);
    stats.early_hand_over = true;
    if (aim_dirty_.empty()) return false;
    // The AIM texels reach the gatherers now, not at the start of the next frame.
    aim_texture_.update(staged_aim_, aim_dirty_);
    aim_dirty_.clear();
    return true;
}

int Pipeline::prime(int max_frames) {
    sync();
    const Clock::time_point t0 = Clock::now();
    if (uses_photon_maps_) {
        photons_->invalidate_all();
        photons_->trace_all();
    }
    const Clock::time_point t1 = Clock::now();
    const int aim_texels = uses_photon_maps_ ? aim_->rebuild_all(photons_->maps()) : 0;
    const Clock::time_point t2 = Clock::now();
    for (int a : aim_->take_dirty_texels()) staged_aim_[size_t(a)] = aim_->radiance()[size_t(a)];
    std::vector<int> all(staged_aim_.size());
    for (size_t a = 0; a < all.size(); ++a) all[a] = int(a);
    aim_texture_.update(staged_aim_, all);
    aim_dirty_.clear();
    const Clock::time_point t3 = Clock::now();
    // Every texel is gathered below with these estimates: its staleness starts at 0.
    if (IimMethod* m = iim_method(); m && mode_ == PipelineMode::selective)
        m->note_indirect_estimates(aim_->indirect_estimates(), aim_->indirect_floors());
    indirect_->prime(*photons_, frame_);
    gpu::gl::Finish();
    int enabled = 0;
    for (const Light& l : scene_.lights) enabled += l.enabled ? 1 : 0;
    scheduler_.seed(
        int(scene_.atlas.texels.size()), ms_since(t3),
        enabled * scene_.settings.photons.groups * scene_.settings.photons.photons_per_group,
        ms_between(t0, t1), aim_texels, ms_between(t1, t2));
    // Caustic photons are traced a slice a frame: plain frames finish them (and anything the
    // bulk work left), each cheap now that nothing else is out of date.
    int frames = 0;
    while (!converged() && frames < max_frames) {
        frame();
        ++frames;
    }
    sync();
    carried_ = PipelineStats{};  // untimed: nothing of it belongs to the next frame
    edit_wait_ms_ = 0.0;
    return frames;
}

GLuint Pipeline::iim_texture() const {
    const IimMethod* m = iim_method();
    return m ? m->texture() : 0;
}

bool Pipeline::converged() const {
    if (cpu_work_.valid()) return false;  // the workers are still at it
    return (photons_->settled() || !uses_photon_maps_) && aim_dirty_.empty() &&
           indirect_->settled() && renderer_->cube_maps_current() &&
           caustic_slices_since_edit_ >= scene_.settings.caustics.frames &&
           staged_caustics_drawn_ && !caustics_deferred_;
}

GatherBackend Pipeline::gather_backend() const {
    const IimMethod* m = iim_method();
    return m ? m->backend() : GatherBackend::gl;
}

void Pipeline::set_gather_backend(GatherBackend backend) {
    if (IimMethod* m = iim_method()) m->set_backend(backend);
}

std::string Pipeline::gather_backend_reason() const {
    const IimMethod* m = iim_method();
    return m ? m->backend_reason() : std::string();
}

const std::vector<char>& Pipeline::texel_pending() const {
    const IimMethod* m = iim_method();
    return m ? m->iim().texel_pending() : kNoPending;
}

const std::vector<int>& Pipeline::last_gathered() const {
    const IimMethod* m = iim_method();
    return m ? m->last_gathered() : kNoneGathered;
}

}  // namespace ag
