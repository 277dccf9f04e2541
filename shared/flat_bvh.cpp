#include "shared/flat_bvh.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace ag {

namespace {

struct Prim {
    Bounds bounds;
    glm::vec3 centre{0.0f};
};

float area(const Bounds& b) {
    if (b.empty()) return 0.0f;
    const glm::vec3 e = b.extent();
    return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
}

Bounds merged(Bounds a, const Bounds& b) {
    if (b.empty()) return a;
    a.add(b.min);
    a.add(b.max);
    return a;
}

struct Builder {
    std::vector<Prim>& prims;
    std::vector<uint32_t>& order;
    std::vector<BvhNode>& nodes;
    int depth = 0;

    // Builds the node for order[begin, end) at nodes.size(); returns its index.
    uint32_t build(uint32_t begin, uint32_t end, int level) {
        depth = std::max(depth, level + 1);
        const uint32_t index = uint32_t(nodes.size());
        nodes.emplace_back();
        Bounds bounds, centres;
        for (uint32_t i = begin; i < end; ++i) {
            bounds = merged(bounds, prims[order[i]].bounds);
            centres.add(prims[order[i]].centre);
        }
        nodes[index].lo = bounds.min;
        nodes[index].hi = bounds.max;
        const uint32_t n = end - begin;
        const auto leaf = [&] {
            nodes[index].link = begin;
            nodes[index].count = n;
            return index;
        };
        if (n <= uint32_t(kBvhMaxLeaf) || level + 1 >= kBvhMaxDepth) return leaf();
        // Binned SAH over the centroids' largest axis (12 bins).
        const glm::vec3 ext = centres.extent();
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        uint32_t mid = begin;
        if (ext[axis] > 0.0f) {
            constexpr int kBins = 12;
            std::array<Bounds, kBins> bin_bounds;
            std::array<uint32_t, kBins> bin_count{};
            const float scale = float(kBins) / ext[axis];
            const auto bin_of = [&](uint32_t p) {
                return std::min(kBins - 1,
                                int((prims[p].centre[axis] - centres.min[axis]) * scale));
            };
            for (uint32_t i = begin; i < end; ++i) {
                const int b = bin_of(order[i]);
                bin_bounds[size_t(b)] = merged(bin_bounds[size_t(b)], prims[order[i]].bounds);
                ++bin_count[size_t(b)];
            }
            std::array<float, kBins - 1> cost{};
            Bounds left;
            uint32_t left_n = 0;
            for (int s = 0; s < kBins - 1; ++s) {
                left = merged(left, bin_bounds[size_t(s)]);
                left_n += bin_count[size_t(s)];
                cost[size_t(s)] = area(left) * float(left_n);
            }
            Bounds right;
            uint32_t right_n = 0;
            for (int s = kBins - 1; s > 0; --s) {
                right = merged(right, bin_bounds[size_t(s)]);
                right_n += bin_count[size_t(s)];
                cost[size_t(s - 1)] += area(right) * float(right_n);
            }
            const int best = int(std::min_element(cost.begin(), cost.end()) - cost.begin());
            mid = uint32_t(std::partition(order.begin() + begin, order.begin() + end,
                                          [&](uint32_t p) { return bin_of(p) <= best; }) -
                           order.begin());
        }
        if (mid == begin || mid == end) {  // equal centroids or a degenerate split: halve
            mid = begin + n / 2;
            std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                             [&](uint32_t a, uint32_t b) {
                                 return prims[a].centre[axis] < prims[b].centre[axis];
                             });
        }
        build(begin, mid, level + 1);
        const uint32_t second = build(mid, end, level + 1);
        nodes[index].link = second;
        nodes[index].count = kBvhInterior | uint32_t(axis);
        return index;
    }
};

}  // namespace

FlatBvh build_flat_bvh(const Scene& scene) {
    FlatBvh bvh;
    std::vector<BvhTriangle> all;
    std::vector<Prim> prims;
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        const Object& obj = scene.objects[o];
        const glm::mat4 m = obj.transform.matrix();
        for (size_t t = 0; t < obj.mesh.triangles.size(); ++t) {
            const glm::uvec3 tri = obj.mesh.triangles[t];
            std::array<glm::vec3, 3> v;
            Prim p;
            for (int k = 0; k < 3; ++k) {
                v[size_t(k)] = glm::vec3(m * glm::vec4(obj.mesh.positions[tri[k]], 1.0f));
                p.bounds.add(v[size_t(k)]);
            }
            p.centre = p.bounds.center();
            prims.push_back(p);
            BvhTriangle b;
            b.v0 = v[0];
            b.e1 = v[1] - v[0];
            b.e2 = v[2] - v[0];
            b.object = uint32_t(o);
            b.triangle = uint32_t(t);
            all.push_back(b);
        }
    }
    if (all.empty()) return bvh;
    std::vector<uint32_t> order(all.size());
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    bvh.nodes.reserve(2 * all.size() / kBvhMaxLeaf + 1);
    Builder builder{prims, order, bvh.nodes};
    builder.build(0, uint32_t(order.size()), 0);
    bvh.depth = builder.depth;
    bvh.triangles.reserve(all.size());
    for (const uint32_t i : order) bvh.triangles.push_back(all[i]);
    return bvh;
}

BvhHit intersect(const FlatBvh& bvh, const glm::vec3& origin, const glm::vec3& direction,
                 float tmin, float tmax) {
    BvhHit hit;
    if (bvh.nodes.empty()) return hit;
    glm::vec3 inv;
    for (int k = 0; k < 3; ++k)
        inv[k] = std::abs(direction[k]) > 1e-30f ? 1.0f / direction[k]
                                                 : std::copysign(1e30f, direction[k]);
    std::array<uint32_t, kBvhMaxDepth> stack{};
    int sp = 0;
    uint32_t node = 0;
    float best = tmax;
    while (true) {
        const BvhNode& n = bvh.nodes[node];
        const glm::vec3 t0 = (n.lo - origin) * inv, t1 = (n.hi - origin) * inv;
        const glm::vec3 near = glm::min(t0, t1), far = glm::max(t0, t1);
        const float a = std::max(std::max(near.x, near.y), std::max(near.z, tmin));
        const float b = std::min(std::min(far.x, far.y), std::min(far.z, best));
        if (a <= b) {
            if (n.count & kBvhInterior) {
                const bool back_first = direction[int(n.count & 3u)] < 0.0f;
                stack[size_t(sp++)] = back_first ? node + 1 : n.link;
                node = back_first ? n.link : node + 1;
                continue;
            }
            for (uint32_t i = n.link; i < n.link + n.count; ++i) {
                const BvhTriangle& tri = bvh.triangles[i];
                const glm::vec3 p = glm::cross(direction, tri.e2);
                const float det = glm::dot(tri.e1, p);
                if (det == 0.0f) continue;
                const float inv_det = 1.0f / det;
                const glm::vec3 s = origin - tri.v0;
                const float u = glm::dot(s, p) * inv_det;
                if (u < 0.0f || u > 1.0f) continue;
                const glm::vec3 q = glm::cross(s, tri.e1);
                const float v = glm::dot(direction, q) * inv_det;
                if (v < 0.0f || u + v > 1.0f) continue;
                const float t = glm::dot(tri.e2, q) * inv_det;
                if (t > tmin && t < best) {
                    best = t;
                    hit = {true, t, tri.object, tri.triangle};
                }
            }
        }
        if (sp == 0) break;
        node = stack[size_t(--sp)];
    }
    return hit;
}

}  // namespace ag
