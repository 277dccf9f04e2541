#include "cpu/media_voxelizer.h"

#include <algorithm>
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
    std::vector<float> coverage(voxels, 0.0f);  // share of the voxel inside glass
    std::vector<int> object(voxels, -1);        // the glass object covering it
    const glm::vec3 voxel = grid.voxel_size();
    const float start_x = std::min(bounds.min.x, scene.world_bounds().min.x) - 1.0f;
    const float weight = 1.0f / float(sub * sub);
    struct Span {
        float enter, exit;
        int object;
    };
    std::vector<float> crossings_x;
    std::vector<int> crossings_object;
    std::vector<Span> spans;
    std::vector<int> parity(scene.objects.size(), 0);
    std::vector<float> opened(scene.objects.size(), 0.0f);
    for (int z = 0; z < size.z; ++z)
        for (int y = 0; y < size.y; ++y)
            for (int sz = 0; sz < sub; ++sz)
                for (int sy = 0; sy < sub; ++sy) {
                    const float py =
                        bounds.min.y + (float(y) + (float(sy) + 0.5f) / float(sub)) * voxel.y;
                    const float pz =
                        bounds.min.z + (float(z) + (float(sz) + 0.5f) / float(sub)) * voxel.z;
                    // Every glass surface along the row, in order: odd crossings of an object
                    // open a span inside it, even ones close it (ray parity).
                    spans.clear();
                    std::fill(parity.begin(), parity.end(), 0);
                    Ray ray{{start_x, py, pz}, {1.0f, 0.0f, 0.0f}, 0.0f, 1e30f};
                    for (int guard = 0; guard < 100000; ++guard) {
                        const RayHit hit = rays.intersect(ray);
                        if (!hit.hit) break;
                        ray.tmin = hit.t + rays.epsilon();
                        const size_t o = size_t(hit.object);
                        if (scene.objects[o].material.type != MaterialType::glass) continue;
                        parity[o] ^= 1;
                        if (parity[o])
                            opened[o] = start_x + hit.t;
                        else
                            spans.push_back({opened[o], start_x + hit.t, hit.object});
                    }
                    // The exact inside length of each voxel along the row.
                    for (const Span& s : spans) {
                        // Clamped as floats first: a span far outside the grid overflows int.
                        const float last = float(size.x - 1);
                        const int x0 =
                            int(std::clamp((s.enter - bounds.min.x) / voxel.x, 0.0f, last));
                        const int x1 =
                            int(std::clamp((s.exit - bounds.min.x) / voxel.x, 0.0f, last));
                        for (int x = x0; x <= x1; ++x) {
                            const float lo = bounds.min.x + float(x) * voxel.x;
                            const float inside =
                                std::min(s.exit, lo + voxel.x) - std::max(s.enter, lo);
                            if (!(inside > 0.0f)) continue;
                            const size_t i = grid.index(x, y, z);
                            coverage[i] += weight * inside / voxel.x;
                            object[i] = s.object;
                        }
                    }
                }
    // Coverage-weighted values at the voxel centre: border voxels mix the two sides (his
    // Fig. 3.7); the index and the media are evaluated at the centre.
    for (int z = 0; z < size.z; ++z)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x) {
                const size_t i = grid.index(x, y, z);
                const glm::vec3 p = grid.voxel_centre(x, y, z);
                const float c = std::min(1.0f, coverage[i]);
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
