// The irradiance cache the way Radiance computes it on the CPU (Ward, Rubinstein & Clear 1988;
// Ward 1994), the baseline of Gautron 2006's Table 4.2: one eye ray per pixel, pixels in scanline
// order, each looked up in an octree of records (ag::IrradianceOctree); where the records' weight
// leaves it uncovered (Σ w < a) a new record is gathered there at once by ray casting and later
// pixels see it (lazy evaluation). No GPU anywhere: what our splatting replaces.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "cpu/irradiance_gather.h"
#include "cpu/ray_tracer.h"
#include "shared/irradiance_octree.h"
#include "shared/scene.h"

namespace ag::cpu {

struct CpuCacheFrame {
    int width = 0, height = 0;
    std::vector<SplatPixel> pixels;  // the eye rays' hits, rows top-down (index y·width + x)
    std::vector<glm::vec3> term;     // Σ w E / Σ w (E/π), 0 where not covered
    std::vector<IrradianceRecord> records;
    double eye_ms = 0.0;     // eye rays
    double record_ms = 0.0;  // gathering the records
    double lookup_ms = 0.0;  // octree lookups and interpolation (and inserts)
};

// The eye rays of scene.camera at width × height: diffuse surfaces covered, normal facing the
// eye; mirrors, glass and misses not covered. Rows top-down.
std::vector<SplatPixel> eye_ray_pixels(const Scene& scene, const RayTracer& rays, int width,
                                       int height);

// Radiance's lazy irradiance cache over `pixels` (from eye_ray_pixels, rows top-down) at accuracy
// a: records gathered by `gather` with `radiance` and `options`, keys counting up from 0.
CpuCacheFrame render_irradiance_cache_cpu(const Scene& scene, const RayTracer& rays,
                                          const IrradianceGather& gather,
                                          const RecordRadiance& radiance,
                                          const RecordGatherOptions& options, float accuracy,
                                          int width, int height);

// The same on given pixels (another G-buffer; eye_ms stays 0).
CpuCacheFrame render_irradiance_cache_cpu(const Scene& scene, std::vector<SplatPixel> pixels,
                                          const IrradianceGather& gather,
                                          const RecordRadiance& radiance,
                                          const RecordGatherOptions& options, float accuracy,
                                          int width, int height);

// Σ w E / Σ w of `records` at every pixel by octree lookups (the interpolation alone).
std::vector<glm::vec3> interpolate_cpu(const Scene& scene,
                                       const std::vector<IrradianceRecord>& records,
                                       const std::vector<SplatPixel>& pixels, float accuracy);

}  // namespace ag::cpu
