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
    const glm::vec3 voxel = grid.voxel_size();
    const float start_x = std::min(bounds.min.x, scene.world_bounds().min.x) - 1.0f;
    const float weight = 1.0f / float(sub * sub * sub);
    struct Crossing {
        float x;
        int object;
    };
    std::vector<Crossing> crossings;
    for (int z = 0; z < size.z; ++z)
        for (int y = 0; y < size.y; ++y)
            for (int sz = 0; sz < sub; ++sz)
                for (int sy = 0; sy < sub; ++sy) {
                    const float py =
                        bounds.min.y + (float(y) + (float(sy) + 0.5f) / float(sub)) * voxel.y;
                    const float pz =
                        bounds.min.z + (float(z) + (float(sz) + 0.5f) / float(sub)) * voxel.z;
                    // Every surface along the row, in order; glass ones toggle parity.
                    crossings.clear();
                    Ray ray{{start_x, py, pz}, {1.0f, 0.0f, 0.0f}, 0.0f, 1e30f};
                    for (int guard = 0; guard < 100000; ++guard) {
                        const RayHit hit = rays.intersect(ray);
                        if (!hit.hit) break;
                        if (scene.objects[size_t(hit.object)].material.type == MaterialType::glass)
                            crossings.push_back({start_x + hit.t, hit.object});
                        ray.tmin = hit.t + rays.epsilon();
                    }
                    size_t next = 0;
                    std::vector<int> parity(scene.objects.size(), 0);
                    int inside = -1;
                    for (int x = 0; x < size.x; ++x)
                        for (int sx = 0; sx < sub; ++sx) {
                            const float px = bounds.min.x +
                                             (float(x) + (float(sx) + 0.5f) / float(sub)) * voxel.x;
                            while (next < crossings.size() && crossings[next].x < px) {
                                const int o = crossings[next++].object;
                                parity[size_t(o)] ^= 1;
                                inside = parity[size_t(o)] ? o : -1;
                            }
                            const glm::vec3 p(px, py, pz);
                            const size_t i = grid.index(x, y, z);
                            float n = 1.0f;
                            const Medium* m = nullptr;
                            if (inside >= 0) {
                                const Material& mat = scene.objects[size_t(inside)].material;
                                n = mat.ior;
                                if (mat.ior_noise.active())
                                    n += mat.ior_noise.amplitude *
                                         perlin_noise(mat.ior_noise.frequency * p,
                                                      mat.ior_noise.seed);
                                if (mat.has_interior) m = &mat.interior;
                            } else {
                                m = world_medium(scene, p);
                            }
                            // Coverage-weighted: border voxels mix the two sides (his Fig. 3.7).
                            grid.n[i] += weight * (n - 1.0f);
                            if (m) {
                                const float density = m->density(p);
                                grid.sigma_s[i] += weight * m->sigma_s * density;
                                grid.sigma_t[i] += weight * m->sigma_t() * density;
                            }
                        }
                }
    return grid;
}

}  // namespace ag::cpu
