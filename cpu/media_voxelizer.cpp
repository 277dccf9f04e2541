#include "cpu/media_voxelizer.h"

#include <algorithm>
#include <array>
#include <vector>

namespace ag::cpu {

namespace {

// The world medium whose box holds p, or null.
const Medium* world_medium(const Scene& scene, const glm::vec3& p) {
    for (const Medium& m : scene.media)
        if (glm::all(glm::greaterThanEqual(p, m.bounds.min)) &&
            glm::all(glm::lessThan(p, m.bounds.max)))
            return &m;
    return nullptr;
}

}  // namespace

MediaGrid voxelize_media(const Scene& scene, const RayTracer& rays, const Bounds& bounds,
                         const glm::ivec3& size, int sub) {
    MediaGrid grid = make_media_grid(bounds, size);
    const size_t voxels = grid.voxel_count();
    // The share of each voxel inside glass as seen by the rows along each axis: exact along the
    // row, a sub × sub midpoint rule across it. Where the surface runs along the rows (its normal
    // across them) the inside length jumps between neighbouring rows and the estimate comes in
    // steps of 1/sub; rows along the normal see a smooth length. At the poles of a ball lens the
    // rows along x alone left errors of ~1/16 in the coverage, which the smoothed index turned
    // into a lens too strong by 4% at 128³ (docs/media.md, "The ball lens across resolutions").
    std::array<std::vector<float>, 3> coverage;
    for (std::vector<float>& c : coverage) c.assign(voxels, 0.0f);
    std::vector<int> object(voxels, -1);  // the glass object covering it
    const glm::vec3 voxel = grid.voxel_size();
    const Bounds world = scene.world_bounds();
    const float weight = 1.0f / float(sub * sub);
    struct Span {
        float enter, exit;
        int object;
    };
    std::vector<Span> spans;
    std::vector<int> parity(scene.objects.size(), 0);
    std::vector<float> opened(scene.objects.size(), 0.0f);
    for (int axis = 0; axis < 3; ++axis) {
        const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;  // across the rows
        const float start = std::min(bounds.min[axis], world.min[axis]) - 1.0f;
        glm::vec3 direction(0.0f);
        direction[axis] = 1.0f;
        std::vector<float>& cover = coverage[size_t(axis)];
        glm::ivec3 cell;
        for (cell[a2] = 0; cell[a2] < size[a2]; ++cell[a2])
            for (cell[a1] = 0; cell[a1] < size[a1]; ++cell[a1])
                for (int s2 = 0; s2 < sub; ++s2)
                    for (int s1 = 0; s1 < sub; ++s1) {
                        glm::vec3 origin;
                        origin[axis] = start;
                        origin[a1] =
                            bounds.min[a1] +
                            (float(cell[a1]) + (float(s1) + 0.5f) / float(sub)) * voxel[a1];
                        origin[a2] =
                            bounds.min[a2] +
                            (float(cell[a2]) + (float(s2) + 0.5f) / float(sub)) * voxel[a2];
                        // Every glass surface along the row, in order: odd crossings of an
                        // object open a span inside it, even ones close it (ray parity).
                        spans.clear();
                        std::fill(parity.begin(), parity.end(), 0);
                        Ray ray{origin, direction, 0.0f, 1e30f};
                        for (int guard = 0; guard < 100000; ++guard) {
                            const RayHit hit = rays.intersect(ray);
                            if (!hit.hit) break;
                            ray.tmin = hit.t + rays.epsilon();
                            const size_t o = size_t(hit.object);
                            if (scene.objects[o].material.type != MaterialType::glass) continue;
                            parity[o] ^= 1;
                            if (parity[o])
                                opened[o] = start + hit.t;
                            else
                                spans.push_back({opened[o], start + hit.t, hit.object});
                        }
                        // The exact inside length of each voxel along the row.
                        for (const Span& s : spans) {
                            // Clamped as floats first: a span far outside the grid overflows int.
                            const float last = float(size[axis] - 1);
                            const int c0 = int(
                                std::clamp((s.enter - bounds.min[axis]) / voxel[axis], 0.0f, last));
                            const int c1 = int(
                                std::clamp((s.exit - bounds.min[axis]) / voxel[axis], 0.0f, last));
                            for (cell[axis] = c0; cell[axis] <= c1; ++cell[axis]) {
                                const float lo = bounds.min[axis] + float(cell[axis]) * voxel[axis];
                                const float inside =
                                    std::min(s.exit, lo + voxel[axis]) - std::max(s.enter, lo);
                                if (!(inside > 0.0f)) continue;
                                const size_t i = grid.index(cell.x, cell.y, cell.z);
                                cover[i] += weight * inside / voxel[axis];
                                object[i] = s.object;
                            }
                        }
                    }
    }
    // Each voxel weighs the three estimates by the squared components of the surface normal,
    // taken from the gradient of their mean (central differences in voxel units): the rows
    // along the normal count most.
    std::vector<float> mean(voxels);
    for (size_t i = 0; i < voxels; ++i)
        mean[i] = (coverage[0][i] + coverage[1][i] + coverage[2][i]) / 3.0f;
    std::vector<float> blended(voxels);
    for (int z = 0; z < size.z; ++z)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x) {
                const glm::ivec3 p(x, y, z);
                const size_t i = grid.index(x, y, z);
                float total = 0.0f, sum = 0.0f;
                for (int a = 0; a < 3; ++a) {
                    glm::ivec3 lo = p, hi = p;
                    lo[a] = std::max(p[a] - 1, 0);
                    hi[a] = std::min(p[a] + 1, size[a] - 1);
                    const float g =
                        mean[grid.index(hi.x, hi.y, hi.z)] - mean[grid.index(lo.x, lo.y, lo.z)];
                    total += g * g;
                    sum += g * g * coverage[size_t(a)][i];
                }
                blended[i] = total > 0.0f ? sum / total : mean[i];
            }
    // Coverage-weighted values at the voxel centre: border voxels mix the two sides (his
    // Fig. 3.7); the index and the media are evaluated at the centre.
    for (int z = 0; z < size.z; ++z)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x) {
                const size_t i = grid.index(x, y, z);
                const glm::vec3 p = grid.voxel_centre(x, y, z);
                const float c = std::clamp(blended[i], 0.0f, 1.0f);
                if (const Medium* m = world_medium(scene, p)) {
                    const float density = m->density(p);
                    grid.sigma_s[i] = (1.0f - c) * m->sigma_s * density;
                    grid.sigma_t[i] = (1.0f - c) * m->sigma_t() * density;
                }
                if (object[i] < 0 || !(c > 0.0f)) continue;
                const Material& mat = scene.objects[size_t(object[i])].material;
                float n = mat.ior;
                if (mat.ior_noise.active())
                    n += mat.ior_noise.amplitude *
                         perlin_noise(mat.ior_noise.frequency * p, mat.ior_noise.seed);
                grid.n[i] = 1.0f + c * (n - 1.0f);
                if (mat.has_interior) {
                    const float density = mat.interior.density(p);
                    grid.sigma_s[i] += c * mat.interior.sigma_s * density;
                    grid.sigma_t[i] += c * mat.interior.sigma_t() * density;
                }
            }
    return grid;
}

}  // namespace ag::cpu
