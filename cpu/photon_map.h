// Per-surface photon maps with stored paths (Larsen ch. 8, 9): each surface owns its photon hits,
// each photon group owns its paths, and a hit links back to its path vertex so that removing a
// whole group's hits is O(1) per hit (swap-remove, the moved hit's owner is patched).
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "cpu/photon_tracer.h"

namespace ag::cpu {

struct PhotonHit {
    glm::vec3 position{0.0f};  // object space of the surface's object
    glm::vec3 power{0.0f};     // incident flux, W
    uint32_t light = 0, group = 0;
    uint32_t vertex = 0;  // index into the owning group's path vertices
    uint8_t bounce = 0;
};

// One photon's interaction as stored in its group's path.
struct PathVertex {
    int surface = -1;
    glm::vec3 position{0.0f};  // world space, for comparison with a re-traced path
    glm::vec3 local{0.0f};     // object space: a hit must also stay put on its moving object
    int32_t hit = -1;          // slot in the surface's hits, -1 if nothing was stored
    glm::vec3 normal{0.0f};    // world space, the side the photon arrived from (VPL orientation)
    glm::vec3 albedo{0.0f};    // the albedo where it landed (the texel's on a textured surface)
};

struct PhotonGroup {
    std::vector<PathVertex> vertices;    // all photons' paths, back to back
    std::vector<uint32_t> photon_begin;  // P + 1 offsets into vertices
    int verify_cursor = 0;               // next photon to verify (round robin)
    bool queued = false;                 // waiting for a full retrace
    bool traced = false;                 // holds hits of the current light state
};

// A hit added (+1) or removed (−1) since the surface's AIM was last built. A group re-traced
// along the same paths removes and re-adds the same hits: those cancel (Aim::update).
struct HitChange {
    glm::vec3 position{0.0f};  // object space, as the hit's
    glm::vec3 power{0.0f};
    uint8_t bounce = 0;
    int8_t sign = 0;
};

struct SurfaceHits {
    std::vector<PhotonHit> hits;
    // Hits added and removed since the AIM rebuild, in order; when they outnumber the hits
    // (a surface left unbuilt through many edits) they are dropped and `changes_overflow` says
    // that anything may have changed.
    std::vector<HitChange> changes;
    bool changes_overflow = false;
    // Aim::net_changes' cache: the indices of the first changes_sorted.size() changes, sorted by
    // what they are (ties by index). A surface left pending is ranked every frame; only the
    // changes logged since are sorted and merged in. Cleared with the log (clear_changes).
    mutable std::vector<uint32_t> changes_sorted;
    // Forgets the log (after an AIM rebuild, or on overflow) and its sorted order.
    void clear_changes() {
        changes.clear();
        changes_sorted.clear();
    }
    glm::dvec3 flux{0.0};          // Σ power of the stored hits
    double delta_f = 0.0;          // Σ |energy| of hits added/removed since the AIM rebuild
    double delta_i = 0.0;          // same, hits with bounce ≥ 1 only, since the IIM update
    glm::dvec3 signed_delta{0.0};  // Σ signed energy since the AIM rebuild (bookkeeping check)
};

// Scalar energy of an RGB flux for the deltas: the channel mean.
inline double energy(const glm::vec3& p) { return (double(p.x) + double(p.y) + double(p.z)) / 3.0; }
inline double energy(const glm::dvec3& p) { return (p.x + p.y + p.z) / 3.0; }

class PhotonMaps {
public:
    // Room for `groups` QMC groups per light, each with up to `max_sets` photon sets
    // (photons.refine_layers): set k of group g lives at group index k·groups + g.
    void resize(size_t surfaces, size_t lights, int groups, int max_sets = 1);

    SurfaceHits& surface(int s) { return surfaces_[size_t(s)]; }
    const SurfaceHits& surface(int s) const { return surfaces_[size_t(s)]; }
    size_t surface_count() const { return surfaces_.size(); }
    PhotonGroup& group(int light, int g) { return groups_[size_t(light)][size_t(g)]; }
    const PhotonGroup& group(int light, int g) const { return groups_[size_t(light)][size_t(g)]; }

    // Removes every hit of the group and forgets its paths.
    void clear_group(int light, int g);
    // Replaces the group's paths with photons[0..count) (one traced path each) and adds the hits.
    void set_group(int light, int g, const std::vector<TracedVertex>* photons, size_t count);
    // Multiplies the power of every hit of the group by `ratio` (light colour edits).
    void rescale_group(int light, int g, const glm::vec3& ratio);

    size_t hit_count() const;
    // Bytes of the stored paths and hits (vertices, offsets, hits; not the change logs).
    size_t stored_bytes() const;

    // Photon sets per group (photons.refine_layers). Each group holds its own number of sets:
    // an edit re-traces the groups it touches (with one set, or with every set it holds under
    // photons.retrace_all_sets) and leaves the others' sets alone.
    // A hit keeps the flux of one photon of one set, Φ / (G·P), and counts with weight
    // 1 / sets of its group (hit_weight) in the surface's flux, its deltas, its change log and
    // the AIM's density estimate: every group's stratum carries its whole flux however many sets
    // it holds, so the estimate is unbiased in any mix.
    int base_groups() const { return base_groups_; }
    int max_sets() const { return max_sets_; }
    int sets(int light, int g) const { return sets_[size_t(light)][size_t(g)]; }
    double weight(int light, int g) const {
        const int n = sets_[size_t(light)][size_t(g % base_groups_)];
        return n > 1 ? 1.0 / double(n) : 1.0;
    }
    double hit_weight(const PhotonHit& h) const { return weight(int(h.light), int(h.group)); }
    // Sets group g (< base_groups()) of the light holds from now on: the hits of its sets below
    // min(old, n) are counted again with weight 1 / n. Sets n and above must be cleared first.
    void set_sets(int light, int g, int n);
    // The fewest sets any group holding photons has: the complete photon sets (1 if none).
    int layers() const;

private:
    // Books a hit of `power` × `weight` added (sign +1) or removed (−1).
    void add_energy(SurfaceHits& s, const glm::vec3& position, const glm::vec3& power,
                    uint8_t bounce, double sign, double weight);

    std::vector<SurfaceHits> surfaces_;
    std::vector<std::vector<PhotonGroup>> groups_;  // [light][set · base_groups_ + group]
    std::vector<std::vector<uint8_t>> sets_;        // [light][group]: sets held, 0 = none yet
    int base_groups_ = 1, max_sets_ = 1;
};

}  // namespace ag::cpu
