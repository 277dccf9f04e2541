// Records indexed by space for interpolation one point at a time, as Radiance does on the CPU
// (Ward, Rubinstein & Clear 1988 §3; Radiance's ambient octree): a loose octree in which a record
// sits in the deepest node that holds its position and whose half-size is at least the radius of
// its zone of influence a·R_k, so a lookup visits only the nodes whose box grown by their own
// half-size holds the point. The CPU counterpart of the GPU splat (Table 4.2's baseline).
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "shared/irradiance_record.h"

namespace ag {

class IrradianceOctree {
public:
    // Records with positions inside the cube of `centre` ± `half_size` (others go to the root);
    // zones of radius accuracy·R_k.
    IrradianceOctree(const glm::vec3& centre, float half_size, float accuracy);
    ~IrradianceOctree();
    IrradianceOctree(IrradianceOctree&&) noexcept;
    IrradianceOctree& operator=(IrradianceOctree&&) noexcept;

    void insert(const IrradianceRecord& record);
    size_t size() const { return records_.size(); }
    const std::vector<IrradianceRecord>& records() const { return records_; }

    // Σ w·E_k(p)/π (rgb) and Σ w (a) over the records with w ≥ 1/a at (p, n) and `frame`: the
    // same sum as splat_records() for one pixel.
    glm::vec4 lookup(const glm::vec3& p, const glm::vec3& n, int frame = 0) const;

private:
    struct Node;
    std::unique_ptr<Node> root_;
    std::vector<IrradianceRecord> records_;
    float accuracy_;
};

}  // namespace ag
