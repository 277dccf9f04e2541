#include "shared/pipeline/media_method.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "cpu/media_tracking.h"
#include "cpu/media_voxelizer.h"
#include "cpu/reference/reference.h"
#include "cpu/sampling.h"
#include "gpu/media_view.h"
#include "shared/media_grid.h"
#include "shared/qmc.h"

namespace ag {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// A number in [0, 1) from a seed and two indices.
float hash_unit(uint32_t seed, uint32_t a, uint32_t b) {
    return float(hash_u32(hash_u32(seed * 0x9E3779B9u + a) ^ (b * 0x85EBCA6Bu))) *
           (1.0f / 4294967296.0f);
}

// The photons that left the grid and met an opaque surface, going on from it (the light surfaces
// send into the media, MediaMethodSettings::surface_bounces): a mirror reflects, anything else
// scatters by the cosine about the normal on the photon's side; each carries its power × the
// surface's grey albedo and starts where its new path enters the grid's box. Outside the box
// there is no medium, so nothing attenuates it on the way. A photon whose surface is glass (the
// grid covers glass, so only at its border) or that meets nothing is gone.
std::vector<MediaPhoton> surface_photons(const Scene& scene, const cpu::RayTracer& rays,
                                         const Bounds& bounds, float voxel,
                                         const std::vector<MediaPhoton>& left, uint32_t seed,
                                         int bounce) {
    std::vector<MediaPhoton> out;
    for (size_t i = 0; i < left.size(); ++i) {
        const MediaPhoton& p = left[i];
        const bool inside = glm::all(glm::greaterThanEqual(p.position, bounds.min)) &&
                            glm::all(glm::lessThan(p.position, bounds.max));
        if (!(p.power > 0.0f) || inside) continue;  // absorbed, or out of steps
        const glm::vec3 d = glm::normalize(p.direction);
        // From a voxel back, where the path was still in the grid and straight (n = 1 there).
        const cpu::RayHit hit = rays.intersect({p.position - voxel * d, d});
        if (!hit.hit) continue;
        const Material& m = scene.objects[size_t(hit.object)].material;
        if (m.type == MaterialType::glass) continue;
        const float albedo = glm::dot(m.albedo, glm::vec3(1.0f / 3.0f));
        if (!(albedo > 0.0f)) continue;
        const glm::vec3 normal = glm::dot(hit.normal, d) < 0.0f ? hit.normal : -hit.normal;
        glm::vec3 direction;
        if (m.type == MaterialType::mirror) {
            direction = glm::reflect(d, normal);
        } else {
            const uint32_t index = uint32_t(i), stream = uint32_t(2 * bounce);
            const float u1 = hash_unit(seed, index, stream),
                        u2 = hash_unit(seed, index, stream + 1);
            const float r = std::sqrt(u1), phi = 2.0f * std::numbers::pi_v<float> * u2;
            const glm::vec3 t = std::abs(normal.x) > 0.5f
                                    ? glm::normalize(glm::cross(normal, glm::vec3(0, 1, 0)))
                                    : glm::normalize(glm::cross(normal, glm::vec3(1, 0, 0)));
            const glm::vec3 b = glm::cross(normal, t);
            direction = r * std::cos(phi) * t + r * std::sin(phi) * b +
                        std::sqrt(std::max(0.0f, 1.0f - u1)) * normal;
        }
        float enter = 0.0f, exit = 0.0f;
        if (!ray_box(bounds, hit.position, direction, 0.0f, 1e30f, enter, exit) || !(exit > enter))
            continue;
        out.push_back({hit.position + enter * direction, direction, p.power * albedo});
    }
    return out;
}

// Photons of the scene's emissive surfaces (not his: his photons leave the one light), whether a
// mesh light or a lamp that is no light ("light": false), none of which the method's light covers
// but whose radiance pt meets on its paths from the fog: `count` Hammersley photons over the front
// faces of every emissive object, a triangle picked in proportion to its power π L̄ A (L̄ the
// emission's grey mean, as the method is grey), a uniform point on it, a cosine direction about
// its front normal; each carries Φ/count, Φ the total, and starts where its path enters the grid's
// box (photons missing the box are dropped: their light never reaches the media). `power` gets Φ.
std::vector<MediaPhoton> emissive_photons(const Scene& scene, const Bounds& bounds, int count,
                                          double& power) {
    struct Emitter {
        glm::vec3 p0, e1, e2, normal;
        double cumulative;  // power up to and including this triangle
    };
    std::vector<Emitter> emitters;
    power = 0.0;
    for (const Object& o : scene.objects) {
        const float l = glm::dot(o.material.emission, glm::vec3(1.0f / 3.0f));
        if (!(l > 0.0f)) continue;
        for (const glm::uvec3& t : o.mesh.triangles) {
            const glm::vec3 p0 = o.transform.apply_point(o.mesh.positions[t.x]);
            const glm::vec3 e1 = o.transform.apply_point(o.mesh.positions[t.y]) - p0;
            const glm::vec3 e2 = o.transform.apply_point(o.mesh.positions[t.z]) - p0;
            const glm::vec3 cross = glm::cross(e1, e2);
            const float twice_area = glm::length(cross);
            if (!(twice_area > 0.0f)) continue;
            power += std::numbers::pi * double(l) * 0.5 * double(twice_area);
            emitters.push_back({p0, e1, e2, cross / twice_area, power});
        }
    }
    std::vector<MediaPhoton> photons;
    if (emitters.empty() || count <= 0) return photons;
    const float each = float(power / double(count));
    for (int i = 0; i < count; ++i) {
        // The first dimension picks the triangle by its power and, rescaled, places the point.
        const double u = (double(i) + 0.5) / double(count) * power;
        const size_t k = std::min(size_t(std::lower_bound(emitters.begin(), emitters.end(), u,
                                                          [](const Emitter& x, double value) {
                                                              return x.cumulative < value;
                                                          }) -
                                         emitters.begin()),
                                  emitters.size() - 1);
        const Emitter& tri = emitters[k];
        const double below = k > 0 ? emitters[k - 1].cumulative : 0.0;
        const float a = float(std::clamp((u - below) / (tri.cumulative - below), 0.0, 1.0));
        const float b = float(radical_inverse(2, uint64_t(i)));
        // Uniform on the triangle: √a folds the square onto it.
        const float sa = std::sqrt(a);
        const glm::vec3 origin = tri.p0 + sa * (1.0f - b) * tri.e1 + sa * b * tri.e2;
        const float r2 = float(radical_inverse(3, uint64_t(i)));
        const float phi = float(2.0 * std::numbers::pi * radical_inverse(5, uint64_t(i)));
        const glm::vec3 t = std::abs(tri.normal.x) > 0.5f
                                ? glm::normalize(glm::cross(tri.normal, glm::vec3(0, 1, 0)))
                                : glm::normalize(glm::cross(tri.normal, glm::vec3(1, 0, 0)));
        const glm::vec3 bt = glm::cross(tri.normal, t);
        const float s = std::sqrt(r2), c = std::sqrt(std::max(0.0f, 1.0f - r2));
        const glm::vec3 dir = s * std::cos(phi) * t + s * std::sin(phi) * bt + c * tri.normal;
        float enter = 0.0f, exit = 0.0f;
        if (!ray_box(bounds, origin, dir, 0.0f, 1e30f, enter, exit) || !(exit > enter)) continue;
        photons.push_back({origin + enter * dir, dir, each});
    }
    return photons;
}

// Phase 1 (ch. 3.2.2): the density over the photon plane from the pilots' statistics, summed
// over blocks of the grid into a coarse grid. For a light inside the grid (free_space) the
// thresholds see the fluence times the squared distance to the light (not his): the free-space
// field of a point light falls as 1/r², whose gradient is no caustic and no shadow border, yet it
// selected every coarse voxel near the light — whose pilots come from every direction, so their
// circles flattened the density — and took the far corners for shadows. With r² taken out, what
// is left to select is where the glass bent or blocked the light (docs/media.md).
// On the sphere of directions (a light inside the grid) the cell's second coordinate is the
// azimuth, periodic: the pilots carry (ox, ox², cos φ, sin φ) and a voxel's mean azimuth and
// spread are circular (the mean resultant's angle; σ = √(−2 ln R̄)), its circle wraps round.
// Plain moments put a voxel lit from both sides of the seam at φ = π, on the wrong side.
std::vector<float> pilot_density(const MediaGrid& grid, const gpu::MediaMarchResult& pilots,
                                 const PhotonSource& source, const MediaAdaptiveSettings& a) {
    const glm::vec3 light = source.light;
    const bool periodic = source.kind == PhotonSource::Kind::sphere;
    const bool free_space = periodic && a.free_space;
    const int longest = std::max({grid.size.x, grid.size.y, grid.size.z});
    const int block = std::max(1, longest / std::max(1, a.coarse));
    const glm::ivec3 coarse = (grid.size + block - 1) / block;
    const size_t cells = size_t(coarse.x) * size_t(coarse.y) * size_t(coarse.z);
    // Per coarse voxel: fluence, crossings, Σ origin x, y, Σ origin² x, y (crossing-weighted).
    std::vector<std::array<double, 6>> sums(cells, std::array<double, 6>{});
    const auto coarse_index = [&](const glm::ivec3& c) {
        return (size_t(c.z) * size_t(coarse.y) + size_t(c.y)) * size_t(coarse.x) + size_t(c.x);
    };
    for (int z = 0; z < grid.size.z; ++z)
        for (int y = 0; y < grid.size.y; ++y)
            for (int x = 0; x < grid.size.x; ++x) {
                const size_t i = grid.index(x, y, z);
                std::array<double, 6>& s = sums[coarse_index(glm::ivec3(x, y, z) / block)];
                const glm::vec3 r = grid.voxel_centre(x, y, z) - light;
                s[0] += double(pilots.fluence[i]) * (free_space ? double(glm::dot(r, r)) : 1.0);
                for (int k = 0; k < 5; ++k) s[size_t(k) + 1] += pilots.stats[5 * i + size_t(k)];
            }
    double mean = 0.0;
    int lit = 0;
    for (const auto& s : sums)
        if (s[1] > 0.0) {
            mean += s[0];
            ++lit;
        }
    const int side = a.pilot_side;
    std::vector<float> density(size_t(side) * size_t(side), 0.0f);
    if (lit > 0) {
        mean /= lit;
        const auto fluence_at = [&](glm::ivec3 c) {
            return sums[coarse_index(glm::clamp(c, glm::ivec3(0), coarse - 1))][0];
        };
        for (int z = 0; z < coarse.z; ++z)
            for (int y = 0; y < coarse.y; ++y)
                for (int x = 0; x < coarse.x; ++x) {
                    const glm::ivec3 c(x, y, z);
                    const std::array<double, 6>& s = sums[coarse_index(c)];
                    if (!(s[1] > 0.0)) continue;
                    // Central differences (one-sided at the border), per coarse voxel.
                    glm::dvec3 gradient;
                    for (int k = 0; k < 3; ++k) {
                        glm::ivec3 lo = c, hi = c;
                        lo[k] = std::max(c[k] - 1, 0);
                        hi[k] = std::min(c[k] + 1, coarse[k] - 1);
                        gradient[k] = hi[k] > lo[k]
                                          ? (fluence_at(hi) - fluence_at(lo)) / (hi[k] - lo[k])
                                          : 0.0;
                    }
                    const bool edge = glm::length(gradient) >= a.gradient * mean;
                    const bool dark = s[0] > 0.0 && s[0] <= a.shadow * mean;
                    if (!edge && !dark) continue;
                    // His circle (Listing B.1): the mean origin, the spread σx + σy as diameter.
                    const double mx = s[2] / s[1];
                    double my = 0.0, sx = 0.0, sy = 0.0;
                    if (periodic) {
                        sx = std::sqrt(std::max(0.0, s[3] / s[1] - mx * mx));
                        const double cosine = s[4] / s[1], sn = s[5] / s[1];
                        const double turn = double(side) / (2.0 * std::numbers::pi);
                        my = std::atan2(sn, cosine) * turn;
                        if (my < 0.0) my += side;
                        const double resultant = std::clamp(std::hypot(cosine, sn), 1e-12, 1.0);
                        sy = std::min(0.5 * side, std::sqrt(-2.0 * std::log(resultant)) * turn);
                    } else {
                        my = s[3] / s[1];
                        sx = std::sqrt(std::max(0.0, s[4] / s[1] - mx * mx));
                        sy = std::sqrt(std::max(0.0, s[5] / s[1] - my * my));
                    }
                    const double r = 0.5 * std::max(1.0, sx + sy);
                    const int x0 = std::max(0, int(std::floor(mx - r))),
                              x1 = std::min(side - 1, int(std::floor(mx + r)));
                    int y0 = int(std::floor(my - r)), y1 = int(std::floor(my + r));
                    if (!periodic) {
                        y0 = std::max(0, y0);
                        y1 = std::min(side - 1, y1);
                    } else if (y1 - y0 >= side) {
                        y1 = y0 + side - 1;
                    }
                    for (int cy = y0; cy <= y1; ++cy)
                        for (int cx = x0; cx <= x1; ++cx) {
                            const double dx = cx + 0.5 - mx, dy = cy + 0.5 - my;
                            if (dx * dx + dy * dy <= r * r ||
                                (cx == int(mx) && cy == int(std::floor(my)))) {
                                const int wy = ((cy % side) + side) % side;
                                density[size_t(wy) * size_t(side) + size_t(cx)] += 1.0f;
                            }
                        }
                }
    }
    // Relative to the densest cell, plus the background, then his 5 × 5 Gaussian (variance 2).
    const float peak = *std::max_element(density.begin(), density.end());
    for (float& d : density) d = (peak > 0.0f ? d / peak : 0.0f) + a.background;
    std::vector<float> smooth(density.size(), 0.0f);
    for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
            float sum = 0.0f, weight = 0.0f;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx) {
                    const int qx = x + dx;
                    int qy = y + dy;
                    if (periodic) qy = (qy + side) % side;
                    if (qx < 0 || qy < 0 || qx >= side || qy >= side) continue;
                    const float w = std::exp(-float(dx * dx + dy * dy) / 4.0f);
                    sum += w * density[size_t(qy) * size_t(side) + size_t(qx)];
                    weight += w;
                }
            smooth[size_t(y) * size_t(side) + size_t(x)] = sum / weight;
        }
    return smooth;
}

gpu::MediaMarchResult march_adaptive(const MediaGrid& grid, const PhotonSource& source,
                                     const MediaMethodSettings& settings,
                                     const gpu::MediaMarchSettings& march,
                                     const gpu::MediaMarcher& marcher, MediaMethodResult& result) {
    const MediaAdaptiveSettings& a = settings.adaptive;
    if (a.pilot_side < 1 || a.coarse < 1 || !(a.background > 0.0f) || !(a.delta_weight > 0.0f))
        throw std::invalid_argument(
            "adaptive media pipeline: pilot_side, coarse, background and delta_weight must be "
            "positive");
    // Phase 1: pilots on a jittered side × side grid, each knowing its cell (ch. 3.2.2).
    Clock::time_point start = Clock::now();
    const int side = a.pilot_side;
    std::vector<MediaPhoton> pilots;
    std::vector<glm::vec4> origins;
    pilots.reserve(size_t(side) * size_t(side));
    MediaPhoton photon;
    for (int cy = 0; cy < side; ++cy)
        for (int cx = 0; cx < side; ++cx) {
            const uint32_t cell = uint32_t(cy * side + cx);
            const glm::vec2 jitter(hash_unit(a.seed, cell, 1) - 0.5f,
                                   hash_unit(a.seed, cell, 2) - 0.5f);
            const glm::vec2 uv = (glm::vec2(cx, cy) + 0.5f + 0.5f * jitter) / float(side);
            if (!source_photon(source, uv, 1.0, side * side, photon)) continue;
            pilots.push_back(photon);
            const float ox = float(cx) + 0.5f, oy = float(cy) + 0.5f;
            if (source.kind == PhotonSource::Kind::sphere) {
                const float phi = 2.0f * std::numbers::pi_v<float> * oy / float(side);
                origins.emplace_back(ox, ox * ox, std::cos(phi), std::sin(phi));
            } else {
                origins.emplace_back(ox, oy, ox * ox, oy * oy);
            }
        }
    result.pilots_marched = pilots.size();
    result.timing.pilot_generation = since(start);
    const gpu::MediaMarchResult piloted = marcher.march(grid, pilots, march, origins, 5);
    result.timing.pilot_marching = piloted.seconds;
    result.timing.octree += piloted.octree_seconds;

    start = Clock::now();
    const PhotonDensity density(side, pilot_density(grid, piloted, source, a), a.bilinear_density);
    result.density = density.cells();
    result.timing.distribution = since(start);

    // Phase 2 (ch. 3.2.3): N photons whose points have density N p over the square, each
    // weighted by 1/(N p), his estimator. On a photon plane, his: Hammersley points through the
    // density. For a light inside the grid (stratified; not his) the density (mean 1) keeps its
    // floor b and spreads its excess mass 1 − b evenly over the cells whose excess is above
    // `dense_cut` of the peak's: two levels, drawn as two sets, N b Hammersley points over the
    // whole square (uniform, the reference pipeline's) and the rest over those cells. Every
    // voxel near a light inside the grid sums photons from all directions, and with his one
    // warped set through a smooth density that sum runs over photons whose weight jumps at every
    // cell edge: white noise where uniform Hammersley points converge fast. Two levels leave one
    // jump, along the selected region's border; the uniform set keeps the smooth field as the
    // reference pipeline has it (docs/media.md). The sets together have the density N p of the
    // two-level density (exactly: each weight uses the rounded counts), so the sum stays
    // unbiased.
    start = Clock::now();
    const int count = settings.photons;
    const glm::vec2 shift =
        a.seed == 0 ? glm::vec2(0.0f) : glm::vec2(hash_unit(a.seed, 0, 3), hash_unit(a.seed, 0, 4));
    const bool stratified = source.kind == PhotonSource::Kind::sphere && a.stratified;
    int uniform_count = 0;
    PhotonDensity excess;
    if (stratified) {
        const std::vector<double>& cells = density.cells();
        const double floor_density = *std::min_element(cells.begin(), cells.end());
        const double peak = *std::max_element(cells.begin(), cells.end()) - floor_density;
        std::vector<float> dense(cells.size(), 0.0f);
        bool any = false;
        for (size_t i = 0; i < cells.size(); ++i)
            if (cells[i] - floor_density > a.dense_cut * peak) {
                dense[i] = 1.0f;
                any = true;
            }
        if (any && peak > 0.0) {
            uniform_count = int(std::lround(double(count) * floor_density));
            excess = PhotonDensity(side, dense);
        }
    }
    const int excess_count = count - uniform_count;
    // The density of the points (mean 1) at uv.
    const auto point_pdf = [&](glm::vec2 uv) {
        if (uniform_count == 0) return density.pdf(uv);
        return (double(uniform_count) + double(excess_count) * excess.pdf(uv)) / double(count);
    };
    std::vector<MediaPhoton> photons;
    std::vector<glm::vec4> inverse_density;
    photons.reserve(size_t(count));
    for (int i = 0; i < count; ++i) {
        glm::vec2 uv;
        if (uniform_count == 0)
            uv = density.sample(hammersley(i, count, shift));
        else if (i < uniform_count)
            uv = hammersley(i, uniform_count, shift);
        else
            uv = excess.sample(hammersley(i - uniform_count, excess_count, shift));
        const double p = point_pdf(uv);
        if (!source_photon(source, uv, p, count, photon)) continue;
        photons.push_back(photon);
        inverse_density.emplace_back(float(1.0 / p), 0.0f, 0.0f, 0.0f);
    }
    result.photons_marched = photons.size();
    result.timing.photon_generation = since(start);
    gpu::MediaMarchResult marched = marcher.march(grid, photons, march, inverse_density, 2);
    result.timing.photon_marching = marched.seconds;
    result.timing.octree += marched.octree_seconds;
    const glm::vec3 voxel = grid.voxel_size();
    for (float f : marched.fluence)
        result.power_deposited += double(f) * voxel.x * voxel.y * voxel.z;
    if (!a.reconstruct) return marched;

    // Reconstruction (ch. 3.2.4): his photon count and mean weight 1/(N p) per voxel.
    start = Clock::now();
    const size_t voxels = grid.voxel_count();
    std::vector<float> crossings(voxels), weight(voxels);
    for (size_t i = 0; i < voxels; ++i) {
        crossings[i] = marched.stats[2 * i];
        weight[i] =
            crossings[i] > 0.0f ? marched.stats[2 * i + 1] / crossings[i] / float(count) : 0.0f;
    }
    // For a light inside the grid (free_space; not his) the pyramid filters fluence × r² and
    // r² is divided out after: blurring the light's convex 1/r² field raised the fog's mean by
    // 0.4% at 50,000 photons on fog_sphere_point, its free-space field × r² is flat.
    std::vector<float> falloff(voxels, 1.0f);
    if (source.kind == PhotonSource::Kind::sphere && a.free_space)
        for (int z = 0; z < grid.size.z; ++z)
            for (int y = 0; y < grid.size.y; ++y)
                for (int x = 0; x < grid.size.x; ++x) {
                    const glm::vec3 r = grid.voxel_centre(x, y, z) - source.light;
                    falloff[grid.index(x, y, z)] = glm::dot(r, r);
                }
    for (size_t i = 0; i < voxels; ++i) {
        marched.fluence[i] *= falloff[i];
        marched.flow[i] *= falloff[i];
    }
    // Δweight is set for 64 voxels along the grid's longest side and scales with the voxel edge
    // (not his): a finer grid has fewer crossings a voxel for the same weights, and its levels
    // blur less in world units. At 128³ the unscaled 2·10⁻⁵ left fog_sphere_point's fog
    // unfiltered at 100,000 photons (RMSE 0.00091; scaled 0.00070, uniform 200k 0.00075).
    const int longest = std::max({grid.size.x, grid.size.y, grid.size.z});
    const float delta_weight = a.delta_weight * 64.0f / float(longest);
    MediaReconstruction filtered =
        reconstruct_adaptive(grid.size, marched.fluence, marched.flow, crossings, weight,
                             delta_weight, a.max_level, a.significance, a.fractional_level);
    result.timing.reconstruction = since(start);
    result.levels = std::move(filtered.level);
    marched.fluence = std::move(filtered.fluence);
    marched.flow = std::move(filtered.flow);
    for (size_t i = 0; i < voxels; ++i) {
        marched.fluence[i] /= falloff[i];
        marched.flow[i] /= falloff[i];
    }
    return marched;
}

}  // namespace

MediaMethodResult render_media(const Scene& scene, const MediaMethodSettings& settings,
                               bool with_view) {
    Bounds bounds;
    for (const Medium& m : scene.media) {
        bounds.add(m.bounds.min);
        bounds.add(m.bounds.max);
    }
    for (const Object& o : scene.objects)
        if (o.material.type == MaterialType::glass)
            for (const glm::vec3& p : o.mesh.positions) bounds.add(o.transform.apply_point(p));
    if (bounds.empty())
        throw std::invalid_argument(scene.path + ": the media method needs media or glass");
    // The first enabled point or spot light (spot cones ignored), else the first quad light.
    const Light* light = nullptr;
    for (const Light& l : scene.lights)
        if (l.enabled && (l.type == LightType::point || l.type == LightType::spot)) {
            light = &l;
            break;
        }
    for (const Light& l : scene.lights)
        if (!light && l.enabled && l.type == LightType::quad) light = &l;
    if (!light)
        throw std::invalid_argument(
            scene.path + ": the media method needs an enabled point, spot or quad light");
    // Cubic voxels, `grid` along the longest side.
    const glm::vec3 extent = bounds.extent();
    const float voxel = std::max({extent.x, extent.y, extent.z}) / float(settings.grid);
    const glm::ivec3 size = glm::max(glm::ivec3(glm::ceil(extent / voxel)), glm::ivec3(1));
    bounds.max = bounds.min + glm::vec3(size) * voxel;

    MediaMethodResult result;
    result.grid = size;
    Clock::time_point start = Clock::now();
    const cpu::RayTracer rays(scene);
    MediaGrid grid = cpu::voxelize_media(scene, rays, bounds, size);
    result.timing.voxelisation = since(start);
    start = Clock::now();
    gaussian_smooth(grid.n, grid.size, 9, 1.5f);  // his 9³ Gaussian, σ = 9/6
    result.timing.smoothing = since(start);
    // The mean of the light's RGB value: the method is grey (Medium is grey).
    const float intensity = glm::dot(light->value(), glm::vec3(1.0f / 3.0f));
    // His photon plane for a point light outside the grid; from the light itself where it is
    // inside; from its surface for a quad light.
    const bool inside = light_in_grid(light->position, bounds);
    start = Clock::now();
    gpu::MediaMarchSettings march;
    march.step = settings.march_step;
    march.deposit = settings.deposit;
    march.octree = settings.octree;
    const gpu::MediaMarcher marcher;
    gpu::MediaMarchResult marched;
    // Marches `photons` on the grid and adds their fluence and flow into `into` and the power they
    // deposit into `power`; returns the march (its photons left for the next bounce).
    const auto march_into = [&](const std::vector<MediaPhoton>& photons,
                                gpu::MediaMarchResult& into, double& power) {
        gpu::MediaMarchResult lit = marcher.march(grid, photons, march);
        result.timing.photon_marching += lit.seconds;
        result.timing.octree += lit.octree_seconds;
        for (size_t i = 0; i < into.fluence.size(); ++i) {
            into.fluence[i] += lit.fluence[i];
            into.flow[i] += lit.flow[i];
            power += double(lit.fluence[i]) * double(voxel) * voxel * voxel;
        }
        return lit;
    };
    // The emissive surfaces' photons (emissive_photons), marched into `into` (their photons left
    // after the march appended to `left` for the surface bounces, where there are any). As many as
    // give each about the power of one of the light's photons, but at least
    // settings.emissive_photons.
    const auto march_emissive = [&](gpu::MediaMarchResult& into, std::vector<MediaPhoton>* left) {
        if (settings.emissive_photons <= 0) return;
        double emitted = 0.0;
        emissive_photons(scene, bounds, 0, emitted);
        if (!(emitted > 0.0)) return;
        const double light_power =
            light->type == LightType::quad
                ? std::numbers::pi * double(intensity) * double(light->quad_area())
                : double(intensity) *
                      (inside ? 4.0 * std::numbers::pi : box_solid_angle(bounds, light->position));
        const double share = light_power > 0.0 ? emitted / light_power : 1.0;
        const int count =
            int(std::clamp(double(settings.photons) * share, double(settings.emissive_photons),
                           4.0 * settings.photons));
        Clock::time_point begin = Clock::now();
        const std::vector<MediaPhoton> photons = emissive_photons(scene, bounds, count, emitted);
        result.timing.photon_generation += since(begin);
        if (photons.empty()) return;
        const gpu::MediaMarchResult lit = march_into(photons, into, result.power_emissive);
        result.photons_emissive += photons.size();
        if (left) left->insert(left->end(), lit.photons.begin(), lit.photons.end());
    };
    if (!settings.adaptive.enabled) {
        std::vector<MediaPhoton> photons;
        if (light->type == LightType::quad) {
            photons = quad_photons(light->corners, intensity, bounds, settings.photons);
        } else if (settings.sampling == PlaneSampling::hammersley) {
            photons = inside ? sphere_photons(light->position, intensity, settings.photons)
                             : plane_photons(light->position, intensity, bounds, settings.photons);
        } else {
            const PhotonSource source = photon_source(light->position, intensity, bounds);
            int count = settings.photons;
            if (settings.sampling != PlaneSampling::random &&
                settings.sampling != PlaneSampling::halton) {
                const int side = std::max(1, int(std::sqrt(double(count))));
                count = side * side;
            }
            glm::vec2 uv;
            MediaPhoton photon;
            for (int i = 0; i < count; ++i)
                if (plane_sample(settings.sampling, i, count, uv) &&
                    source_photon(source, uv, 1.0, count, photon))
                    photons.push_back(photon);
        }
        result.photons_marched = photons.size();
        result.timing.photon_generation = since(start);
        marched = marcher.march(grid, photons, march);
        result.timing.photon_marching = marched.seconds;
        result.timing.octree += marched.octree_seconds;
        for (float f : marched.fluence)
            result.power_deposited += double(f) * double(voxel) * voxel * voxel;
        std::vector<MediaPhoton> left = std::move(marched.photons);
        march_emissive(marched, &left);
        for (int bounce = 0; bounce < settings.surface_bounces; ++bounce) {
            start = Clock::now();
            std::vector<MediaPhoton> from_surfaces =
                surface_photons(scene, rays, bounds, voxel, left, settings.seed, bounce);
            result.timing.photon_generation += since(start);
            if (from_surfaces.empty()) break;
            gpu::MediaMarchResult again = march_into(from_surfaces, marched, result.power_bounced);
            result.photons_bounced += from_surfaces.size();
            left = std::move(again.photons);
        }
    } else {
        if (light->type == LightType::quad)
            throw std::invalid_argument(
                scene.path +
                ": the adaptive media pipeline needs a point or spot light (a photon plane)");
        marched = march_adaptive(grid, photon_source(light->position, intensity, bounds), settings,
                                 march, marcher, result);
        // Unfiltered: the adaptive reconstruction is of the light's photons.
        march_emissive(marched, nullptr);
    }
    if (!with_view) {
        result.grids = std::move(grid);
        result.fluence = std::move(marched.fluence);
        result.flow = std::move(marched.flow);
        return result;
    }

    result.grids = std::move(grid);
    result.fluence = std::move(marched.fluence);
    result.flow = std::move(marched.flow);
    result.tint = intensity > 0.0f ? light->value() / intensity : glm::vec3(0.0f);
    Camera camera = scene.camera;
    if (settings.width > 0 && settings.height > 0) {
        camera.width = settings.width;
        camera.height = settings.height;
    }
    start = Clock::now();
    result.volume = view_media(scene, result, camera, settings, &result.transmittance);
    result.indirect = view_fog_on_surfaces(scene, result, camera, settings);
    if (settings.through_glass)
        result.specular = view_through_glass(scene, result, camera, settings, &result.glass);
    result.timing.viewing = since(start);
    return result;
}

// Mirrors the fog's light on the surfaces is followed through (view_fog_on_surfaces).
constexpr int kFogMirrorBounces = 2;

// Ratio-tracking estimates averaged per pixel for the camera ray's transmittance in perturbed
// media (homogeneous ones are exact with one).
constexpr int kTransmittanceEstimates = 8;

Image view_media(const Scene& scene, const MediaMethodResult& media, const Camera& camera,
                 const MediaMethodSettings& settings, Image* transmittance) {
    // The view march stops at the first surface the camera ray meets (the volume term's
    // definition; the straight ray, as the frame's other terms see it).
    const cpu::RayTracer rays(scene);
    const cpu::MediaTracker tracker(scene);
    std::vector<float> max_distance(size_t(camera.width) * size_t(camera.height));
    if (transmittance) *transmittance = Image(camera.width, camera.height);
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const cpu::Ray ray{camera.eye,
                               camera_ray_direction(camera, float(x) + 0.5f, float(y) + 0.5f)};
            const cpu::RayHit hit = rays.intersect(ray);
            const size_t i = size_t(y) * size_t(camera.width) + size_t(x);
            max_distance[i] = hit.hit ? hit.t : 1e30f;
            if (!transmittance) continue;
            // What dims the surface the straight camera ray meets, as pt's delta tracking does:
            // exact in homogeneous media; the mean of kTransmittanceEstimates ratio-tracking
            // estimates in perturbed ones. Along the straight ray, not the view march's bent one:
            // near glass the smoothed index bends the march into the glass's absorbing interior.
            float sum = 0.0f;
            for (int k = 0; k < kTransmittanceEstimates; ++k) {
                cpu::HashedStream more(cpu::mix64(i * kTransmittanceEstimates + size_t(k)));
                sum += tracker.transmittance(ray, max_distance[i], -1, more);
            }
            transmittance->set_rgb(x, y, glm::vec3(sum / float(kTransmittanceEstimates)));
        }
    gpu::MediaViewSettings view;
    view.step = settings.view_step;
    view.phase_k = scene.media.empty() ? 0.0f : scene.media[0].phase_k;
    view.phase_spread = settings.phase_spread;
    Image volume =
        gpu::MediaView().render(media.grids, media.fluence, media.flow, camera, view, max_distance);
    // Grey to the light's colour.
    for (int y = 0; y < volume.height; ++y)
        for (int x = 0; x < volume.width; ++x) volume.set_rgb(x, y, volume.rgb(x, y) * media.tint);
    return volume;
}

Image view_fog_on_surfaces(const Scene& scene, const MediaMethodResult& media, const Camera& camera,
                           const MediaMethodSettings& settings) {
    Image out(camera.width, camera.height);
    const int n = settings.fog_on_surfaces_rays;
    if (n <= 0 || media.fluence.empty()) return out;
    const cpu::RayTracer rays(scene);
    const cpu::MediaTracker tracker(scene);
    const float eps = rays.epsilon();
    // Every march ray, the pixel it adds to and its weight: albedo / N × the light's colour,
    // times the transmittance up to the mirror that reflected it, where one did.
    std::vector<gpu::MediaViewRay> march;
    struct Share {
        int x, y;
        glm::vec3 weight;
    };
    std::vector<Share> shares;
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const cpu::Ray ray{camera.eye,
                               camera_ray_direction(camera, float(x) + 0.5f, float(y) + 0.5f)};
            const cpu::RayHit hit = rays.intersect(ray);
            if (!hit.hit) continue;
            const Object& object = scene.objects[size_t(hit.object)];
            if (object.material.type != MaterialType::diffuse) continue;
            if (glm::dot(ray.direction, hit.normal) >= 0.0f) continue;  // lightmaps: front only
            const glm::vec3 albedo = albedo_at(object, hit.triangle, hit.barycentric);
            if (!glm::any(glm::greaterThan(albedo, glm::vec3(0.0f)))) continue;
            // A Hammersley set over the hemisphere, rotated per pixel (Cranley-Patterson).
            const uint32_t pixel = uint32_t(y) * uint32_t(camera.width) + uint32_t(x);
            const float r1 = hash_unit(settings.seed ^ 0x6f67u, pixel, 0u);
            const float r2 = hash_unit(settings.seed ^ 0x6f67u, pixel, 1u);
            for (int k = 0; k < n; ++k) {
                const float u1 = std::fmod((float(k) + 0.5f) / float(n) + r1, 1.0f);
                const float u2 = std::fmod(float(radical_inverse(2, uint64_t(k))) + r2, 1.0f);
                cpu::Ray r{hit.position + eps * hit.normal,
                           cpu::cosine_direction(hit.normal, u1, u2)};
                glm::vec3 weight = albedo / float(n) * media.tint;
                // Up to kFogMirrorBounces mirrors on the way (pt's paths from the surface go on
                // through them to the fog behind): the march goes on from each, dimmed by the
                // media up to it.
                for (int bounce = 0; bounce <= kFogMirrorBounces; ++bounce) {
                    const cpu::RayHit next = rays.intersect(r);
                    gpu::MediaViewRay m;
                    m.origin = r.origin;
                    m.direction = r.direction;
                    m.max_distance = next.hit ? next.t : 1e30f;
                    march.push_back(m);
                    shares.push_back({x, y, weight});
                    if (!next.hit ||
                        scene.objects[size_t(next.hit ? next.object : 0)].material.type !=
                            MaterialType::mirror ||
                        glm::dot(r.direction, next.normal) >= 0.0f)
                        break;
                    cpu::HashedStream more(cpu::mix64(uint64_t(pixel) * 4096u + uint64_t(k)));
                    weight *= tracker.transmittance(r, next.t, -1, more);
                    r = cpu::specular_split(scene.objects[size_t(next.object)].material, next,
                                            r.direction, eps)
                            .reflected;
                }
            }
        }
    gpu::MediaViewSettings view;
    view.step = settings.fog_on_surfaces_step;
    view.phase_k = scene.media.empty() ? 0.0f : scene.media[0].phase_k;
    view.phase_spread = settings.phase_spread;
    const std::vector<gpu::MediaViewEnd> ends =
        gpu::MediaView().march(media.grids, media.fluence, media.flow, march, view);
    for (size_t i = 0; i < shares.size(); ++i)
        out.set_rgb(shares[i].x, shares[i].y,
                    out.rgb(shares[i].x, shares[i].y) + ends[i].radiance * shares[i].weight);
    return out;
}

namespace {

// Mirrors and glass followed behind the glass (surface_radiance) up to this many bounces; glass
// splits into its reflected and refracted rays, so at most 2^kBehindGlassBounces paths a pixel.
constexpr int kBehindGlassBounces = 4;

// The light a surface sends back along `ray` to where the ray started: a diffuse surface's
// emission and its albedo/π × the direct irradiance from the scene's lights (shadowed,
// attenuated by the media); a mirror's or glass's, that of the rays it reflects and refracts
// (Fresnel-weighted, both followed, kBehindGlassBounces deep); times the media's transmittance
// on the way (`inside`: the glass object the ray travels in, −1 for none). Black where the ray
// meets nothing or a diffuse back face. Not the fog's single scattering on these rays, nor the
// surfaces' indirect light.
glm::vec3 surface_radiance(const Scene& scene, const cpu::RayTracer& rays,
                           const cpu::MediaTracker& tracker, const cpu::Ray& ray, uint64_t key,
                           int inside = -1, int depth = 0) {
    const cpu::RayHit hit = rays.intersect(ray);
    if (!hit.hit) return glm::vec3(0.0f);
    const Object& object = scene.objects[size_t(hit.object)];
    cpu::HashedStream more(key);
    const float transmittance = tracker.transmittance(ray, hit.t, inside, more);
    if (object.material.type != MaterialType::diffuse) {
        if (depth >= kBehindGlassBounces) return glm::vec3(0.0f);
        const cpu::SpecularSplit split =
            cpu::specular_split(object.material, hit, ray.direction, rays.epsilon());
        const uint64_t next = cpu::mix64(key + 0x9e3779b97f4a7c15ull);
        glm::vec3 radiance =
            split.reflectance *
            surface_radiance(scene, rays, tracker, split.reflected, next ^ 1u, inside, depth + 1);
        if (object.material.type == MaterialType::glass && split.reflectance < 1.0f) {
            const bool entering = glm::dot(ray.direction, hit.normal) < 0.0f;
            radiance += (1.0f - split.reflectance) *
                        surface_radiance(scene, rays, tracker, split.refracted, next ^ 2u,
                                         entering ? hit.object : -1, depth + 1);
        }
        return radiance * transmittance;
    }
    if (glm::dot(ray.direction, hit.normal) >= 0.0f) return glm::vec3(0.0f);
    glm::vec3 radiance = object.material.emission;
    const glm::vec3 albedo = albedo_at(object, hit.triangle, hit.barycentric);
    if (glm::any(glm::greaterThan(albedo, glm::vec3(0.0f))))
        radiance += albedo / std::numbers::pi_v<float> *
                    cpu::direct_irradiance(scene, rays, hit.position, hit.normal, 16, 0.5f, 0.5f,
                                           &tracker, &more);
    return radiance * transmittance;
}

}  // namespace

Image view_through_glass(const Scene& scene, const MediaMethodResult& media, const Camera& camera,
                         const MediaMethodSettings& settings, std::vector<uint8_t>* glass) {
    const cpu::RayTracer rays(scene);
    const cpu::MediaTracker tracker(scene);
    const float eps = rays.epsilon();
    Image out(camera.width, camera.height);
    if (glass) glass->assign(size_t(camera.width) * size_t(camera.height), 0);
    // The pixels whose camera ray meets glass first: its Fresnel reflection there (marched
    // through the fog to the surface it shows: his isosurface reflection, with the fog), and the
    // march on into it.
    struct Pixel {
        int x = 0, y = 0;
        glm::vec3 reflected{0.0f};  // F × T to the glass × the surface the reflected ray shows
        float reflectance = 0.0f;   // F × T to the glass
        float transmitted = 0.0f;   // 1 − F at the entry
        float ior = 1.5f;
    };
    std::vector<Pixel> pixels;
    std::vector<gpu::MediaViewRay> entering, reflecting;
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const glm::vec3 d = camera_ray_direction(camera, float(x) + 0.5f, float(y) + 0.5f);
            const cpu::RayHit hit = rays.intersect({camera.eye, d});
            if (!hit.hit) continue;
            const Material& m = scene.objects[size_t(hit.object)].material;
            if (m.type != MaterialType::glass) continue;
            if (glass) (*glass)[size_t(y) * size_t(camera.width) + size_t(x)] = 1;
            const uint64_t key = cpu::mix64(uint64_t(y) * uint64_t(camera.width) + uint64_t(x));
            const cpu::SpecularSplit split = cpu::specular_split(m, hit, d, eps);
            cpu::HashedStream more(key);
            Pixel p{x, y, glm::vec3(0.0f), 0.0f, 1.0f - split.reflectance, m.ior};
            p.reflectance =
                split.reflectance * tracker.transmittance({camera.eye, d}, hit.t, -1, more);
            p.reflected =
                p.reflectance * surface_radiance(scene, rays, tracker, split.reflected, key ^ 1u);
            pixels.push_back(p);
            gpu::MediaViewRay back;
            back.origin = split.reflected.origin;
            back.direction = glm::normalize(split.reflected.direction);
            const cpu::RayHit seen = rays.intersect(split.reflected);
            back.max_distance = seen.hit ? seen.t : 1e30f;
            reflecting.push_back(back);
            gpu::MediaViewRay r;
            r.origin = camera.eye;
            r.direction = d;
            r.split = hit.t;  // the light scattered before the glass is the volume term's
            // Once in the glass (its smoothed index begins), until back in air: a grazing ray
            // may never reach the index deep inside.
            r.n_leave = 1.0f + 0.01f * (m.ior - 1.0f);
            entering.push_back(r);
        }
    gpu::MediaViewSettings view;
    view.step = settings.view_step;
    view.phase_k = scene.media.empty() ? 0.0f : scene.media[0].phase_k;
    view.phase_spread = settings.phase_spread;
    const gpu::MediaView marcher;
    const std::vector<gpu::MediaViewEnd> inside =
        marcher.march(media.grids, media.fluence, media.flow, entering, view);
    // Out of the glass bent: straight on through the fog to the surface behind (n = 1 there).
    std::vector<gpu::MediaViewRay> behind(pixels.size());
    std::vector<float> leaving(pixels.size(), 0.0f);  // 1 − F where the ray leaves the glass
    for (size_t i = 0; i < pixels.size(); ++i) {
        if (!inside[i].ended) continue;  // out of steps: lost
        const glm::vec3 o = inside[i].position, d = inside[i].direction;
        behind[i].origin = o;
        behind[i].direction = d;
        const cpu::RayHit hit = rays.intersect({o, d});
        behind[i].max_distance = hit.hit ? hit.t : 1e30f;
        // The exit's Fresnel factor, from the glass surface the bent ray came out of (F is the
        // same from either side).
        const cpu::RayHit back = rays.intersect({o, -d});
        if (back.hit && scene.objects[size_t(back.object)].material.type == MaterialType::glass) {
            float cos_t = 0.0f;
            leaving[i] = 1.0f - cpu::fresnel_dielectric(std::abs(glm::dot(d, back.normal)),
                                                        1.0f / pixels[i].ior, cos_t);
        } else {
            leaving[i] = 1.0f;
        }
    }
    const std::vector<gpu::MediaViewEnd> after =
        marcher.march(media.grids, media.fluence, media.flow, behind, view);
    const std::vector<gpu::MediaViewEnd> reflected =
        marcher.march(media.grids, media.fluence, media.flow, reflecting, view);
    for (size_t i = 0; i < pixels.size(); ++i) {
        const Pixel& p = pixels[i];
        glm::vec3 seen = inside[i].radiance * media.tint;
        if (inside[i].ended) {
            const uint64_t key = cpu::mix64(uint64_t(p.y) * uint64_t(camera.width) + uint64_t(p.x));
            const glm::vec3 surface = surface_radiance(
                scene, rays, tracker, {behind[i].origin, behind[i].direction}, key ^ 2u);
            // `surface` carries the fog's transmittance from the exit to the surface already.
            seen +=
                leaving[i] * inside[i].transmittance * (after[i].radiance * media.tint + surface);
        }
        out.set_rgb(p.x, p.y,
                    p.reflected + p.reflectance * reflected[i].radiance * media.tint +
                        p.transmitted * seen);
    }
    return out;
}

Image media_slice_view(const MediaMethodResult& media, MediaField field, int axis, int layer,
                       int width, int height) {
    const MediaGrid& grid = media.grids;
    Image out(width, height);
    std::vector<float> values;
    switch (field) {
        case MediaField::n:
            values = grid.n;
            for (float& v : values) v -= 1.0f;
            break;
        case MediaField::sigma_s:
            values = grid.sigma_s;
            break;
        case MediaField::fluence:
            values = media.fluence;
            break;
        case MediaField::level:
            values.assign(media.levels.begin(), media.levels.end());
            break;
    }
    if (values.size() != grid.voxel_count() || grid.voxel_count() == 0) return out;
    axis = std::clamp(axis, 0, 2);
    const Image slice = grid_slice(grid, values, axis, std::clamp(layer, 0, grid.size[axis] - 1));
    float peak = 0.0f;
    for (float v : slice.pixels) peak = std::max(peak, std::abs(v));
    const float scale = peak > 0.0f ? 1.0f / peak : 0.0f;
    // Fit: the largest whole scale of voxels to pixels that fits, else a fraction of one.
    const float fit =
        std::min(float(width) / float(slice.width), float(height) / float(slice.height));
    const int w = std::max(1, int(fit * float(slice.width))),
              h = std::max(1, int(fit * float(slice.height)));
    const int x0 = (width - w) / 2, y0 = (height - h) / 2;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int sx = std::min(slice.width - 1, int(float(x) / fit));
            const int sy = std::min(slice.height - 1, int(float(y) / fit));
            out.set_rgb(x0 + x, y0 + y, slice.rgb(sx, sy) * scale);
        }
    return out;
}

}  // namespace ag
