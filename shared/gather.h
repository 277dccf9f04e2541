// Final gathering behind one interface (Larsen ch. 11): gpu::HemiPlaneGather renders hemi-planes,
// cpu::CpuGather casts rays. Both read the AIMs they are bound to and return, per texel record,
// E_indirect/π and the share of the view that showed back faces. What a result means for the IIM
// (valid or not, repaired from neighbours, blended in) is decided once, by cpu::Iim.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "shared/settings.h"

namespace ag {

struct GatherResult {
    glm::vec3 iim{0.0f};         // E_indirect / π: a diffuse surface reflects albedo × iim
    float back_fraction = 0.0f;  // weighted share of the view that shows back faces
};

class Gatherer {
public:
    virtual ~Gatherer() = default;
    virtual GatherBackend backend() const = 0;
    // Gathers the texel records `texels` (indices into scene.atlas.texels) from the current scene
    // and the AIMs as they are now; results in the same order. Deterministic for any thread count.
    virtual std::vector<GatherResult> gather(const std::vector<int>& texels) = 0;
};

}  // namespace ag
