#include "gpu/media_marcher.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "gpu/media_ray_step.h"

namespace ag::gpu {

namespace {

const char* kMarchCompute = R"(
layout(local_size_x = 64) in;
struct Photon {
    vec4 position;   // xyz, w = power
    vec4 direction;  // xyz unit, w = 1 while in the grid, 0 once it left
};
layout(std430, binding = 0) buffer Photons { Photon photons[]; };
layout(std430, binding = 1) readonly buffer IndexGrid { float n_grid[]; };
layout(std430, binding = 2) readonly buffer Extinction { float sigma_t_grid[]; };
// Per voxel: fluence and fluence × photon direction (his luminance-weighted mean direction), each
// a 64-bit two's-complement fixed-point sum in two 32-bit words (low, high).
layout(std430, binding = 3) buffer Fluence { uint fluence[]; };
// Optional per-voxel statistics for the adaptive pipeline (ch. 3.2): stat_count sums per voxel,
// Σ crossing and Σ crossing × attribute k − 1 of each photon (its weight, or its origin on the
// photon plane and its square), a crossing being the chord length in voxel edges (track length)
// or 1 per voxel credited (walk). Fixed point like the fluence, with their own scale.
layout(std430, binding = 4) readonly buffer Attributes { vec4 attributes[]; };
layout(std430, binding = 5) buffer Stats { uint stats[]; };
// His octree (ch. 3.1.3) as an array: per voxel, the edge (in voxels) of the largest aligned cube
// around it in which the march's reads of n and σ_t all see one value; 0: none.
layout(std430, binding = 6) readonly buffer Octree { int cube_edge[]; };
uniform int octree;  // 1: long steps through those cubes
uniform int stat_count;
uniform float stat_scale;
vec4 photon_attribute = vec4(0.0);
uniform float fixed_scale;  // fixed-point units per unit of deposit
uniform int photon_count;
uniform ivec3 size;
uniform vec3 grid_min;
uniform vec3 voxel;      // world size of a voxel
uniform float step;      // Δs, world units
uniform int max_steps;
uniform int walk;        // 1: Pfeuti's voxel walk, 0: track length

int cell_index(ivec3 c) { return (c.z * size.y + c.y) * size.x + c.x; }
bool in_grid(ivec3 c) { return all(greaterThanEqual(c, ivec3(0))) && all(lessThan(c, size)); }

// Trilinear sample of a grid at g (voxel coordinates, centres at i + 0.5), clamped at the border.
float sample_n(vec3 g) {
    vec3 p = g - 0.5;
    ivec3 i0 = ivec3(floor(p));
    vec3 f = p - vec3(i0);
    float r = 0.0;
    for (int k = 0; k < 8; ++k) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        ivec3 c = clamp(i0 + o, ivec3(0), size - 1);
        vec3 w = mix(1.0 - f, f, vec3(o));
        r += w.x * w.y * w.z * n_grid[cell_index(c)];
    }
    return r;
}
float nearest_sigma_t(vec3 g) {
    return sigma_t_grid[cell_index(clamp(ivec3(floor(g)), ivec3(0), size - 1))];
}
float index_at(vec3 g) { return sample_n(g); }
// ∇n in world units: central differences of the trilinear n over one voxel.
vec3 index_gradient(vec3 g) {
    vec3 d;
    d.x = sample_n(g + vec3(0.5, 0, 0)) - sample_n(g - vec3(0.5, 0, 0));
    d.y = sample_n(g + vec3(0, 0.5, 0)) - sample_n(g - vec3(0, 0.5, 0));
    d.z = sample_n(g + vec3(0, 0, 0.5)) - sample_n(g - vec3(0, 0, 0.5));
    return d / voxel;
}
)";

// The ray step (gpu/media_ray_step.h) comes between the two halves.
const char* kMarchDeposits = R"(

// Integer sums do not depend on the order of the adds, so the grid is the same on every run
// (float atomics or a float CAS loop would not be). llvmpipe has no 64-bit atomics: the low word
// takes the sign-extended value, its carry and the sign go to the high word.
void add_fixed(int slot, float v) {
    int q = int(clamp(round(v * fixed_scale), -2147483647.0, 2147483647.0));
    if (q == 0) return;
    uint old = atomicAdd(fluence[2 * slot], uint(q));
    uint sum = old + uint(q);
    int high = (sum < old ? 1 : 0) + (q < 0 ? -1 : 0);
    if (high != 0) atomicAdd(fluence[2 * slot + 1], uint(high));
}
void add_stat(int slot, float v) {
    int q = int(clamp(round(v * stat_scale), -2147483647.0, 2147483647.0));
    if (q == 0) return;
    uint old = atomicAdd(stats[2 * slot], uint(q));
    uint sum = old + uint(q);
    int high = (sum < old ? 1 : 0) + (q < 0 ? -1 : 0);
    if (high != 0) atomicAdd(stats[2 * slot + 1], uint(high));
}
void add_stats(int cell, float crossing) {
    for (int k = 0; k < stat_count; ++k)
        add_stat(stat_count * cell + k, crossing * (k == 0 ? 1.0 : photon_attribute[k - 1]));
}
void add(int cell, float v, vec3 dir) {
    add_fixed(4 * cell, v);
    add_fixed(4 * cell + 1, v * dir.x);
    add_fixed(4 * cell + 2, v * dir.y);
    add_fixed(4 * cell + 3, v * dir.z);
}

// Track length: power × chord length of a→b (voxel coordinates) in every voxel it crosses,
// by Amanatides–Woo, divided by the voxel volume: each voxel's mean fluence, whatever the
// direction.
// The photon's power falls along the segment as exp(−optical t), t ∈ [0, 1] (Beer–Lambert with
// σ_t constant over it): each chord gets ∫ of it exactly, so that one long step through a
// constant medium deposits what many short ones do.
void deposit_track(vec3 a, vec3 b, float power, float optical) {
    vec3 d = b - a;
    float t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; ++k) {
        if (abs(d[k]) < 1e-12) {
            if (a[k] < 0.0 || a[k] >= float(size[k])) return;
            continue;
        }
        float ta = (0.0 - a[k]) / d[k], tb = (float(size[k]) - a[k]) / d[k];
        t0 = max(t0, min(ta, tb));
        t1 = min(t1, max(ta, tb));
    }
    if (!(t0 < t1)) return;
    float world_length = length(d * voxel);
    vec3 dir = d * voxel / world_length;
    float scale = power * world_length / (voxel.x * voxel.y * voxel.z);
    ivec3 cell = clamp(ivec3(floor(a + 0.5 * (t0 + min(t1, t0 + 1e-4)) * d)), ivec3(0), size - 1);
    ivec3 stepi = ivec3(sign(d));
    vec3 tmax = vec3(1e30), tdelta = vec3(1e30);
    for (int k = 0; k < 3; ++k) {
        if (d[k] > 0.0) {
            tmax[k] = (float(cell[k] + 1) - a[k]) / d[k];
            tdelta[k] = 1.0 / d[k];
        } else if (d[k] < 0.0) {
            tmax[k] = (float(cell[k]) - a[k]) / d[k];
            tdelta[k] = -1.0 / d[k];
        }
    }
    float t = t0;
    for (int guard = 0; guard < 4 * (size.x + size.y + size.z); ++guard) {
        float tn = min(min(tmax.x, tmax.y), tmax.z);
        float te = min(tn, t1);
        if (te > t) {
            float dt = te - t;
            float share = optical * dt > 1e-6
                              ? exp(-optical * t) * (1.0 - exp(-optical * dt)) / optical
                              : exp(-optical * t) * dt;
            add(cell_index(cell), scale * share, dir);
            if (stat_count > 0) add_stats(cell_index(cell), (te - t) * length(d));
        }
        if (tn >= t1) break;
        t = tn;
        if (tmax.x == tn) {
            cell.x += stepi.x;
            tmax.x += tdelta.x;
        } else if (tmax.y == tn) {
            cell.y += stepi.y;
            tmax.y += tdelta.y;
        } else {
            cell.z += stepi.z;
            tmax.z += tdelta.z;
        }
        if (!in_grid(cell)) break;
    }
}

// Pfeuti's walk (ch. 3.1.5): one voxel per voxel centre passed along the axis of largest change,
// each credited with power × that axis's voxel edge: right along an axis, short of the chord
// length by the direction's major-axis cosine elsewhere (up to √3 on the body diagonal).
void deposit_walk(vec3 a, vec3 b, float power) {
    vec3 d = b - a;
    vec3 ad = abs(d);
    int m = ad.x >= ad.y && ad.x >= ad.z ? 0 : (ad.y >= ad.z ? 1 : 2);
    if (ad[m] == 0.0) return;
    float lo = min(a[m], b[m]), hi = max(a[m], b[m]);
    float scale = power * voxel[m] / (voxel.x * voxel.y * voxel.z);
    vec3 dir = normalize(d * voxel);
    for (int k = int(ceil(lo - 0.5)); float(k) + 0.5 < hi; ++k) {
        vec3 p = a + ((float(k) + 0.5 - a[m]) / d[m]) * d;
        ivec3 c = ivec3(floor(p));
        if (in_grid(c)) {
            add(cell_index(c), scale, dir);
            if (stat_count > 0) add_stats(cell_index(c), 1.0);
        }
    }
}

void main() {
    int id = int(gl_GlobalInvocationID.x);
    if (id >= photon_count) return;
    vec3 x = photons[id].position.xyz;
    float power = photons[id].position.w;
    if (stat_count > 0) photon_attribute = attributes[id];
    vec3 g = (x - grid_min) / voxel;
    // A photon on the box's face starts just inside it.
    g = clamp(g, vec3(1e-4), vec3(size) - 1e-4);
    x = grid_min + g * voxel;
    float n = sample_n(g);
    vec3 v = n * photons[id].direction.xyz;  // v = n dx/ds (eq. 2.8)
    float inside = 1.0;
    for (int i = 0; i < max_steps; ++i) {
        vec3 x1 = x;
        float ds = step;
        if (octree != 0) {
            // Through a constant cube in one go (his octree step sizes), a whole number of
            // steps so that the march goes on in step with the uniform one: straight (∇n = 0),
            // and the deposits the same (deposit_track integrates each chord).
            ivec3 c = clamp(ivec3(floor(g)), ivec3(0), size - 1);
            int e = cube_edge[cell_index(c)];
            if (e > 1) {
                vec3 lo = vec3((c / e) * e), hi = min(lo + float(e), vec3(size));
                vec3 dg = normalize(v) / voxel;
                float t = 1e30;
                for (int k = 0; k < 3; ++k) {
                    if (dg[k] > 0.0) t = min(t, (hi[k] - g[k]) / dg[k]);
                    else if (dg[k] < 0.0) t = min(t, (lo[k] - g[k]) / dg[k]);
                }
                float whole = floor(t / step);
                if (whole > 1.0) ds = whole * step;
            }
        }
        ray_step(x1, v, n, ds);  // eqs. 2.10/2.11
        vec3 g1 = (x1 - grid_min) / voxel;
        bool leaving = any(lessThan(g1, vec3(0.0))) || any(greaterThanEqual(g1, vec3(size)));
        if (leaving) {
            // The last step ends on the box: the medium (and the grid) ends there, and the part
            // outside would take ½ a step's attenuation too many on average (1% of the power
            // a mirror under 1/16-voxel fog sends back).
            vec3 dg = g1 - g;
            float t = 1.0;
            for (int k = 0; k < 3; ++k) {
                if (dg[k] < 0.0) t = min(t, -g[k] / dg[k]);
                else if (dg[k] > 0.0) t = min(t, (float(size[k]) - g[k]) / dg[k]);
            }
            t = clamp(t, 0.0, 1.0);
            x1 = x + t * (x1 - x);
            g1 = g + t * dg;
        }
        // The segment's mean power under Beer–Lambert, σ_t taken constant over it.
        float optical = nearest_sigma_t(0.5 * (g + g1)) * length(x1 - x);
        float mean_power = optical > 1e-6 ? power * (1.0 - exp(-optical)) / optical : power;
        if (walk != 0) deposit_walk(g, g1, mean_power); else deposit_track(g, g1, power, optical);
        power *= exp(-optical);
        x = x1;
        g = g1;
        if (leaving) {
            x += 1e-3 * min(voxel.x, min(voxel.y, voxel.z)) * normalize(v);  // just outside
            inside = 0.0;
            break;
        }
    }
    photons[id].position = vec4(x, power);
    photons[id].direction = vec4(normalize(v), inside);
}
)";

}  // namespace

const std::vector<int32_t>& MediaMarcher::cached_octree(const MediaGrid& grid) const {
    // Keyed by the grids themselves (the octree reads n and σ_t only): compared in well under a
    // millisecond at 64³, against ~5 ms to build, and never stale.
    if (!octree_key_.has_value() || octree_key_->size != grid.size || octree_key_->n != grid.n ||
        octree_key_->sigma_t != grid.sigma_t) {
        octree_ = media_octree(grid);
        octree_key_ = OctreeKey{grid.size, grid.n, grid.sigma_t};
        ++octree_builds_;
    }
    return octree_;
}

std::vector<int32_t> media_octree(const MediaGrid& grid) {
    const glm::ivec3 s = grid.size;
    const size_t count = grid.voxel_count();
    const auto at = [&](int x, int y, int z) {
        return (size_t(z) * size_t(s.y) + size_t(y)) * size_t(s.x) + size_t(x);
    };
    // Voxels with a face neighbour of another n or σ_t, then grown by 2 voxels along each axis
    // (a box of 5³): the march's trilinear reads, gradients and step ends reach 1.5 voxels from
    // where a step lies, so a cube none of whose voxels is marked reads one value throughout.
    std::vector<uint8_t> mark(count, 0);
    for (int z = 0; z < s.z; ++z)
        for (int y = 0; y < s.y; ++y)
            for (int x = 0; x < s.x; ++x) {
                const size_t i = at(x, y, z);
                const glm::ivec3 p(x, y, z);
                for (int k = 0; k < 3; ++k) {
                    glm::ivec3 q = p;
                    ++q[k];
                    if (q[k] >= s[k]) continue;
                    const size_t j = at(q.x, q.y, q.z);
                    if (grid.n[i] != grid.n[j] || grid.sigma_t[i] != grid.sigma_t[j])
                        mark[i] = mark[j] = 1;
                }
            }
    for (int k = 0; k < 3; ++k) {
        const std::vector<uint8_t> before = mark;
        for (int z = 0; z < s.z; ++z)
            for (int y = 0; y < s.y; ++y)
                for (int x = 0; x < s.x; ++x) {
                    const glm::ivec3 p(x, y, z);
                    uint8_t m = 0;
                    for (int o = -2; o <= 2 && !m; ++o) {
                        glm::ivec3 q = p;
                        q[k] += o;
                        if (q[k] >= 0 && q[k] < s[k]) m = before[at(q.x, q.y, q.z)];
                    }
                    mark[at(x, y, z)] = m;
                }
    }
    // The level pyramid (his Listing 3.1, bottom up): a cube of edge 2e is constant where its
    // eight cubes of edge e are (those outside the grid count as constant).
    std::vector<int32_t> edge(count, 0);
    std::vector<uint8_t> level(count);
    for (size_t i = 0; i < count; ++i) level[i] = mark[i] ? 0 : 1;
    glm::ivec3 dims = s;
    for (int e = 2; e <= std::max({s.x, s.y, s.z}); e *= 2) {
        const glm::ivec3 up = (dims + 1) / 2;
        std::vector<uint8_t> next(size_t(up.x) * size_t(up.y) * size_t(up.z), 1);
        bool any = false;
        for (int z = 0; z < up.z; ++z)
            for (int y = 0; y < up.y; ++y)
                for (int x = 0; x < up.x; ++x) {
                    uint8_t ok = 1;
                    for (int c = 0; c < 8 && ok; ++c) {
                        const glm::ivec3 q(2 * x + (c & 1), 2 * y + ((c >> 1) & 1),
                                           2 * z + ((c >> 2) & 1));
                        if (q.x < dims.x && q.y < dims.y && q.z < dims.z)
                            ok = level[(size_t(q.z) * size_t(dims.y) + size_t(q.y)) *
                                           size_t(dims.x) +
                                       size_t(q.x)];
                    }
                    next[(size_t(z) * size_t(up.y) + size_t(y)) * size_t(up.x) + size_t(x)] = ok;
                    any = any || ok;
                }
        if (!any) break;
        for (int z = 0; z < s.z; ++z)
            for (int y = 0; y < s.y; ++y)
                for (int x = 0; x < s.x; ++x)
                    if (next[(size_t(z / e) * size_t(up.y) + size_t(y / e)) * size_t(up.x) +
                             size_t(x / e)])
                        edge[at(x, y, z)] = e;
        level = std::move(next);
        dims = up;
    }
    return edge;
}

MediaMarcher::MediaMarcher()
    : program_("media photon march", std::string(kMarchCompute) + kMediaRayStep + kMarchDeposits) {}

MediaMarchResult MediaMarcher::march(const MediaGrid& grid, const std::vector<MediaPhoton>& photons,
                                     const MediaMarchSettings& settings,
                                     const std::vector<glm::vec4>& attributes,
                                     int stat_count) const {
    if (stat_count < 0 || stat_count > 5 || (stat_count > 0 && attributes.size() != photons.size()))
        throw std::invalid_argument(
            "MediaMarcher::march: 0 to 5 statistics, with one attribute vector per photon");
    MediaMarchResult result;
    const size_t voxels = grid.voxel_count();
    std::vector<glm::vec4> packed(2 * photons.size());
    for (size_t i = 0; i < photons.size(); ++i) {
        packed[2 * i] = glm::vec4(photons[i].position, photons[i].power);
        packed[2 * i + 1] = glm::vec4(photons[i].direction, 1.0f);
        result.entered += double(photons[i].power);
    }
    const auto upload = [](const void* data, size_t bytes, GLuint binding) {
        Buffer b = make_buffer();
        gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, b.get());
        gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(std::max<size_t>(bytes, 16)), data,
                       GL_DYNAMIC_COPY);
        gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, b.get());
        return b;
    };
    const Buffer photon_buffer = upload(packed.data(), packed.size() * sizeof(glm::vec4), 0);
    const Buffer n_buffer = upload(grid.n.data(), voxels * sizeof(float), 1);
    const Buffer sigma_buffer = upload(grid.sigma_t.data(), voxels * sizeof(float), 2);
    const std::vector<uint32_t> zeros(8 * voxels, 0u);
    const Buffer fluence_buffer = upload(zeros.data(), zeros.size() * sizeof(uint32_t), 3);
    const Buffer attribute_buffer =
        upload(attributes.data(), stat_count > 0 ? attributes.size() * sizeof(glm::vec4) : 0, 4);
    const std::vector<uint32_t> stat_zeros(2 * size_t(stat_count) * voxels, 0u);
    const Buffer stat_buffer = upload(stat_zeros.data(), stat_zeros.size() * sizeof(uint32_t), 5);
    const bool octree = settings.octree && settings.deposit == MediaDeposit::track_length;
    const auto octree_start = std::chrono::steady_clock::now();
    const std::vector<int32_t> none;
    const std::vector<int32_t>& cubes = octree ? cached_octree(grid) : none;
    result.octree_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - octree_start).count();
    const Buffer octree_buffer = upload(cubes.data(), cubes.size() * sizeof(int32_t), 6);

    const glm::vec3 voxel = grid.voxel_size();
    const float ds = settings.step * std::min({voxel.x, voxel.y, voxel.z});
    const int max_steps =
        settings.max_steps > 0
            ? settings.max_steps
            : int(8.0f * float(grid.size.x + grid.size.y + grid.size.z) / settings.step);
    program_.use();
    program_.set("photon_count", int(photons.size()));
    program_.set("size", grid.size);
    program_.set("grid_min", grid.bounds.min);
    program_.set("voxel", voxel);
    program_.set("step", ds);
    program_.set("max_steps", max_steps);
    program_.set("walk", settings.deposit == MediaDeposit::voxel_walk ? 1 : 0);
    program_.set("octree", octree ? 1 : 0);
    // The largest single deposit (the brightest photon over the longest piece of path one
    // deposit covers) maps to 2^30 units, so no deposit overflows 32 bits.
    float max_power = 0.0f;
    for (const MediaPhoton& p : photons) max_power = std::max(max_power, p.power);
    const float longest = std::max(ds, std::sqrt(3.0f) * std::max({voxel.x, voxel.y, voxel.z}));
    const double max_deposit =
        double(max_power) * double(longest) / (double(voxel.x) * double(voxel.y) * voxel.z);
    const float fixed_scale = max_deposit > 0.0 ? float(1073741824.0 / max_deposit) : 1.0f;
    program_.set("fixed_scale", fixed_scale);
    // The largest single statistic (the longest crossing, √3 voxels, times the largest
    // attribute) maps to 2^30 units too.
    float max_attribute = 1.0f;
    if (stat_count > 1)
        for (const glm::vec4& a : attributes)
            for (int k = 0; k < stat_count - 1; ++k)
                max_attribute = std::max(max_attribute, std::abs(a[k]));
    const float longest_crossing = std::max(std::sqrt(3.0f), settings.step);
    const float stat_scale = float(1073741824.0 / (double(max_attribute) * longest_crossing));
    program_.set("stat_count", stat_count);
    program_.set("stat_scale", stat_scale);
    gl::Finish();
    const auto start = std::chrono::steady_clock::now();
    gl::DispatchCompute(GLuint((photons.size() + 63) / 64), 1, 1);
    gl::MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    gl::Finish();
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::vector<uint32_t> words(8 * voxels);
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, fluence_buffer.get());
    gl::GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(words.size() * sizeof(uint32_t)),
                         words.data());
    const auto value = [&](size_t slot) {
        const uint64_t bits = (uint64_t(words[2 * slot + 1]) << 32) | words[2 * slot];
        return float(double(static_cast<int64_t>(bits)) / double(fixed_scale));
    };
    result.fluence.resize(voxels);
    result.flow.resize(voxels);
    for (size_t i = 0; i < voxels; ++i) {
        result.fluence[i] = value(4 * i);
        result.flow[i] = glm::vec3(value(4 * i + 1), value(4 * i + 2), value(4 * i + 3));
    }
    if (stat_count > 0) {
        std::vector<uint32_t> stat_words(stat_zeros.size());
        gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, stat_buffer.get());
        gl::GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                             GLsizeiptr(stat_words.size() * sizeof(uint32_t)), stat_words.data());
        result.stats.resize(size_t(stat_count) * voxels);
        for (size_t i = 0; i < result.stats.size(); ++i) {
            const uint64_t bits = (uint64_t(stat_words[2 * i + 1]) << 32) | stat_words[2 * i];
            result.stats[i] = float(double(static_cast<int64_t>(bits)) / double(stat_scale));
        }
    }
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, photon_buffer.get());
    gl::GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(packed.size() * sizeof(glm::vec4)),
                         packed.data());
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    result.photons.resize(photons.size());
    for (size_t i = 0; i < photons.size(); ++i) {
        const glm::vec4 p = packed[2 * i], d = packed[2 * i + 1];
        result.photons[i] = {glm::vec3(p), glm::vec3(d), p.w};
        result.absorbed += double(photons[i].power) - double(p.w);
        if (d.w == 0.0f) result.escaped += double(p.w);
    }
    check_gl("MediaMarcher::march");
    return result;
}

}  // namespace ag::gpu
