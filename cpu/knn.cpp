#include "cpu/knn.h"

#include <flann/flann.hpp>

namespace ag::cpu {

struct KnnIndex::Impl {
    using Index = flann::KDTreeSingleIndex<flann::L2_Simple<float>>;
    std::unique_ptr<Index> index;
};

KnnIndex::KnnIndex() : impl_(std::make_unique<Impl>()) {}
KnnIndex::~KnnIndex() = default;
KnnIndex::KnnIndex(KnnIndex&&) noexcept = default;
KnnIndex& KnnIndex::operator=(KnnIndex&&) noexcept = default;

void KnnIndex::build(const std::vector<glm::vec3>& points) {
    points_.resize(points.size() * 3);
    for (size_t i = 0; i < points.size(); ++i)
        points_[3 * i] = points[i].x, points_[3 * i + 1] = points[i].y,
                    points_[3 * i + 2] = points[i].z;
    impl_->index.reset();
    if (points.empty()) return;
    const flann::Matrix<float> data(points_.data(), points.size(), 3);
    // Leaf size 10: the exact single kd-tree is fastest for the 10^2–10^5 hits of one surface.
    impl_->index = std::make_unique<Impl::Index>(data, flann::KDTreeSingleIndexParams(10));
    impl_->index->buildIndex();
}

int KnnIndex::query(const glm::vec3& p, int k, std::vector<int>& indices,
                    std::vector<float>& dist2) const {
    const int n = std::min<int>(k, int(points_.size() / 3));
    indices.resize(size_t(std::max(n, 0)));
    dist2.resize(size_t(std::max(n, 0)));
    if (n <= 0) return 0;
    float q[3] = {p.x, p.y, p.z};
    flann::Matrix<float> query(q, 1, 3);
    flann::Matrix<int> out_indices(indices.data(), 1, size_t(n));
    flann::Matrix<float> out_dist(dist2.data(), 1, size_t(n));
    flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED);
    params.sorted = true;
    impl_->index->knnSearch(query, out_indices, out_dist, size_t(n), params);
    return n;
}

}  // namespace ag::cpu
