#include "cpu/vpl_visibility.h"

#include <algorithm>

namespace ag::cpu {

namespace {

// Segment a → b against triangle t (Möller–Trumbore), strictly inside the segment.
bool segment_hits(const glm::vec3& a, const glm::vec3& b, const std::array<glm::vec3, 3>& t) {
    const glm::vec3 d = b - a, e1 = t[1] - t[0], e2 = t[2] - t[0];
    const glm::vec3 p = glm::cross(d, e2);
    const float det = glm::dot(e1, p);
    if (std::abs(det) < 1e-12f) return false;
    const float inv = 1.0f / det;
    const glm::vec3 s = a - t[0];
    const float u = glm::dot(s, p) * inv;
    if (u < 0.0f || u > 1.0f) return false;
    const glm::vec3 q = glm::cross(s, e1);
    const float v = glm::dot(d, q) * inv;
    if (v < 0.0f || u + v > 1.0f) return false;
    const float t_hit = glm::dot(e2, q) * inv;
    return t_hit > 1e-4f && t_hit < 1.0f - 1e-4f;
}

// The occlusion pyramid of a triangular patch seen from light position l: three side planes
// through l and an edge, and the patch's plane, all with normals pointing inside.
struct Pyramid {
    std::array<glm::vec4, 4> planes;
    Pyramid(const glm::vec3& l, const std::array<glm::vec3, 3>& v) {
        for (int i = 0; i < 3; ++i) {
            const glm::vec3& a = v[size_t(i)];
            const glm::vec3& b = v[size_t((i + 1) % 3)];
            const glm::vec3& c = v[size_t((i + 2) % 3)];
            glm::vec3 n = glm::cross(a - l, b - l);
            if (glm::dot(n, c - l) < 0.0f) n = -n;
            planes[size_t(i)] = glm::vec4(n, -glm::dot(n, l));
        }
        glm::vec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
        if (glm::dot(n, l - v[0]) < 0.0f) n = -n;
        planes[3] = glm::vec4(n, -glm::dot(n, v[0]));
        for (glm::vec4& p : planes) p /= std::max(1e-30f, glm::length(glm::vec3(p)));
    }
    float distance(int i, const glm::vec3& x) const {
        return glm::dot(glm::vec3(planes[size_t(i)]), x) + planes[size_t(i)].w;
    }
};

}  // namespace

VisibilityDatabase::VisibilityDatabase(const Scene& scene, const std::vector<Vpl>& lights,
                                       int depth, int polygon_blocker_limit)
    : scene_(scene), lights_(lights), depth_(depth), polygon_limit_(polygon_blocker_limit) {
    Bounds b;
    for (const Object& o : scene.objects)
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    tolerance_ = 1e-5f * glm::length(b.extent());
    shapes_.resize(scene.objects.size());
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        make_shape(int(o));
        add_nodes(int(o));
    }
    pairs_.resize(nodes_.size() * lights_.size());
    std::vector<int> all(scene.objects.size());
    for (size_t o = 0; o < all.size(); ++o) all[o] = int(o);
    for (int root : roots_)
        for (int l = 0; l < light_count(); ++l) classify_tree(root, l, all, {});
}

void VisibilityDatabase::make_shape(int object) {
    const Object& o = scene_.objects[size_t(object)];
    BlockerShape& s = shapes_[size_t(object)];
    s = BlockerShape{};
    s.sphere = int(o.mesh.triangles.size()) > polygon_limit_;
    Bounds b;
    for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    s.centre = b.center();
    for (const glm::vec3& p : o.mesh.positions)
        s.radius = std::max(s.radius, glm::length(o.transform.apply_point(p) - s.centre));
    if (s.sphere) return;
    for (const glm::uvec3& t : o.mesh.triangles)
        s.triangles.push_back({o.transform.apply_point(o.mesh.positions[t.x]),
                               o.transform.apply_point(o.mesh.positions[t.y]),
                               o.transform.apply_point(o.mesh.positions[t.z])});
}

void VisibilityDatabase::add_nodes(int object) {
    const Object& o = scene_.objects[size_t(object)];
    root_of_.resize(scene_.objects.size());
    if (o.material.type != MaterialType::diffuse) return;  // only diffuse patches are shaded
    for (const glm::uvec3& t : o.mesh.triangles) {
        roots_.push_back(add_node(
            {o.mesh.positions[t.x], o.mesh.positions[t.y], o.mesh.positions[t.z]}, object, -1, 0));
        root_of_[size_t(object)].push_back(roots_.back());
    }
}

int VisibilityDatabase::add_node(const std::array<glm::vec3, 3>& local, int object, int parent,
                                 int depth) {
    nodes_.emplace_back();
    const int index = int(nodes_.size()) - 1;
    fill(index, local, object, parent, depth);
    return index;
}

void VisibilityDatabase::fill(int slot, const std::array<glm::vec3, 3>& local, int object,
                              int parent, int depth) {
    const Transform& tr = scene_.objects[size_t(object)].transform;
    Node& n = nodes_[size_t(slot)];
    n.local = local;
    n.object = object;
    n.parent = parent;
    for (int i = 0; i < 3; ++i) n.v[size_t(i)] = tr.apply_point(local[size_t(i)]);
    if (depth >= depth_) return;
    // Midpoint subdivision; the four children take consecutive slots.
    const glm::vec3 m01 = 0.5f * (local[0] + local[1]), m12 = 0.5f * (local[1] + local[2]),
                    m20 = 0.5f * (local[2] + local[0]);
    const std::array<std::array<glm::vec3, 3>, 4> kids = {
        {{local[0], m01, m20}, {m01, local[1], m12}, {m20, m12, local[2]}, {m01, m12, m20}}};
    const int first = int(nodes_.size());
    nodes_[size_t(slot)].first_child = first;
    nodes_.resize(nodes_.size() + 4);
    for (int c = 0; c < 4; ++c) fill(first + c, kids[size_t(c)], object, slot, depth + 1);
}

bool VisibilityDatabase::behind(int node, int light) const {
    const Node& n = nodes_[size_t(node)];
    const Vpl& l = lights_[size_t(light)];
    const glm::vec3 normal = glm::cross(n.v[1] - n.v[0], n.v[2] - n.v[0]);
    // The light is behind the patch's front, or every corner behind the light's hemisphere.
    bool all_behind = true;
    for (const glm::vec3& v : n.v)
        all_behind = all_behind && glm::dot(v - l.position, l.normal) <= 0.0f;
    return glm::dot(l.position - n.v[0], normal) <= 0.0f || all_behind;
}

Occlusion VisibilityDatabase::classify(int node, int light, int object) const {
    const Node& n = nodes_[size_t(node)];
    if (object == n.object) return Occlusion::none;
    ++work_.blocker_tests;
    const Pyramid pyr(lights_[size_t(light)].position, n.v);
    const BlockerShape& s = shapes_[size_t(object)];
    // Touching the pyramid (a wall meeting the patch along an edge) blocks no ray inside it.
    const float tol = tolerance_;
    for (int i = 0; i < 4; ++i)
        if (pyr.distance(i, s.centre) <= tol - s.radius) return Occlusion::none;
    if (s.sphere) return Occlusion::partial;  // a bounding sphere never proves full occlusion
    bool any = false;
    const glm::vec3& l = lights_[size_t(light)].position;
    for (const auto& t : s.triangles) {
        bool outside = false;
        for (int i = 0; i < 4 && !outside; ++i)
            outside = pyr.distance(i, t[0]) <= tol && pyr.distance(i, t[1]) <= tol &&
                      pyr.distance(i, t[2]) <= tol;
        if (outside) continue;
        any = true;
        // One convex polygon holding all three edges of the pyramid holds its whole section.
        if (segment_hits(l, n.v[0], t) && segment_hits(l, n.v[1], t) && segment_hits(l, n.v[2], t))
            return Occlusion::full;
    }
    return any ? Occlusion::partial : Occlusion::none;
}

void VisibilityDatabase::set_flag(Pair& p, int object, Occlusion o) {
    auto it = std::find_if(p.blockers.begin(), p.blockers.end(),
                           [&](const Flag& f) { return f.object == object; });
    if (o == Occlusion::none) {
        if (it != p.blockers.end()) p.blockers.erase(it);
    } else if (it != p.blockers.end()) {
        it->occlusion = o;
    } else {
        p.blockers.push_back({object, o});
    }
}

Occlusion VisibilityDatabase::state_of(const Pair& p) {
    if (p.state == Occlusion::behind) return Occlusion::behind;
    Occlusion s = Occlusion::none;
    for (const Flag& f : p.blockers) {
        if (f.occlusion == Occlusion::full) return Occlusion::full;
        s = Occlusion::partial;
    }
    return s;
}

void VisibilityDatabase::classify_tree(int node, int light, const std::vector<int>& candidates,
                                       const std::vector<int>& full) {
    Pair& p = pair(node, light);
    p.blockers.clear();
    const Node& n = nodes_[size_t(node)];
    if (behind(node, light)) {
        // Everything below is behind too (same plane; corners inside the parent's).
        p.state = Occlusion::behind;
        if (n.first_child >= 0)
            for (int c = 0; c < 4; ++c) classify_tree(n.first_child + c, light, {}, {});
        return;
    }
    // A blocker full for the parent is full here (the pyramid is inside the parent's); children
    // re-test only the blockers partial for the parent.
    std::vector<int> partial, full_here = full;
    for (int o : full) p.blockers.push_back({o, Occlusion::full});
    for (int o : candidates) {
        const Occlusion c = classify(node, light, o);
        if (c != Occlusion::none) p.blockers.push_back({o, c});
        if (c == Occlusion::partial) partial.push_back(o);
        if (c == Occlusion::full) full_here.push_back(o);
    }
    p.state = Occlusion::none;
    p.state = state_of(p);
    if (n.first_child >= 0)
        for (int c = 0; c < 4; ++c) classify_tree(n.first_child + c, light, partial, full_here);
}

void VisibilityDatabase::propagate(int node, int light, int object, Occlusion o) {
    Pair& p = pair(node, light);
    if (p.state == Occlusion::behind) return;
    set_flag(p, object, o);
    p.state = state_of(p);
    const Node& n = nodes_[size_t(node)];
    if (n.first_child >= 0)
        for (int c = 0; c < 4; ++c) propagate(n.first_child + c, light, object, o);
}

void VisibilityDatabase::update(int node, int light, int object) {
    Pair& p = pair(node, light);
    if (p.state == Occlusion::behind) return;
    Occlusion old = Occlusion::none;
    for (const Flag& f : p.blockers)
        if (f.object == object) old = f.occlusion;
    const Occlusion now = classify(node, light, object);
    if (now == Occlusion::partial) {
        // Table 4-1, column Partial: recursive update (re-test the children).
        ++work_.recursive;
        set_flag(p, object, now);
        p.state = state_of(p);
        const Node& n = nodes_[size_t(node)];
        if (n.first_child >= 0)
            for (int c = 0; c < 4; ++c) update(n.first_child + c, light, object);
    } else if (now == old) {
        ++work_.unchanged;  // Full → Full, None → None: no change
    } else {
        ++work_.propagated;  // change state, propagate to children without tests
        propagate(node, light, object, now);
    }
}

void VisibilityDatabase::object_moved(int object) {
    make_shape(object);
    // The mover's own patches: new geometry, classified again against everything.
    std::vector<int> all(scene_.objects.size());
    for (size_t o = 0; o < all.size(); ++o) all[o] = int(o);
    const Transform& tr = scene_.objects[size_t(object)].transform;
    for (Node& n : nodes_)
        if (n.object == object)
            for (int i = 0; i < 3; ++i) n.v[size_t(i)] = tr.apply_point(n.local[size_t(i)]);
    for (int root : roots_) {
        const bool own = nodes_[size_t(root)].object == object;
        for (int l = 0; l < light_count(); ++l) {
            if (own)
                classify_tree(root, l, all, {});
            else
                update(root, l, object);
        }
    }
}

int VisibilityDatabase::leaf_at(int object, int triangle, glm::vec2 uv) const {
    if (object < 0 || size_t(object) >= root_of_.size() || root_of_[size_t(object)].empty())
        return -1;
    int node = root_of_[size_t(object)][size_t(triangle)];
    // Barycentrics (b0, b1, b2) = (1 − u − v, u, v); fill()'s children are the corner
    // triangles at v0, v1, v2 and the middle one.
    float b1 = uv.x, b2 = uv.y;
    while (nodes_[size_t(node)].first_child >= 0) {
        const float b0 = 1.0f - b1 - b2;
        const int first = nodes_[size_t(node)].first_child;
        if (b0 >= 0.5f) {
            node = first, b1 = 2.0f * b1, b2 = 2.0f * b2;
        } else if (b1 >= 0.5f) {  // (m01, v1, m12): c1 = 1 − 2 b0 − 2 b2, c2 = 2 b2
            node = first + 1, b1 = 1.0f - 2.0f * b0 - 2.0f * b2, b2 = 2.0f * b2;
        } else if (b2 >= 0.5f) {  // (m20, m12, v2): c1 = 2 b1, c2 = 1 − 2 b0 − 2 b1
            node = first + 2, b2 = 1.0f - 2.0f * b0 - 2.0f * b1, b1 = 2.0f * b1;
        } else {  // (m01, m12, m20): c1 = 1 − 2 b0, c2 = 1 − 2 b1
            node = first + 3;
            const float c1 = 1.0f - 2.0f * b0, c2 = 1.0f - 2.0f * b1;
            b1 = c1, b2 = c2;
        }
    }
    return node;
}

VisibilityCounters VisibilityDatabase::counters() const {
    VisibilityCounters c = work_;
    c.none = c.partial = c.full = c.behind = 0;
    for (size_t n = 0; n < nodes_.size(); ++n) {
        if (nodes_[n].first_child >= 0) continue;
        for (int l = 0; l < light_count(); ++l) switch (state(int(n), l)) {
                case Occlusion::none:
                    ++c.none;
                    break;
                case Occlusion::partial:
                    ++c.partial;
                    break;
                case Occlusion::full:
                    ++c.full;
                    break;
                case Occlusion::behind:
                    ++c.behind;
                    break;
            }
    }
    return c;
}

}  // namespace ag::cpu
