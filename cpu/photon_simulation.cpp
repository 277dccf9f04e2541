#include "cpu/photon_simulation.h"

#include <algorithm>
#include <chrono>
#include <glm/gtc/quaternion.hpp>
#include <set>

#include "shared/scene_edit.h"

namespace ag::cpu {

namespace {

// Does the segment a + t·d, t ∈ [0, 1] (or [0, ∞) for a ray), meet the box? Slab test, closed
// box: a segment that only touches a face counts.
bool segment_meets_box(const glm::vec3& a, const glm::vec3& d, bool ray, const Bounds& box) {
    float t0 = 0.0f, t1 = ray ? 1e30f : 1.0f;
    for (int k = 0; k < 3; ++k) {
        if (d[k] == 0.0f) {
            if (a[k] < box.min[k] || a[k] > box.max[k]) return false;
            continue;
        }
        const float inv = 1.0f / d[k];
        float near = (box.min[k] - a[k]) * inv, far = (box.max[k] - a[k]) * inv;
        if (near > far) std::swap(near, far);
        t0 = std::max(t0, near);
        t1 = std::min(t1, far);
        if (t0 > t1) return false;
    }
    return true;
}

bool boxes_overlap(const Bounds& a, const Bounds& b) {
    return !a.empty() && !b.empty() && glm::all(glm::lessThanEqual(a.min, b.max)) &&
           glm::all(glm::lessThanEqual(b.min, a.max));
}

// One placement of a moved object: its padded bounds in its own frame (an oriented box in the
// world) and their world AABB for the broad phase.
struct Placement {
    glm::mat3 to_local{1.0f};
    glm::vec3 translation{0.0f};
    Bounds local, world;
};

Placement make_placement(const Transform& t, const Bounds& local) {
    Placement p;
    p.to_local = glm::mat3_cast(glm::conjugate(t.rotation));
    p.translation = t.translation;
    p.local = local;
    for (int c = 0; c < 8; ++c)
        p.world.add(
            t.apply_point({c & 1 ? local.max.x : local.min.x, c & 2 ? local.max.y : local.min.y,
                           c & 4 ? local.max.z : local.min.z}));
    return p;
}

}  // namespace

PhotonSimulation::PhotonSimulation(const Scene& scene, ThreadPool& pool)
    : scene_(scene), pool_(pool) {
    rays_ = std::make_unique<RayTracer>(scene_);
    tracer_ = std::make_unique<PhotonTracer>(scene_, *rays_);
    const int groups = scene_.settings.photons.groups;
    // Room for the refinement layers the scene asks for, and no more (56 bytes an empty group).
    max_layers_ = std::max(1, scene_.settings.photons.refine_layers);
    maps_.resize(scene_.surfaces.size(), scene_.lights.size(), groups, max_layers_);
    tolerance_ = scene_.settings.photons.path_tolerance * scene_.diagonal();
    seen_sequence_ = scene_.version;
    traced_power_.resize(scene_.lights.size());
    invalidations_.assign(scene_.lights.size(), 0);
    segments_.resize(scene_.lights.size() * size_t(groups) * size_t(max_layers_));
    for (const Object& o : scene_.objects) {
        placed_.push_back(o.transform);
        object_bounds_.push_back(mesh_bounds(o.mesh));
    }
    for (int l = 0; l < int(scene_.lights.size()); ++l) {
        traced_power_[size_t(l)] = tracer_->photon_power(l);
        if (!scene_.lights[size_t(l)].enabled) continue;
        for (int g = 0; g < groups; ++g) {
            maps_.group(l, g).queued = true;
            queue_.insert({group_flux(l, g), l, g});
        }
    }
}

double PhotonSimulation::group_flux(int light, int group) const {
    if (!maps_.group(light, group).traced)
        return double(scene_.settings.photons.photons_per_group) *
               energy(tracer_->photon_power(light));
    // Every set of the group, each hit at the group's weight (the flux its books hold).
    double flux = 0.0;
    for (int k = 0; k < maps_.sets(light, group); ++k)
        for (const PathVertex& v : maps_.group(light, k * maps_.base_groups() + group).vertices)
            if (v.hit >= 0) flux += energy(maps_.surface(v.surface).hits[size_t(v.hit)].power);
    return flux * maps_.weight(light, group);
}

size_t PhotonSimulation::segment_index(int light, int set_group) const {
    return size_t(light) * size_t(scene_.settings.photons.groups) * size_t(max_layers_) +
           size_t(set_group);
}

void PhotonSimulation::clear_sets(int light, int group, int keep) {
    const int groups = scene_.settings.photons.groups;
    // Last set first, in a fixed order (the maps are the same on any thread count).
    for (int k = maps_.sets(light, group) - 1; k >= keep; --k) {
        maps_.clear_group(light, k * groups + group);
        segments_[segment_index(light, k * groups + group)] = GroupSegments{};
    }
    maps_.set_sets(light, group, keep);
}

void PhotonSimulation::invalidate(int light, int group, PhotonFrameStats& stats) {
    PhotonGroup& g = maps_.group(light, group);
    if (g.queued || !scene_.lights[size_t(light)].enabled) return;  // a dark light has no photons
    g.queued = true;
    // Largest flux first: the flux its stored hits carry (what the maps are wrong by), or for a
    // group with no hits yet the flux it emits.
    queue_.insert({group_flux(light, group), light, group});
    invalidated_.emplace_back(light, group);
    ++stats.groups_invalidated;
    ++invalidations_[size_t(light)];
}

void PhotonSimulation::apply_changes(PhotonFrameStats& stats) {
    const int groups = scene_.settings.photons.groups;
    std::vector<bool> moved(scene_.objects.size(), false);
    changed_ = false;
    for (const SceneChange& c : changes_since(scene_, seen_sequence_)) {
        if (c.kind != ChangeKind::camera) changed_ = true;
        switch (c.kind) {
            case ChangeKind::object_transform:
                moved[size_t(c.index)] = true;  // queried below, once per object
                break;
            case ChangeKind::object_material: {
                // Every photon that reached a front face of this object left a hit there, so the
                // hits name exactly the groups whose Russian roulette saw the old albedo.
                std::set<std::pair<int, int>> touched;
                for (int s = 0; s < int(scene_.surfaces.size()); ++s) {
                    if (scene_.surfaces[size_t(s)].object != c.index) continue;
                    for (const PhotonHit& h : maps_.surface(s).hits)  // every photon set's
                        touched.emplace(int(h.light), int(h.group) % groups);
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
                    if (old_power[k] > 0.0f)
                        ratio[k] = new_power[k] / old_power[k];
                    else if (new_power[k] > 0.0f)
                        rescalable = false;  // nothing to scale from
                }
                for (int g = 0; g < groups; ++g) {
                    if (!rescalable) {
                        invalidate(c.index, g, stats);
                        continue;
                    }
                    for (int k = 0; k < maps_.sets(c.index, g); ++k)
                        if (maps_.group(c.index, k * groups + g).traced)
                            maps_.rescale_group(c.index, k * groups + g, ratio);
                }
                break;
            }
            case ChangeKind::light_enabled: {
                traced_power_[size_t(c.index)] = tracer_->photon_power(c.index);
                if (scene_.lights[size_t(c.index)].enabled) {
                    for (int g = 0; g < groups; ++g) invalidate(c.index, g, stats);
                } else {
                    for (int g = 0; g < groups; ++g) {
                        clear_sets(c.index, g, 0);
                        maps_.group(c.index, g).queued = false;
                    }
                    std::erase_if(queue_, [&](const QueuedGroup& q) { return q.light == c.index; });
                }
                break;
            }
            case ChangeKind::camera:
                break;
        }
    }
    if (!scene_.changes.empty())
        seen_sequence_ = std::max(seen_sequence_, scene_.changes.back().sequence);
    // Paths were traced with every object where placed_ says; several edits of one object since
    // the last frame count as one move from there to where it is now.
    std::vector<std::pair<int, Transform>> placements;  // (object, transform before)
    for (int o = 0; o < int(moved.size()); ++o) {
        const Transform& now = scene_.objects[size_t(o)].transform;
        Transform& before = placed_[size_t(o)];
        if (!moved[size_t(o)] ||
            (before.translation == now.translation && before.rotation == now.rotation))
            continue;
        placements.emplace_back(o, before);
        before = now;
    }
    if (!placements.empty()) {
        if (query_on_) invalidate_crossing(placements, stats);
        rays_->update(scene_);
    }
    tracer_->refresh();
}

void PhotonSimulation::invalidate_crossing(const std::vector<std::pair<int, Transform>>& moved,
                                           PhotonFrameStats& stats) {
    const auto start = std::chrono::steady_clock::now();
    // Stored segments start at a vertex, rays at that vertex offset by epsilon along the normal:
    // pad every box by a few epsilons so a ray that grazes the object is never missed.
    const float pad = 10.0f * rays_->epsilon();
    std::vector<Placement> placements;
    for (const auto& [o, before] : moved) {
        Bounds local = object_bounds_[size_t(o)];
        if (local.empty()) continue;
        local.min -= glm::vec3(pad);
        local.max += glm::vec3(pad);
        placements.push_back(make_placement(before, local));
        placements.push_back(make_placement(scene_.objects[size_t(o)].transform, local));
    }
    stats.objects_moved = int(moved.size());
    const auto crosses = [&](const glm::vec3& a, const glm::vec3& d, bool ray) {
        for (const Placement& p : placements)
            if (segment_meets_box(p.to_local * (a - p.translation), p.to_local * d, ray, p.local))
                return true;
        return false;
    };

    // Every photon set of every group: a path of any set crossing a placement invalidates the
    // group (all its sets).
    const int groups = scene_.settings.photons.groups;
    const size_t per_light = size_t(groups) * size_t(max_layers_);
    const size_t count = scene_.lights.size() * per_light;
    std::vector<uint8_t> hit(count, 0);
    std::vector<uint64_t> tested(count, 0);
    pool_.parallel_for(
        count,
        [&](size_t i) {
            const int l = int(i / per_light), gi = int(i % per_light), g = gi % groups;
            const PhotonGroup& base = maps_.group(l, g);
            if (!base.traced || base.queued || gi / groups >= maps_.sets(l, g)) return;
            const PhotonGroup& group = maps_.group(l, gi);
            if (!group.traced) return;
            const GroupSegments& seg = segments_[i];
            // Broad phase: the group's segments' bounds against each placement's world AABB.
            bool near = false;
            for (const Placement& p : placements) near = near || boxes_overlap(seg.bounds, p.world);
            if (!near && !seg.escapes) return;
            // Narrow phase: each segment against each placement's oriented box.
            uint64_t n = 0;
            for (size_t k = 0; k + 1 < group.photon_begin.size() && !hit[i]; ++k) {
                glm::vec3 a = seg.ends[k].origin;
                if (near) {
                    for (uint32_t v = group.photon_begin[k]; v < group.photon_begin[k + 1]; ++v) {
                        const glm::vec3 b = group.vertices[v].position;
                        ++n;
                        if (crosses(a, b - a, false)) {
                            hit[i] = 1;
                            break;
                        }
                        a = b;
                    }
                } else if (group.photon_begin[k + 1] > group.photon_begin[k]) {
                    a = group.vertices[group.photon_begin[k + 1] - 1].position;
                }
                if (!hit[i] && seg.ends[k].escape != glm::vec3(0.0f)) {
                    ++n;
                    if (crosses(a, seg.ends[k].escape, true)) hit[i] = 1;
                }
            }
            tested[i] = n;
        },
        4);
    // Invalidate in group order on this thread: the queue is the same for any thread count.
    std::vector<uint8_t> crossed(scene_.lights.size() * size_t(groups), 0);
    for (size_t i = 0; i < count; ++i) {
        stats.query_segments_tested += tested[i];
        if (hit[i])
            crossed[(i / per_light) * size_t(groups) + (i % per_light) % size_t(groups)] = 1;
    }
    for (size_t i = 0; i < crossed.size(); ++i) {
        if (!crossed[i]) continue;
        const int before = stats.groups_invalidated;
        invalidate(int(i / size_t(groups)), int(i % size_t(groups)), stats);
        stats.groups_invalidated_by_query += stats.groups_invalidated - before;
    }
    stats.query_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

bool PhotonSimulation::same_path(const PhotonGroup& group, int photon,
                                 const std::vector<TracedVertex>& path) const {
    const uint32_t begin = group.photon_begin[size_t(photon)],
                   end = group.photon_begin[size_t(photon) + 1];
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

void PhotonSimulation::store_segments(int l, int set_group, const PathEnds* ends) {
    const int per_group = scene_.settings.photons.photons_per_group;
    GroupSegments& seg = segments_[segment_index(l, set_group)];
    seg = GroupSegments{};
    seg.ends.assign(ends, ends + per_group);
    for (const PathEnds& e : seg.ends) {
        seg.bounds.add(e.origin);
        seg.escapes = seg.escapes || e.escape != glm::vec3(0.0f);
    }
    for (const PathVertex& v : maps_.group(l, set_group).vertices) seg.bounds.add(v.position);
}

void PhotonSimulation::trace_groups(const std::vector<std::pair<int, int>>& groups,
                                    const std::vector<int>& sets) {
    const int per_group = scene_.settings.photons.photons_per_group;
    const size_t jobs = groups.size() * size_t(per_group);
    if (traced_.size() < jobs) traced_.resize(jobs);
    if (traced_ends_.size() < jobs) traced_ends_.resize(jobs);
    pool_.parallel_for(
        jobs,
        [&](size_t job) {
            const size_t gi = job / size_t(per_group), p = job % size_t(per_group);
            traced_[job].clear();  // keeps its capacity from earlier frames
            traced_ends_[job] = tracer_->trace(groups[gi].first, groups[gi].second, int(p),
                                               traced_[job], sets.empty() ? 0 : sets[gi]);
        },
        8);
}

void PhotonSimulation::grow_groups(const std::vector<std::pair<int, int>>& groups) {
    const int per_group = scene_.settings.photons.photons_per_group;
    const int base = scene_.settings.photons.groups;
    std::vector<int> sets;
    for (const auto& [l, g] : groups) sets.push_back(maps_.sets(l, g));
    trace_groups(groups, sets);
    // Each group's new set joins the maps at once, its other sets re-weighted (in group order on
    // this thread: the maps are the same for any thread count).
    for (size_t gi = 0; gi < groups.size(); ++gi) {
        const auto [l, g] = groups[gi];
        const int k = sets[gi];
        maps_.set_sets(l, g, k + 1);
        maps_.set_group(l, k * base + g, &traced_[gi * size_t(per_group)], size_t(per_group));
        store_segments(l, k * base + g, &traced_ends_[gi * size_t(per_group)]);
    }
}

void PhotonSimulation::trim_sets(int most) {
    for (int l = 0; l < int(scene_.lights.size()); ++l)
        for (int g = 0; g < scene_.settings.photons.groups; ++g)
            if (maps_.sets(l, g) > most) clear_sets(l, g, most);
}

std::vector<std::pair<int, int>> PhotonSimulation::groups_to_grow() const {
    std::vector<std::pair<int, int>> out;
    if (!growth_on_) return out;
    const int target = target_layers();
    for (int l = 0; l < int(scene_.lights.size()); ++l) {
        if (!scene_.lights[size_t(l)].enabled) continue;
        for (int g = 0; g < scene_.settings.photons.groups; ++g) {
            const int n = maps_.sets(l, g);
            if (n >= 1 && n < target && !maps_.group(l, g).queued) out.emplace_back(l, g);
        }
    }
    // The groups with the fewest sets first (those an edit re-traced), then in (light, group)
    // order: a fixed order, and a settled scene grows one complete set after another.
    std::stable_sort(out.begin(), out.end(), [&](const auto& a, const auto& b) {
        return maps_.sets(a.first, a.second) < maps_.sets(b.first, b.second);
    });
    return out;
}

int PhotonSimulation::retrace_sets(int light, int group) const {
    return scene_.settings.photons.retrace_all_sets ? std::max(1, maps_.sets(light, group)) : 1;
}

void PhotonSimulation::retrace_groups(const std::vector<std::pair<int, int>>& groups) {
    const int per_group = scene_.settings.photons.photons_per_group;
    const int base = scene_.settings.photons.groups;
    // One job list over every set re-traced: set k of group i as its own entry.
    std::vector<std::pair<int, int>> jobs;
    std::vector<int> sets;
    for (const auto& [l, g] : groups)
        for (int k = 0; k < retrace_sets(l, g); ++k) {
            jobs.emplace_back(l, g);
            sets.push_back(k);
        }
    trace_groups(jobs, sets);
    // Merge in group order on this thread: the maps end up identical for any thread count. A
    // re-traced group starts again from one photon set (its extra sets held the old scene), or
    // with photons.retrace_all_sets keeps its sets, each re-traced (same weights: the hits whose
    // paths did not change come back as they were and cancel in the AIM's change log).
    for (size_t j = 0; j < jobs.size(); ++j) {
        const auto [l, g] = jobs[j];
        const int k = sets[j];
        if (k == 0 && maps_.sets(l, g) > retrace_sets(l, g)) clear_sets(l, g, 0);
        maps_.set_group(l, k * base + g, &traced_[j * size_t(per_group)], size_t(per_group));
        maps_.group(l, g).queued = false;
        store_segments(l, k * base + g, &traced_ends_[j * size_t(per_group)]);
    }
}

PhotonFrameStats PhotonSimulation::frame() { return frame(scene_.settings.photons.retrace_budget); }

int PhotonSimulation::invalidate_all() {
    PhotonFrameStats stats;
    for (int l = 0; l < int(scene_.lights.size()); ++l)
        for (int g = 0; g < scene_.settings.photons.groups; ++g) invalidate(l, g, stats);
    return stats.groups_invalidated;
}

PhotonFrameStats PhotonSimulation::frame(int retrace_budget, bool grow) {
    PhotonFrameStats stats;
    stats.frame = ++frame_;
    invalidated_.clear();
    apply_changes(stats);
    const PhotonSettings& settings = scene_.settings.photons;

    // Verification: re-trace the next photon(s) of every traced group and compare paths.
    struct Job {
        int light, group, photon;
    };
    std::vector<Job> jobs;
    for (int l = 0; l < int(scene_.lights.size()); ++l) {
        if (!scene_.lights[size_t(l)].enabled) continue;
        for (int g = 0; g < settings.groups; ++g) {
            PhotonGroup& group = maps_.group(l, g);
            if (!group.traced || group.queued || !verify_on_) continue;
            for (int v = 0; v < std::min(settings.verify_per_frame, settings.photons_per_group);
                 ++v) {
                jobs.push_back({l, g, group.verify_cursor});
                group.verify_cursor = (group.verify_cursor + 1) % settings.photons_per_group;
            }
        }
    }
    std::vector<std::vector<TracedVertex>> paths(jobs.size());
    pool_.parallel_for(
        jobs.size(),
        [&](size_t i) { tracer_->trace(jobs[i].light, jobs[i].group, jobs[i].photon, paths[i]); },
        16);
    stats.photons_verified = int(jobs.size());
    for (size_t i = 0; i < jobs.size(); ++i)
        if (!same_path(maps_.group(jobs[i].light, jobs[i].group), jobs[i].photon, paths[i]))
            invalidate(jobs[i].light, jobs[i].group, stats);
    // Refinement switched off or lowered: the sets above the target leave the maps. (An edit
    // re-traces only the groups it touches, retrace_groups; the other groups keep their sets.)
    trim_sets(growth_on_ ? target_layers() : 1);

    // Work off the queue under the budget (whole groups; at least one per frame).
    std::vector<std::pair<int, int>> batch;
    int budget = retrace_budget;
    int photons = 0;
    while (!queue_.empty()) {
        const int cost =
            retrace_sets(queue_.begin()->light, queue_.begin()->group) * settings.photons_per_group;
        if (!batch.empty() && budget < cost) break;
        batch.emplace_back(queue_.begin()->light, queue_.begin()->group);
        queue_.erase(queue_.begin());
        budget -= cost;
        photons += cost;
    }
    retrace_groups(batch);
    stats.groups_retraced = int(batch.size());
    stats.photons_retraced = photons;
    stats.groups_queued = int(queue_.size());

    // Refinement with what the budget has left (whole groups; one if no repair ran this frame),
    // one more set for each group taken, the fewest-set groups first. Not in a frame that saw an
    // edit: the scene must have held still for a whole frame.
    if (grow && queue_.empty() && growth_pending() && !changed_ && stats.groups_invalidated == 0) {
        const std::vector<std::pair<int, int>> todo = groups_to_grow();
        std::vector<std::pair<int, int>> more;
        for (size_t next = 0; next < todo.size() && ((batch.empty() && more.empty()) ||
                                                     budget >= settings.photons_per_group);
             ++next) {
            more.push_back(todo[next]);
            budget -= settings.photons_per_group;
        }
        grow_groups(more);
        stats.photons_grown = int(more.size()) * settings.photons_per_group;
    }
    stats.layers = layers();
    return stats;
}

void PhotonSimulation::trace_all() {
    PhotonFrameStats ignored;
    apply_changes(ignored);
    std::vector<std::pair<int, int>> all;
    queue_.clear();
    for (int l = 0; l < int(scene_.lights.size()); ++l)
        for (int g = 0; g < scene_.settings.photons.groups; ++g) {
            if (scene_.lights[size_t(l)].enabled)
                all.emplace_back(l, g);
            else
                clear_sets(l, g, 0);
            maps_.group(l, g).queued = false;
        }
    retrace_groups(all);
    // Every refinement set, one complete set after another, as growth would add them.
    for (std::vector<std::pair<int, int>> todo = groups_to_grow(); !todo.empty();
         todo = groups_to_grow()) {
        const int fewest = maps_.sets(todo.front().first, todo.front().second);
        std::erase_if(todo,
                      [&](const auto& lg) { return maps_.sets(lg.first, lg.second) > fewest; });
        grow_groups(todo);
    }
}

LightGroupState PhotonSimulation::light_state(int light) const {
    LightGroupState s;
    for (int g = 0; g < scene_.settings.photons.groups; ++g) {
        const PhotonGroup& group = maps_.group(light, g);
        if (group.queued)
            ++s.queued;
        else if (group.traced)
            ++s.valid;
        else
            ++s.invalid;
    }
    return s;
}

}  // namespace ag::cpu
