#include "gpu/gpu_photon_mapper.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "gpu/media_glsl.h"
#include "gpu/media_uniforms.h"
#include "shared/flat_bvh.h"
#include "shared/photon_sampling.h"

namespace ag::gpu {

namespace {

// Storage-buffer bindings (the BVH uses 6 and 7).
enum : GLuint {
    kPhotonsBinding = 0,
    kCounterBinding = 1,
    kTileBoundsBinding = 2,
    kTileCountsBinding = 3,
    kTileOffsetsBinding = 4,
    kIndicesBinding = 5,
    kTileCursorBinding = 8,
    kEmittersBinding = 9,
    kMaterialsBinding = 10,
};

const char* kPhotonCommon = R"(
struct Photon { vec4 position; vec4 power; };  // w, w: the octahedral direction it came from
layout(std430, binding = 0) buffer Photons { Photon photons[]; };
layout(std430, binding = 1) buffer Counter { uint photon_count; uint index_overflow; uint refined; uint pad; };
uniform uint capacity;
uint photon_total() { return min(photon_count, capacity); }
)";

// One path per invocation (§5.3.2, Listing 5.7/5.10): the emitter by power with the Hammersley
// point's first coordinate (stratified over emitters, then rescaled inside the chosen one), the
// position from the point, directions from TEA; hits from the second on are stored.
const char* kTrace = R"(
layout(local_size_x = 64) in;
struct Emitter { vec3 a; uint type; vec3 b; float cos_outer; vec3 c; float cos_inner;
                 vec3 power; float cdf_lo; vec3 normal; float cdf_hi; };
layout(std430, binding = 9) readonly buffer Emitters { Emitter emitters[]; };
layout(std430, binding = 10) readonly buffer Materials { vec4 materials[]; };  // albedo or ior, type
uniform uint paths, path_base, frame_index, emitter_count;
uniform int bounces, kwast;
uniform float epsilon;
void main() {
    uint i = group_index() * 64u + gl_LocalInvocationID.x;
    if (i >= paths || emitter_count == 0u) return;
    uvec2 seed = tea_seed(path_base + i, 0u);
    // This frame's Hammersley set, shifted by a per-frame rotation so frames add new points.
    vec2 h = fract(hammersley(i, paths) + tea_unit(tea_seed(frame_index, 0x51ED27u)));
    uint lo = 0u, hi = emitter_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (h.x < emitters[mid].cdf_hi) hi = mid; else lo = mid + 1u;
    }
    Emitter e = emitters[lo];
    float pk = e.cdf_hi - e.cdf_lo;
    if (pk <= 0.0) return;
    vec2 u = vec2(clamp((h.x - e.cdf_lo) / pk, 0.0, 0.99999994), h.y);
    seed = tea_next(seed);
    vec2 r = tea_unit(seed);
    vec3 power = e.power / (float(paths) * pk);
    if (kwast != 0) power *= 100.0;  // his lightIntensity / (0.01 · numPaths)
    vec3 o = e.a, d;
    if (e.type == 0u) {
        d = uniform_sphere(u);
    } else if (e.type == 1u) {
        // Uniform in the outer cone; the weight turns Φ/N into I·f(θ)·Ω_o/N (as on the CPU).
        float co = e.cos_outer, ci = e.cos_inner, c = 1.0 - u.x * (1.0 - co);
        float s = sqrt(max(0.0, 1.0 - c * c)), a = 2.0 * kPhotonPi * u.y;
        d = frame_around(e.b) * vec3(s * cos(a), s * sin(a), c);
        float f = c >= ci ? 1.0 : (ci > co ? max(0.0, (c - co) / (ci - co)) : 0.0);
        float mean = (1.0 - ci) + 0.5 * (ci - co);
        power *= mean > 0.0 ? f * (1.0 - co) / mean : 0.0;
    } else if (e.type == 2u) {
        vec2 q = concentric_disc(u);
        mat3 f = frame_around(e.b);
        o = e.a + e.c.x * (q.x * f[0] + q.y * f[1] - 1.01 * e.b);
        d = e.b;
    } else {
        if (e.type == 3u) {
            o = e.a + u.x * e.b + u.y * e.c;
        } else {
            float s = sqrt(u.x);
            o = e.a + s * (1.0 - u.y) * e.b + s * u.y * e.c;
        }
        o += epsilon * e.normal;
        d = cosine_direction(r, e.normal);
    }
    // Diffuse vertices are counted: hits from the second on are stored (his "second bounce"),
    // up to `bounces` stored. Mirrors and glass carry the photon on unchanged (reflected, or
    // refracted by the Fresnel share), anywhere along the path, as pt's single-bounce indirect
    // term counts L S* D S* D paths; a chain of more than kSpecularVertices ends it.
    const int kSpecularVertices = 8;
    int diffuse = 0, specular = 0;
    while (true) {
        BvhHit hit;
        if (!bvh_intersect(o, d, 0.0, 1e30, hit)) break;
        // Beer–Lambert through the media boxes along the segment, the path unchanged, as the CPU
        // photon tracer dims its photons (mean σ_t; glass interiors and noise left out, as in the
        // frame's direct light). Without it a lamp inside dense fog lit the room.
        power *= media_transmittance(o, d, hit.t);
        vec3 x = o + hit.t * d;
        vec4 m = materials[hit.object];
        BvhTriangle tri = bvh_triangles[hit.index];
        vec3 n = normalize(cross(tri.e1, tri.e2));
        int type = int(m.w + 0.5);
        if (type != kMaterialDiffuse) {
            if (++specular > kSpecularVertices) break;
            vec3 facing = dot(n, d) < 0.0 ? n : -n;  // towards the incoming side
            seed = tea_next(seed);
            float cos_i = -dot(d, facing), cos_t = 0.0, reflectance = 1.0;
            float eta = dot(n, d) < 0.0 ? 1.0 / m.x : m.x;  // glass: .x holds the ior
            if (type == kMaterialGlass) {
                float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
                if (sin2_t < 1.0) {
                    cos_t = sqrt(1.0 - sin2_t);
                    // Unpolarised Fresnel for a dielectric (as fresnel_dielectric on the CPU).
                    float rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
                    float rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
                    reflectance = 0.5 * (rs * rs + rp * rp);
                }
            }
            if (type == kMaterialGlass && tea_unit(seed).x >= reflectance) {
                d = normalize(eta * d + (eta * cos_i - cos_t) * facing);
                o = x - epsilon * facing;
            } else {
                d = reflect(d, facing);
                o = x + epsilon * facing;
            }
            continue;
        }
        // Light reaching the back of a diffuse surface is absorbed, as in the CPU photon tracers
        // and pt (surfaces are one-sided; a wall lit from both sides needs thickness). Stored
        // there, a photon inside a closed box lit the box's outside through the cone filter,
        // whose sphere reaches through the box's zero-thickness walls at its edges.
        if (dot(n, d) >= 0.0) break;
        if (diffuse >= 1) {
            uint at = atomicAdd(photon_count, 1u);
            vec2 enc = octahedral_encode(-d);
            if (at < capacity) photons[at] = Photon(vec4(x, enc.x), vec4(power, enc.y));
        }
        if (diffuse == bounces) break;
        ++diffuse;
        // The albedo where it landed: base × the texel (bilinear) on a textured surface.
        power *= m.rgb * texture_albedo(hit.object, hit.index, hit.barycentric);
        if (kwast != 0) power /= kPhotonPi;  // his Kd / π / p at the bounce
        seed = tea_next(seed);
        d = cosine_direction(tea_unit(seed), n);
        o = x + epsilon * n;
    }
}
)";

// Tiles: view-space depth bounds per 8×8 tile and the exact photon–tile test both binnings use, so
// their lists agree (§5.3.3.1: four side planes through the eye and the tile's corners, and the
// depth range, each widened by the radius).
const char* kTileCommon = R"(
layout(std430, binding = 2) buffer TileBounds { vec2 tile_depth[]; };  // x > y: empty tile
layout(std430, binding = 3) buffer TileCounts { uint tile_counts[]; };
layout(std430, binding = 4) buffer TileOffsets { uint tile_offsets[]; };
layout(std430, binding = 5) buffer Indices { uint indices[]; };
layout(std430, binding = 8) buffer TileCursor { uint tile_cursor[]; };
uniform mat4 view;
uniform vec2 proj_scale;  // P[0][0], P[1][1]
uniform ivec2 tiles, size;
uniform float radius;
uniform uint index_capacity;
vec3 photon_view(uint i) { return (view * vec4(photons[i].position.xyz, 1.0)).xyz; }
bool photon_in_tile(vec3 p, int tx, int ty) {
    vec2 zr = tile_depth[ty * tiles.x + tx];
    float d = -p.z;
    if (zr.x > zr.y || d < zr.x - radius || d > zr.y + radius) return false;
    vec2 lo = 2.0 * vec2(tx, ty) * 8.0 / vec2(size) - 1.0;
    vec2 hi = 2.0 * vec2(min(ivec2(tx + 1, ty + 1) * 8, size)) / vec2(size) - 1.0;
    vec3 planes[4] = vec3[4](vec3(proj_scale.x, 0.0, lo.x), vec3(-proj_scale.x, 0.0, -hi.x),
                             vec3(0.0, proj_scale.y, lo.y), vec3(0.0, -proj_scale.y, -hi.y));
    for (int k = 0; k < 4; ++k)
        if (dot(planes[k], p) < -radius * length(planes[k])) return false;
    return true;
}
// The tiles the sphere's projection can touch: X/D over the box [x ± r] × [d ± r] (D > 0) is
// bounded by its corners; one tile of margin against rounding. All tiles if it reaches the eye.
void tile_range(vec3 p, out ivec2 lo, out ivec2 hi) {
    float d = -p.z;
    lo = ivec2(0);
    hi = tiles - 1;
    if (d - radius <= 1e-6 * radius) return;
    float dn = d - radius, df = d + radius;
    vec2 a = proj_scale * min((p.xy - radius) / dn, (p.xy - radius) / df);
    vec2 b = proj_scale * max((p.xy + radius) / dn, (p.xy + radius) / df);
    lo = max(ivec2(floor((a * 0.5 + 0.5) * vec2(size) / 8.0)) - 1, ivec2(0));
    hi = min(ivec2(floor((b * 0.5 + 0.5) * vec2(size) / 8.0)) + 1, tiles - 1);
}
)";

const char* kTileBounds = R"(
layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D position_map, normal_map;
shared uint zmin, zmax;
void main() {
    uint t = group_index();
    ivec2 tile = ivec2(int(t) % tiles.x, int(t) / tiles.x);
    if (gl_LocalInvocationIndex == 0u) {
        zmin = 0x7F7FFFFFu;
        zmax = 0u;
    }
    barrier();
    ivec2 px = tile * 8 + ivec2(gl_LocalInvocationID.xy);
    if (px.x < size.x && px.y < size.y && texelFetch(position_map, px, 0).w > 0.0) {
        uint z = floatBitsToUint(max(texelFetch(normal_map, px, 0).w, 0.0));
        atomicMin(zmin, z);
        atomicMax(zmax, z);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u)
        tile_depth[t] = zmin > zmax ? vec2(1.0, 0.0) : vec2(uintBitsToFloat(zmin), uintBitsToFloat(zmax));
}
)";

// Scatter binning: one invocation per photon, over the tiles its disc can touch.
const char* kScatter = R"(
layout(local_size_x = 64) in;
uniform int insert;
void main() {
    uint i = group_index() * 64u + gl_LocalInvocationID.x;
    if (i >= photon_total()) return;
    vec3 p = photon_view(i);
    ivec2 lo, hi;
    tile_range(p, lo, hi);
    for (int ty = lo.y; ty <= hi.y; ++ty)
        for (int tx = lo.x; tx <= hi.x; ++tx) {
            if (!photon_in_tile(p, tx, ty)) continue;
            uint t = uint(ty * tiles.x + tx);
            if (insert == 0) {
                atomicAdd(tile_counts[t], 1u);
            } else {
                uint at = tile_offsets[t] + atomicAdd(tile_cursor[t], 1u);
                if (at < index_capacity) indices[at] = i; else index_overflow = 1u;
            }
        }
}
)";

// The thesis's binning (Listing 5.12): one work group per tile, its 64 threads striding over every
// photon.
const char* kBrute = R"(
layout(local_size_x = 64) in;
uniform int insert;
shared uint n;
void main() {
    uint t = group_index();
    int tx = int(t) % tiles.x, ty = int(t) / tiles.x;
    if (gl_LocalInvocationIndex == 0u) n = 0u;
    barrier();
    uint total = photon_total();
    if (tile_depth[t].x <= tile_depth[t].y)
        for (uint i = gl_LocalInvocationIndex; i < total; i += 64u) {
            if (!photon_in_tile(photon_view(i), tx, ty)) continue;
            uint slot = atomicAdd(n, 1u);
            if (insert != 0) {
                uint at = tile_offsets[t] + slot;
                if (at < index_capacity) indices[at] = i; else index_overflow = 1u;
            }
        }
    barrier();
    if (insert == 0 && gl_LocalInvocationIndex == 0u) tile_counts[t] = n;
}
)";

// Eq. 5.6 with k = 1 over the photons of the pixel's tile: E/π = Σ Φ_p w_p / ((1 − 2/3) π r² · π)
// over photons arriving at the front of the surface; `kwast` adds his N·L. The sum is taken in
// 64-bit fixed point (units of `fixed_unit`, 2⁻²⁴ of the largest photon power; two 32-bit words
// with carry), so it does not depend on the order of the tile's list, which GPU atomics choose:
// the same seed gives the same bits on every run and with either binning.
const char* kEstimate = R"(
uniform sampler2D position_map, normal_map, ids_map;
uniform float estimate_scale, fixed_unit;
uniform int kwast;
vec3 estimate(ivec2 px, vec3 x, vec3 n) {
    int t = (px.y / 8) * tiles.x + px.x / 8;
    uint begin = min(tile_offsets[t], index_capacity), end = min(tile_offsets[t + 1], index_capacity);
    uvec3 lo = uvec3(0u), hi = uvec3(0u);
    for (uint k = begin; k < end; ++k) {
        Photon ph = photons[indices[k]];
        float d = distance(ph.position.xyz, x);
        if (d >= radius) continue;
        float cos_in = dot(n, octahedral_decode(vec2(ph.position.w, ph.power.w)));
        if (cos_in <= 0.0) continue;
        vec3 c = ph.power.xyz * cone_weight(d, radius, 1.0) * (kwast != 0 ? min(cos_in, 1.0) : 1.0);
        uvec3 carry;
        lo = uaddCarry(lo, uvec3(clamp(c / fixed_unit + 0.5, 0.0, 4294967040.0)), carry);
        hi += carry;
    }
    return (vec3(hi) * 4294967296.0 + vec3(lo)) * (fixed_unit * estimate_scale);
}
)";

const char* kEstimateLow = R"(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) writeonly uniform image2D low_image;
uniform int low_res;
uniform ivec2 low_size;
void main() {
    ivec2 lp = ivec2(gl_GlobalInvocationID.xy);
    if (lp.x >= low_size.x || lp.y >= low_size.y) return;
    ivec2 s = min(lp * low_res + low_res / 2, size - 1);
    vec4 pos = texelFetch(position_map, s, 0);
    vec3 e = pos.w > 0.0 ? estimate(s, pos.xyz, texelFetch(normal_map, s, 0).xyz) : vec3(0.0);
    imageStore(low_image, lp, vec4(e, 1.0));
}
)";

// Full resolution (Listing 5.18): bilinear from the four low-resolution samples around the pixel,
// unless one of them sees another material, a normal turned by more than edge_normal or a point
// off the pixel's plane; then the estimate again at the pixel. a = 1 marks those pixels.
const char* kComposite = R"(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 1) writeonly uniform image2D result_image;
uniform sampler2D low_map;
uniform int low_res;
uniform ivec2 low_size;
uniform float edge_normal, edge_distance;
shared uint group_refined;
void main() {
    if (gl_LocalInvocationIndex == 0u) group_refined = 0u;
    barrier();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x < size.x && p.y < size.y) {
        vec4 pos = texelFetch(position_map, p, 0);
        vec4 result = vec4(0.0);
        if (pos.w > 0.0) {
            vec3 n = texelFetch(normal_map, p, 0).xyz;
            float id = texelFetch(ids_map, p, 0).g;
            bool edge = low_res <= 1;
            vec3 acc = vec3(0.0);
            if (!edge) {
                vec2 q = (vec2(p) + 0.5) / float(low_res) - 0.5;
                ivec2 base = ivec2(floor(q));
                vec2 f = q - vec2(base);
                for (int j = 0; j <= 1; ++j)
                    for (int i = 0; i <= 1; ++i) {
                        ivec2 lp = clamp(base + ivec2(i, j), ivec2(0), low_size - 1);
                        ivec2 s = min(lp * low_res + low_res / 2, size - 1);
                        vec4 sp = texelFetch(position_map, s, 0);
                        if (sp.w <= 0.0 || texelFetch(ids_map, s, 0).g != id ||
                            dot(texelFetch(normal_map, s, 0).xyz, n) < edge_normal ||
                            abs(dot(sp.xyz - pos.xyz, n)) > edge_distance)
                            edge = true;
                        float w = (i == 1 ? f.x : 1.0 - f.x) * (j == 1 ? f.y : 1.0 - f.y);
                        acc += w * texelFetch(low_map, lp, 0).rgb;
                    }
            }
            if (edge) {
                acc = estimate(p, pos.xyz, n);
                atomicAdd(group_refined, 1u);
            }
            result = vec4(acc, edge ? 1.0 : 0.0);
        }
        imageStore(result_image, p, result);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && group_refined > 0u) atomicAdd(refined, group_refined);
}
)";

// The viewer's picture of the binning: each pixel coloured by its tile's photon count (log scale,
// blue → red, 1 to 2¹⁶ photons; black: none; grey: a tile with no geometry), tile edges darker;
// a holds the count.
const char* kTileView = R"(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 2) writeonly uniform image2D tile_image;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    int t = (p.y / 8) * tiles.x + p.x / 8;
    uint n = tile_offsets[t + 1] - tile_offsets[t];
    float s = clamp(log2(1.0 + float(n)) / 16.0, 0.0, 1.0);
    vec3 c = clamp(1.5 - abs(4.0 * s - vec3(3.0, 2.0, 1.0)), 0.0, 1.0);
    if (n == 0u) c = tile_depth[t].x > tile_depth[t].y ? vec3(0.05) : vec3(0.0);
    if (p.x % 8 == 0 || p.y % 8 == 0) c *= 0.6;
    imageStore(tile_image, p, vec4(c, float(n)));
}
)";

// The trace walks the BVH; the tile passes read the tiles instead.
std::string with_common(const char* body, bool tiles) {
    return std::string(kPhotonSamplingGlsl) + kComputeGroupIndex +
           (tiles ? "" : std::string(kBvhTraversalGlsl) + kSurfaceAlbedoGlsl) + kPhotonCommon +
           (tiles ? kTileCommon : "") + body;
}

float luminance(const glm::vec3& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

GLuint groups_for(uint64_t n, uint64_t per) { return GLuint((n + per - 1) / per); }

}  // namespace

std::vector<PhotonEmitter> make_photon_emitters(const Scene& scene) {
    std::vector<PhotonEmitter> out;
    for (const Light& l : scene.lights) {
        if (!l.enabled) continue;
        PhotonEmitter e;
        e.power = l.power();
        switch (l.type) {
            case LightType::point:
                e.type = kEmitterPoint;
                e.a = l.position;
                break;
            case LightType::spot:
                e.type = kEmitterSpot;
                e.a = l.position;
                e.b = l.direction;
                e.cos_outer = l.cos_outer();
                e.cos_inner = l.cos_inner();
                break;
            case LightType::sun:
                e.type = kEmitterSun;
                e.a = l.sun_center;
                e.b = l.direction;
                e.c = glm::vec3(l.sun_radius, 0.0f, 0.0f);
                break;
            case LightType::quad:
                e.type = kEmitterQuad;
                e.a = l.corners[0];
                e.b = l.corners[1] - l.corners[0];
                e.c = l.corners[3] - l.corners[0];
                e.normal = l.quad_normal();
                break;
            case LightType::mesh: {
                // One emitter per triangle, each with its share of the light's area.
                const Object& o = scene.objects[size_t(l.object)];
                float lo = 0.0f;
                for (size_t t = 0; t < l.triangle_cdf.size(); ++t) {
                    const glm::uvec3 tri = o.mesh.triangles[t];
                    PhotonEmitter m;
                    m.type = kEmitterTriangle;
                    m.a = o.transform.apply_point(o.mesh.positions[tri.x]);
                    m.b = o.transform.apply_point(o.mesh.positions[tri.y]) - m.a;
                    m.c = o.transform.apply_point(o.mesh.positions[tri.z]) - m.a;
                    m.normal = glm::normalize(glm::cross(m.b, m.c));
                    m.power = e.power * (l.triangle_cdf[t] - lo);
                    lo = l.triangle_cdf[t];
                    if (m.power != glm::vec3(0.0f)) out.push_back(m);
                }
                continue;
            }
        }
        if (e.power != glm::vec3(0.0f)) out.push_back(e);
    }
    double total = 0.0;
    for (const PhotonEmitter& e : out) total += std::max(0.0f, luminance(e.power));
    if (total <= 0.0) return {};
    double running = 0.0;
    for (PhotonEmitter& e : out) {
        e.cdf_lo = float(running / total);
        running += std::max(0.0f, luminance(e.power));
        e.cdf_hi = float(running / total);
    }
    out.back().cdf_hi = 1.0f;
    return out;
}

GpuPhotonMapper::GpuPhotonMapper(const Scene& scene, const GBuffer& g_buffer)
    : scene_(scene),
      g_buffer_(g_buffer),
      width_(g_buffer.width()),
      height_(g_buffer.height()),
      tiles_x_((width_ + kPhotonTile - 1) / kPhotonTile),
      tiles_y_((height_ + kPhotonTile - 1) / kPhotonTile) {
    const GpuPmSettings& s = scene.settings.gpu_pm;
    const int f = std::max(1, s.low_res);
    low_w_ = (width_ + f - 1) / f;
    low_h_ = (height_ + f - 1) / f;
    trace_ = Program::compute("gpu_pm trace",
                              std::string(kMediaTransmittanceGlsl) + with_common(kTrace, false));
    tile_bounds_ = Program::compute("gpu_pm tile bounds", with_common(kTileBounds, true));
    count_scatter_ = Program::compute("gpu_pm scatter binning", with_common(kScatter, true));
    count_brute_ = Program::compute("gpu_pm brute-force binning", with_common(kBrute, true));
    estimate_low_ =
        Program::compute("gpu_pm low-resolution estimate",
                         with_common((std::string(kEstimate) + kEstimateLow).c_str(), true));
    composite_ = Program::compute("gpu_pm composite",
                                  with_common((std::string(kEstimate) + kComposite).c_str(), true));
    tile_view_program_ = Program::compute("gpu_pm tile view", with_common(kTileView, true));
    capacity_ = size_t(s.paths) * size_t(s.frames) * size_t(s.bounces);
    photons_ = make_storage_buffer(std::max<size_t>(capacity_, 1) * sizeof(Photon));
    counter_ = make_storage_buffer(4 * sizeof(uint32_t));
    const size_t tiles = size_t(tiles_x_) * size_t(tiles_y_);
    tile_bounds_buffer_ = make_storage_buffer(tiles * sizeof(glm::vec2));
    tile_counts_ = make_storage_buffer(tiles * sizeof(uint32_t));
    tile_offsets_ = make_storage_buffer((tiles + 1) * sizeof(uint32_t));
    tile_cursor_ = make_storage_buffer(tiles * sizeof(uint32_t));
    index_capacity_ = std::clamp<size_t>(capacity_ * 64, size_t(1) << 20, size_t(1) << 26);
    indices_ = make_storage_buffer(index_capacity_ * sizeof(uint32_t));
    low_radiance_ = make_float_texture(low_w_, low_h_);
    result_ = make_float_texture(width_, height_);
    reset();
}

void GpuPhotonMapper::reset() {
    const FlatBvh bvh = build_flat_bvh(scene_);
    bvh_.upload(bvh);
    albedo_.upload(scene_, bvh);
    const std::vector<PhotonEmitter> emitters = make_photon_emitters(scene_);
    emitter_count_ = uint32_t(emitters.size());
    emitters_ = make_storage_buffer(std::max<size_t>(emitters.size(), 1) * sizeof(PhotonEmitter),
                                    emitters.empty() ? nullptr : emitters.data());
    std::vector<glm::vec4> materials;
    for (const Object& o : scene_.objects)
        // Diffuse: the albedo (× the texture in the trace); glass: its ior in .x (mirrors and
        // glass pass photons on unchanged, as pt's paths).
        materials.emplace_back(
            o.material.type == MaterialType::glass ? glm::vec3(o.material.ior) : base_albedo(o),
            float(int(o.material.type)));
    if (materials.empty()) materials.emplace_back(0.0f);
    materials_ = make_storage_buffer(materials.size() * sizeof(glm::vec4), materials.data());
    radius_ = scene_.settings.gpu_pm.radius * scene_.diagonal();
    // The largest power one photon can carry: the trace's Φ_e / (paths · p_e), up to 2× for a
    // spot's weight, ×100 under `kwast` (albedo ≤ 1 only lowers it).
    max_photon_power_ = 0.0f;
    for (const PhotonEmitter& e : emitters) {
        const float p = e.cdf_hi - e.cdf_lo;
        if (p > 0.0f)
            max_photon_power_ =
                std::max(max_photon_power_, std::max({e.power.r, e.power.g, e.power.b}) *
                                                (e.type == kEmitterSpot ? 2.0f : 1.0f) / p);
    }
    if (scene_.settings.gpu_pm.estimator == GpuPmEstimator::kwast) max_photon_power_ *= 100.0f;
    clear_photons();
}

void GpuPhotonMapper::clear_photons() {
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, counter_.get());
    gl::ClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT,
                        nullptr);
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    frames_ = 0;
    paths_total_ = 0;
    ++revision_;
    check_gl("GpuPhotonMapper::clear_photons");
}

bool GpuPhotonMapper::settled() const { return frames_ >= scene_.settings.gpu_pm.frames; }

uint32_t GpuPhotonMapper::photon_bound() const {
    return uint32_t(
        std::min<uint64_t>(capacity_, paths_total_ * uint64_t(scene_.settings.gpu_pm.bounces)));
}

void GpuPhotonMapper::trace() {
    const GpuPmSettings& s = scene_.settings.gpu_pm;
    if (settled()) return;
    trace_.use();
    trace_.set("paths", unsigned(s.paths));
    trace_.set("path_base", unsigned(paths_total_));
    trace_.set("frame_index", unsigned(frames_));
    trace_.set("emitter_count", unsigned(emitter_count_));
    trace_.set("bounces", s.bounces);
    trace_.set("kwast", s.estimator == GpuPmEstimator::kwast ? 1 : 0);
    trace_.set("epsilon", 1e-5f * scene_.diagonal());
    trace_.set("capacity", unsigned(capacity_));
    set_media_uniforms(trace_, scene_);
    bvh_.bind();
    albedo_.bind();
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kPhotonsBinding, photons_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kCounterBinding, counter_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kEmittersBinding, emitters_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kMaterialsBinding, materials_.get());
    dispatch_compute(groups_for(uint64_t(s.paths), 64));
    ++frames_;
    paths_total_ += uint64_t(s.paths);
    ++revision_;
    gl::UseProgram(0);
    check_gl("GpuPhotonMapper::trace");
}

void GpuPhotonMapper::set_view_uniforms(const Program& p, const GBuffer::View& view) const {
    p.use();
    p.set("view", view.view);
    p.set("proj_scale", glm::vec2(view.projection[0][0], view.projection[1][1]));
    gl::Uniform2i(p.location("tiles"), tiles_x_, tiles_y_);
    gl::Uniform2i(p.location("size"), width_, height_);
    p.set("radius", radius_);
    p.set("index_capacity", unsigned(index_capacity_));
    p.set("capacity", unsigned(capacity_));
    p.set("position_map", 0);
    p.set("normal_map", 1);
    p.set("ids_map", 2);
}

void GpuPhotonMapper::bind_tile_buffers() const {
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kPhotonsBinding, photons_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kCounterBinding, counter_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kTileBoundsBinding, tile_bounds_buffer_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kTileCountsBinding, tile_counts_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kTileOffsetsBinding, tile_offsets_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kIndicesBinding, indices_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kTileCursorBinding, tile_cursor_.get());
}

void GpuPhotonMapper::bin(const GBuffer::View& view) {
    const GLuint tiles = GLuint(tiles_x_ * tiles_y_);
    for (const GLuint b : {tile_counts_.get(), tile_cursor_.get()}) {
        gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, b);
        gl::ClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT,
                            nullptr);
    }
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    bind_tile_buffers();
    set_view_uniforms(tile_bounds_, view);
    dispatch_compute(tiles);
    const bool brute = scene_.settings.gpu_pm.binning == GpuPmBinning::brute;
    const Program& binning = brute ? count_brute_ : count_scatter_;
    const GLuint groups = brute ? tiles : groups_for(photon_bound(), 64);
    set_view_uniforms(binning, view);
    binning.set("insert", 0);
    dispatch_compute(groups);
    prefix_sum_.exclusive(tile_counts_.get(), tile_offsets_.get(), tiles);
    bind_tile_buffers();  // the prefix sum used bindings 0-2 for its own
    set_view_uniforms(binning, view);
    binning.set("insert", 1);
    dispatch_compute(groups);
}

void GpuPhotonMapper::render() {
    const GBuffer::View& view = g_buffer_.last_view();
    radius_ = scene_.settings.gpu_pm.radius * scene_.diagonal();
    // Per-render counters (the overflow flag and refined pixels) start at 0; the photon count
    // stays.
    const uint32_t zero[3] = {0, 0, 0};
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, counter_.get());
    gl::BufferSubData(GL_SHADER_STORAGE_BUFFER, sizeof(uint32_t), sizeof zero, zero);
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    for (int unit = 0; unit < 3; ++unit) {
        gl::ActiveTexture(GLenum(GL_TEXTURE0 + unit));
        gl::BindTexture(GL_TEXTURE_2D, g_buffer_.texture(unit == 0   ? GBufferTarget::position
                                                         : unit == 1 ? GBufferTarget::normal
                                                                     : GBufferTarget::ids));
    }
    bin(view);
    const GpuPmSettings& s = scene_.settings.gpu_pm;
    const float norm = photon::cone_normalisation(radius_, 1.0f);
    const float scale =
        frames_ > 0 ? 1.0f / (float(frames_) * std::numbers::pi_v<float> * norm) : 0.0f;
    // Photon power is Φ_e / (paths · p_e): the fixed-point unit follows the paths per frame.
    const float fixed_unit =
        std::max(max_photon_power_ / float(std::max(1, s.paths)), 1e-30f) * 0x1p-24f;
    const int f = std::max(1, s.low_res);
    if (f > 1) {
        set_view_uniforms(estimate_low_, view);
        estimate_low_.set("estimate_scale", scale);
        estimate_low_.set("fixed_unit", fixed_unit);
        estimate_low_.set("kwast", s.estimator == GpuPmEstimator::kwast ? 1 : 0);
        estimate_low_.set("low_res", f);
        gl::Uniform2i(estimate_low_.location("low_size"), low_w_, low_h_);
        gl::BindImageTexture(0, low_radiance_.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        gl::DispatchCompute(groups_for(uint64_t(low_w_), 8), groups_for(uint64_t(low_h_), 8), 1);
        gl::MemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    set_view_uniforms(composite_, view);
    composite_.set("estimate_scale", scale);
    composite_.set("fixed_unit", fixed_unit);
    composite_.set("kwast", s.estimator == GpuPmEstimator::kwast ? 1 : 0);
    composite_.set("low_res", f);
    gl::Uniform2i(composite_.location("low_size"), low_w_, low_h_);
    composite_.set("edge_normal", s.edge_normal);
    composite_.set("edge_distance", s.edge_distance * radius_);
    composite_.set("low_map", 3);
    gl::ActiveTexture(GL_TEXTURE3);
    gl::BindTexture(GL_TEXTURE_2D, low_radiance_.get());
    gl::BindImageTexture(1, result_.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    gl::DispatchCompute(groups_for(uint64_t(width_), 8), groups_for(uint64_t(height_), 8), 1);
    gl::MemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                      GL_SHADER_STORAGE_BARRIER_BIT);
    for (int unit = 3; unit >= 0; --unit) {
        gl::ActiveTexture(GLenum(GL_TEXTURE0 + unit));
        gl::BindTexture(GL_TEXTURE_2D, 0);
    }
    gl::UseProgram(0);
    check_gl("GpuPhotonMapper::render");
}

GLuint GpuPhotonMapper::render_tile_view() {
    if (!tile_view_) tile_view_ = make_float_texture(width_, height_);
    const GBuffer::View& view = g_buffer_.last_view();
    bind_tile_buffers();
    set_view_uniforms(tile_view_program_, view);
    gl::BindImageTexture(2, tile_view_.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    gl::DispatchCompute(groups_for(uint64_t(width_), 8), groups_for(uint64_t(height_), 8), 1);
    gl::MemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    gl::UseProgram(0);
    check_gl("GpuPhotonMapper::render_tile_view");
    return tile_view_.get();
}

uint32_t GpuPhotonMapper::stored_photons() const {
    return read_buffer_as<uint32_t>(counter_.get(), 1)[0];
}

bool GpuPhotonMapper::index_overflow() const {
    return read_buffer_as<uint32_t>(counter_.get(), 2)[1] != 0;
}

int GpuPhotonMapper::refined_pixels() const {
    return int(read_buffer_as<uint32_t>(counter_.get(), 3)[2]);
}

std::vector<GpuPhotonMapper::Photon> GpuPhotonMapper::read_photons() const {
    const size_t n = std::min<size_t>(stored_photons(), capacity_);
    return read_buffer_as<Photon>(photons_.get(), n);
}

std::vector<std::vector<uint32_t>> GpuPhotonMapper::read_tile_lists() const {
    const size_t tiles = size_t(tiles_x_) * size_t(tiles_y_);
    const std::vector<uint32_t> offsets = read_buffer_as<uint32_t>(tile_offsets_.get(), tiles + 1);
    const std::vector<uint32_t> indices =
        read_buffer_as<uint32_t>(indices_.get(), std::min<size_t>(offsets[tiles], index_capacity_));
    std::vector<std::vector<uint32_t>> lists(tiles);
    for (size_t t = 0; t < tiles; ++t) {
        const size_t end = std::min<size_t>(offsets[t + 1], indices.size());
        for (size_t k = offsets[t]; k < end; ++k) lists[t].push_back(indices[k]);
        std::sort(lists[t].begin(), lists[t].end());
    }
    return lists;
}

}  // namespace ag::gpu
