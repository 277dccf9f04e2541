#include "cpu/iim.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "shared/charts.h"
#include "shared/lightmap_sample.h"
#include "shared/qmc.h"

namespace ag::cpu {

Iim::Iim(const Scene& scene) : scene_(scene) {
    const size_t records = scene_.atlas.texels.size();
    const size_t n = size_t(scene_.atlas.width) * size_t(scene_.atlas.height);
    is_pending_.assign(records, 1);
    valid_.assign(records, 0);
    texel_generation_.assign(records, -1);
    moved_.assign(records, 0);
    passes_.assign(records, 0);
    sum_.assign(records, glm::dvec3(0.0));
    valid_samples_.assign(records, 0);
    raw_.assign(n, glm::vec3(0.0f));
    from_.assign(n, glm::vec3(0.0f));
    to_.assign(n, glm::vec3(0.0f));
    shown_.assign(n, glm::vec3(0.0f));
    blend_start_.assign(n, -1);
    footprint_.resize(records);
    for (int t = 0; t < int(records); ++t) pending_.push_back(t);
    surface_texels_.resize(scene_.surfaces.size());
    object_texels_.resize(scene_.objects.size());
    for (int t = 0; t < int(records); ++t) {
        const int o = scene_.atlas.texels[size_t(t)].object;
        if (o >= 0 && size_t(o) < object_texels_.size()) object_texels_[size_t(o)].push_back(t);
    }
    for (int t = 0; t < int(records); ++t) {
        const int s = scene_.atlas.texels[size_t(t)].surface;
        if (s >= 0 && size_t(s) < surface_texels_.size()) surface_texels_[size_t(s)].push_back(t);
    }
}

void Iim::schedule(PhotonMaps& maps) {
    // Larsen ch. 11: re-gather the texels of surfaces whose indirect photon hits changed most.
    std::vector<int> surfaces;
    for (int s = 0; s < int(maps.surface_count()); ++s) {
        const SurfaceHits& h = maps.surface(s);
        const double flux = std::abs(energy(h.flux));
        if (h.delta_i <= 0.0 ||
            (flux > 0.0 && h.delta_i / flux <= double(scene_.settings.aim.delta_threshold)))
            continue;
        surfaces.push_back(s);
    }
    std::stable_sort(surfaces.begin(), surfaces.end(), [&](int a, int b) {
        return maps.surface(a).delta_i > maps.surface(b).delta_i;
    });
    if (surfaces.empty()) return;  // (queue_moved placed moved texels by their priority)
    // Texels never gathered show no indirect light at all, the largest error there is: they keep
    // their place ahead of everything, or an object edited every frame would starve them. Then
    // the photons say where the light changed: those texels go before everything else queued by
    // proximity to a moved object or by a sweep, largest Δi first (a texel already queued moves
    // up to its surface's place). With screen coverage known, each class is split: the texels
    // the camera sees go first, then the rest in the same order.
    std::vector<int> order;
    order.reserve(pending_.size());
    std::vector<char> moved(is_pending_.size(), 0);
    for (int t : pending_)
        if (texel_generation_[size_t(t)] < 0) {
            moved[size_t(t)] = 1;
            order.push_back(t);
        }
    std::vector<int> changed;
    for (int t : pending_)  // texels of moved objects rank among the changed ones
        if (moved_[size_t(t)] && !moved[size_t(t)]) {
            moved[size_t(t)] = 1;
            changed.push_back(t);
        }
    for (int s : surfaces) {
        maps.surface(s).delta_i = 0.0;
        if (size_t(s) >= surface_texels_.size()) continue;
        for (int t : surface_texels_[size_t(s)]) {
            if (moved[size_t(t)]) continue;
            moved[size_t(t)] = 1;
            is_pending_[size_t(t)] = 1;
            changed.push_back(t);
        }
    }
    // Within them, the texels whose own indirect estimate moved most since they were last
    // gathered go first (one whose estimate is not known keeps its surface's place, first).
    // Where the camera sees them, a texel's share of the image's relative squared error is
    // about its staleness squared times the pixels it covers: that product orders them, so a
    // texel filling much of the screen goes before an equally stale one seen in a few pixels.
    if (!estimate_.empty())
        std::stable_sort(changed.begin(), changed.end(),
                         [&](int a, int b) { return priority(a) > priority(b); });
    order.insert(order.end(), changed.begin(), changed.end());
    for (int t : pending_)
        if (!moved[size_t(t)]) order.push_back(t);
    std::stable_partition(order.begin(), order.end(), [&](int t) { return seen(t); });
    pending_.assign(order.begin(), order.end());
}

void Iim::note_indirect_estimates(const std::vector<float>& estimates,
                                  const std::vector<float>& floors) {
    if (estimates.size() != texel_generation_.size() || floors.size() != estimates.size()) return;
    if (estimate_gathered_.empty()) estimate_gathered_.assign(estimates.size(), -1.0f);
    estimate_ = estimates;
    estimate_floor_ = floors;
}

float Iim::staleness(int record) const {
    if (estimate_.empty()) return std::numeric_limits<float>::infinity();
    const float now = estimate_[size_t(record)], then = estimate_gathered_[size_t(record)];
    if (now < 0.0f || then < 0.0f) return std::numeric_limits<float>::infinity();
    const float denominator = now + then + estimate_floor_[size_t(record)];
    return denominator > 0.0f ? std::abs(now - then) / denominator : 0.0f;
}

float Iim::priority(int record) const {
    if (moved_[size_t(record)]) {
        const float pixels = coverage_.empty() ? 0.0f : coverage_[size_t(record)];
        return pixels > 0.0f ? pixels : std::numeric_limits<float>::infinity();
    }
    const float s = staleness(record);
    if (coverage_.empty() || !std::isfinite(s)) return s;
    const float pixels = coverage_[size_t(record)];
    if (pixels <= 0.0f) return s;  // unseen ones are partitioned after the seen
    // The texel's share of the image's relative squared error, as the error is measured: its
    // change relative to the value it will have (a surface whose light falls to a third shows
    // 200% too bright until gathered, one whose light triples 67% too dark).
    const float now = estimate_[size_t(record)], then = estimate_gathered_[size_t(record)];
    const float denominator = now + estimate_floor_[size_t(record)];
    const float e = denominator > 0.0f ? std::abs(now - then) / denominator : 0.0f;
    return e * e * pixels;
}

void Iim::set_coverage(const std::vector<float>& per_record) {
    if (per_record.size() != texel_generation_.size()) {
        coverage_.clear();
        seen_records_.clear();
        return;
    }
    coverage_ = per_record;
    seen_records_.clear();
    for (size_t t = 0; t < coverage_.size(); ++t)
        if (coverage_[t] > 0.0f) seen_records_.push_back(int(t));
    // What was queued before the camera moved keeps its classes, seen texels first.
    std::vector<int> order(pending_.begin(), pending_.end());
    std::stable_partition(order.begin(), order.end(), [&](int t) { return seen(t); });
    pending_.assign(order.begin(), order.end());
}

void Iim::invalidate_all() {
    for (int t = 0; t < int(scene_.atlas.texels.size()); ++t)
        if (!is_pending_[size_t(t)]) {
            is_pending_[size_t(t)] = 1;
            pending_.push_back(t);
        }
}

void Iim::queue_inside(const std::vector<Bounds>& regions) {
    std::vector<std::pair<float, int>> found;  // (distance to the nearest region centre, record)
    for (int t = 0; t < int(scene_.atlas.texels.size()); ++t) {
        if (is_pending_[size_t(t)]) continue;
        const TexelRecord& r = scene_.atlas.texels[size_t(t)];
        const glm::vec3 p = scene_.objects[size_t(r.object)].transform.apply_point(r.position);
        float nearest = -1.0f;
        for (const Bounds& b : regions)
            if (glm::all(glm::greaterThanEqual(p, b.min)) &&
                glm::all(glm::lessThanEqual(p, b.max))) {
                const float d = glm::length(p - b.center());
                nearest = nearest < 0.0f ? d : std::min(nearest, d);
            }
        if (nearest >= 0.0f) found.emplace_back(nearest, t);
    }
    std::sort(found.begin(), found.end());
    for (const auto& [d, t] : found) {
        is_pending_[size_t(t)] = 1;
        pending_.push_back(t);
    }
}

void Iim::queue_moved(const std::vector<int>& objects) {
    std::vector<int> front;
    std::vector<char> taken(is_pending_.size(), 0);
    for (int o : objects) {
        if (o < 0 || size_t(o) >= object_texels_.size()) continue;
        for (int t : object_texels_[size_t(o)])
            if (texel_generation_[size_t(t)] >= 0 && !taken[size_t(t)]) {
                moved_[size_t(t)] = 1;
                is_pending_[size_t(t)] = 1;
                taken[size_t(t)] = 1;
                front.push_back(t);
            }
    }
    if (front.empty()) return;
    // Behind texels never gathered, ahead of the rest, by priority (seen ones first below).
    std::stable_sort(front.begin(), front.end(),
                     [&](int a, int b) { return priority(a) > priority(b); });
    std::vector<int> order;
    order.reserve(pending_.size() + front.size());
    for (int t : pending_)
        if (texel_generation_[size_t(t)] < 0) {
            taken[size_t(t)] = 1;
            order.push_back(t);
        }
    order.insert(order.end(), front.begin(), front.end());
    for (int t : pending_)
        if (!taken[size_t(t)]) order.push_back(t);
    std::stable_partition(order.begin(), order.end(), [&](int t) { return seen(t); });
    pending_.assign(order.begin(), order.end());
}

IimFrameStats Iim::gather(Gatherer& gatherer, int budget, uint64_t frame) {
    std::vector<int> batch;
    std::vector<char> in_batch(texel_generation_.size(), 0);
    // Queued texels (seen ones first), up to the first one the camera does not see.
    auto take_queued = [&](bool seen_only) {
        while (!pending_.empty() && int(batch.size()) < budget) {
            const int t = pending_.front();
            if (seen_only && !seen(t)) break;
            in_batch[size_t(t)] = 1;
            batch.push_back(t);
            is_pending_[size_t(t)] = 0;
            moved_[size_t(t)] = 0;
            pending_.pop_front();
        }
    };
    take_queued(!coverage_.empty());
    // Then the texels the camera sees that were gathered with older AIMs, before the queued
    // ones it does not see: the picture is made of them. A texel's gather reads the light of
    // everything it sees, not its own photon hits, so one whose surface's hits barely changed
    // (Δi below the threshold) may still be far off: after a lamp of the conference room goes
    // off, its chairs' texels showed three times their light until the last of the queue.
    // Most stale first by the image error they carry (priority), then the longest stale.
    const size_t n = texel_generation_.size();
    if (!coverage_.empty() && int(batch.size()) < budget) {
        std::vector<std::pair<float, int>> keyed;  // (priority, record) of the stale seen ones
        for (int t : seen_records_)
            if (!is_pending_[size_t(t)] && texel_generation_[size_t(t)] < aim_generation_ &&
                !in_batch[size_t(t)])
                keyed.emplace_back(priority(t), t);
        const size_t take = std::min(keyed.size(), size_t(budget) - batch.size());
        std::partial_sort(keyed.begin(), keyed.begin() + std::ptrdiff_t(take), keyed.end(),
                          [&](const auto& a, const auto& b) {
                              if (a.first != b.first) return a.first > b.first;
                              const int ga = texel_generation_[size_t(a.second)],
                                        gb = texel_generation_[size_t(b.second)];
                              return ga != gb ? ga < gb : a.second < b.second;
                          });
        for (size_t k = 0; k < take; ++k) {
            in_batch[size_t(keyed[k].second)] = 1;
            batch.push_back(keyed[k].second);
        }
    }
    take_queued(false);
    // The rest of the budget refreshes texels gathered with older AIMs, round robin, so the IIM
    // settles on the final AIMs once edits stop.
    for (size_t visited = 0; visited < n && int(batch.size()) < budget; ++visited) {
        const size_t t = sweep_;
        sweep_ = (sweep_ + 1) % n;
        if (!is_pending_[t] && texel_generation_[t] < aim_generation_ && !in_batch[t]) {
            in_batch[t] = 1;
            batch.push_back(int(t));
        }
    }
    IimFrameStats stats;
    if (batch.empty()) {
        // Nothing queued or stale: refine settled texels, round robin, so every texel gets its
        // k-th pass before any gets its (k+1)-th.
        const int max_passes = std::max(1, scene_.settings.gather.refine_passes);
        int fewest =
            max_passes;  // a settled scene costs one pass over the records, not one a level
        for (size_t t = 0; t < n; ++t)
            if (refinable(t)) fewest = std::min(fewest, passes_[t]);
        for (int level = fewest; level < max_passes && int(batch.size()) < budget; ++level) {
            for (size_t visited = 0; visited < n && int(batch.size()) < budget; ++visited) {
                const size_t t = refine_sweep_;
                refine_sweep_ = (refine_sweep_ + 1) % n;
                if (refinable(t) && passes_[t] <= level && !in_batch[t]) {
                    in_batch[t] = 1;
                    batch.push_back(int(t));
                }
            }
        }
        stats = refine_records(gatherer, batch, frame);
    } else {
        stats = gather_records(gatherer, batch, frame);
    }
    stats.pending = int(pending_.size());
    return stats;
}

bool Iim::refinable(size_t t) const {
    return valid_[t] && !is_pending_[t] && texel_generation_[t] == aim_generation_ &&
           passes_[t] < std::max(1, scene_.settings.gather.refine_passes);
}

glm::vec2 Iim::refine_offset(int pass) {
    // Shifted by ½ so that pass 0 is the centre, the point every first gather uses.
    auto centred = [](double x) { return float(x + 0.5 >= 1.0 ? x - 0.5 : x + 0.5) - 0.5f; };
    return {centred(radical_inverse(2, uint64_t(pass))),
            centred(radical_inverse(3, uint64_t(pass)))};
}

void Iim::start_mean(int record, glm::vec3 value, bool valid) {
    const TexelRecord& t = scene_.atlas.texels[size_t(record)];
    raw_[size_t(t.y) * size_t(scene_.atlas.width) + size_t(t.x)] = value;
    passes_[size_t(record)] = 1;
    sum_[size_t(record)] = valid ? glm::dvec3(value) : glm::dvec3(0.0);
    valid_samples_[size_t(record)] = valid ? 1 : 0;
}

IimFrameStats Iim::refine_records(Gatherer& gatherer, const std::vector<int>& batch,
                                  uint64_t frame) {
    IimFrameStats stats;
    last_gathered_.clear();
    if (batch.empty()) return stats;
    // Each pass reads its own point of the footprint (an average over the footprint, not the
    // centre's point sample: a texel then holds what bilinear reconstruction of a box-filtered
    // signal needs, and small bright patches, such as the light a ball lens focuses, are not
    // missed or over-weighted) with its own ray set (the CPU gather's shift is keyed by it).
    std::vector<GatherPoint> points;
    std::vector<int> owner;  // per point: index into batch
    for (size_t k = 0; k < batch.size(); ++k) {
        const int r = batch[k];
        const int pass = passes_[size_t(r)];
        const std::optional<FootprintPoint> p = texel_point_at(
            scene_, r, scene_.settings.gather.refine_footprint * refine_offset(pass));
        if (!p) continue;  // off the chart: this pass has nothing to add
        const TexelRecord& t = scene_.atlas.texels[size_t(r)];
        const Transform& transform = scene_.objects[size_t(t.object)].transform;
        const uint32_t key = hash_u32(uint32_t(r) ^ hash_u32(uint32_t(pass) + 0x2545f491u));
        points.push_back(
            {transform.apply_point(p->position), transform.apply_vector(p->normal), key});
        owner.push_back(int(k));
    }
    const std::vector<GatherResult> results =
        points.empty() ? std::vector<GatherResult>{} : gatherer.gather_points(points);
    for (size_t i = 0; i < results.size(); ++i) {
        // A point inside geometry (beside a contact) says nothing about the texel's light.
        if (results[i].back_fraction > kBackFaceInvalidFraction) continue;
        const size_t r = size_t(batch[size_t(owner[i])]);
        sum_[r] += glm::dvec3(results[i].iim);
        ++valid_samples_[r];
    }
    const int w = scene_.atlas.width;
    for (int r : batch) {
        ++passes_[size_t(r)];
        if (valid_samples_[size_t(r)] == 0) continue;
        const TexelRecord& t = scene_.atlas.texels[size_t(r)];
        raw_[size_t(t.y) * size_t(w) + size_t(t.x)] =
            glm::vec3(sum_[size_t(r)] / double(valid_samples_[size_t(r)]));
    }
    repair_and_blend(batch, frame);
    stats.gathered = int(batch.size());
    stats.refined = int(batch.size());
    last_gathered_ = batch;
    return stats;
}

IimFrameStats Iim::gather_records(Gatherer& gatherer, const std::vector<int>& batch,
                                  uint64_t frame) {
    IimFrameStats stats;
    last_gathered_.clear();
    if (batch.empty()) return stats;
    for (int t : batch) {
        texel_generation_[size_t(t)] = aim_generation_;
        if (!estimate_.empty()) estimate_gathered_[size_t(t)] = estimate_[size_t(t)];
    }

    const std::vector<GatherResult> results = gatherer.gather(batch);
    std::vector<int> invalid;
    for (size_t k = 0; k < batch.size(); ++k) {
        // Behind or inside geometry: take the chart's valid neighbours instead of leaking.
        const bool valid = results[k].back_fraction <= kBackFaceInvalidFraction;
        start_mean(batch[k], results[k].iim, valid);
        valid_[size_t(batch[k])] = valid;
        if (!valid) invalid.push_back(batch[k]);
    }
    stats.relocated = relocate(gatherer, invalid);
    repair_and_blend(batch, frame);
    stats.gathered = int(batch.size());
    stats.invalid = int(invalid.size());
    last_gathered_ = batch;
    return stats;
}

void Iim::defer_repairs() {
    deferring_ = true;
    deferred_.clear();
}

void Iim::repair_deferred(uint64_t frame) {
    if (!deferring_) return;
    deferring_ = false;
    repair_and_blend(deferred_, frame);
    deferred_.clear();
}

void Iim::repair_and_blend(const std::vector<int>& batch, uint64_t frame) {
    if (deferring_) {
        deferred_.insert(deferred_.end(), batch.begin(), batch.end());
        return;
    }
    const int w = scene_.atlas.width;
    // Repaired values follow their sources: every invalid texel gathered so far is filled again
    // from the valid values as they are now, not only this batch's. Otherwise a texel repaired
    // before a neighbour was re-gathered keeps the old value, and the settled IIM would depend
    // on the order texels were gathered in (an edited pipeline would not end where a fresh one
    // does).
    std::vector<int> repair;
    for (size_t r = 0; r < valid_.size(); ++r)
        if (!valid_[r] && texel_generation_[r] >= 0) repair.push_back(int(r));
    std::vector<char> in_batch(valid_.size(), 0);
    for (int r : batch) in_batch[size_t(r)] = 1;
    std::vector<glm::vec3> before(repair.size());
    for (size_t j = 0; j < repair.size(); ++j) {
        const TexelRecord& t = scene_.atlas.texels[size_t(repair[j])];
        before[j] = raw_[size_t(t.y) * size_t(w) + size_t(t.x)];
    }
    if (!repair.empty()) repair_invalid_texels(scene_.atlas, raw_, valid_, repair);

    auto start_blend = [&](int r) {
        const TexelRecord& t = scene_.atlas.texels[size_t(r)];
        const size_t a = size_t(t.y) * size_t(w) + size_t(t.x);
        from_[a] = shown_[a];
        to_[a] = raw_[a];
        if (blend_start_[a] < 0) blending_.push_back(int(a));
        blend_start_[a] = int(frame);
    };
    for (int r : batch) start_blend(r);
    for (size_t j = 0; j < repair.size(); ++j) {
        const TexelRecord& t = scene_.atlas.texels[size_t(repair[j])];
        if (!in_batch[size_t(repair[j])] &&
            raw_[size_t(t.y) * size_t(w) + size_t(t.x)] != before[j])
            start_blend(repair[j]);
    }
}

int Iim::relocate(Gatherer& gatherer, std::vector<int>& invalid) {
    // A texel whose centre lies inside geometry (the floor under a box) still has part of its
    // footprint outside: gather at the footprint point nearest the centre that sees few back
    // faces. Its value is then the light beside the contact, not its neighbours' (which would
    // carry the open floor's light up to the box, a leak of 50% in the box's shadow).
    // The points are tried in rounds, nearest first, each round only for the texels no earlier
    // point served: the same point wins as when all are gathered, at a fraction of the gathers
    // (most texels find one at the first or second point).
    for (int r : invalid)
        if (footprint_[size_t(r)].empty())
            footprint_[size_t(r)] = texel_footprint_points(scene_, r);
    std::vector<int> open = invalid, next;
    std::vector<GatherPoint> points;
    std::vector<int> owners;
    int relocated = 0;
    for (size_t k = 0; !open.empty(); ++k) {
        points.clear();
        owners.clear();
        next.clear();
        for (int r : open) {
            const std::vector<FootprintPoint>& footprint = footprint_[size_t(r)];
            if (k >= footprint.size()) continue;
            const TexelRecord& t = scene_.atlas.texels[size_t(r)];
            const Transform& transform = scene_.objects[size_t(t.object)].transform;
            points.push_back({transform.apply_point(footprint[k].position),
                              transform.apply_vector(footprint[k].normal),
                              uint32_t(r) * 9u + uint32_t(k) + 1u});
            owners.push_back(r);
        }
        if (points.empty()) break;
        const std::vector<GatherResult> results = gatherer.gather_points(points);
        for (size_t i = 0; i < owners.size(); ++i) {
            const int r = owners[i];
            if (results[i].back_fraction <= kBackFaceInvalidFraction) {
                start_mean(r, results[i].iim, true);
                valid_[size_t(r)] = 1;
                ++relocated;
            } else {
                next.push_back(r);
            }
        }
        open.swap(next);
    }
    std::vector<int> still;
    for (int r : invalid)
        if (!valid_[size_t(r)]) still.push_back(r);
    invalid.swap(still);
    return relocated;
}

const std::vector<int>& Iim::blend(uint64_t frame, int blend_frames) {
    // Two IIM buffers, blended over `blend_frames` so new gathers never pop.
    std::vector<int> still;
    for (int a : blending_) {
        const float t = std::min(1.0f, float(int(frame) - blend_start_[size_t(a)] + 1) /
                                           float(std::max(1, blend_frames)));
        shown_[size_t(a)] = glm::mix(from_[size_t(a)], to_[size_t(a)], t);
        if (t < 1.0f)
            still.push_back(a);
        else
            blend_start_[size_t(a)] = -1;
    }
    changed_.swap(blending_);
    blending_.swap(still);
    return changed_;
}

bool Iim::complete() const {
    if (!pending_.empty()) return false;
    for (int g : texel_generation_)
        if (g < aim_generation_) return false;
    for (size_t r = 0; r < passes_.size(); ++r)
        if (refinable(r)) return false;
    return true;
}

bool Iim::settled() const { return blending_.empty() && complete(); }

}  // namespace ag::cpu
