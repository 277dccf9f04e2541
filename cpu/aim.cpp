#include "cpu/aim.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <tuple>

#include "cpu/knn.h"
#include "cpu/reference/reference.h"
#include "cpu/sampling.h"
#include "shared/chart_cells.h"
#include "shared/charts.h"
#include "shared/lightmap_sample.h"

namespace ag::cpu {

namespace {

constexpr int kTextureSubsamples = 4;  // per texel side, for its mean albedo
constexpr int kDirectSubsamples = 4;   // per texel side, for its mean direct irradiance (exact)

// Points of the disc that measure how much of it can receive photons: a sunflower (Vogel)
// spiral, each point standing for 1/64 of the disc's area. A fixed pattern keeps the AIM
// deterministic and the same for a rebuild from the same hits.
constexpr int kDiscSamples = 64;
// The least disc fraction an estimate is divided by (a quarter disc in a right-angled corner is
// 0.25; sharper corners of a chart must not blow the estimate up).
constexpr double kMinDiscFraction = 0.125;
// A texel part is covered when the first face a ray along its normal meets is a back face (it lies
// inside a solid: the floor under a box resting on it) or lies within this many texels (under an
// open surface lying on it, or a solid a hair above it). Photons cannot land there.
constexpr float kCoveredGap = 0.01f;

// Whether the ray from `origin` along unit `dir` crosses box `b` (expanded by `pad`) at t ≥ 0.
bool ray_crosses(const glm::vec3& origin, const glm::vec3& dir, const Bounds& b, float pad) {
    float t0 = 0.0f, t1 = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
        const float lo = b.min[a] - pad, hi = b.max[a] + pad;
        if (std::abs(dir[a]) < 1e-12f) {
            if (origin[a] < lo || origin[a] > hi) return false;
            continue;
        }
        const float ta = (lo - origin[a]) / dir[a], tb = (hi - origin[a]) / dir[a];
        t0 = std::max(t0, std::min(ta, tb));
        t1 = std::min(t1, std::max(ta, tb));
        if (t0 > t1) return false;
    }
    return true;
}

// Whether a ray from some point of world triangle (p0, p1, p2) along its unit normal `normal`
// may cross box `b` expanded by `pad`: false only when the box lies wholly behind the triangle's
// plane or wholly beside the prism the triangle sweeps along its normal (a conservative filter
// before the cells' own ray_crosses tests).
bool prism_may_cross(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
                     const glm::vec3& normal, const Bounds& b, float pad) {
    const glm::vec3 side =
        std::abs(normal.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
    const glm::vec3 e1 = glm::normalize(glm::cross(normal, side)), e2 = glm::cross(normal, e1);
    const glm::vec3 lo = b.min - pad, hi = b.max + pad;
    // Rounding: the cells' origins and the boxes' slabs are floats; a margin well above it.
    const float margin =
        1e-4f * (glm::length(hi - lo) + glm::length(p1 - p0) + glm::length(p2 - p0)) + pad;
    glm::vec3 box_lo(std::numeric_limits<float>::infinity()), box_hi(-box_lo);
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 c((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
        const glm::vec3 q(glm::dot(c, e1), glm::dot(c, e2), glm::dot(c, normal));
        box_lo = glm::min(box_lo, q);
        box_hi = glm::max(box_hi, q);
    }
    glm::vec3 tri_lo(std::numeric_limits<float>::infinity()), tri_hi(-tri_lo);
    for (const glm::vec3& p : {p0, p1, p2}) {
        const glm::vec3 q(glm::dot(p, e1), glm::dot(p, e2), glm::dot(p, normal));
        tri_lo = glm::min(tri_lo, q);
        tri_hi = glm::max(tri_hi, q);
    }
    if (box_hi.z < tri_lo.z - margin) return false;  // behind the triangle's plane
    return !(box_hi.x < tri_lo.x - margin || box_lo.x > tri_hi.x + margin ||
             box_hi.y < tri_lo.y - margin || box_lo.y > tri_hi.y + margin);
}

Bounds object_world_bounds(const Object& o) {
    Bounds b;
    for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    return b;
}

const std::array<glm::vec2, kDiscSamples>& disc_pattern() {
    static const std::array<glm::vec2, kDiscSamples> pattern = [] {
        std::array<glm::vec2, kDiscSamples> p{};
        const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
        for (int i = 0; i < kDiscSamples; ++i) {
            const double r = std::sqrt((i + 0.5) / kDiscSamples), a = golden * i;
            p[size_t(i)] = glm::vec2(float(r * std::cos(a)), float(r * std::sin(a)));
        }
        return p;
    }();
    return pattern;
}

// The density at the disc's centre (u = 0) of E(u) = a + g·u fitted to the flux on the part of
// the disc on the chart: s0 = a·A + g·m1 and s1 = a·m1 + M2·g (flux and its first moment, per
// disc area; A, m1, M2 the part's area and moments). Where the light falls or rises towards
// the edge, the mean over the cut disc (s0 / A) is the density at the part's centroid, inside
// the chart, not at the texel centre on the edge. Bounded to [½, 2] × s0 / A where the part is
// too thin to fit a slope reliably.
double density_at_centre(const Aim::DiscPart& part, double s0, const glm::dvec2& s1) {
    const double mean = s0 / part.area;
    if (std::abs(glm::determinant(part.second)) < 1e-12) return mean;
    const glm::dmat2 inv = glm::inverse(part.second);
    const double denominator = part.area - glm::dot(part.first, inv * part.first);
    if (!(denominator > 1e-6)) return mean;
    const double a = (s0 - glm::dot(part.first, inv * s1)) / denominator;
    return std::clamp(a, 0.5 * mean, 2.0 * mean);
}

// The mean of the object's albedo texture over texel `t`: n × n points of the texel square in
// atlas space, each mapped onto the record's triangle by its atlas-space barycentrics (clamped
// onto the triangle, so points beyond it read its nearest edge).
glm::vec3 texel_texture_mean(const Scene& scene, const TexelRecord& t) {
    const Object& object = scene.objects[size_t(t.object)];
    const Material& m = object.material;
    if (!m.albedo_map || m.type != MaterialType::diffuse) return glm::vec3(1.0f);
    if (!object.mesh.has_texcoords() || t.triangle < 0) return m.albedo_map->mean;
    const glm::vec2* c = &scene.atlas.corner_uvs[size_t(t.object)][3 * size_t(t.triangle)];
    const glm::vec2 e1 = c[1] - c[0], e2 = c[2] - c[0];
    const float det = e1.x * e2.y - e1.y * e2.x;
    glm::vec3 sum(0.0f);
    for (int j = 0; j < kTextureSubsamples; ++j)
        for (int i = 0; i < kTextureSubsamples; ++i) {
            const glm::vec2 p = glm::vec2(float(t.x), float(t.y)) +
                                (glm::vec2(float(i), float(j)) + 0.5f) / float(kTextureSubsamples);
            glm::vec2 b(1.0f / 3.0f);
            if (std::abs(det) > 1e-12f) {
                const glm::vec2 d = p - c[0];
                b = {(d.x * e2.y - d.y * e2.x) / det, (e1.x * d.y - e1.y * d.x) / det};
                b = glm::max(b, 0.0f);
                if (b.x + b.y > 1.0f) b /= b.x + b.y;
            }
            sum += m.albedo_map->sample(object.mesh.texcoord(t.triangle, b));
        }
    return sum / float(kTextureSubsamples * kTextureSubsamples);
}

}  // namespace

Aim::Aim(const Scene& scene, ThreadPool& pool) : scene_(scene), pool_(pool) {
    if (scene_.settings.aim.boundary_correction || scene_.settings.aim.covered_texels)
        coverage_ = texel_coverage_masks(scene_);
    surface_texels_.resize(scene_.surfaces.size());
    for (int i = 0; i < int(scene_.atlas.texels.size()); ++i)
        surface_texels_[size_t(scene_.atlas.texels[size_t(i)].surface)].push_back(i);
    const size_t n = size_t(scene_.atlas.width) * size_t(scene_.atlas.height);
    radiance_.assign(n, glm::vec3(0.0f));
    irradiance_.assign(n, glm::vec3(0.0f));
    dirty_flag_.assign(n, 0);
    indirect_.assign(scene_.atlas.texels.size(), -1.0f);
    raw_e_.assign(scene_.atlas.texels.size(), glm::vec3(0.0f));
    raw_indirect_.assign(scene_.atlas.texels.size(), glm::vec3(0.0f));
    reach2_.assign(scene_.atlas.texels.size(), std::numeric_limits<float>::infinity());
    built_.assign(scene_.surfaces.size(), 0);
    built_albedo_.assign(scene_.surfaces.size(), glm::vec3(0.0f));
    indirect_floor_.assign(scene_.atlas.texels.size(), 0.0f);
    texture_mean_.resize(scene_.atlas.texels.size());
    pool_.parallel_for(
        texture_mean_.size(),
        [&](size_t i) { texture_mean_[i] = texel_texture_mean(scene_, scene_.atlas.texels[i]); },
        256);
    disc_on_.assign(scene_.atlas.texels.size(), ~uint64_t(0));
    if (scene_.settings.aim.exact_direct) rays_ = std::make_unique<RayTracer>(scene_);
    // The covered cells are tested at the first rebuild (sync_covered), not here: a pipeline whose
    // indirect method reads no photon maps never builds an AIM and pays nothing for them.
    if (scene_.settings.aim.covered_texels) {
        covered_.assign(n, 0);
        open_ = coverage_;
        open_fraction_.assign(scene_.atlas.texels.size(), 1.0f);
        open_record_.assign(scene_.atlas.texels.size(), 1);
        covered_changed_.assign(scene_.surfaces.size(), 0);
        cell_claims_.assign(scene_.atlas.charts.size(), {});
        claim_begin_.assign(scene_.atlas.charts.size(), {});
    }
}

bool Aim::test_covered(int chart_id, const std::vector<Bounds>* boxes) {
    const LightmapAtlas& atlas = scene_.atlas;
    const Chart& chart = atlas.charts[size_t(chart_id)];
    const Object& object = scene_.objects[size_t(chart.object)];
    const Mesh& mesh = object.mesh;
    const std::vector<glm::vec2>& uvs = atlas.corner_uvs[size_t(chart.object)];
    constexpr int n = kCoverageSubdivision;
    const float gap = kCoveredGap * chart.texel_size;
    const float pad = gap + 2.0f * rays_->epsilon();
    static_assert(n * n <= 16, "a texel's cells are the bits of a uint16_t");
    std::vector<uint32_t>& claims = cell_claims_[size_t(chart_id)];
    std::vector<uint32_t>& begin = claim_begin_[size_t(chart_id)];
    const bool first = begin.empty();  // the first test walks the cells and notes who places them
    // Per texel of the chart's rectangle: cells tested (the first triangle holding a cell's point
    // places it, as texel_coverage_masks does), and covered among them.
    const size_t w = size_t(chart.width);
    std::vector<uint16_t> cover(w * size_t(chart.height), 0), tested(cover.size(), 0),
        done(first ? cover.size() : 0, 0);
    // A cell's state is its ray's first hit along the normal of the triangle that places it.
    const auto test_cell = [&](size_t local, uint16_t bit, const glm::vec3& p,
                               const glm::vec3& normal) {
        const glm::vec3 origin = p + rays_->epsilon() * normal;
        if (boxes && !std::any_of(boxes->begin(), boxes->end(), [&](const Bounds& bx) {
                return ray_crosses(origin, normal, bx, pad);
            }))
            return;
        tested[local] = uint16_t(tested[local] | bit);
        const RayHit hit = rays_->intersect({origin, normal, 0.0f, 1e30f});
        if (!hit.hit) return;
        // Glass lets photons through: it covers nothing.
        if (scene_.objects[size_t(hit.object)].material.type == MaterialType::glass) return;
        if (glm::dot(hit.normal, normal) > 0.0f || hit.t < gap)
            cover[local] = uint16_t(cover[local] | bit);
    };
    if (first) begin.push_back(0);
    for (size_t k = 0; k < chart.triangles.size(); ++k) {
        const int tri = chart.triangles[k];
        const glm::uvec3 f = mesh.triangles[size_t(tri)];
        const glm::vec3 p0 = mesh.positions[f.x], p1 = mesh.positions[f.y],
                        p2 = mesh.positions[f.z];
        const glm::vec3 face = glm::cross(p1 - p0, p2 - p0);
        const bool flat = glm::dot(face, face) <= 0.0f;
        const glm::vec3 normal =
            flat ? glm::vec3(0.0f) : glm::normalize(object.transform.apply_vector(face));
        const auto point = [&](double u, double v) {
            return object.transform.apply_point(p0 + float(u) * (p1 - p0) + float(v) * (p2 - p0));
        };
        if (first) {
            if (!flat)
                visit_triangle_cells(
                    chart, uvs, tri, [&](int x, int y, int i, int j, double u, double v) {
                        const size_t local = size_t(y - chart.y) * w + size_t(x - chart.x);
                        const int cell = n * j + i;
                        const uint16_t bit = uint16_t(1u << cell);
                        if (done[local] & bit) return;
                        done[local] = uint16_t(done[local] | bit);
                        claims.push_back(uint32_t(local) * 16u + uint32_t(cell));
                        test_cell(local, bit, point(u, v), normal);
                    });
            begin.push_back(uint32_t(claims.size()));
            continue;
        }
        if (begin[k] == begin[k + 1]) continue;
        if (boxes) {
            const glm::vec3 w0 = object.transform.apply_point(p0),
                            w1 = object.transform.apply_point(p1),
                            w2 = object.transform.apply_point(p2);
            if (!std::any_of(boxes->begin(), boxes->end(), [&](const Bounds& bx) {
                    return prism_may_cross(w0, w1, w2, normal, bx, pad);
                }))
                continue;
        }
        const glm::dvec2 a(uvs[3 * size_t(tri)]), b(uvs[3 * size_t(tri) + 1]),
            c(uvs[3 * size_t(tri) + 2]);
        const double det = (b - a).x * (c - a).y - (b - a).y * (c - a).x;
        for (uint32_t at = begin[k]; at < begin[k + 1]; ++at) {
            const size_t local = claims[at] / 16u;
            const int cell = int(claims[at] % 16u);
            const int x = chart.x + int(local % w), y = chart.y + int(local / w);
            const glm::dvec2 uv = cell_barycentrics(a, b, c, det, x, y, cell % n, cell / n);
            test_cell(local, uint16_t(1u << cell), point(uv.x, uv.y), normal);
        }
    }
    bool changed = false;
    for (int y = 0; y < chart.height; ++y)
        for (int x = 0; x < chart.width; ++x) {
            const size_t local = size_t(y) * w + size_t(x);
            if (!tested[local]) continue;
            const size_t at = size_t(chart.y + y) * size_t(atlas.width) + size_t(chart.x + x);
            const uint16_t now = uint16_t((covered_[at] & ~tested[local]) | cover[local]);
            if (now == covered_[at]) continue;
            changed = true;
            covered_[at] = now;
            open_[at] = uint16_t(coverage_[at] & ~now);
            const int r = atlas.texel_at(chart.x + x, chart.y + y);
            if (r < 0) continue;
            const int on = std::popcount(unsigned(coverage_[at]));
            open_fraction_[size_t(r)] =
                on == 0 ? 1.0f : float(std::popcount(unsigned(open_[at]))) / float(on);
            open_record_[size_t(r)] = on == 0 || open_[at] != 0 ? 1 : 0;
        }
    return changed;
}

void Aim::sync_covered() {
    if (!scene_.settings.aim.covered_texels) return;
    const size_t objects = scene_.objects.size();
    const bool first = covered_transforms_.empty();
    std::vector<Bounds> boxes;
    std::vector<char> moved(objects, 0);
    if (first) {
        covered_transforms_.resize(objects);
        covered_bounds_.resize(objects);
    }
    for (size_t o = 0; o < objects; ++o) {
        const Transform& t = scene_.objects[o].transform;
        if (!first && t.translation == covered_transforms_[o].translation &&
            t.rotation == covered_transforms_[o].rotation)
            continue;
        const Bounds now = object_world_bounds(scene_.objects[o]);
        if (!first) {
            boxes.push_back(covered_bounds_[o]);
            boxes.push_back(now);
            moved[o] = 1;
        }
        covered_transforms_[o] = t;
        covered_bounds_[o] = now;
    }
    if (!first && boxes.empty()) return;
    if (!rays_)
        rays_ = std::make_unique<RayTracer>(scene_);
    else
        rays_->update(scene_);
    // A cell's state is its ray's first hit: it can change only where the ray crosses a moved
    // object's old or new bounds, or where the cell itself moved.
    const size_t charts = scene_.atlas.charts.size();
    std::vector<char> changed(charts, 0);
    pool_.parallel_for(
        charts,
        [&](size_t c) {
            const bool all = first || moved[size_t(scene_.atlas.charts[c].object)];
            changed[c] = test_covered(int(c), all ? nullptr : &boxes) ? 1 : 0;
        },
        1);
    for (size_t c = 0; c < charts; ++c)
        if (changed[c]) covered_changed_[size_t(scene_.atlas.charts[c].surface)] = 1;
}

glm::vec3 Aim::direct_over_texel(int record) const {
    const TexelRecord& t = scene_.atlas.texels[size_t(record)];
    const Transform& transform = scene_.objects[size_t(t.object)].transform;
    // One area-light sample per point: the grid's 16 points together sample the light as the
    // frame's direct term does (settings.direct.area_light_samples, 16 by default).
    const int quad_samples = std::max(
        1, scene_.settings.direct.area_light_samples / (kDirectSubsamples * kDirectSubsamples));
    glm::dvec3 sum(0.0);
    int points = 0;
    for (int j = 0; j < kDirectSubsamples; ++j)
        for (int i = 0; i < kDirectSubsamples; ++i) {
            const glm::vec2 offset =
                (glm::vec2(float(i), float(j)) + 0.5f) / float(kDirectSubsamples) - 0.5f;
            const std::optional<FootprintPoint> fp = texel_point_at(scene_, record, offset);
            if (!fp) continue;
            const glm::vec3 p = transform.apply_point(fp->position);
            const glm::vec3 n = transform.apply_vector(fp->normal);
            // Inside another solid (a ray along the normal meets a back face first): no light
            // arrives there and no one sees it.
            const RayHit above = rays_->intersect({p + rays_->epsilon() * n, n, 0.0f, 1e30f});
            if (above.hit && glm::dot(above.normal, n) > 0.0f) continue;
            const int k = j * kDirectSubsamples + i;
            sum += glm::dvec3(
                direct_irradiance(scene_, *rays_, p, n, quad_samples,
                                  hashed_uniform(uint64_t(record), uint64_t(2 * k)),
                                  hashed_uniform(uint64_t(record), uint64_t(2 * k + 1))));
            ++points;
        }
    if (points == 0) return glm::vec3(0.0f);
    return glm::vec3(sum / double(points));
}

int Aim::rebuild_surface(PhotonMaps& maps, int surface) {
    sync_covered();
    return estimate_surface(maps, surface, nullptr);
}

int Aim::estimate_surface(PhotonMaps& maps, int surface, const std::vector<glm::vec3>* changed) {
    SurfaceHits& s = maps.surface(surface);
    const std::vector<int>& texels = surface_texels_[size_t(surface)];
    const glm::vec3 albedo = albedo_of(surface);
    const bool exact = scene_.settings.aim.exact_direct;
    // Exact direct light follows the geometry, not only the hits: every texel again.
    if (exact) changed = nullptr;
    const bool covered = scene_.settings.aim.covered_texels;
    const bool correct = scene_.settings.aim.boundary_correction;

    // The texels to estimate: all of them, or those whose kNN disc of the last build reaches a
    // changed hit. Another texel keeps its nearest hits, and so its estimate, bit for bit: a
    // removed hit farther than its k-th nearest was not among them, an added one farther away
    // does not join them.
    std::vector<int> todo;
    if (!changed) {
        todo.resize(texels.size());
        std::iota(todo.begin(), todo.end(), 0);
    } else if (!changed->empty()) {
        KnnIndex near_change;
        near_change.build(*changed);
        std::vector<char> reached(texels.size(), 0);
        pool_.parallel_for(
            texels.size(),
            [&](size_t i) {
                const int r = texels[i];
                if (!std::isfinite(reach2_[size_t(r)])) {
                    reached[i] = 1;
                    return;
                }
                thread_local std::vector<int> idx;
                thread_local std::vector<float> d2;
                const TexelRecord& t = scene_.atlas.texels[size_t(r)];
                if (near_change.query(t.position, 1, idx, d2) == 1)
                    reached[i] = d2[0] <= reach2_[size_t(r)] * (1.0f + 1e-5f) ? 1 : 0;
            },
            64);
        for (size_t i = 0; i < texels.size(); ++i)
            if (reached[i]) todo.push_back(int(i));
    }
    // Covered cells changed (an object moved): a texel whose kNN disc now counts other sample
    // points is estimated again, though its nearest hits are the same.
    if (changed && covered && correct && scene_.settings.aim.covered_disc &&
        covered_changed_[size_t(surface)]) {
        std::vector<char> again(texels.size(), 0);
        for (int i : todo) again[size_t(i)] = 2;
        pool_.parallel_for(
            texels.size(),
            [&](size_t i) {
                if (again[i]) return;
                const int r = texels[i];
                double r2 = double(reach2_[size_t(r)]);
                if (r2 <= 0.0) {
                    const double texel =
                        scene_.atlas.charts[size_t(scene_.atlas.texels[size_t(r)].chart)]
                            .texel_size;
                    r2 = texel * texel / std::numbers::pi;
                }
                if (disc_on_surface(r, std::sqrt(r2)).on != disc_on_[size_t(r)]) again[i] = 1;
            },
            64);
        for (size_t i = 0; i < texels.size(); ++i)
            if (again[i] == 1) todo.push_back(int(i));
    }

    // With exact direct light the kNN estimate is over the hits that bounced at least once (the
    // direct hits' light comes from shadow rays), and it is scaled to their flux alone.
    if (exact) rays_->update(scene_);
    std::vector<int> used;  // indices into s.hits of the hits the estimate counts
    used.reserve(s.hits.size());
    glm::dvec3 used_flux(0.0);
    // Each hit counts with its group's weight, 1 / its photon sets (photons.refine_layers).
    std::vector<double> weight;
    weight.reserve(s.hits.size());
    for (size_t i = 0; i < s.hits.size(); ++i) {
        if (exact && s.hits[i].bounce < 1) continue;
        used.push_back(int(i));
        weight.push_back(maps.hit_weight(s.hits[i]));
        used_flux += glm::dvec3(s.hits[i].power) * weight.back();
    }
    KnnIndex index;
    if (!todo.empty()) {
        std::vector<glm::vec3> points(used.size());
        for (size_t i = 0; i < used.size(); ++i) points[i] = s.hits[size_t(used[i])].position;
        index.build(points);
    }
    const int k = scene_.settings.aim.knn;
    const bool linear = correct && scene_.settings.aim.boundary_linear;
    std::vector<glm::vec3> direct(exact ? texels.size() : 0, glm::vec3(0.0f));

    // Unscaled estimates per texel of the surface (kept per record between builds).
    std::vector<glm::vec3> e(texels.size()), indirect(texels.size());
    for (size_t i = 0; i < texels.size(); ++i) {
        e[i] = raw_e_[size_t(texels[i])];
        indirect[i] = raw_indirect_[size_t(texels[i])];
    }
    pool_.parallel_for(
        todo.size(),
        [&](size_t job) {
            const size_t i = size_t(todo[job]);
            const TexelRecord& t = scene_.atlas.texels[size_t(texels[i])];
            if (exact) direct[i] = direct_over_texel(texels[i]);
            thread_local std::vector<int> idx;
            thread_local std::vector<float> d2;
            const int n = index.query(t.position, k, idx, d2);
            // Changes farther than the k-th nearest hit leave the estimate as it is; with fewer
            // than k hits, any change reaches it.
            reach2_[size_t(texels[i])] =
                n == k ? d2[size_t(n - 1)] : std::numeric_limits<float>::infinity();
            e[i] = indirect[i] = glm::vec3(0.0f);
            if (n == 0) return;
            // Density estimate over the disc through the n-th nearest hit (Jensen; Larsen ch. 10).
            double r2 = double(d2[size_t(n - 1)]);
            if (r2 <= 0.0) {
                const double texel = scene_.atlas.charts[size_t(t.chart)].texel_size;
                r2 = texel * texel / std::numbers::pi;
            }
            // Only the part of the disc on the surface holds photons: divide by its area.
            DiscPart part;
            if (correct) part = disc_on_surface(texels[i], std::sqrt(r2));
            disc_on_[size_t(texels[i])] = part.on;
            const double disc = std::numbers::pi * r2;
            glm::dvec3 sum(0.0), bounced(0.0);
            // First moments of the flux about the texel centre, u in units of the radius.
            std::array<glm::dvec2, 3> sum_u{}, bounced_u{};
            const double inv_r = 1.0 / std::sqrt(r2);
            for (int j = 0; j < n; ++j) {
                const PhotonHit& hit = s.hits[size_t(used[size_t(idx[size_t(j)])])];
                const glm::dvec3 power = glm::dvec3(hit.power) * weight[size_t(idx[size_t(j)])];
                sum += power;
                if (hit.bounce >= 1) bounced += power;
                if (part.area >= 1.0 || !linear) continue;
                const glm::vec3 d = hit.position - t.position;
                const glm::dvec2 u = inv_r * glm::dvec2(glm::dot(d, part.b1), glm::dot(d, part.b2));
                for (int c = 0; c < 3; ++c) {
                    sum_u[size_t(c)] += power[c] * u;
                    if (hit.bounce >= 1) bounced_u[size_t(c)] += power[c] * u;
                }
            }
            if (part.area >= 1.0 || !linear) {
                const double cut = std::numbers::pi * (r2 * part.area);  // as before the fit
                e[i] = glm::vec3(sum / cut);
                indirect[i] = glm::vec3(bounced / cut);
                return;
            }
            for (int c = 0; c < 3; ++c) {
                e[i][c] = float(density_at_centre(part, sum[c] / disc, sum_u[size_t(c)] / disc));
                indirect[i][c] =
                    float(density_at_centre(part, bounced[c] / disc, bounced_u[size_t(c)] / disc));
            }
        },
        16);

    for (int i : todo) {
        raw_e_[size_t(texels[size_t(i)])] = e[size_t(i)];
        raw_indirect_[size_t(texels[size_t(i)])] = indirect[size_t(i)];
    }
    built_albedo_[size_t(surface)] = albedo;
    built_[size_t(surface)] = 1;
    s.clear_changes();
    s.changes_overflow = false;
    if (covered) covered_changed_[size_t(surface)] = 0;

    // Scale the surface's estimates so that their integral, Σ E·area, equals the flux its photon
    // hits actually carry: the AIM conserves energy per surface. Without the boundary correction
    // the kNN disc reaches past the surface's edges and the estimate falls there (to about ½ on
    // an edge, ¼ in a corner), and this scale lifts the whole surface instead, leaving its edges
    // dark and its middle bright.
    // With exact direct light only the bounced hits' estimate is scaled, to their flux.
    // Parts inside or under another object receive none of that flux (aim.covered_texels): only
    // the open part of each texel counts, or the covered texels' estimates (the photons around
    // them) would lower every visible texel of the surface.
    glm::dvec3 estimated(0.0);
    for (size_t i = 0; i < texels.size(); ++i) {
        const int r = texels[i];
        const double open = covered ? double(open_fraction_[size_t(r)]) : 1.0;
        estimated += glm::dvec3(e[i]) * double(scene_.atlas.texels[size_t(r)].area) * open;
    }
    // The books hold each hit at its group's weight (photons.refine_layers).
    const glm::dvec3 flux = exact ? used_flux : s.flux;
    for (int c = 0; c < 3; ++c) {
        const double scale = estimated[c] > 0.0 ? flux[c] / estimated[c] : 0.0;
        for (glm::vec3& v : e) v[c] = float(double(v[c]) * scale);
        for (glm::vec3& v : indirect) v[c] = float(double(v[c]) * scale);
    }
    for (size_t i = 0; i < direct.size(); ++i) e[i] += direct[i];
    double mean_indirect = 0.0;
    for (const glm::vec3& v : indirect) mean_indirect += double(energy(v));
    const float floor_indirect =
        texels.empty() ? 0.0f : float(0.05 * mean_indirect / double(texels.size()));

    for (size_t i = 0; i < texels.size(); ++i) {
        const TexelRecord& t = scene_.atlas.texels[size_t(texels[i])];
        const size_t a = size_t(t.y) * size_t(scene_.atlas.width) + size_t(t.x);
        irradiance_[a] = e[i];
        radiance_[a] = albedo * texture_mean_[size_t(texels[i])] / float(std::numbers::pi) * e[i];
        indirect_[size_t(texels[i])] = float(energy(indirect[i]));
        indirect_floor_[size_t(texels[i])] = floor_indirect;
        if (!dirty_flag_[a]) {
            dirty_flag_[a] = 1;
            dirty_.push_back(int(a));
        }
    }
    // Wholly covered texels are seen by no one, but the gathers read the lightmap bilinearly beside
    // the contact: they take the value of their open neighbours on the chart.
    if (covered) {
        std::vector<int> shut;
        for (int r : texels)
            if (!open_record_[size_t(r)]) shut.push_back(r);
        if (!shut.empty()) {
            repair_invalid_texels(scene_.atlas, radiance_, open_record_, shut);
            repair_invalid_texels(scene_.atlas, irradiance_, open_record_, shut);
        }
    }
    s.delta_f = 0.0;
    s.signed_delta = glm::dvec3(0.0);
    return int(todo.size());
}

std::optional<std::vector<glm::vec3>> Aim::net_changes(const SurfaceHits& s, double* energy_out) {
    if (s.changes_overflow) return std::nullopt;
    // A hit removed and added again (a re-traced photon that landed where it did) cancels: sort
    // the changes by what they are, sum the signs of equal ones. The order of the log's prefix
    // is kept from the last call; the tail logged since is sorted and merged into it, which gives
    // the same order as sorting the whole log (ties go by index, so the order is total).
    std::vector<uint32_t>& order = s.changes_sorted;
    if (order.size() > s.changes.size()) order.clear();
    auto key = [&](uint32_t i) {
        const HitChange& c = s.changes[i];
        return std::make_tuple(c.position.x, c.position.y, c.position.z, c.power.x, c.power.y,
                               c.power.z, c.bounce);
    };
    const auto before = [&](uint32_t a, uint32_t b) {
        const auto ka = key(a), kb = key(b);
        return ka != kb ? ka < kb : a < b;
    };
    const size_t sorted = order.size();
    order.resize(s.changes.size());
    std::iota(order.begin() + std::ptrdiff_t(sorted), order.end(), uint32_t(sorted));
    std::sort(order.begin() + std::ptrdiff_t(sorted), order.end(), before);
    std::inplace_merge(order.begin(), order.begin() + std::ptrdiff_t(sorted), order.end(), before);
    std::vector<glm::vec3> out;
    double e = 0.0;
    for (size_t i = 0; i < order.size();) {
        size_t j = i;
        int sum = 0;
        while (j < order.size() && key(order[j]) == key(order[i]))
            sum += s.changes[order[j++]].sign;
        if (sum != 0) {
            const HitChange& c = s.changes[order[i]];
            out.push_back(c.position);
            e += std::abs(double(sum) * energy(c.power));
        }
        i = j;
    }
    if (energy_out) *energy_out = e;
    return out;
}

Aim::DiscPart Aim::disc_on_surface(int record, double radius) const {
    const LightmapAtlas& atlas = scene_.atlas;
    const TexelRecord& t = atlas.texels[size_t(record)];
    const Chart& chart = atlas.charts[size_t(t.chart)];
    DiscPart part;
    // Past the chart's edge a surface of several charts may go on in another chart (elsewhere in
    // the atlas): there the disc is taken to lie on the surface. The parts of one tiled chart
    // (lightmap.refine_tile) share its plane, so the disc is tested on each of them.
    const std::vector<int>& surface_charts = scene_.surfaces[size_t(t.surface)].charts;
    const bool tiled = chart.tile_group >= 0 &&
                       std::all_of(surface_charts.begin(), surface_charts.end(), [&](int c) {
                           return atlas.charts[size_t(c)].tile_group == chart.tile_group;
                       });
    if (surface_charts.size() != 1 && !tiled) return part;
    // With aim.covered_disc the parts inside or under another object are off the surface too.
    const std::vector<uint16_t>& masks =
        scene_.settings.aim.covered_texels && scene_.settings.aim.covered_disc ? open_ : coverage_;
    const auto on_surface = [&](const glm::vec3& p) {
        if (on_chart(atlas, masks, t.chart, chart_atlas_position(chart, p))) return true;
        if (!tiled) return false;
        for (int c : surface_charts)
            if (c != t.chart &&
                on_chart(atlas, masks, c, chart_atlas_position(atlas.charts[size_t(c)], p)))
                return true;
        return false;
    };
    const glm::vec3 n = t.normal;
    const glm::vec3 a = std::abs(n.x) > 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1, 0, 0);
    part.b1 = glm::normalize(a - n * glm::dot(n, a));
    part.b2 = glm::cross(n, part.b1);
    int on = 0;
    glm::dvec2 first(0.0);
    glm::dmat2 second(0.0);
    part.on = 0;
    for (int i = 0; i < kDiscSamples; ++i) {
        const glm::vec2& s = disc_pattern()[size_t(i)];
        const glm::vec3 p = t.position + float(radius) * (s.x * part.b1 + s.y * part.b2);
        if (!on_surface(p)) continue;
        part.on |= uint64_t(1) << i;
        ++on;
        const glm::dvec2 u(s);
        first += u;
        second += glm::outerProduct(u, u);
    }
    if (on == kDiscSamples) return part;
    part.area = std::max(kMinDiscFraction, double(on) / double(kDiscSamples));
    part.first = first / double(kDiscSamples);
    part.second = second / double(kDiscSamples);
    return part;
}

int Aim::update(PhotonMaps& maps, int* surfaces_rebuilt) {
    return update(maps, scene_.settings.aim.surfaces_per_frame, std::numeric_limits<int>::max(),
                  surfaces_rebuilt);
}

int Aim::rebuild_round_robin(PhotonMaps& maps, int max_texels, int* surfaces_rebuilt) {
    const size_t n = maps.surface_count();
    int texels = 0, surfaces = 0;
    for (size_t visited = 0; visited < n && (surfaces == 0 || texels < max_texels); ++visited) {
        const int s = int(round_robin_);
        round_robin_ = (round_robin_ + 1) % n;
        texels += rebuild_surface(maps, s);
        ++surfaces;
    }
    if (surfaces_rebuilt) *surfaces_rebuilt = surfaces;
    return texels;
}

int Aim::update(PhotonMaps& maps, int max_surfaces, int max_texels, int* surfaces_rebuilt) {
    // A surface built before re-estimates only the texels its net hit changes reach; one whose
    // hits came back as they were (every change cancelled) and whose albedo is the same is left
    // alone. A surface never built, or whose changes overflowed, is rebuilt whole.
    struct Candidate {
        int surface;
        double delta;  // Σ |energy| of the net changes (or the gross Δf where not known)
        std::optional<std::vector<glm::vec3>> changed;
    };
    sync_covered();
    std::vector<Candidate> candidates;
    for (int s = 0; s < int(maps.surface_count()); ++s) {
        SurfaceHits& h = maps.surface(s);
        const bool recoloured = built_[size_t(s)] && built_albedo_[size_t(s)] != albedo_of(s);
        // Its covered parts changed (an object moved onto it or away): scale and fill again.
        const bool recovered = !covered_changed_.empty() && covered_changed_[size_t(s)];
        if (h.delta_f <= 0.0 && !recoloured && !recovered) continue;
        Candidate c{s, h.delta_f, std::nullopt};
        if (built_[size_t(s)] && !scene_.settings.aim.exact_direct) {
            c.changed = net_changes(h, &c.delta);
            if (c.changed && c.changed->empty() && !recoloured && !recovered) {
                h.clear_changes();
                h.delta_f = 0.0;
                h.signed_delta = glm::dvec3(0.0);
                continue;
            }
        }
        const double flux = std::abs(energy(h.flux));
        if (!recoloured && !recovered && flux > 0.0 &&
            c.delta / flux <= double(scene_.settings.aim.delta_threshold))
            continue;
        candidates.push_back(std::move(c));
    }
    // Largest Δf / A first (Larsen ch. 10); ties by surface id for determinism.
    auto key = [&](const Candidate& c) {
        return c.delta / std::max(1e-30f, scene_.surfaces[size_t(c.surface)].area);
    };
    std::stable_sort(candidates.begin(), candidates.end(),
                     [&](const Candidate& a, const Candidate& b) { return key(a) > key(b); });
    const int budget = std::min<int>(int(candidates.size()), max_surfaces);
    int texels = 0, surfaces = 0;
    for (int i = 0; i < budget && (surfaces == 0 || texels < max_texels); ++i, ++surfaces) {
        Candidate& c = candidates[size_t(i)];
        texels += estimate_surface(maps, c.surface, c.changed ? &*c.changed : nullptr);
    }
    if (surfaces_rebuilt) *surfaces_rebuilt = surfaces;
    return texels;
}

glm::vec3 Aim::albedo_of(int surface) const {
    const Object& object = scene_.objects[size_t(scene_.surfaces[size_t(surface)].object)];
    return object.material.type == MaterialType::diffuse ? object.material.albedo : glm::vec3(0.0f);
}

int Aim::rebuild_all(PhotonMaps& maps) {
    int texels = 0;
    for (int s = 0; s < int(maps.surface_count()); ++s) texels += rebuild_surface(maps, s);
    return texels;
}

std::vector<int> Aim::take_dirty_texels() {
    std::vector<int> out;
    out.swap(dirty_);
    for (int a : out) dirty_flag_[size_t(a)] = 0;
    return out;
}

}  // namespace ag::cpu
