#include "gpu/gpu_bvh.h"

#include <cstring>
#include <string>

#include "gpu/prefix_sum.h"

namespace ag::gpu {

const char* const kBvhTraversalGlsl = R"(
struct BvhNode { vec3 lo; uint link; vec3 hi; uint count; };
struct BvhTriangle { vec3 v0; uint object; vec3 e1; uint triangle; vec3 e2; uint pad; };
layout(std430, binding = 6) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(std430, binding = 7) readonly buffer BvhTriangles { BvhTriangle bvh_triangles[]; };
// index: into bvh_triangles; barycentric: (u, v) of the triangle's v1 and v2 at the hit.
struct BvhHit { float t; uint object; uint triangle; uint index; vec2 barycentric; };
const uint kBvhInteriorBit = 0x80000000u;
bool bvh_intersect(vec3 origin, vec3 direction, float tmin, float tmax, out BvhHit hit) {
    hit.t = tmax;
    hit.object = 0u;
    hit.triangle = 0u;
    hit.index = 0u;
    hit.barycentric = vec2(0.0);
    if (bvh_nodes.length() == 0) return false;
    vec3 inv;
    for (int k = 0; k < 3; ++k)
        inv[k] = abs(direction[k]) > 1e-30 ? 1.0 / direction[k]
                                           : (direction[k] < 0.0 ? -1e30 : 1e30);
    uint stack[64];
    int sp = 0;
    uint node = 0u;
    bool found = false;
    while (true) {
        BvhNode n = bvh_nodes[node];
        vec3 t0 = (n.lo - origin) * inv, t1 = (n.hi - origin) * inv;
        vec3 near = min(t0, t1), far = max(t0, t1);
        float a = max(max(near.x, near.y), max(near.z, tmin));
        float b = min(min(far.x, far.y), min(far.z, hit.t));
        if (a <= b) {
            if ((n.count & kBvhInteriorBit) != 0u) {
                bool back_first = direction[int(n.count & 3u)] < 0.0;
                stack[sp++] = back_first ? node + 1u : n.link;
                node = back_first ? n.link : node + 1u;
                continue;
            }
            for (uint i = n.link; i < n.link + n.count; ++i) {
                BvhTriangle tri = bvh_triangles[i];
                vec3 p = cross(direction, tri.e2);
                float det = dot(tri.e1, p);
                if (det == 0.0) continue;
                float inv_det = 1.0 / det;
                vec3 s = origin - tri.v0;
                float u = dot(s, p) * inv_det;
                if (u < 0.0 || u > 1.0) continue;
                vec3 q = cross(s, tri.e1);
                float v = dot(direction, q) * inv_det;
                if (v < 0.0 || u + v > 1.0) continue;
                float t = dot(tri.e2, q) * inv_det;
                if (t > tmin && t < hit.t) {
                    hit.t = t;
                    hit.object = tri.object;
                    hit.triangle = tri.triangle;
                    hit.index = i;
                    hit.barycentric = vec2(u, v);
                    found = true;
                }
            }
        }
        if (sp == 0) break;
        node = stack[--sp];
    }
    return found;
}
)";

namespace {

const std::string kTraceSource = std::string(kComputeGroupIndex) + kBvhTraversalGlsl + R"(
layout(local_size_x = 64) in;
struct TraceRay { vec3 origin; float tmin; vec3 direction; float tmax; };
layout(std430, binding = 0) readonly buffer Rays { TraceRay rays[]; };
layout(std430, binding = 1) writeonly buffer Hits { uvec4 hits[]; };
uniform uint count;
void main() {
    uint i = group_index() * 64u + gl_LocalInvocationID.x;
    if (i >= count) return;
    BvhHit h;
    bool found = bvh_intersect(rays[i].origin, rays[i].direction, rays[i].tmin, rays[i].tmax, h);
    hits[i] = uvec4(found ? 1u : 0u, floatBitsToUint(h.t), h.object, h.triangle);
}
)";

}  // namespace

void GpuBvh::upload(const FlatBvh& bvh) {
    node_count_ = bvh.nodes.size();
    triangle_count_ = bvh.triangles.size();
    // A zero-sized buffer cannot be bound: an empty BVH gets one leaf without triangles.
    std::vector<BvhNode> nodes = bvh.nodes;
    if (nodes.empty()) nodes.emplace_back();
    std::vector<BvhTriangle> triangles = bvh.triangles;
    if (triangles.empty()) triangles.emplace_back();
    nodes_ = make_storage_buffer(nodes.size() * sizeof(BvhNode), nodes.data());
    triangles_ = make_storage_buffer(triangles.size() * sizeof(BvhTriangle), triangles.data());
}

void GpuBvh::bind() const {
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kBvhNodeBinding, nodes_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kBvhTriangleBinding, triangles_.get());
}

size_t GpuBvh::bytes() const {
    return node_count_ * sizeof(BvhNode) + triangle_count_ * sizeof(BvhTriangle);
}

std::vector<BvhHit> GpuBvh::trace(const std::vector<Ray>& rays) {
    static_assert(sizeof(Ray) == 32);
    if (rays.empty()) return {};
    if (!trace_) trace_ = Program::compute("bvh trace", kTraceSource);
    Buffer ray_buffer = make_storage_buffer(rays.size() * sizeof(Ray), rays.data());
    Buffer hit_buffer = make_storage_buffer(rays.size() * sizeof(glm::uvec4));
    trace_.use();
    trace_.set("count", unsigned(rays.size()));
    bind();
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, ray_buffer.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, hit_buffer.get());
    dispatch_compute(GLuint((rays.size() + 63) / 64));
    const std::vector<glm::uvec4> raw = read_buffer_as<glm::uvec4>(hit_buffer.get(), rays.size());
    std::vector<BvhHit> hits(rays.size());
    for (size_t i = 0; i < raw.size(); ++i) {
        hits[i].hit = raw[i].x != 0;
        std::memcpy(&hits[i].t, &raw[i].y, sizeof(float));
        hits[i].object = raw[i].z;
        hits[i].triangle = raw[i].w;
    }
    gl::UseProgram(0);
    check_gl("GpuBvh::trace");
    return hits;
}

}  // namespace ag::gpu
