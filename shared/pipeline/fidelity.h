// The per-stage error budget of the indirect term (issue #12, docs/fidelity.md): at the texel
// centres, (a) the AIM against path-traced outgoing radiance, (b) each gather of the AIMs against a
// full-hemisphere ray gather of the same AIMs (Gautron 2006, Table 4.1: plane without correction,
// renormalised, stretched), (c) that against path-traced irradiance; and on the image, (d) the IIM
// as the camera sees it (interpolation, dilation, repair) against per-pixel gathering.
#pragma once

#include <glm/glm.hpp>
#include <map>
#include <string>
#include <vector>

#include "shared/image.h"
#include "shared/parallel.h"
#include "shared/scene.h"

namespace ag {

struct FidelityOptions {
    int pt_paths = 4096;        // path-traced irradiance: paths per texel centre
    int reference_rays = 4096;  // rays of the full-hemisphere gather the plane gathers are held to
    int pixel_rays = 1024;      // rays of the per-pixel gather of stage (d)
    // Path-traced paths at every pixel centre (0 = none): an estimator independent of the pt
    // image (stratified directions, no pixel footprint, no light tracing), so stage (e) can hold
    // the per-pixel gather to it and the pt image to it at the same points.
    int pt_pixels = 0;
    int width = 96, height = 96;
    // Stage (b)'s hemi-plane variants (GL and CPU, each border correction, and the CPU gather at
    // the scene's ray count): the slowest part on a fine layout (a GL hemi-plane per texel and
    // variant). false leaves them out; the pipeline's own gather and stages (a), (c)–(e) stay.
    bool gather_variants = true;
    bool gl = true;  // GL stages (hemi-plane gathers, the frame); needs a current context
    // Optional: the indirect term of a pt reference at width × height (afterglow reference
    // --method pt); stage (e) holds the frame's and the per-pixel gather's indirect term to it.
    Image reference_indirect;
};

// One comparison: `test` against `reference` over `count` texels (or pixels) of `region`.
struct FidelityRow {
    std::string stage, test, reference, region;
    int count = 0;
    double mean_ratio = 0.0;  // Σ area·lum(test) / Σ area·lum(reference) (pixels: area 1)
    double rms = 0.0;         // RMS relative error of the luminance, √mean(((t − r) / r)²)
    double rel_mse = 0.0;     // image stages: relMSE (shared/metrics.h); texel stages: 0
    glm::dvec3 test_mean{0.0}, reference_mean{0.0};  // image stages: mean colour (tint)
};

struct FidelityReport {
    std::vector<FidelityRow> rows;
    // Per texel record: every quantity by name (E/π for irradiance, radiance for the AIM).
    std::map<std::string, std::vector<glm::vec3>> texel_values;
    std::vector<char> texel_valid;  // the texel's centre sees few back faces
    int routed = 0;  // texels the pipeline's GL gather handed to the rays (they see specular)
    Image frame_indirect, pixel_indirect, mask;  // stage (d): what the camera sees, per pixel
    Image pt_pixels;  // with FidelityOptions::pt_pixels: ρ/π E_indirect at each pixel centre
};

// Photons traced to completion and every AIM rebuilt first; the scene's settings otherwise.
FidelityReport measure_fidelity(Scene& scene, const FidelityOptions& options, ThreadPool& pool);

// The report as a table (text) and as CSV: rows, then per-texel values.
std::string fidelity_table(const FidelityReport& report);
std::string fidelity_csv(const Scene& scene, const FidelityReport& report);

}  // namespace ag
