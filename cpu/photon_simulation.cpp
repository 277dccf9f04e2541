#include "cpu/photon_simulation.h"

#include <algorithm>
#include <set>

#include "shared/scene_edit.h"

namespace ag::cpu {

PhotonSimulation::PhotonSimulation(const Scene& scene, ThreadPool& pool) : scene_(scene), pool_(pool) {
    rays_ = std::make_unique<RayTracer>(scene_);
    tracer_ = std::make_unique<PhotonTracer>(scene_, *rays_);
    const int groups = scene_.settings.photons.groups;
    maps_.resize(scene_.surfaces.size(), scene_.lights.size(), groups);
    tolerance_ = scene_.settings.photons.path_tolerance * scene_.diagonal();
    seen_sequence_ = scene_.version;
    traced_power_.resize(scene_.lights.size());
    invalidations_.assign(scene_.lights.size(), 0);
    for (int l = 0; l < int(scene_.lights.size()); ++l) {
        traced_power_[size_t(l)] = tracer_->photon_power(l);
        if (!scene_.lights[size_t(l)].enabled) continue;
        for (int g = 0; g < groups; ++g) {
            maps_.group(l, g).queued = true;
            queue_.emplace_back(l, g);
        }
    }
}

void PhotonSimulation::invalidate(int light, int group, PhotonFrameStats& stats) {
    PhotonGroup& g = maps_.group(light, group);
    if (g.queued || !scene_.lights[size_t(light)].enabled) return;  // a dark light has no photons
    g.queued = true;
    queue_.emplace_back(light, group);
    ++stats.groups_invalidated;
    ++invalidations_[size_t(light)];
}

void PhotonSimulation::apply_changes(PhotonFrameStats& stats) {
    const int groups = scene_.settings.photons.groups;
    bool moved = false;
    for (const SceneChange& c : changes_since(scene_, seen_sequence_)) {
        switch (c.kind) {
            case ChangeKind::object_transform:
                moved = true;  // verification finds the groups whose paths changed
                break;
            case ChangeKind::object_material: {
                // Every photon that reached a front face of this object left a hit there, so the
                // hits name exactly the groups whose Russian roulette saw the old albedo.
                std::set<std::pair<int, int>> touched;
                for (int s = 0; s < int(scene_.surfaces.size()); ++s) {
                    if (scene_.surfaces[size_t(s)].object != c.index) continue;
                    for (const PhotonHit& h : maps_.surface(s).hits) touched.emplace(int(h.light), int(h.group));
                }
                for (const auto& [l, g] : touched) invalidate(l, g, stats);
                break;
            }
            case ChangeKind::light_position:
                for (int g = 0; g < groups; ++g) invalidate(c.index, g, stats);
                break;
            case ChangeKind::light_power: {
                const glm::vec3 old_power = traced_power_[size_t(c.index)];
                const glm::vec3 new_power = tracer_->photon_power(c.index);
                traced_power_[size_t(c.index)] = new_power;
                if (!scene_.lights[size_t(c.index)].enabled) break;
                bool rescalable = true;
                glm::vec3 ratio(1.0f);
                for (int k = 0; k < 3; ++k) {
                    if (old_power[k] > 0.0f) ratio[k] = new_power[k] / old_power[k];
                    else if (new_power[k] > 0.0f) rescalable = false;  // nothing to scale from
                }
                for (int g = 0; g < groups; ++g) {
                    if (!rescalable) invalidate(c.index, g, stats);
                    else if (maps_.group(c.index, g).traced) maps_.rescale_group(c.index, g, ratio);
                }
                break;
            }
            case ChangeKind::light_enabled: {
                traced_power_[size_t(c.index)] = tracer_->photon_power(c.index);
                if (scene_.lights[size_t(c.index)].enabled) {
                    for (int g = 0; g < groups; ++g) invalidate(c.index, g, stats);
                } else {
                    for (int g = 0; g < groups; ++g) {
                        maps_.clear_group(c.index, g);
                        maps_.group(c.index, g).queued = false;
                    }
                    std::erase_if(queue_, [&](const auto& q) { return q.first == c.index; });
                }
                break;
            }
            case ChangeKind::camera:
                break;
        }
    }
    if (!scene_.changes.empty()) seen_sequence_ = std::max(seen_sequence_, scene_.changes.back().sequence);
    if (moved) rays_->update(scene_);
    tracer_->refresh();
}

bool PhotonSimulation::same_path(const PhotonGroup& group, int photon, const std::vector<TracedVertex>& path) const {
    const uint32_t begin = group.photon_begin[size_t(photon)], end = group.photon_begin[size_t(photon) + 1];
    if (end - begin != path.size()) return false;
    const float tol2 = tolerance_ * tolerance_;
    for (uint32_t i = begin; i < end; ++i) {
        const PathVertex& v = group.vertices[i];
        const TracedVertex& t = path[i - begin];
        if (v.surface != t.surface) return false;
        const glm::vec3 d = v.position - t.position, dl = v.local - t.local_position;
        // World positions catch changed paths; object-space positions catch a hit that stays in
        // place in the world while its object turns under it (e.g. a cube spinning about y).
        if (glm::dot(d, d) > tol2 || glm::dot(dl, dl) > tol2) return false;
    }
    return true;
}

void PhotonSimulation::retrace_groups(const std::vector<std::pair<int, int>>& groups) {
    const int per_group = scene_.settings.photons.photons_per_group;
    const size_t jobs = groups.size() * size_t(per_group);
    if (traced_.size() < jobs) traced_.resize(jobs);
    pool_.parallel_for(jobs, [&](size_t job) {
        const size_t gi = job / size_t(per_group), p = job % size_t(per_group);
        traced_[job].clear();  // keeps its capacity from earlier frames
        tracer_->trace(groups[gi].first, groups[gi].second, int(p), traced_[job]);
    }, 8);
    // Merge in group order on this thread: the maps end up identical for any thread count.
    for (size_t gi = 0; gi < groups.size(); ++gi) {
        maps_.set_group(groups[gi].first, groups[gi].second, &traced_[gi * size_t(per_group)], size_t(per_group));
        maps_.group(groups[gi].first, groups[gi].second).queued = false;
    }
}

PhotonFrameStats PhotonSimulation::frame() { return frame(scene_.settings.photons.retrace_budget); }

int PhotonSimulation::invalidate_all() {
    PhotonFrameStats stats;
    for (int l = 0; l < int(scene_.lights.size()); ++l)
        for (int g = 0; g < scene_.settings.photons.groups; ++g) invalidate(l, g, stats);
    return stats.groups_invalidated;
}

PhotonFrameStats PhotonSimulation::frame(int retrace_budget) {
    PhotonFrameStats stats;
    stats.frame = ++frame_;
    apply_changes(stats);
    const PhotonSettings& settings = scene_.settings.photons;

    // Verification: re-trace the next photon(s) of every traced group and compare paths.
    struct Job { int light, group, photon; };
    std::vector<Job> jobs;
    for (int l = 0; l < int(scene_.lights.size()); ++l) {
        if (!scene_.lights[size_t(l)].enabled) continue;
        for (int g = 0; g < settings.groups; ++g) {
            PhotonGroup& group = maps_.group(l, g);
            if (!group.traced || group.queued) continue;
            for (int v = 0; v < std::min(settings.verify_per_frame, settings.photons_per_group); ++v) {
                jobs.push_back({l, g, group.verify_cursor});
                group.verify_cursor = (group.verify_cursor + 1) % settings.photons_per_group;
            }
        }
    }
    std::vector<std::vector<TracedVertex>> paths(jobs.size());
    pool_.parallel_for(jobs.size(), [&](size_t i) { tracer_->trace(jobs[i].light, jobs[i].group, jobs[i].photon, paths[i]); }, 16);
    stats.photons_verified = int(jobs.size());
    for (size_t i = 0; i < jobs.size(); ++i)
        if (!same_path(maps_.group(jobs[i].light, jobs[i].group), jobs[i].photon, paths[i]))
            invalidate(jobs[i].light, jobs[i].group, stats);

    // Work off the queue under the budget (whole groups; at least one per frame).
    std::vector<std::pair<int, int>> batch;
    int budget = retrace_budget;
    while (!queue_.empty() && (batch.empty() || budget >= settings.photons_per_group)) {
        batch.push_back(queue_.front());
        queue_.pop_front();
        budget -= settings.photons_per_group;
    }
    retrace_groups(batch);
    stats.groups_retraced = int(batch.size());
    stats.photons_retraced = int(batch.size()) * settings.photons_per_group;
    stats.groups_queued = int(queue_.size());
    return stats;
}

void PhotonSimulation::trace_all() {
    PhotonFrameStats ignored;
    apply_changes(ignored);
    std::vector<std::pair<int, int>> all;
    queue_.clear();
    for (int l = 0; l < int(scene_.lights.size()); ++l)
        for (int g = 0; g < scene_.settings.photons.groups; ++g) {
            if (scene_.lights[size_t(l)].enabled) all.emplace_back(l, g);
            else maps_.clear_group(l, g);
            maps_.group(l, g).queued = false;
        }
    retrace_groups(all);
}

LightGroupState PhotonSimulation::light_state(int light) const {
    LightGroupState s;
    for (int g = 0; g < scene_.settings.photons.groups; ++g) {
        const PhotonGroup& group = maps_.group(light, g);
        if (group.queued) ++s.queued;
        else if (group.traced) ++s.valid;
        else ++s.invalid;
    }
    return s;
}

}  // namespace ag::cpu
