// Irradiance cache records (Gautron 2006 ch. 2.3, 4.3): Ward's weight and its cut-off at a·R_k,
// the behind test, extrapolation, and the CPU scan (Algorithm 4) covering every pixel with fewer
// records as the accuracy a grows.
#include "shared/irradiance_record.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ag {

namespace {

IrradianceRecord record_at(glm::vec3 p, float r, glm::vec3 iim = glm::vec3(1.0f)) {
    IrradianceRecord rec;
    rec.position = p;
    rec.normal = glm::vec3(0.0f, 0.0f, 1.0f);
    rec.harmonic_distance = r;
    rec.iim = iim;
    return rec;
}

// A width × height grid of pixels on the unit square of the plane z = 0, normals +z; the first
// pixel is background.
std::vector<SplatPixel> grid(int width, int height) {
    std::vector<SplatPixel> px(size_t(width) * size_t(height));
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            SplatPixel& p = px[size_t(y) * size_t(width) + size_t(x)];
            p.position = glm::vec3((x + 0.5f) / float(width), (y + 0.5f) / float(height), 0.0f);
            p.normal = glm::vec3(0.0f, 0.0f, 1.0f);
            p.covered = !(x == 0 && y == 0);  // one background pixel
        }
    return px;
}

// R_k grows with the distance from the plane's corner: small records near it, large far away.
IrradianceRecord make_at(const SplatPixel& p, size_t) {
    return record_at(p.position, 0.02f + 0.1f * glm::length(glm::vec2(p.position)),
                     glm::vec3(p.position.x, p.position.y, 1.0f));
}

}  // namespace

TEST(IrradianceRecord, WardWeightIsOneOverAAtTheRadiusAOfR) {
    const IrradianceRecord r = record_at(glm::vec3(0.0f), 2.0f);
    const glm::vec3 n(0.0f, 0.0f, 1.0f);
    for (float a : {0.1f, 0.3f, 0.7f})
        EXPECT_NEAR(ward_weight(r, glm::vec3(a * 2.0f, 0.0f, 0.0f), n), 1.0f / a, 1e-4f / a);
    EXPECT_EQ(ward_weight(r, glm::vec3(0.0f), n), kMaxWardWeight);
    // A tilted normal lowers the weight: 1 − cos 60° = ½.
    const glm::vec3 tilted(std::sin(1.0471976f), 0.0f, std::cos(1.0471976f));
    EXPECT_NEAR(ward_weight(r, glm::vec3(0.0f), tilted), 1.0f / std::sqrt(0.5f), 1e-4f);
    // A point below the record's tangent plane (the record is in front of it) gets nothing.
    EXPECT_EQ(ward_weight(r, glm::vec3(0.5f, 0.0f, -0.5f), n), 0.0f);
    EXPECT_GT(ward_weight(r, glm::vec3(0.5f, 0.0f, 0.5f), n), 0.0f);
}

TEST(IrradianceRecord, ExtrapolationAddsGradientsAndTemporalChange) {
    IrradianceRecord r = record_at(glm::vec3(0.0f), 1.0f, glm::vec3(1.0f, 2.0f, 3.0f));
    r.translation_gradient[1] = glm::vec3(1.0f, 0.0f, 0.0f);  // green rises along x
    r.rotation_gradient[0] = glm::vec3(0.0f, 1.0f, 0.0f);     // red rises tilting about y
    r.temporal_gradient = glm::vec3(0.0f, 0.0f, -0.5f);
    r.born = 10;
    const glm::vec3 n = glm::normalize(glm::vec3(0.1f, 0.0f, 1.0f));  // n_k × n ≈ (0, 0.1, 0)
    const glm::vec3 e = extrapolate(r, glm::vec3(0.2f, 0.0f, 0.0f), n, 12);
    EXPECT_NEAR(e.x, 1.0f + glm::cross(r.normal, n).y, 1e-6f);
    EXPECT_NEAR(e.y, 2.2f, 1e-6f);
    EXPECT_NEAR(e.z, 2.0f, 1e-6f);
}

TEST(IrradianceRecord, SplatOfOneRecordIsItsExtrapolation) {
    std::vector<SplatPixel> px = grid(16, 16);
    IrradianceRecord r = record_at(glm::vec3(0.5f, 0.5f, 0.0f), 0.5f, glm::vec3(2.0f));
    r.translation_gradient[0] = glm::vec3(1.0f, 0.0f, 0.0f);
    std::vector<glm::vec4> sums;
    splat_records({r}, px, 0.5f, 0, sums);
    const std::vector<glm::vec3> e = normalise_splat(sums);
    int inside = 0;
    for (size_t i = 0; i < px.size(); ++i) {
        const float d = glm::length(px[i].position - r.position);
        if (!px[i].covered || d > 0.5f * 0.5f * 0.999f) continue;
        ++inside;
        EXPECT_NEAR(e[i].x, 2.0f + (px[i].position.x - 0.5f), 1e-5f);
    }
    EXPECT_GT(inside, 20);
    EXPECT_EQ(sums[0], glm::vec4(0.0f));  // background pixel
}

TEST(IrradianceRecord, ScanCoversEveryPixelWithFewerRecordsAsAGrows) {
    const std::vector<SplatPixel> px = grid(64, 64);
    int previous = 1 << 30;
    for (float a : {0.1f, 0.2f, 0.4f, 0.8f}) {
        std::vector<IrradianceRecord> records;
        std::vector<glm::vec4> sums;
        const int added = add_records_by_scan(records, px, a, 0, sums, make_at);
        EXPECT_EQ(added, int(records.size()));
        for (size_t i = 0; i < px.size(); ++i) {
            if (px[i].covered) {
                ASSERT_GE(sums[i].a, a) << "pixel " << i << " at a = " << a;
            }
        }
        // The sums the scan kept are the sums of a fresh splat of all its records.
        std::vector<glm::vec4> again;
        splat_records(records, px, a, 0, again);
        for (size_t i = 0; i < px.size(); i += 97)
            EXPECT_NEAR(again[i].a, sums[i].a, 1e-3f * sums[i].a);
        EXPECT_LT(added, previous) << "a = " << a;
        previous = added;
    }
}

TEST(IrradianceRecord, ScanStopsAtItsBudget) {
    const std::vector<SplatPixel> px = grid(32, 32);
    std::vector<IrradianceRecord> records;
    std::vector<glm::vec4> sums;
    EXPECT_EQ(add_records_by_scan(records, px, 0.1f, 0, sums, make_at, 5), 5);
    EXPECT_EQ(records.size(), 5u);
}

}  // namespace ag
