#include "cpu/photon_map.h"

#include <cassert>
#include <cmath>

namespace ag::cpu {

void PhotonMaps::resize(size_t surfaces, size_t lights, int groups_per_light) {
    surfaces_.assign(surfaces, SurfaceHits{});
    layers_ = 1;
    groups_.assign(lights, std::vector<PhotonGroup>(size_t(groups_per_light)));
}

void PhotonMaps::add_energy(SurfaceHits& s, const glm::vec3& position, const glm::vec3& power,
                            uint8_t bounce, double sign) {
    if (!s.changes_overflow) {
        if (s.changes.size() >= 4 * s.hits.size() + 64) {
            s.changes_overflow = true;
            std::vector<HitChange>().swap(s.changes);
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
    for (const PathVertex& v : group.vertices) {
        if (v.hit < 0) continue;
        SurfaceHits& s = surfaces_[size_t(v.surface)];
        const PhotonHit removed = s.hits[size_t(v.hit)];
        add_energy(s, removed.position, removed.power, removed.bounce, -1.0);
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
                add_energy(s, t.local_position, t.power, t.bounce, +1.0);
            }
            group.vertices.push_back(v);
        }
    }
    group.photon_begin.push_back(uint32_t(group.vertices.size()));
    group.traced = true;
}

void PhotonMaps::rescale_group(int light, int g, const glm::vec3& ratio) {
    PhotonGroup& group = groups_[size_t(light)][size_t(g)];
    for (const PathVertex& v : group.vertices) {
        if (v.hit < 0) continue;
        SurfaceHits& s = surfaces_[size_t(v.surface)];
        PhotonHit& hit = s.hits[size_t(v.hit)];
        add_energy(s, hit.position, hit.power, hit.bounce, -1.0);
        hit.power *= ratio;
        add_energy(s, hit.position, hit.power, hit.bounce, +1.0);
    }
}

void PhotonMaps::set_layers(int layers) {
    if (layers == layers_) return;
    layers_ = layers;
    for (SurfaceHits& s : surfaces_) {
        if (s.hits.empty()) continue;
        const double e = std::abs(energy(s.flux));
        s.delta_f += e;
        s.delta_i += e;
    }
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
