#include "shared/irradiance_octree.h"

#include <array>

namespace ag {

struct IrradianceOctree::Node {
    glm::vec3 centre{0.0f};
    float half = 1.0f;
    std::vector<uint32_t> records;  // indices into records_
    std::array<std::unique_ptr<Node>, 8> children;
};

namespace {
constexpr int kMaxDepth = 24;

int child_of(const glm::vec3& centre, const glm::vec3& p) {
    return (p.x >= centre.x ? 1 : 0) | (p.y >= centre.y ? 2 : 0) | (p.z >= centre.z ? 4 : 0);
}
}  // namespace

IrradianceOctree::IrradianceOctree(const glm::vec3& centre, float half_size, float accuracy)
    : root_(std::make_unique<Node>()), accuracy_(accuracy) {
    root_->centre = centre;
    root_->half = half_size;
}
IrradianceOctree::~IrradianceOctree() = default;
IrradianceOctree::IrradianceOctree(IrradianceOctree&&) noexcept = default;
IrradianceOctree& IrradianceOctree::operator=(IrradianceOctree&&) noexcept = default;

void IrradianceOctree::insert(const IrradianceRecord& record) {
    const uint32_t index = uint32_t(records_.size());
    records_.push_back(record);
    const float radius = accuracy_ * record.harmonic_distance;
    const glm::vec3& p = record.position;
    Node* node = root_.get();
    // A record outside the root cube stays at the root, which every lookup visits.
    const glm::vec3 off = glm::abs(p - node->centre);
    const bool inside = off.x <= node->half && off.y <= node->half && off.z <= node->half;
    for (int depth = 0; inside && depth < kMaxDepth && radius <= 0.5f * node->half; ++depth) {
        const int c = child_of(node->centre, p);
        std::unique_ptr<Node>& child = node->children[size_t(c)];
        if (!child) {
            child = std::make_unique<Node>();
            child->half = 0.5f * node->half;
            child->centre = node->centre + child->half * glm::vec3((c & 1) ? 1.0f : -1.0f,
                                                                   (c & 2) ? 1.0f : -1.0f,
                                                                   (c & 4) ? 1.0f : -1.0f);
        }
        node = child.get();
    }
    node->records.push_back(index);
}

glm::vec4 IrradianceOctree::lookup(const glm::vec3& p, const glm::vec3& n, int frame) const {
    glm::vec4 sum(0.0f);
    const float cutoff = 1.0f / accuracy_;
    // Every record in a node lies in its cube and reaches at most its half-size beyond it
    // (the root's also hold records from anywhere: always visited).
    std::vector<const Node*> stack{root_.get()};
    bool root = true;
    while (!stack.empty()) {
        const Node* node = stack.back();
        stack.pop_back();
        if (!root) {
            const glm::vec3 off = glm::abs(p - node->centre);
            const float reach = 2.0f * node->half;
            if (off.x > reach || off.y > reach || off.z > reach) continue;
        }
        root = false;
        for (uint32_t k : node->records) {
            const IrradianceRecord& r = records_[k];
            const float w = ward_weight(r, p, n);
            if (w < cutoff) continue;
            sum += glm::vec4(w * extrapolate(r, p, n, frame), w);
        }
        for (const std::unique_ptr<Node>& c : node->children)
            if (c) stack.push_back(c.get());
    }
    return sum;
}

}  // namespace ag
