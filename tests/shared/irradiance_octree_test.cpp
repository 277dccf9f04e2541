// The octree of records (Radiance's way of finding the records that cover a point, the CPU
// baseline of Gautron's Table 4.2): its lookup must find every record whose zone holds the point,
// so it sums exactly what the brute-force splat over all records sums.
#include "shared/irradiance_octree.h"

#include <gtest/gtest.h>

#include <random>

namespace ag {

namespace {

// Records and points scattered over [−1, 1]³ with radii over three decades, random normals and
// non-zero gradients, some records outside the octree's cube.
struct Cloud {
    std::vector<IrradianceRecord> records;
    std::vector<SplatPixel> points;
    explicit Cloud(uint32_t seed) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f), e(-3.0f, 0.0f);
        auto unit = [&] {
            glm::vec3 v;
            do v = glm::vec3(u(rng), u(rng), u(rng));
            while (glm::length(v) < 0.1f || glm::length(v) > 1.0f);
            return glm::normalize(v);
        };
        for (int k = 0; k < 3000; ++k) {
            IrradianceRecord r;
            r.position = glm::vec3(u(rng), u(rng), u(rng)) * (k % 100 == 0 ? 3.0f : 1.0f);
            r.normal = unit();
            r.harmonic_distance = std::pow(10.0f, e(rng));
            r.iim = glm::vec3(0.5f + 0.5f * u(rng), 0.5f, 0.2f);
            r.rotation_gradient = glm::mat3(0.01f * u(rng));
            r.translation_gradient = glm::mat3(0.02f * u(rng));
            records.push_back(r);
        }
        for (int i = 0; i < 4000; ++i) {
            SplatPixel p;
            // Half the points near records (so that many are covered), half anywhere.
            if (i % 2 == 0) {
                const IrradianceRecord& r = records[size_t(i / 2) % records.size()];
                p.position = r.position + 0.03f * r.harmonic_distance * unit();
                p.normal = glm::normalize(r.normal + 0.01f * unit());
            } else {
                p.position = glm::vec3(u(rng), u(rng), u(rng));
                p.normal = unit();
            }
            p.covered = true;
            points.push_back(p);
        }
    }
};

}  // namespace

TEST(IrradianceOctree, LookupSumsWhatTheBruteForceSplatSums) {
    const Cloud cloud(3);
    for (float a : {0.1f, 0.3f, 0.9f}) {
        IrradianceOctree octree(glm::vec3(0.0f), 1.0f, a);
        for (const IrradianceRecord& r : cloud.records) octree.insert(r);
        std::vector<glm::vec4> brute;
        splat_records(cloud.records, cloud.points, a, 0, brute);
        int covered = 0;
        for (size_t i = 0; i < cloud.points.size(); ++i) {
            const glm::vec4 s = octree.lookup(cloud.points[i].position, cloud.points[i].normal);
            // The same terms in another order: float sums agree to rounding.
            EXPECT_NEAR(s.a, brute[i].a, 1e-5f * std::max(1.0f, brute[i].a)) << "a " << a;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(s[c], brute[i][c], 1e-5f * std::max(1.0f, std::abs(brute[i][c])));
            covered += brute[i].a > 0.0f ? 1 : 0;
        }
        // The test means something only if many points are covered by some record.
        EXPECT_GT(covered, int(cloud.points.size()) / 3) << "a " << a;
    }
}

TEST(IrradianceOctree, RecordsOnNodeBoundariesAreFound) {
    // Records on a grid that puts many exactly on the nodes' dividing planes (x or y = 0, ±0.5,
    // ±0.25), points walking across them: fails if a record is filed in a child whose grown box
    // does not reach the point.
    IrradianceOctree octree(glm::vec3(0.0f), 1.0f, 0.5f);
    std::vector<IrradianceRecord> records;
    for (int i = -4; i <= 4; ++i)
        for (int j = -4; j <= 4; ++j) {
            IrradianceRecord r;
            r.position = glm::vec3(0.25f * float(i), 0.25f * float(j), 0.0f);
            r.normal = glm::vec3(0.0f, 0.0f, 1.0f);
            r.harmonic_distance = 0.5f;  // zones of 0.25: the grid's plane is covered
            r.iim = glm::vec3(float(i + 5));
            records.push_back(r);
            octree.insert(r);
        }
    std::vector<SplatPixel> pts;
    for (int i = 0; i <= 40; ++i)
        pts.push_back({glm::vec3(-1.0f + 0.05f * float(i), 0.01f * float(i), 0.0f),
                       glm::vec3(0.0f, 0.0f, 1.0f), true});
    std::vector<glm::vec4> brute;
    splat_records(records, pts, 0.5f, 0, brute);
    for (size_t i = 0; i < pts.size(); ++i) {
        const glm::vec4 s = octree.lookup(pts[i].position, pts[i].normal);
        EXPECT_NEAR(s.a, brute[i].a, 1e-4f);
        EXPECT_NEAR(s.r, brute[i].r, 1e-3f);
        EXPECT_GT(s.a, 0.0f);
    }
}

}  // namespace ag
