#include "shared/irradiance_record.h"

#include <algorithm>
#include <cmath>

namespace ag {

float ward_weight(const IrradianceRecord& r, const glm::vec3& p, const glm::vec3& n) {
    const glm::vec3 d = p - r.position;
    // Ward 1988: a record lying in front of the point (on the side its normal faces) sees things
    // the point does not; tolerance 5% of R_k against curvature and float noise.
    if (glm::dot(d, 0.5f * (n + r.normal)) < -0.05f * r.harmonic_distance) return 0.0f;
    const float angular = std::sqrt(std::max(0.0f, 1.0f - glm::dot(n, r.normal)));
    const float e = glm::length(d) / r.harmonic_distance + angular;
    return e > 1.0f / kMaxWardWeight ? 1.0f / e : kMaxWardWeight;
}

glm::vec3 extrapolate(const IrradianceRecord& r, const glm::vec3& p, const glm::vec3& n,
                      int frame) {
    const glm::vec3 axis = glm::cross(r.normal, n);
    const glm::vec3 d = p - r.position;
    glm::vec3 e = r.iim + float(frame - r.born) * r.temporal_gradient;
    e +=
        axis * r.rotation_gradient + d * r.translation_gradient;  // row vector × matrix: per column
    return glm::max(e, glm::vec3(0.0f));
}

void splat_records(const std::vector<IrradianceRecord>& records,
                   const std::vector<SplatPixel>& pixels, float accuracy, int frame,
                   std::vector<glm::vec4>& sums) {
    sums.resize(pixels.size(), glm::vec4(0.0f));
    const float cutoff = 1.0f / accuracy;
    for (const IrradianceRecord& r : records)
        for (size_t i = 0; i < pixels.size(); ++i) {
            const SplatPixel& px = pixels[i];
            if (!px.covered) continue;
            const float w = ward_weight(r, px.position, px.normal);
            if (w < cutoff) continue;
            sums[i] += glm::vec4(w * extrapolate(r, px.position, px.normal, frame), w);
        }
}

std::vector<glm::vec3> normalise_splat(const std::vector<glm::vec4>& sums) {
    std::vector<glm::vec3> out(sums.size(), glm::vec3(0.0f));
    for (size_t i = 0; i < sums.size(); ++i)
        if (sums[i].a > 0.0f) out[i] = glm::vec3(sums[i]) / sums[i].a;
    return out;
}

int add_records_by_scan(std::vector<IrradianceRecord>& records,
                        const std::vector<SplatPixel>& pixels, float accuracy, int frame,
                        std::vector<glm::vec4>& sums, const MakeRecord& make, int max_new) {
    sums.resize(pixels.size(), glm::vec4(0.0f));
    int added = 0;
    for (size_t i = 0; i < pixels.size() && added < max_new; ++i) {
        if (!pixels[i].covered || !needs_record(sums[i], accuracy)) continue;
        records.push_back(make(pixels[i], i));
        splat_records({records.back()}, pixels, accuracy, frame, sums);
        ++added;
        // A record must cover the pixel it was made for (w is at its cap there); if its normal
        // disagrees with the pixel's, count the pixel as covered to avoid an endless loop.
        if (needs_record(sums[i], accuracy)) sums[i].a = accuracy;
    }
    return added;
}

}  // namespace ag
