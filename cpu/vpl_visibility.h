// Geometric visibility classification of (patch, light) pairs (Barczak 2006 §4.3.1, §4.5.1):
// an occlusion pyramid from a light to each patch, blockers tested against it (walls and other
// simple objects polygon by polygon, complex ones by bounding sphere), each pair labelled not (N),
// partly (P) or fully (F) occluded; P patches are subdivided into a hierarchy whose children
// re-test only their parent's partial blockers; a moved object is re-tested alone and the
// database updated by Table 4-1. Only P pairs need shadow-map lookups.
#pragma once

#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "shared/scene.h"
#include "shared/vpl.h"

namespace ag::cpu {

enum class Occlusion : uint8_t { none, partial, full, behind };  // behind: no light reaches it

struct VisibilityCounters {
    uint64_t none = 0, partial = 0, full = 0, behind = 0;  // leaf (patch, light) labels
    uint64_t blocker_tests = 0;                            // pyramid tests made
    // Table 4-1's actions taken by object_moved(): no change, recursive update, change and
    // propagate to children.
    uint64_t unchanged = 0, recursive = 0, propagated = 0;
};

class VisibilityDatabase {
public:
    // Patches: every triangle of every object, subdivided `depth` times (4 children per level).
    // Objects with at most `polygon_blocker_limit` triangles block polygon by polygon, larger ones
    // by bounding sphere. An object never blocks its own patches (self-shadowing is the shadow
    // maps' business).
    VisibilityDatabase(const Scene& scene, const std::vector<Vpl>& lights, int depth,
                       int polygon_blocker_limit = 32);

    // Object `object` has moved (the scene holds its new transform): its own patches are
    // classified again; every other node re-tests only it, by Table 4-1.
    void object_moved(int object);

    struct Node {
        std::array<glm::vec3, 3> v;      // world space
        std::array<glm::vec3, 3> local;  // object space
        int object = -1;
        int parent = -1, first_child = -1;  // children: first_child .. first_child + 3
    };
    const std::vector<Node>& nodes() const { return nodes_; }
    bool leaf(int node) const { return nodes_[size_t(node)].first_child < 0; }
    Occlusion state(int node, int light) const { return pair(node, light).state; }
    // The label of (node, light) from a single blocker object, as the pyramid test gives it.
    Occlusion classify(int node, int light, int object) const;
    // The leaf holding the point at Embree barycentrics `uv` of (object, triangle); -1 if that
    // object has no patches (mirrors, glass).
    int leaf_at(int object, int triangle, glm::vec2 uv) const;
    // Leaf labels now (recounted) and the work counters since construction.
    VisibilityCounters counters() const;
    int light_count() const { return int(lights_.size()); }

private:
    struct Flag {
        int object;
        Occlusion occlusion;  // partial or full
    };
    struct Pair {
        Occlusion state = Occlusion::none;
        std::vector<Flag> blockers;
    };
    struct BlockerShape {
        bool sphere = false;
        glm::vec3 centre{0.0f};
        float radius = 0.0f;
        std::vector<std::array<glm::vec3, 3>> triangles;  // world space
    };

    Pair& pair(int node, int light) {
        return pairs_[size_t(node) * lights_.size() + size_t(light)];
    }
    const Pair& pair(int node, int light) const {
        return pairs_[size_t(node) * lights_.size() + size_t(light)];
    }
    void make_shape(int object);
    void add_nodes(int object);
    int add_node(const std::array<glm::vec3, 3>& local, int object, int parent, int depth);
    void fill(int slot, const std::array<glm::vec3, 3>& local, int object, int parent, int depth);
    // Full classification of (node, light) against `candidates` (and `full`, blockers known to
    // occlude it fully), then its children against the blockers it found partial.
    void classify_tree(int node, int light, const std::vector<int>& candidates,
                       const std::vector<int>& full);
    void set_flag(Pair& p, int object, Occlusion o);
    static Occlusion state_of(const Pair& p);
    // Table 4-1 for the mover at (node, light).
    void update(int node, int light, int object);
    void propagate(int node, int light, int object, Occlusion o);
    bool behind(int node, int light) const;

    const Scene& scene_;
    std::vector<Vpl> lights_;
    int depth_, polygon_limit_;
    std::vector<Node> nodes_;
    std::vector<int> roots_;
    std::vector<std::vector<int>> root_of_;  // [object][triangle] → root node
    std::vector<Pair> pairs_;
    std::vector<BlockerShape> shapes_;  // per object
    mutable VisibilityCounters work_;
    float tolerance_ = 0.0f;  // world units: a blocker this close outside a pyramid plane misses
};

}  // namespace ag::cpu
