// Irradiance cache records and their interpolation (Gautron 2006 ch. 2.3 and 4.3, after Ward,
// Rubinstein & Clear 1988 and Ward & Heckbert 1992): Ward's weight, the zone of influence a·R_k,
// first-order extrapolation by rotation and translation gradients, and the splat of a record set
// into per-pixel sums (Σ w E, Σ w), the CPU twin of gpu::RadianceCacheSplat.
#pragma once

#include <functional>
#include <glm/glm.hpp>
#include <limits>
#include <vector>

namespace ag {

// One record k = {p_k, n_k, E_k, R_k, ∇_r, ∇_t} (Gautron's 22 floats, plus its life in time).
struct IrradianceRecord {
    glm::vec3 position{0.0f};  // p_k, world space
    glm::vec3 normal{0.0f, 0.0f, 1.0f};
    glm::vec3 iim{0.0f};  // E_k / π (the IIM convention: a diffuse surface reflects ρ·iim)
    float harmonic_distance = 1.0f;  // R_k: harmonic mean distance to what the hemisphere sees
    // Column c is the gradient of channel c of iim: rotation (Ward & Heckbert 1992, eq. 8) and
    // translation (Křivánek et al. 2005, the cosine-weighted form of Ward & Heckbert eq. 11).
    glm::mat3 rotation_gradient{0.0f};
    glm::mat3 translation_gradient{0.0f};
    // Temporal caching (Gautron ch. 5): frame made, last frame of life (inclusive), and the
    // temporal gradient of iim (extrapolated, eq. 5.12, or interpolated, eq. 5.15) per frame.
    int born = 0;
    int expires = std::numeric_limits<int>::max();
    glm::vec3 temporal_gradient{0.0f};
};

// Ward's weight w_k(p, n) = 1 / (|p − p_k| / R_k + √(1 − n·n_k)) (Gautron eq. 2.5); 0 for points
// in front of the record's tangent plane (Ward 1988: the record would see behind itself) and
// capped at kMaxWardWeight at the record itself.
inline constexpr float kMaxWardWeight = 1e6f;
float ward_weight(const IrradianceRecord& r, const glm::vec3& p, const glm::vec3& n);

// E_k(p, n) / π by the gradients (additive form, Gautron eq. 5.9 / 5.11) at frame `frame`:
// iim + (n_k × n)·∇_r + (p − p_k)·∇_t + ∇_t E · (frame − born).
glm::vec3 extrapolate(const IrradianceRecord& r, const glm::vec3& p, const glm::vec3& n,
                      int frame = 0);

// A pixel of the splat's G-buffer: world position and unit normal; `covered` false for pixels
// that need no indirect term (background, mirrors, glass).
struct SplatPixel {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};
    bool covered = false;
};

// Per pixel Σ w·E_k(p)/π (rgb) and Σ w (a) over the records with w ≥ 1/a (Gautron Algorithm 3).
struct SplatSums {
    std::vector<glm::vec4> sums;
};

// Adds `records` into `sums` (sized like `pixels`), accuracy a, at `frame`.
void splat_records(const std::vector<IrradianceRecord>& records,
                   const std::vector<SplatPixel>& pixels, float accuracy, int frame,
                   std::vector<glm::vec4>& sums);

// Σ w E / Σ w per pixel; zero where nothing covers it.
std::vector<glm::vec3> normalise_splat(const std::vector<glm::vec4>& sums);

// Gautron eq. 2.9: a covered pixel needs a new record where Σ w < a.
inline bool needs_record(const glm::vec4& sum, float accuracy) { return sum.a < accuracy; }

// Gautron Algorithm 4, step 4 (the thesis's CPU scan): pixels in order; where a covered pixel's
// Σ w < a, `make` computes a record at it, which is appended to `records` and splatted into `sums`
// at once, so later pixels see it. One pass leaves every covered pixel with Σ w ≥ a. Returns the
// number of records added; stops after `max_new` (the rest waits for the next frame).
using MakeRecord = std::function<IrradianceRecord(const SplatPixel& pixel, size_t index)>;
int add_records_by_scan(std::vector<IrradianceRecord>& records,
                        const std::vector<SplatPixel>& pixels, float accuracy, int frame,
                        std::vector<glm::vec4>& sums, const MakeRecord& make,
                        int max_new = std::numeric_limits<int>::max());

}  // namespace ag
