#include "gpu/media_uniforms.h"

#include <algorithm>
#include <string>

#include "gpu/media_glsl.h"

namespace ag::gpu {

void set_media_uniforms(const Program& program, const Scene& scene) {
    const size_t media = std::min(scene.media.size(), size_t(kMaxMediaBoxes));
    program.set("media_count", int(media));
    for (size_t m = 0; m < media; ++m) {
        const std::string k = "[" + std::to_string(m) + "]";
        program.set(("media_min" + k).c_str(), scene.media[m].bounds.min);
        program.set(("media_max" + k).c_str(), scene.media[m].bounds.max);
        program.set(("media_sigma_t" + k).c_str(), scene.media[m].sigma_t());
    }
}

}  // namespace ag::gpu
