// Exact k-nearest-neighbour queries over 3D points (photon hits of one surface, Larsen ch. 10).
// FLANN's single kd-tree behind a small interface: all FLANN use lives in knn.cpp.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <vector>

namespace ag::cpu {

class KnnIndex {
public:
    KnnIndex();
    ~KnnIndex();
    KnnIndex(KnnIndex&&) noexcept;
    KnnIndex& operator=(KnnIndex&&) noexcept;

    // Copies the points and builds the tree. An empty set is allowed (queries find nothing).
    void build(const std::vector<glm::vec3>& points);
    size_t size() const { return points_.size(); }

    // The min(k, size) nearest points to `p`, nearest first: indices into the built points and
    // squared distances. Returns how many were found. Thread-safe after build().
    int query(const glm::vec3& p, int k, std::vector<int>& indices,
              std::vector<float>& dist2) const;

private:
    struct Impl;
    std::vector<float> points_;  // xyz, owned: FLANN keeps a pointer into it
    std::unique_ptr<Impl> impl_;
};

}  // namespace ag::cpu
