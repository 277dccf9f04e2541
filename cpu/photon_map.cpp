#include "cpu/photon_map.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace ag::cpu {

namespace {
// A surface's change log past this many entries per stored hit (plus 64) is dropped and the
// surface rebuilt whole (changes_overflow): by then most of its texels change anyway, and the
// log costs more to net than the kNN it would save. A rebuild gives to the bit what the local
// update gives (AimUpdate.LocalUpdateEqualsAWholeRebuild), so this is a matter of speed only.
constexpr size_t kChangesPerHit = 2;
}  // namespace

void PhotonMaps::resize(size_t surfaces, size_t lights, int groups, int max_sets) {
    surfaces_.assign(surfaces, SurfaceHits{});
    base_groups_ = std::max(1, groups);
    max_sets_ = std::clamp(max_sets, 1, 255);
    groups_.assign(lights, std::vector<PhotonGroup>(size_t(base_groups_) * size_t(max_sets_)));
    sets_.assign(lights, std::vector<uint8_t>(size_t(base_groups_), 0));
}

void PhotonMaps::add_energy(SurfaceHits& s, const glm::vec3& position, const glm::vec3& raw,
                            uint8_t bounce, double sign, double weight) {
    const glm::vec3 power = weight == 1.0 ? raw : raw * float(weight);
    if (!s.changes_overflow) {
        if (s.changes.size() >= kChangesPerHit * s.hits.size() + 64) {
            s.changes_overflow = true;
            std::vector<HitChange>().swap(s.changes);
            std::vector<uint32_t>().swap(s.changes_sorted);
        } else {
            s.changes.push_back(HitChange{position, power, bounce, int8_t(sign > 0.0 ? 1 : -1)});
        }
    }
    s.flux += sign * glm::dvec3(power);
    s.signed_delta += sign * glm::dvec3(power);
    const double e = std::abs(energy(power));
    s.delta_f += e;
    if (bounce >= 1) s.delta_i += e;
}

void PhotonMaps::clear_group(int light, int g) {
    PhotonGroup& group = groups_[size_t(light)][size_t(g)];
    const double w = weight(light, g);
    for (const PathVertex& v : group.vertices) {
        if (v.hit < 0) continue;
        SurfaceHits& s = surfaces_[size_t(v.surface)];
        const PhotonHit removed = s.hits[size_t(v.hit)];
        add_energy(s, removed.position, removed.power, removed.bounce, -1.0, w);
        // Swap-remove: the last hit takes the freed slot; patch its owner's path vertex.
        const size_t last = s.hits.size() - 1;
        if (size_t(v.hit) != last) {
            s.hits[size_t(v.hit)] = s.hits[last];
            const PhotonHit& moved = s.hits[size_t(v.hit)];
            groups_[moved.light][moved.group].vertices[moved.vertex].hit = v.hit;
        }
        s.hits.pop_back();
    }
    group.vertices.clear();
    group.photon_begin.clear();
    group.traced = false;
}

void PhotonMaps::set_group(int light, int g, const std::vector<TracedVertex>* photons,
                           size_t count) {
    clear_group(light, g);
    uint8_t& sets = sets_[size_t(light)][size_t(g % base_groups_)];
    assert(g / base_groups_ < std::max<int>(1, sets));
    if (sets == 0) sets = 1;  // the group's first set
    const double w = weight(light, g);
    PhotonGroup& group = groups_[size_t(light)][size_t(g)];
    group.photon_begin.reserve(count + 1);
    for (size_t p = 0; p < count; ++p) {
        const std::vector<TracedVertex>& path = photons[p];
        group.photon_begin.push_back(uint32_t(group.vertices.size()));
        for (const TracedVertex& t : path) {
            PathVertex v{t.surface, t.position, t.local_position, -1, t.normal, t.albedo};
            if (t.stored) {
                SurfaceHits& s = surfaces_[size_t(t.surface)];
                v.hit = int32_t(s.hits.size());
                s.hits.push_back(PhotonHit{t.local_position, t.power, uint32_t(light), uint32_t(g),
                                           uint32_t(group.vertices.size()), t.bounce});
                add_energy(s, t.local_position, t.power, t.bounce, +1.0, w);
            }
            group.vertices.push_back(v);
        }
    }
    group.photon_begin.push_back(uint32_t(group.vertices.size()));
    group.traced = true;
}

void PhotonMaps::rescale_group(int light, int g, const glm::vec3& ratio) {
    PhotonGroup& group = groups_[size_t(light)][size_t(g)];
    const double w = weight(light, g);
    for (const PathVertex& v : group.vertices) {
        if (v.hit < 0) continue;
        SurfaceHits& s = surfaces_[size_t(v.surface)];
        PhotonHit& hit = s.hits[size_t(v.hit)];
        add_energy(s, hit.position, hit.power, hit.bounce, -1.0, w);
        hit.power *= ratio;
        add_energy(s, hit.position, hit.power, hit.bounce, +1.0, w);
    }
}

void PhotonMaps::set_sets(int light, int g, int n) {
    uint8_t& sets = sets_[size_t(light)][size_t(g)];
    n = std::clamp(n, 0, max_sets_);
    if (n == int(sets)) return;
    const double before = weight(light, g);
    const double after = n > 1 ? 1.0 / double(n) : 1.0;
    if (before != after) {
        // The hits of the sets kept count again with the new weight (in set order, then path
        // order: the books are the same for any thread count).
        for (int k = 0; k < std::min<int>(sets, n); ++k) {
            const PhotonGroup& group = groups_[size_t(light)][size_t(k * base_groups_ + g)];
            for (const PathVertex& v : group.vertices) {
                if (v.hit < 0) continue;
                SurfaceHits& s = surfaces_[size_t(v.surface)];
                const PhotonHit& hit = s.hits[size_t(v.hit)];
                add_energy(s, hit.position, hit.power, hit.bounce, -1.0, before);
                add_energy(s, hit.position, hit.power, hit.bounce, +1.0, after);
            }
        }
    }
    for (int k = n; k < int(sets); ++k)
        assert(!groups_[size_t(light)][size_t(k * base_groups_ + g)].traced);
    sets = uint8_t(n);
}

int PhotonMaps::layers() const {
    int fewest = 0;
    for (const std::vector<uint8_t>& light : sets_)
        for (uint8_t n : light)
            if (n > 0 && (fewest == 0 || n < fewest)) fewest = n;
    return std::max(1, fewest);
}

size_t PhotonMaps::stored_bytes() const {
    size_t n = 0;
    for (const SurfaceHits& s : surfaces_) n += s.hits.size() * sizeof(PhotonHit);
    for (const std::vector<PhotonGroup>& light : groups_)
        for (const PhotonGroup& g : light)
            n += g.vertices.size() * sizeof(PathVertex) + g.photon_begin.size() * sizeof(uint32_t);
    return n;
}

size_t PhotonMaps::hit_count() const {
    size_t n = 0;
    for (const SurfaceHits& s : surfaces_) n += s.hits.size();
    return n;
}

}  // namespace ag::cpu
