// Built-in shapes: box, icosphere, quad, bumpy height field and lumpy cube sphere, all
// counter-clockwise outward.
#include "shared/shapes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <unordered_map>
#include <utility>

namespace ag {
namespace {

// Convex shapes centred at the origin: a front face points away from the centre. Fixing the
// winding from that saves hand-checking every index table.
void orient_outward(Mesh& mesh) {
    for (int i = 0; i < int(mesh.triangles.size()); ++i) {
        glm::uvec3& t = mesh.triangles[size_t(i)];
        const glm::vec3 centroid =
            (mesh.positions[t.x] + mesh.positions[t.y] + mesh.positions[t.z]) / 3.0f;
        if (glm::dot(triangle_cross(mesh, i), centroid) < 0.0f) std::swap(t.y, t.z);
    }
}

// splitmix64: a fixed, portable generator so bump fields are identical on every platform
// (std:: distributions are not).
struct SplitMix {
    uint64_t state;
    uint64_t next() {
        uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    float uniform(float lo, float hi) {
        return lo + (hi - lo) * float(double(next() >> 11) * 0x1.0p-53);
    }
};

// Texture coordinates for flat-faced shapes: each triangle projected along its dominant normal
// axis and normalised by the mesh's bounds there, so every face of a box (and a quad) shows the
// whole image once, upright when seen from outside (v up the wall; on floors and ceilings v runs
// towards −z and +z).
void planar_texcoords(Mesh& mesh) {
    const Bounds b = mesh_bounds(mesh);
    const glm::vec3 size = glm::max(b.extent(), glm::vec3(1e-20f));
    mesh.texcoords.clear();
    mesh.texcoords.reserve(3 * mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const glm::vec3 n = triangle_cross(mesh, int(t));
        const glm::vec3 a = glm::abs(n);
        for (int k = 0; k < 3; ++k) {
            const glm::vec3 q = (mesh.positions[mesh.triangles[t][k]] - b.min) / size;  // [0,1]³
            glm::vec2 uv;
            if (a.y >= a.x && a.y >= a.z)
                uv = n.y > 0.0f ? glm::vec2(q.x, 1.0f - q.z) : glm::vec2(q.x, q.z);
            else if (a.x >= a.z)
                uv = n.x > 0.0f ? glm::vec2(1.0f - q.z, q.y) : glm::vec2(q.z, q.y);
            else
                uv = n.z > 0.0f ? glm::vec2(q.x, q.y) : glm::vec2(1.0f - q.x, q.y);
            mesh.texcoords.push_back(uv);
        }
    }
}

}  // namespace

Mesh make_box(const glm::vec3& size) {
    Mesh mesh;
    const glm::vec3 h = 0.5f * size;
    // Corner i has x = +h.x if bit 0 is set, y if bit 1, z if bit 2. Sharing the 8 corners keeps
    // the box closed, which crease segmentation and shadow-volume adjacency rely on.
    for (int i = 0; i < 8; ++i)
        mesh.positions.push_back(
            {(i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z});
    constexpr unsigned kFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    for (const auto& f : kFaces) {
        mesh.triangles.push_back({f[0], f[1], f[2]});
        mesh.triangles.push_back({f[0], f[2], f[3]});
    }
    orient_outward(mesh);
    planar_texcoords(mesh);
    return mesh;
}

Mesh make_sphere(float radius, int subdivisions) {
    Mesh mesh;
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    const glm::vec3 ico[12] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                               {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                               {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (const glm::vec3& p : ico) mesh.positions.push_back(glm::normalize(p));
    mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                      {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                      {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                      {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    orient_outward(mesh);

    for (int s = 0; s < subdivisions; ++s) {
        // Shared edge midpoints keep the sphere watertight.
        std::map<std::pair<unsigned, unsigned>, unsigned> midpoints;
        auto midpoint = [&](unsigned a, unsigned b) {
            const auto key = std::minmax(a, b);
            auto [it, inserted] = midpoints.try_emplace(key, unsigned(mesh.positions.size()));
            if (inserted)
                mesh.positions.push_back(glm::normalize(mesh.positions[a] + mesh.positions[b]));
            return it->second;
        };
        std::vector<glm::uvec3> finer;
        finer.reserve(mesh.triangles.size() * 4);
        for (const glm::uvec3& tri : mesh.triangles) {
            const unsigned ab = midpoint(tri.x, tri.y), bc = midpoint(tri.y, tri.z),
                           ca = midpoint(tri.z, tri.x);
            finer.push_back({tri.x, ab, ca});
            finer.push_back({tri.y, bc, ab});
            finer.push_back({tri.z, ca, bc});
            finer.push_back({ab, bc, ca});
        }
        mesh.triangles = std::move(finer);
    }
    for (glm::vec3& p : mesh.positions) p *= radius;
    return mesh;
}

Mesh make_quad(float width, float depth) {
    const float x = 0.5f * width, z = 0.5f * depth;
    Mesh mesh;
    mesh.positions = {{-x, 0, -z}, {-x, 0, z}, {x, 0, z}, {x, 0, -z}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};  // (−x,−z) → (−x,+z) → (+x,+z) turns about +Y
    planar_texcoords(mesh);
    return mesh;
}

Mesh make_bumpy_plane(float width, float depth, int resolution, float amplitude, uint32_t seed) {
    // A few plane waves of random direction, 1.5–4 cycles across the plane, under the window
    // sin(πu)·sin(πv): the edges stay at height 0 so the plane meets walls without gaps, and the
    // bumps stay gentle enough at any resolution that adjacent faces remain within a 30° crease
    // angle (one surface, as Larsen's bumpy floor in Fig. 10.1).
    constexpr int kWaves = 6;
    SplitMix rng{0x5EEDB0F5ull ^ (uint64_t(seed) << 32 | seed)};
    glm::vec2 frequency[kWaves];
    float phase[kWaves], weight[kWaves], weight_sum = 0.0f;
    for (int k = 0; k < kWaves; ++k) {
        const float angle = rng.uniform(0.0f, 2.0f * std::numbers::pi_v<float>);
        const float cycles = rng.uniform(1.5f, 4.0f);
        frequency[k] =
            2.0f * std::numbers::pi_v<float> * cycles * glm::vec2(std::cos(angle), std::sin(angle));
        phase[k] = rng.uniform(0.0f, 2.0f * std::numbers::pi_v<float>);
        weight[k] = rng.uniform(0.5f, 1.0f);
        weight_sum += weight[k];
    }
    auto height = [&](float u, float v) {
        float h = 0.0f;
        for (int k = 0; k < kWaves; ++k)
            h += weight[k] * std::sin(frequency[k].x * u + frequency[k].y * v + phase[k]);
        return amplitude * std::sin(std::numbers::pi_v<float> * u) *
               std::sin(std::numbers::pi_v<float> * v) * h / weight_sum;
    };

    Mesh mesh;
    const int n = resolution + 1;
    mesh.positions.reserve(size_t(n) * size_t(n));
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const float u = float(i) / float(resolution), v = float(j) / float(resolution);
            mesh.positions.push_back({(u - 0.5f) * width, height(u, v), (v - 0.5f) * depth});
        }
    mesh.triangles.reserve(2 * size_t(resolution) * size_t(resolution));
    for (int j = 0; j < resolution; ++j)
        for (int i = 0; i < resolution; ++i) {
            const unsigned v00 = unsigned(j * n + i), v10 = v00 + 1, v01 = v00 + unsigned(n),
                           v11 = v01 + 1;
            // Same turn as make_quad: (−x,−z) → (−x,+z) → (+x,+z) faces +Y.
            mesh.triangles.push_back({v00, v01, v11});
            mesh.triangles.push_back({v00, v11, v10});
        }
    return mesh;
}

int lumpy_sphere_cells(long long triangles) {
    return std::max(1, int(std::lround(std::sqrt(double(std::max(triangles, 12ll)) / 12.0))));
}

Mesh make_lumpy_sphere(float radius, int cells, float amplitude, uint32_t seed) {
    // Lumps: a few waves along random directions, 2–7 cycles round the sphere, as the bumpy plane.
    constexpr int kWaves = 8;
    SplitMix rng{0x10B5F3E2ull ^ (uint64_t(seed) << 32 | seed)};
    glm::vec3 axis[kWaves];
    float cycles[kWaves], phase[kWaves], weight[kWaves], weight_sum = 0.0f;
    for (int k = 0; k < kWaves; ++k) {
        const float z = rng.uniform(-1.0f, 1.0f),
                    a = rng.uniform(0.0f, 2.0f * std::numbers::pi_v<float>);
        const float s = std::sqrt(std::max(0.0f, 1.0f - z * z));
        axis[k] = {s * std::cos(a), s * std::sin(a), z};
        cycles[k] = rng.uniform(2.0f, 7.0f);
        phase[k] = rng.uniform(0.0f, 2.0f * std::numbers::pi_v<float>);
        weight[k] = rng.uniform(0.5f, 1.0f);
        weight_sum += weight[k];
    }
    auto lump = [&](const glm::vec3& d) {
        float h = 0.0f;
        for (int k = 0; k < kWaves; ++k)
            h += weight[k] *
                 std::sin(cycles[k] * std::numbers::pi_v<float> * glm::dot(axis[k], d) + phase[k]);
        return h / weight_sum;
    };

    // Lattice points (i, j, k) ∈ [0, n]³ on the cube's surface, each made once, so faces meeting at
    // an edge share its vertices. tan() spreads them evenly over the sphere.
    const int n = std::max(1, cells);
    Mesh mesh;
    std::unordered_map<uint64_t, unsigned> index;
    index.reserve(size_t(6) * size_t(n + 1) * size_t(n + 1));
    auto vertex = [&](int i, int j, int k) {
        const uint64_t key =
            (uint64_t(i) * uint64_t(n + 1) + uint64_t(j)) * uint64_t(n + 1) + uint64_t(k);
        auto [it, inserted] = index.try_emplace(key, unsigned(mesh.positions.size()));
        if (inserted) {
            auto warp = [&](int c) {
                return std::tan(0.25f * std::numbers::pi_v<float> *
                                (2.0f * float(c) / float(n) - 1.0f));
            };
            mesh.positions.push_back(glm::normalize(glm::vec3(warp(i), warp(j), warp(k))));
        }
        return it->second;
    };
    mesh.triangles.reserve(size_t(12) * size_t(n) * size_t(n));
    for (int axis_index = 0; axis_index < 3; ++axis_index)
        for (const int side : {0, n})
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) {
                    auto at = [&](int u, int v) {
                        int c[3];
                        c[axis_index] = side;
                        c[(axis_index + 1) % 3] = u;
                        c[(axis_index + 2) % 3] = v;
                        return vertex(c[0], c[1], c[2]);
                    };
                    const unsigned v00 = at(a, b), v10 = at(a + 1, b), v01 = at(a, b + 1),
                                   v11 = at(a + 1, b + 1);
                    mesh.triangles.push_back({v00, v10, v11});
                    mesh.triangles.push_back({v00, v11, v01});
                }
    orient_outward(mesh);  // on the unit sphere, before the lumps could tilt a face inwards
    for (glm::vec3& p : mesh.positions) p *= radius + amplitude * lump(p);
    return mesh;
}

Mesh make_torus(float radius, float tube_radius, int rings, int sides) {
    Mesh mesh;
    mesh.positions.reserve(size_t(rings) * size_t(sides));
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < sides; ++j) {
            const float u = 2.0f * std::numbers::pi_v<float> * float(i) / float(rings);
            const float v = 2.0f * std::numbers::pi_v<float> * float(j) / float(sides);
            const glm::vec3 c(std::cos(u), 0.0f, std::sin(u));  // towards the tube's centre line
            mesh.positions.push_back(
                radius * c + tube_radius * (std::cos(v) * c + glm::vec3(0, std::sin(v), 0)));
        }
    mesh.triangles.reserve(2 * size_t(rings) * size_t(sides));
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < sides; ++j) {
            const unsigned v00 = unsigned(i * sides + j);
            const unsigned v10 = unsigned(((i + 1) % rings) * sides + j);
            const unsigned v11 = unsigned(((i + 1) % rings) * sides + (j + 1) % sides);
            const unsigned v01 = unsigned(i * sides + (j + 1) % sides);
            // u turns from +X to +Z, v from outward to +Y: (u, v, then u) faces out of the tube.
            mesh.triangles.push_back({v00, v11, v10});
            mesh.triangles.push_back({v00, v01, v11});
        }
    return mesh;
}

}  // namespace ag
