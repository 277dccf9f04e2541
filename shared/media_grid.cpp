#include "shared/media_grid.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "shared/media.h"
#include "shared/qmc.h"

namespace ag {

MediaGrid make_media_grid(const Bounds& bounds, const glm::ivec3& size) {
    MediaGrid g;
    g.bounds = bounds;
    g.size = size;
    g.n.assign(g.voxel_count(), 1.0f);
    g.sigma_s.assign(g.voxel_count(), 0.0f);
    g.sigma_t.assign(g.voxel_count(), 0.0f);
    return g;
}

Image grid_slice(const MediaGrid& grid, const std::vector<float>& values, int axis, int layer) {
    const int u_axis = axis == 0 ? 1 : 0, v_axis = axis == 2 ? 1 : 2;
    Image image(grid.size[u_axis], grid.size[v_axis]);
    for (int v = 0; v < image.height; ++v)
        for (int u = 0; u < image.width; ++u) {
            glm::ivec3 c(0);
            c[axis] = layer;
            c[u_axis] = u;
            c[v_axis] = image.height - 1 - v;
            image.set_rgb(u, v, glm::vec3(values[grid.index(c.x, c.y, c.z)]));
        }
    return image;
}

void gaussian_smooth(std::vector<float>& values, const glm::ivec3& size, int taps, float sigma) {
    const int half = taps / 2;
    std::vector<float> weights(static_cast<size_t>(taps));
    float total = 0.0f;
    for (int i = 0; i < taps; ++i) {
        const float d = float(i - half);
        weights[size_t(i)] = std::exp(-0.5f * d * d / (sigma * sigma));
        total += weights[size_t(i)];
    }
    for (float& w : weights) w /= total;
    std::vector<float> out(values.size());
    const auto at = [&](const glm::ivec3& p) {
        return (size_t(p.z) * size_t(size.y) + size_t(p.y)) * size_t(size.x) + size_t(p.x);
    };
    for (int axis = 0; axis < 3; ++axis) {
        for (int z = 0; z < size.z; ++z)
            for (int y = 0; y < size.y; ++y)
                for (int x = 0; x < size.x; ++x) {
                    const glm::ivec3 p(x, y, z);
                    float sum = 0.0f;
                    for (int i = 0; i < taps; ++i) {
                        glm::ivec3 q = p;
                        q[axis] = std::clamp(p[axis] + i - half, 0, size[axis] - 1);
                        sum += weights[size_t(i)] * values[at(q)];
                    }
                    out[at(p)] = sum;
                }
        values.swap(out);
    }
}

bool light_in_grid(const glm::vec3& light, const Bounds& grid) {
    return glm::all(glm::greaterThanEqual(light, grid.min)) &&
           glm::all(glm::lessThanEqual(light, grid.max));
}

PhotonSource photon_source(const glm::vec3& light, float intensity, const Bounds& grid) {
    PhotonSource source;
    source.light = light;
    source.intensity = intensity;
    source.grid = grid;
    if (light_in_grid(light, grid)) {
        source.kind = PhotonSource::Kind::sphere;
        return source;
    }
    source.axis = glm::normalize(grid.center() - light);
    const glm::vec3 axis = source.axis;
    source.u = glm::normalize(
        glm::cross(axis, std::abs(axis.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0)));
    source.v = glm::cross(axis, source.u);
    // The plane at distance 1 along the axis; its half-size covers every corner's projection.
    for (int c = 0; c < 8; ++c) {
        const glm::vec3 corner((c & 1) ? grid.max.x : grid.min.x, (c & 2) ? grid.max.y : grid.min.y,
                               (c & 4) ? grid.max.z : grid.min.z);
        const glm::vec3 q = corner - light;
        const float t = glm::dot(q, axis);
        if (!(t > 0.0f))
            throw std::invalid_argument(
                "plane_photons: the light must lie outside the grid, "
                "every corner in front of it");
        source.half = std::max({source.half, std::abs(glm::dot(q, source.u)) / t,
                                std::abs(glm::dot(q, source.v)) / t});
    }
    return source;
}

bool source_photon(const PhotonSource& source, glm::vec2 uv, double pdf, int count,
                   MediaPhoton& photon) {
    if (source.kind == PhotonSource::Kind::sphere) {
        const float z = 1.0f - 2.0f * uv.x;
        const float phi = float(2.0 * std::numbers::pi) * uv.y;
        const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        photon = {source.light,
                  {r * std::cos(phi), r * std::sin(phi), z},
                  float(4.0 * std::numbers::pi * source.intensity / (count * pdf))};
        return true;
    }
    const float half = source.half;
    const glm::vec3 q = source.axis + (2.0f * uv.x - 1.0f) * half * source.u +
                        (2.0f * uv.y - 1.0f) * half * source.v;
    const float r = glm::length(q);
    const glm::vec3 dir = q / r;
    float enter = 0.0f, exit = 0.0f;
    if (!ray_box(source.grid, source.light, dir, 0.0f, 1e30f, enter, exit)) return false;
    // Solid angle of the cell: ΔA cosθ / r² with cosθ = 1/r at distance 1.
    const double cell = double(2.0f * half) * double(2.0f * half) / (double(count) * pdf);
    photon = {source.light + enter * dir, dir, float(source.intensity * cell / double(r * r * r))};
    return true;
}

glm::vec2 hammersley(int i, int count, glm::vec2 shift) {
    const glm::vec2 p((float(i) + 0.5f) / float(count), float(radical_inverse(2, uint64_t(i))));
    return glm::fract(p + shift);
}

bool plane_sample(PlaneSampling order, int i, int count, glm::vec2& uv) {
    const auto unit = [](uint32_t a, uint32_t b) {
        return float(hash_u32(hash_u32(a * 0x9E3779B9u + 0x7F4A7C15u) ^ b) >> 8) / float(1u << 24);
    };
    const int side = std::max(1, int(std::sqrt(double(count))));
    switch (order) {
        case PlaneSampling::random:
            uv = {unit(uint32_t(i), 1u), unit(uint32_t(i), 2u)};
            return true;
        case PlaneSampling::halton:
            uv = {float(radical_inverse(2, uint64_t(i) + 1)),
                  float(radical_inverse(3, uint64_t(i) + 1))};
            return true;
        case PlaneSampling::hammersley:
            uv = hammersley(i, count, glm::vec2(0.0f));
            return true;
        default:
            break;
    }
    if (i >= side * side) return false;
    const bool rows = order == PlaneSampling::grid_rows || order == PlaneSampling::jitter_rows;
    const bool jitter =
        order == PlaneSampling::jitter_rows || order == PlaneSampling::jitter_columns;
    const int a = i % side, b = i / side;
    const glm::vec2 cell = rows ? glm::vec2(a, b) : glm::vec2(b, a);
    const glm::vec2 offset =
        jitter ? glm::vec2(unit(uint32_t(i), 3u), unit(uint32_t(i), 4u)) : glm::vec2(0.5f);
    uv = (cell + offset) / float(side);
    return true;
}

std::vector<MediaPhoton> plane_photons(const glm::vec3& light, float intensity, const Bounds& grid,
                                       int count) {
    PhotonSource source = photon_source(light, intensity, grid);
    if (source.kind != PhotonSource::Kind::plane)
        throw std::invalid_argument(
            "plane_photons: the light must lie outside the grid, every corner in front of it");
    std::vector<MediaPhoton> photons;
    photons.reserve(size_t(count));
    MediaPhoton photon;
    for (int i = 0; i < count; ++i)
        if (source_photon(source, hammersley(i, count, glm::vec2(0.0f)), 1.0, count, photon))
            photons.push_back(photon);
    return photons;
}

std::vector<MediaPhoton> sphere_photons(const glm::vec3& light, float intensity, int count) {
    PhotonSource source;
    source.kind = PhotonSource::Kind::sphere;
    source.light = light;
    source.intensity = intensity;
    std::vector<MediaPhoton> photons(static_cast<size_t>(count));
    for (int i = 0; i < count; ++i)
        source_photon(source, hammersley(i, count, glm::vec2(0.0f)), 1.0, count,
                      photons[size_t(i)]);
    return photons;
}

namespace {

// The knots of a bilinear density's `side` + 1 segments along one axis: 0, ½/side, 1½/side, …,
// 1 − ½/side, 1; knot k holds the value of the centre clamp(k − 1, 0, side − 1).
double knot(int k, int side) {
    if (k <= 0) return 0.0;
    if (k > side) return 1.0;
    return (double(k) - 0.5) / double(side);
}
int knot_centre(int k, int side) { return std::clamp(k - 1, 0, side - 1); }

// The fraction s ∈ [0, 1] of a linear segment of length h, values a → b, holding mass `mass`
// from its start: h (a s + (b − a) s²/2) = mass, in the form without cancellation.
double invert_linear(double a, double b, double h, double mass) {
    const double m = mass / h;
    const double root = std::sqrt(std::max(0.0, a * a + 2.0 * (b - a) * m));
    const double denominator = a + root;
    if (!(denominator > 0.0)) return 0.5;
    return std::clamp(2.0 * m / denominator, 0.0, 1.0);
}

// The last index lo in [0, n) with c(lo) ≤ target (c ascending from c(0) = 0, n + 1 values),
// past segments of zero mass.
template <typename Cumulative>
int find_segment(const Cumulative& c, int n, double target) {
    int lo = 0, hi = n;  // c(lo) ≤ target < c(hi)
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (c(mid) <= target)
            lo = mid;
        else
            hi = mid;
    }
    while (lo + 1 < n && c(lo + 1) <= target) ++lo;  // skip empty cells
    return lo;
}

}  // namespace

PhotonDensity::PhotonDensity(int side, const std::vector<float>& cells, bool bilinear)
    : side_(side), bilinear_(bilinear) {
    if (side < 1 || cells.size() != size_t(side) * size_t(side))
        throw std::invalid_argument("PhotonDensity: expected side² cells");
    double total = 0.0;
    for (float c : cells) {
        if (!(c >= 0.0f)) throw std::invalid_argument("PhotonDensity: a negative cell");
        total += c;
    }
    if (!(total > 0.0)) throw std::invalid_argument("PhotonDensity: all cells are zero");
    const double cells_count = double(side) * side;
    pdf_.resize(cells.size());
    for (size_t i = 0; i < cells.size(); ++i) pdf_[i] = double(cells[i]) * cells_count / total;
    if (bilinear) {
        // Along x within each row, and along y over the rows' means: trapezoids between knots.
        const size_t knots = size_t(side) + 2;
        rows_.assign(size_t(side) * knots, 0.0);
        std::vector<double> mean(size_t(side), 0.0);
        for (int y = 0; y < side; ++y) {
            double* row = &rows_[size_t(y) * knots];
            const double* value = &pdf_[size_t(y) * size_t(side)];
            for (int k = 0; k <= side; ++k)
                row[k + 1] =
                    row[k] + 0.5 * (knot(k + 1, side) - knot(k, side)) *
                                 (value[knot_centre(k, side)] + value[knot_centre(k + 1, side)]);
            for (int x = 0; x < side; ++x) mean[size_t(y)] += value[x] / double(side);
        }
        marginal_.assign(knots, 0.0);
        for (int k = 0; k <= side; ++k)
            marginal_[size_t(k) + 1] =
                marginal_[size_t(k)] +
                0.5 * (knot(k + 1, side) - knot(k, side)) *
                    (mean[size_t(knot_centre(k, side))] + mean[size_t(knot_centre(k + 1, side))]);
        return;
    }
    marginal_.assign(size_t(side) + 1, 0.0);
    rows_.assign(size_t(side) * (size_t(side) + 1), 0.0);
    for (int y = 0; y < side; ++y) {
        double* row = &rows_[size_t(y) * (size_t(side) + 1)];
        for (int x = 0; x < side; ++x) row[x + 1] = row[x] + pdf_[size_t(y) * size_t(side) + x];
        marginal_[size_t(y) + 1] = marginal_[size_t(y)] + row[side];
    }
}

double PhotonDensity::pdf(glm::vec2 uv) const {
    if (bilinear_) {
        // Between the centres around uv (clamped at the outer half cells).
        const auto around = [&](float t, int& lo, int& hi, double& f) {
            const double c = std::clamp(double(t) * side_ - 0.5, 0.0, double(side_ - 1));
            lo = std::min(int(c), side_ - 1);
            hi = std::min(lo + 1, side_ - 1);
            f = c - lo;
        };
        int x0, x1, y0, y1;
        double fx, fy;
        around(uv.x, x0, x1, fx);
        around(uv.y, y0, y1, fy);
        const auto at = [&](int x, int y) { return pdf_[size_t(y) * size_t(side_) + size_t(x)]; };
        return (1.0 - fy) * ((1.0 - fx) * at(x0, y0) + fx * at(x1, y0)) +
               fy * ((1.0 - fx) * at(x0, y1) + fx * at(x1, y1));
    }
    const int x = std::clamp(int(uv.x * float(side_)), 0, side_ - 1);
    const int y = std::clamp(int(uv.y * float(side_)), 0, side_ - 1);
    return pdf_[size_t(y) * size_t(side_) + size_t(x)];
}

glm::vec2 PhotonDensity::sample(glm::vec2 uniform) const {
    const double below_one = std::nextafter(1.0, 0.0);
    if (bilinear_) {
        const int n = side_, segments = side_ + 1;
        const size_t knots = size_t(side_) + 2;
        // The marginal along y: linear between the knots, there the row's mean (its profile's
        // integral over x, the last of its cumulative masses).
        const auto row_mean = [&](int k) {
            return rows_[size_t(knot_centre(k, n)) * knots + knots - 1];
        };
        const double ty = double(uniform.y) * marginal_[size_t(segments)];
        const int sy = find_segment([&](int k) { return marginal_[size_t(k)]; }, segments, ty);
        const double hy = knot(sy + 1, n) - knot(sy, n);
        const double fy =
            invert_linear(row_mean(sy), row_mean(sy + 1), hy, ty - marginal_[size_t(sy)]);
        const double y = std::min(knot(sy, n) + fy * hy, below_one);
        // The conditional along x at y: the two knot rows' profiles blended, (1 − fy) and fy.
        const double* lo = &rows_[size_t(knot_centre(sy, n)) * knots];
        const double* hi = &rows_[size_t(knot_centre(sy + 1, n)) * knots];
        const auto cumulative = [&](int k) { return (1.0 - fy) * lo[k] + fy * hi[k]; };
        const double* vlo = &pdf_[size_t(knot_centre(sy, n)) * size_t(n)];
        const double* vhi = &pdf_[size_t(knot_centre(sy + 1, n)) * size_t(n)];
        const auto value = [&](int k) {
            const int c = knot_centre(k, n);
            return (1.0 - fy) * vlo[c] + fy * vhi[c];
        };
        const double tx = double(uniform.x) * cumulative(segments);
        const int sx = find_segment(cumulative, segments, tx);
        const double hx = knot(sx + 1, n) - knot(sx, n);
        const double fx = invert_linear(value(sx), value(sx + 1), hx, tx - cumulative(sx));
        const double x = std::min(knot(sx, n) + fx * hx, below_one);
        return {float(x), float(y)};
    }
    // Inverts a cumulative sum `c` (n + 1 entries, c[0] = 0) at u ∈ [0, 1): the cell and the
    // position inside it, linear within the cell.
    const auto invert = [&](const double* c, int n, double u) {
        const double target = u * c[n];
        const int lo = find_segment([&](int k) { return c[k]; }, n, target);
        const double width = c[lo + 1] - c[lo];
        const double t = width > 0.0 ? std::clamp((target - c[lo]) / width, 0.0, 1.0) : 0.5;
        return std::min((double(lo) + t) / double(n), below_one);
    };
    const double y = invert(marginal_.data(), side_, double(uniform.y));
    const int row = std::clamp(int(y * side_), 0, side_ - 1);
    const double x = invert(&rows_[size_t(row) * (size_t(side_) + 1)], side_, double(uniform.x));
    return {float(x), float(y)};
}

namespace {

glm::ivec3 half_size(const glm::ivec3& s) { return glm::max((s + 1) / 2, glm::ivec3(1)); }

size_t at(const glm::ivec3& size, const glm::ivec3& p) {
    return (size_t(p.z) * size_t(size.y) + size_t(p.y)) * size_t(size.x) + size_t(p.x);
}

// One level down: the [1 3 3 1]/8 filter along each axis in turn, coarse cell i over fine cells
// 2i − 1 … 2i + 2 (clamped at the border).
template <class T>
std::vector<T> downsample(const std::vector<T>& values, const glm::ivec3& size) {
    static const float taps[4] = {0.125f, 0.375f, 0.375f, 0.125f};
    std::vector<T> current = values;
    glm::ivec3 current_size = size;
    for (int axis = 0; axis < 3; ++axis) {
        glm::ivec3 next_size = current_size;
        next_size[axis] = std::max((current_size[axis] + 1) / 2, 1);
        std::vector<T> next(size_t(next_size.x) * size_t(next_size.y) * size_t(next_size.z));
        for (int z = 0; z < next_size.z; ++z)
            for (int y = 0; y < next_size.y; ++y)
                for (int x = 0; x < next_size.x; ++x) {
                    const glm::ivec3 p(x, y, z);
                    T sum{};
                    for (int k = 0; k < 4; ++k) {
                        glm::ivec3 q = p;
                        q[axis] = std::clamp(2 * p[axis] - 1 + k, 0, current_size[axis] - 1);
                        sum += taps[k] * current[at(current_size, q)];
                    }
                    next[at(next_size, p)] = sum;
                }
        current.swap(next);
        current_size = next_size;
    }
    return current;
}

// Box filters over 2 × 2 × 2 children: photon crossings (the sum over the children / 2: a photon
// crossing a voxel twice the size crosses about two of its children) and the mean weight over the
// children with photons (Listing B.2).
void downsample_counts(const std::vector<float>& count, const std::vector<float>& weight,
                       const glm::ivec3& size, std::vector<float>& count_out,
                       std::vector<float>& weight_out) {
    const glm::ivec3 next = half_size(size);
    count_out.assign(size_t(next.x) * size_t(next.y) * size_t(next.z), 0.0f);
    weight_out.assign(count_out.size(), 0.0f);
    for (int z = 0; z < next.z; ++z)
        for (int y = 0; y < next.y; ++y)
            for (int x = 0; x < next.x; ++x) {
                float c = 0.0f, w = 0.0f;
                int with = 0;
                for (int k = 0; k < 8; ++k) {
                    const glm::ivec3 q =
                        2 * glm::ivec3(x, y, z) + glm::ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
                    if (glm::any(glm::greaterThanEqual(q, size))) continue;
                    c += count[at(size, q)];
                    if (weight[at(size, q)] > 0.0f) {
                        w += weight[at(size, q)];
                        ++with;
                    }
                }
                count_out[at(next, {x, y, z})] = 0.5f * c;
                weight_out[at(next, {x, y, z})] = with > 0 ? w / float(with) : 0.0f;
            }
}

// Trilinear read of a level (voxel centres at i + ½) at `g`, in that level's voxel coordinates.
template <class T>
T trilinear(const std::vector<T>& values, const glm::ivec3& size, glm::vec3 g) {
    const glm::vec3 p = g - 0.5f;
    const glm::ivec3 i0 = glm::ivec3(glm::floor(p));
    const glm::vec3 f = p - glm::vec3(i0);
    T r{};
    for (int k = 0; k < 8; ++k) {
        const glm::ivec3 o(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        const glm::ivec3 c = glm::clamp(i0 + o, glm::ivec3(0), size - 1);
        const glm::vec3 w = glm::mix(1.0f - f, f, glm::vec3(o));
        r += (w.x * w.y * w.z) * values[at(size, c)];
    }
    return r;
}

}  // namespace

MediaReconstruction reconstruct_adaptive(const glm::ivec3& size, const std::vector<float>& fluence,
                                         const std::vector<glm::vec3>& flow,
                                         const std::vector<float>& count,
                                         const std::vector<float>& weight, float delta_weight,
                                         int max_level, float significance, bool fractional) {
    std::vector<glm::ivec3> sizes{size};
    std::vector<std::vector<float>> fluence_levels{fluence}, count_levels{count},
        weight_levels{weight};
    std::vector<std::vector<glm::vec3>> flow_levels{flow};
    while (int(sizes.size()) <= max_level &&
           glm::any(glm::greaterThan(sizes.back(), glm::ivec3(1)))) {
        const glm::ivec3 s = sizes.back();
        fluence_levels.push_back(downsample(fluence_levels.back(), s));
        flow_levels.push_back(downsample(flow_levels.back(), s));
        std::vector<float> c, w;
        downsample_counts(count_levels.back(), weight_levels.back(), s, c, w);
        count_levels.push_back(std::move(c));
        weight_levels.push_back(std::move(w));
        sizes.push_back(half_size(s));
    }
    MediaReconstruction out;
    out.max_level = int(sizes.size()) - 1;
    const int top = out.max_level;
    out.fluence.resize(fluence.size());
    out.flow.resize(fluence.size());
    out.level.resize(fluence.size());
    for (int z = 0; z < size.z; ++z)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x) {
                const glm::vec3 centre = glm::vec3(x, y, z) + 0.5f;
                const auto read = [&](const auto& levels, int l) {
                    return trilinear(levels[size_t(l)], sizes[size_t(l)], centre / float(1 << l));
                };
                // Photon weight filter: the mean weight where at least one photon passed, from
                // the first level that has one.
                int w_level = 0;
                while (w_level < top && read(count_levels, w_level) < 1.0f) ++w_level;
                const float w = read(weight_levels, w_level);
                // His ⌊w / Δweight⌋, or (fractional, not his) w / Δweight itself: the voxel
                // reads between the two levels around it, so the filter does not jump where w
                // crosses a multiple of Δweight.
                const float ratio = w / delta_weight;
                const float wl = fractional ? ratio : std::floor(ratio);
                const float weight_level = std::clamp(wl, 0.0f, float(top));
                // Centre-surround filter (Listing B.3): up a level while the difference between
                // successive levels does not grow.
                int level = 0;
                if (top >= 2) {
                    float centre_value = read(fluence_levels, 0);
                    float surround = read(fluence_levels, 1);
                    float diff = std::abs(centre_value - surround);
                    centre_value = surround;
                    surround = read(fluence_levels, 2);
                    float next_diff = std::abs(centre_value - surround);
                    while (next_diff <= diff && level + 2 < top) {
                        ++level;
                        centre_value = surround;
                        surround = read(fluence_levels, level + 2);
                        diff = next_diff;
                        next_diff = std::abs(centre_value - surround);
                    }
                }
                const float combined = std::min(float(level), weight_level);
                level = int(std::ceil(combined));
                // Significance stop (not his; the intersection-of-confidence-intervals rule of
                // adaptive kernel estimation): up a level only while the step from this level's
                // value to the next is within `significance` standard errors, each level's
                // relative error 1/√(photons crossing its voxel). His centre-surround test climbs
                // wherever the differences shrink, which beside a caustic's focus they do after
                // the first level: the voxels beside it read the blurred focus.
                if (significance > 0.0f) {
                    int l = 0;
                    while (l < level) {
                        const float c0 = read(fluence_levels, l), c1 = read(fluence_levels, l + 1);
                        const float n0 = std::max(read(count_levels, l), 1e-3f);
                        const float n1 = std::max(read(count_levels, l + 1), 1e-3f);
                        const float variance = c0 * c0 / n0 + c1 * c1 / n1;
                        if ((c1 - c0) * (c1 - c0) > significance * significance * variance) break;
                        ++l;
                    }
                    level = l;
                }
                // A fractional level l0 + t reads (1 − t) of level l0 and t of level l0 + 1 (the
                // stop may cut it to the integer level where it halted).
                const float final_level = std::min(combined, float(level));
                const int l0 = int(std::floor(final_level));
                const float t = final_level - float(l0);
                const size_t i = at(size, {x, y, z});
                out.level[i] = uint8_t(std::lround(final_level));
                out.fluence[i] = read(fluence_levels, l0);
                out.flow[i] = read(flow_levels, l0);
                if (t > 0.0f) {
                    out.fluence[i] += t * (read(fluence_levels, l0 + 1) - out.fluence[i]);
                    out.flow[i] += t * (read(flow_levels, l0 + 1) - out.flow[i]);
                }
            }
    return out;
}

std::vector<MediaPhoton> quad_photons(const std::array<glm::vec3, 4>& corners, float radiance,
                                      const Bounds& grid, int count) {
    const glm::vec3 e1 = corners[1] - corners[0], e3 = corners[3] - corners[0];
    const glm::vec3 cross = glm::cross(e1, e3);
    const float area = glm::length(cross);
    const glm::vec3 n = cross / area;
    const glm::vec3 t = glm::normalize(e1), b = glm::cross(n, t);
    const float power = float(std::numbers::pi * radiance * area / count);
    std::vector<MediaPhoton> photons;
    photons.reserve(size_t(count));
    for (int i = 0; i < count; ++i) {
        // Position: 2D Hammersley; direction: radical inverses in bases 3 and 5, cosine-weighted.
        const float u = (float(i) + 0.5f) / float(count),
                    v = float(radical_inverse(2, uint64_t(i)));
        const float r2 = float(radical_inverse(3, uint64_t(i)));
        const float phi = float(2.0 * std::numbers::pi * radical_inverse(5, uint64_t(i)));
        const float s = std::sqrt(r2), c = std::sqrt(std::max(0.0f, 1.0f - r2));
        const glm::vec3 dir = s * std::cos(phi) * t + s * std::sin(phi) * b + c * n;
        const glm::vec3 origin = corners[0] + u * e1 + v * e3;
        float enter = 0.0f, exit = 0.0f;
        if (!ray_box(grid, origin, dir, 0.0f, 1e30f, enter, exit)) continue;
        photons.push_back({origin + enter * dir, dir, power});
    }
    return photons;
}

double box_solid_angle(const Bounds& b, const glm::vec3& from) {
    // A rectangle [x1, x2] × [y1, y2] at distance z: Σ ± atan(xy / (z √(x² + y² + z²))).
    const auto rect = [](double x1, double x2, double y1, double y2, double z) {
        const auto f = [z](double x, double y) {
            return std::atan(x * y / (z * std::sqrt(x * x + y * y + z * z)));
        };
        return f(x2, y2) - f(x1, y2) - f(x2, y1) + f(x1, y1);
    };
    double omega = 0.0;
    for (int a = 0; a < 3; ++a) {
        const int i = (a + 1) % 3, j = (a + 2) % 3;
        double z = 0.0;
        if (from[a] < b.min[a])
            z = double(b.min[a]) - from[a];
        else if (from[a] > b.max[a])
            z = double(from[a]) - b.max[a];
        else
            continue;
        omega += rect(double(b.min[i]) - from[i], double(b.max[i]) - from[i],
                      double(b.min[j]) - from[j], double(b.max[j]) - from[j], z);
    }
    return omega;
}

}  // namespace ag
