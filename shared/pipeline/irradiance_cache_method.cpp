#include "shared/pipeline/irradiance_cache_method.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <optional>

#include "gpu/gl.h"
#include "shared/input_error.h"
#include "shared/scene_edit.h"

namespace ag {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

Bounds world_bounds(const Object& o) {
    Bounds b;
    for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    return b;
}

bool inside(const Bounds& b, const glm::vec3& p) {
    return glm::all(glm::greaterThanEqual(p, b.min)) && glm::all(glm::lessThanEqual(p, b.max));
}

// Whether a light differs between the frame and the next (then shading the reprojected hits again
// tells something; otherwise it repeats the same shading).
bool lights_move(const Scene& now, const Scene& next) {
    if (now.lights.size() != next.lights.size()) return true;
    for (size_t i = 0; i < now.lights.size(); ++i) {
        const Light &a = now.lights[i], &b = next.lights[i];
        if (a.position != b.position || a.intensity != b.intensity || a.radiance != b.radiance ||
            a.corners != b.corners || a.enabled != b.enabled || a.direction != b.direction ||
            a.irradiance != b.irradiance || a.cone_inner != b.cone_inner ||
            a.cone_outer != b.cone_outer)
            return true;
    }
    return false;
}
}  // namespace

IrradianceCacheMethod::IrradianceCacheMethod(const Scene& scene, const gpu::SceneMeshes& meshes,
                                             const std::vector<glm::vec3>& aim_values, int width,
                                             int height)
    : scene_(scene),
      aim_(aim_values),
      splat_(scene, meshes, width, height),
      rays_(scene),
      gather_(scene, rays_, pool_) {
    if (scene_.settings.rc.gather == RcGather::gl) {
        if (scene_.settings.rc.source != RcSource::aim)
            throw InputError(
                "settings: rc.gather: \"gl\" reads the AIM texture, so it needs rc.source "
                "\"aim\" (got \"direct\"; direct light has no texture): use rc.gather \"rays\"");
        aim_texture_ = std::make_unique<gpu::LightmapTexture>(scene.atlas);
        plane_ = std::make_unique<gpu::HemiPlaneGather>(scene, meshes, 1, aim_texture_.get(), true);
    }
    if (!scene_.changes.empty()) seen_sequence_ = scene_.changes.back().sequence;
    version_ = scene_.version;
}

cpu::RecordRadiance IrradianceCacheMethod::radiance_source(const Scene& scene,
                                                           const cpu::RayTracer& rays) const {
    if (scene_.settings.rc.source == RcSource::direct)
        return cpu::direct_radiance_source(scene, rays, scene_.settings.rc.shadow_samples);
    return cpu::aim_radiance_source(scene, aim_);
}

cpu::RecordGatherOptions IrradianceCacheMethod::gather_options() const {
    const RcSettings& rc = scene_.settings.rc;
    cpu::RecordGatherOptions o;
    o.theta = rc.theta_strata;
    o.phi = rc.phi_strata;
    o.min_distance = rc.min_radius * scene_.diagonal();
    o.max_distance = rc.max_radius * scene_.diagonal();
    o.seed = scene_.settings.seed;
    return o;
}

IrradianceRecord IrradianceCacheMethod::plane_record(const GatherPoint& at) {
    if (aim_texture_stale_) {
        aim_texture_->update_all(aim_);
        aim_texture_stale_ = false;
    }
    const GatherResult g = plane_->gather_points({at}).front();
    const cpu::RecordGatherOptions options = gather_options();
    IrradianceRecord r;
    r.position = at.position;
    r.normal = glm::normalize(at.normal);
    r.iim = g.iim;
    r.harmonic_distance =
        std::clamp(g.harmonic_distance, options.min_distance, options.max_distance);
    return r;  // no gradients: a mipmap reduction gives sums, not the strata's neighbours
}

IrradianceRecord IrradianceCacheMethod::make_record(const GatherPoint& at, int frame) {
    const RcSettings& rc = scene_.settings.rc;
    const bool temporal = rc.max_lifespan > 0;
    if (plane_) {
        // The hemi-plane keeps no strata to reproject: a record lives δt_max frames.
        IrradianceRecord r = plane_record(at);
        r.born = frame;
        if (temporal) r.expires = frame + rc.max_lifespan - 1;
        return r;
    }
    std::vector<cpu::RecordSample> samples;
    const cpu::RecordGatherOptions options = gather_options();
    IrradianceRecord r = gather_.gather_one(at, radiance_source(scene_, rays_), options,
                                            temporal && lookahead_ ? &samples : nullptr);
    r.born = frame;
    if (!temporal) return r;  // lives until an edit or an AIM change retires it
    int life = rc.max_lifespan;
    if (lookahead_) {
        std::vector<Transform> now, next;
        for (const Object& o : scene_.objects) now.push_back(o.transform);
        for (const Object& o : lookahead_->objects) next.push_back(o.transform);
        // Direct-light records shade the moved hits again with the next frame's lights (shadow
        // rays against this frame's geometry) when the lights change; AIM records carry theirs
        // (the AIMs of t+1 are not known yet).
        std::optional<cpu::RecordRadiance> next_radiance;
        if (rc.source == RcSource::direct && lights_move(scene_, *lookahead_))
            next_radiance = cpu::direct_radiance_source(*lookahead_, rays_, rc.shadow_samples);
        const glm::vec3 predicted =
            cpu::reproject_record(r, samples, now, next, options.theta, options.phi,
                                  next_radiance ? &*next_radiance : nullptr);
        life = cpu::record_lifespan(r.iim, predicted, rc.temporal_accuracy, rc.max_lifespan);
        // Extrapolated temporal gradient (Gautron eq. 5.12): the change over the next frame.
        r.temporal_gradient = predicted - r.iim;
        predictions_.push_back({r, predicted, at.key});
    }
    r.expires = frame + life - 1;
    return r;
}

void IrradianceCacheMethod::read_changes() {
    const bool temporal = scene_.settings.rc.max_lifespan > 0;
    const int now = std::numeric_limits<int>::min();  // "expired": replaced in place
    for (const SceneChange& c : changes_since(scene_, seen_sequence_)) {
        switch (c.kind) {
            case ChangeKind::camera:
                break;  // records are view-independent (Gautron §4.7.2)
            case ChangeKind::object_transform: {
                if (temporal && lookahead_) break;  // the lifespans foresaw it
                // Records on or in the object's new place are gone; records within one object
                // diagonal of it see it change under a large solid angle and expire at once;
                // without temporal caching every record does (they may all see it).
                Bounds b = world_bounds(scene_.objects[size_t(c.index)]);
                const glm::vec3 skin(0.02f * scene_.diagonal());
                Bounds on = b;
                on.min -= skin;
                on.max += skin;
                const glm::vec3 grow(glm::length(b.extent()));
                b.min -= grow;
                b.max += grow;
                const size_t before = records_.size();
                std::erase_if(records_,
                              [&](const IrradianceRecord& r) { return inside(on, r.position); });
                stats_.dropped += int(before - records_.size());
                for (IrradianceRecord& r : records_)
                    if (!temporal || inside(b, r.position)) r.expires = now;
                break;
            }
            case ChangeKind::light_position:
            case ChangeKind::light_power:
            case ChangeKind::light_enabled:
                // Direct-light records made with a look-ahead were shaded at t+1 with the next
                // frame's lights: their lifespans foresaw it (as for object transforms).
                if (temporal && lookahead_ && scene_.settings.rc.source == RcSource::direct) break;
                for (IrradianceRecord& r : records_) r.expires = now;
                break;
            default:  // materials change what every record saw
                for (IrradianceRecord& r : records_) r.expires = now;
                break;
        }
    }
    if (!scene_.changes.empty()) seen_sequence_ = scene_.changes.back().sequence;
}

void IrradianceCacheMethod::run(int frame, int budget, bool everything) {
    const float a = scene_.settings.rc.accuracy;
    if (scene_.version != version_) {
        rays_.update(scene_);
        version_ = scene_.version;
    }
    predictions_.clear();
    stats_.added = stats_.replaced = 0;
    const Clock::time_point t1 = Clock::now();
    splat_.render_gbuffer();
    const std::vector<SplatPixel> pixels = splat_.read_gbuffer();
    double splat_ms = ms_since(t1);

    const Clock::time_point t0 = Clock::now();
    // Expired records first, oldest first, recomputed where they are (Gautron §5.2.3: the
    // accuracy pattern stays put, so nothing flickers); an expired record no pixel uses any more
    // (left in the air by a moving object, or out of view) is deleted instead (Gautron §5.3, there
    // by occlusion queries; the view may come back to it, and a cache miss then makes a new one).
    const float cutoff = 1.0f / a;
    auto used = [&](const IrradianceRecord& r) {
        for (const SplatPixel& px : pixels)
            if (px.covered && ward_weight(r, px.position, px.normal) >= cutoff) return true;
        return false;
    };
    const size_t before = records_.size();
    std::erase_if(records_,
                  [&](const IrradianceRecord& r) { return r.expires < frame && !used(r); });
    stats_.deleted = int(before - records_.size());
    std::vector<size_t> expired;
    for (size_t k = 0; k < records_.size(); ++k)
        if (records_[k].expires < frame) expired.push_back(k);
    std::stable_sort(expired.begin(), expired.end(),
                     [&](size_t x, size_t y) { return records_[x].expires < records_[y].expires; });
    const size_t replace = everything ? expired.size() : std::min(expired.size(), size_t(budget));
    for (size_t i = 0; i < replace; ++i) {
        IrradianceRecord& r = records_[expired[i]];
        r = make_record({r.position, r.normal, uint32_t(stats_.records_made++)}, frame);
    }
    stats_.replaced = int(replace);
    stats_.expired_pending = int(expired.size() - replace);
    const double replace_ms = ms_since(t0);

    const Clock::time_point t3 = Clock::now();
    splat_.clear();
    splat_.splat(records_, a, frame);
    gpu::gl::Finish();
    stats_.splat_ms = splat_ms + ms_since(t3);

    const Clock::time_point t2 = Clock::now();
    const int left = everything ? std::numeric_limits<int>::max() : budget - int(replace);
    double make_ms = 0.0;
    const MakeRecord make = [&](const SplatPixel& px, size_t) {
        const Clock::time_point tm = Clock::now();
        IrradianceRecord r =
            make_record({px.position, px.normal, uint32_t(stats_.records_made++)}, frame);
        make_ms += ms_since(tm);
        return r;
    };
    int added = 0;
    if (left > 0) {
        added = scene_.settings.rc.scan == RcScan::gpu
                    ? splat_.add_records_gpu_scan(records_, pixels, a, frame, make, left)
                    : splat_.add_records_cpu_scan(records_, pixels, a, frame, make, left);
    }
    stats_.added = added;
    stats_.uncovered_left = left <= 0 || added >= left;
    splat_.normalise();
    gpu::gl::Finish();
    stats_.scan_ms = ms_since(t2) - make_ms;
    stats_.gather_ms = replace_ms + make_ms;
    stats_.records = int(records_.size());
    ++revision_;
}

void IrradianceCacheMethod::update(const IndirectInputs& in, PipelineStats& stats) {
    mode_ = in.mode;
    stats_.dropped = 0;
    const int frame = int(in.frame);
    read_changes();
    if (in.aim_changed) aim_texture_stale_ = true;
    if (in.aim_changed && scene_.settings.rc.source == RcSource::aim)
        for (IrradianceRecord& r : records_) r.expires = std::numeric_limits<int>::min();
    // Per-frame recomputation (the baseline of Gautron's Table 5.2): a new cache every frame.
    if (in.mode == PipelineMode::full) records_.clear();
    run(frame, scene_.settings.rc.records_per_frame, in.mode == PipelineMode::full);
    stats.iim_texels_gathered = stats_.added + stats_.replaced;
    stats.iim_texels_pending = stats_.expired_pending + (stats_.uncovered_left ? 1 : 0);
}

void IrradianceCacheMethod::hand_over(cpu::PhotonSimulation&, PipelineStats& stats) {
    stats.iim_texels_pending = stats_.expired_pending + (stats_.uncovered_left ? 1 : 0);
}

void IrradianceCacheMethod::prime(cpu::PhotonSimulation&, uint64_t frame) {
    read_changes();
    aim_texture_stale_ = true;
    records_.clear();
    run(int(frame), 0, true);
}

gpu::IndirectTerm IrradianceCacheMethod::term() const {
    return gpu::IndirectTerm{splat_.term(), gpu::IndirectSpace::screen, revision_};
}

bool IrradianceCacheMethod::settled() const {
    return !stats_.uncovered_left && stats_.expired_pending == 0;
}

}  // namespace ag
