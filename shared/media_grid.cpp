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

std::vector<MediaPhoton> plane_photons(const glm::vec3& light, float intensity, const Bounds& grid,
                                       int count) {
    const glm::vec3 axis = glm::normalize(grid.center() - light);
    glm::vec3 u =
        glm::cross(axis, std::abs(axis.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0));
    u = glm::normalize(u);
    const glm::vec3 v = glm::cross(axis, u);
    // The plane at distance 1 along the axis; its half-size covers every corner's projection.
    float half = 0.0f;
    for (int c = 0; c < 8; ++c) {
        const glm::vec3 corner((c & 1) ? grid.max.x : grid.min.x, (c & 2) ? grid.max.y : grid.min.y,
                               (c & 4) ? grid.max.z : grid.min.z);
        const glm::vec3 q = corner - light;
        const float t = glm::dot(q, axis);
        if (!(t > 0.0f))
            throw std::invalid_argument(
                "plane_photons: the light must lie outside the grid, "
                "every corner in front of it");
        half = std::max({half, std::abs(glm::dot(q, u)) / t, std::abs(glm::dot(q, v)) / t});
    }
    const double cell = double(2.0f * half) * double(2.0f * half) / double(count);
    std::vector<MediaPhoton> photons;
    photons.reserve(size_t(count));
    for (int i = 0; i < count; ++i) {
        // 2D Hammersley: (i + ½)/N and the base-2 radical inverse.
        const float a = (float(i) + 0.5f) / float(count);
        const float b = float(radical_inverse(2, uint64_t(i)));
        const glm::vec3 q = axis + (2.0f * a - 1.0f) * half * u + (2.0f * b - 1.0f) * half * v;
        const float r = glm::length(q);
        const glm::vec3 dir = q / r;
        float enter = 0.0f, exit = 0.0f;
        if (!ray_box(grid, light, dir, 0.0f, 1e30f, enter, exit)) continue;
        // Solid angle of the cell: ΔA cosθ / r² with cosθ = 1/r at distance 1.
        photons.push_back({light + enter * dir, dir, float(intensity * cell / double(r * r * r))});
    }
    return photons;
}

std::vector<MediaPhoton> sphere_photons(const glm::vec3& light, float intensity, int count) {
    std::vector<MediaPhoton> photons;
    photons.reserve(size_t(count));
    const float power = float(4.0 * std::numbers::pi * intensity / count);
    for (int i = 0; i < count; ++i) {
        const float z = 1.0f - 2.0f * (float(i) + 0.5f) / float(count);
        const float phi = float(2.0 * std::numbers::pi * radical_inverse(2, uint64_t(i)));
        const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        photons.push_back({light, {r * std::cos(phi), r * std::sin(phi), z}, power});
    }
    return photons;
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
