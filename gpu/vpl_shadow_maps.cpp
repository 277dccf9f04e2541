#include "gpu/vpl_shadow_maps.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "gpu/gl.h"

namespace ag::gpu {

const char* const kVplMapGlsl = R"(
layout(std430, binding = 0) readonly buffer Vpls { vec4 vpl_data[]; };
vec3 vpl_position(int i) { return vpl_data[3 * i].xyz; }
vec3 vpl_normal(int i) { return vpl_data[3 * i + 1].xyz; }
vec3 vpl_power(int i) { return vpl_data[3 * i + 2].xyz; }
void vpl_basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}
// World offset d from VPL i in its frame (z along the normal).
vec3 vpl_local(int i, vec3 d) {
    vec3 t, b;
    vpl_basis(vpl_normal(i), t, b);
    return vec3(dot(d, t), dot(d, b), dot(d, vpl_normal(i)));
}
// Map coordinates in [0,1]² of a local direction with p.z ≥ 0. Octahedral (kind 0):
// o = p / (|x| + |y| + z) fills the diamond |o.x| + |o.y| ≤ 1, turned 45° onto the square.
// Paraboloid (kind 1): d.xy / (1 + d.z).
vec2 vpl_map_uv(vec3 p, int kind) {
    if (kind == 0) {
        vec2 o = p.xy / (abs(p.x) + abs(p.y) + p.z);
        return 0.5 * vec2(o.x + o.y, o.x - o.y) + 0.5;
    }
    vec3 d = normalize(p);
    return 0.5 * d.xy / (1.0 + d.z) + 0.5;
}
// Whether VPL i's map sees the point x with normal n at distance r from it. The map is tile
// i mod t² of layer i / t² (t = tiles a side, its record's position.w; vpl_map_layout), read
// half a texel inside its tile. The point is moved off its surface by about a texel's footprint
// at that distance (normal offset: `offset_scale` is half a texel's angle) and compared with a
// small relative bias: no self-shadowing acne. Points behind the VPL's plane are not in its map
// (seen). The offset never carries a point in front of the plane across it, out of the map: it
// is cut to leave at least half the point's height above the plane (with maps 8 texels across the
// offset is a quarter of the distance, and a ceiling 5 cm above a lamp closed in a box was seen
// from 20 cm on).
bool vpl_map_visible(sampler2DArray maps, int i, vec3 x, vec3 n, float r, int kind,
                     float offset_scale, float relative_bias) {
    vec3 p0 = vpl_local(i, x - vpl_position(i));
    vec3 p = vpl_local(i, x + n * (r * offset_scale) - vpl_position(i));
    if (p0.z > 0.0 && p.z < 0.5 * p0.z) p = mix(p0, p, 0.5 * p0.z / (p0.z - p.z));
    if (p.z <= 0.0) return true;
    int tiles = int(vpl_data[3 * i].w);
    int tile = i % (tiles * tiles);
    vec2 uv = vpl_map_uv(p, kind);
    if (tiles > 1) {
        float half_texel = 0.5 * float(tiles) / float(textureSize(maps, 0).x);
        uv = (vec2(tile % tiles, tile / tiles) + clamp(uv, half_texel, 1.0 - half_texel)) /
             float(tiles);
    }
    float stored = texture(maps, vec3(uv, float(i / (tiles * tiles)))).r;
    return length(p) <= stored * (1.0 + relative_bias);
}
)";

namespace {

const char* const kMapVertex = R"(
layout(location = 0) in vec3 position;
uniform mat4 model;
uniform int first, kind, listed, list_offset;
uniform float near_distance, far_distance;
// Culled passes: instance k of a draw is (VPL, face) instances[list_offset + k] (VplShadowMaps).
layout(std430, binding = 4) readonly buffer Instances { uint instances[]; };
out vec3 v_local;
out vec3 v_clip;
out vec4 v_tile_clip;
flat out int v_layer;
void main() {
    int faces = kind == 0 ? 4 : 1;
    int instance = listed != 0 ? int(instances[list_offset + gl_InstanceID]) : gl_InstanceID;
    int vi = first + instance / faces;
    int face = instance % faces;
    vec3 p = vpl_local(vi, (model * vec4(position, 1.0)).xyz - vpl_position(vi));
    int tiles = int(vpl_data[3 * vi].w);
    v_local = p;
    v_layer = vi / (tiles * tiles);
    if (kind == 0) {
        // Face (sx, sy): the perspective projection onto the plane sx·x + sy·y + z = 1, whose
        // depth w = sx·x + sy·y + z is the octahedral norm there; clipped to its octant.
        float sx = (face & 1) != 0 ? -1.0 : 1.0;
        float sy = (face & 2) != 0 ? -1.0 : 1.0;
        float w = sx * p.x + sy * p.y + p.z;
        float n = near_distance, f = far_distance;
        gl_Position = vec4(p.x + p.y, p.x - p.y, (w * (f + n) - 2.0 * f * n) / (f - n), w);
        v_clip = vec3(sx * p.x, sy * p.y, p.z);
    } else {
        float r = length(p);
        vec3 d = p / max(r, 1e-30);
        gl_Position = vec4(d.xy / (1.0 + d.z), 2.0 * r / far_distance - 1.0, 1.0);
        v_clip = vec3(1.0, 1.0, p.z);
    }
    v_tile_clip = vec4(1.0);
    if (tiles > 1) {
        // Tile (tx, ty) of the layer: the map's [-1, 1]² scaled into its cell, clipped there
        // (an edge of a paraboloid map's triangle that crosses the horizon reaches beyond it).
        int tile = vi % (tiles * tiles);
        vec4 c = gl_Position;
        v_tile_clip = vec4(c.w - c.x, c.w + c.x, c.w - c.y, c.w + c.y);
        vec2 cell = vec2(2 * (tile % tiles) + 1 - tiles, 2 * (tile / tiles) + 1 - tiles);
        gl_Position.xy = (c.xy + cell * c.w) / float(tiles);
    }
}
)";

const char* const kMapGeometry = R"(
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;
in vec3 v_local[];
in vec3 v_clip[];
in vec4 v_tile_clip[];
flat in int v_layer[];
out vec3 f_local;
out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[7];
};
void main() {
    // Wholly outside the face's octant (or below the horizon): nothing to clip, nothing to draw.
    for (int c = 0; c < 3; ++c)
        if (v_clip[0][c] < 0.0 && v_clip[1][c] < 0.0 && v_clip[2][c] < 0.0) return;
    for (int i = 0; i < 3; ++i) {
        gl_Position = gl_in[i].gl_Position;
        gl_ClipDistance[0] = v_clip[i].x;
        gl_ClipDistance[1] = v_clip[i].y;
        gl_ClipDistance[2] = v_clip[i].z;
        for (int c = 0; c < 4; ++c) gl_ClipDistance[3 + c] = v_tile_clip[i][c];
        gl_Layer = v_layer[0];
        f_local = v_local[i];
        EmitVertex();
    }
    EndPrimitive();
}
)";

const char* const kMapFragment = R"(
in vec3 f_local;
layout(location = 0) out float out_distance;
void main() { out_distance = length(f_local); }
)";

}  // namespace

VplMapLimits VplMapLimits::gl_limits() {
    VplMapLimits l;
    gl::GetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &l.max_layers);
    gl::GetIntegerv(GL_MAX_TEXTURE_SIZE, &l.max_texture_size);
    return l;
}

VplMapLayout vpl_map_layout(int count, int size, const VplMapLimits& limits) {
    auto fail = [&](const std::string& why) {
        throw std::runtime_error(
            "vpl.map_size " + std::to_string(size) + ": " + std::to_string(count) +
            " shadow maps " + why + " (the GL allows " + std::to_string(limits.max_layers) +
            " array layers of at most " + std::to_string(limits.max_texture_size) + "² texels)");
    };
    if (size < 1 || size > limits.max_texture_size) fail("do not fit one texture");
    VplMapLayout l;
    const int most_tiles = limits.max_texture_size / size;
    while (int64_t(l.tiles) * l.tiles * limits.max_layers < int64_t(count)) {
        if (++l.tiles > most_tiles) fail("do not fit the array layers even as an atlas");
    }
    const int per_layer = l.tiles * l.tiles;
    l.layers = std::max(1, (count + per_layer - 1) / per_layer);
    return l;
}

VplShadowMaps::VplShadowMaps(const Scene& scene, const SceneMeshes& meshes, int size,
                             VplMapKind kind, float near_distance, const VplMapLimits& limits)
    : scene_(scene),
      meshes_(meshes),
      size_(size),
      kind_(kind),
      near_(near_distance),
      limits_(limits),
      program_("vpl shadow map", std::string(kVplMapGlsl) + kMapVertex, kMapGeometry, kMapFragment),
      vpl_buffer_(make_buffer()),
      layered_(make_framebuffer()),
      single_(make_framebuffer()),
      instances_(make_buffer()) {
    (void)vpl_map_layout(1, size_, limits_);  // the size alone must fit
    Bounds b;
    for (const Object& o : scene.objects)
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const Mesh& mesh = scene.objects[i].mesh;
        const int triangles = int(mesh.triangles.size());
        uint64_t counted = 0;
        for (int first = 0; first < triangles; first += kChunkTriangles) {
            Chunk c;
            c.object = i, c.first = first;
            c.count = std::min(kChunkTriangles, triangles - first);
            Bounds cb;
            for (int t = first; t < first + c.count; ++t)
                for (int k = 0; k < 3; ++k)
                    cb.add(mesh.positions[size_t(mesh.triangles[size_t(t)][k])]);
            c.min = cb.min, c.max = cb.max;
            // The run's share of the object's vertices (the shares sum to them exactly).
            const uint64_t upto =
                uint64_t(mesh.positions.size()) * uint64_t(first + c.count) / uint64_t(triangles);
            c.vertices = upto - counted;
            counted = upto;
            chunks_.push_back(c);
        }
    }
    // Moved objects stay within a few scene diagonals; the far plane only bounds the depth range.
    far_ = 4.0f * std::max(1e-3f, glm::length(b.extent()));
}

void VplShadowMaps::bind_buffer() const {
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, vpl_buffer_.get());
}

void VplShadowMaps::set_vpls(const std::vector<Vpl>& vpls) {
    const int count = int(vpls.size());
    if (count > capacity_) {
        // Grow (with room) and start the new arrays cleared: nothing drawn reads as unoccluded.
        // The layout is checked before any GL call, so a scene with too many VPLs fails here
        // with the limits named, not with an incomplete framebuffer.
        const int capacity = std::max(count, capacity_ + capacity_ / 2);
        VplMapLayout layout;
        try {
            layout = vpl_map_layout(capacity, size_, limits_);
        } catch (const std::runtime_error&) {
            layout = vpl_map_layout(count, size_, limits_);  // without the room, if that fits
        }
        const int side = layout.side(size_);
        distance_ = make_texture();
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, distance_.get());
        gl::TexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_R32F, side, side, layout.layers);
        gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        const float far = 1e30f;
        gl::ClearTexImage(distance_.get(), 0, GL_RED, GL_FLOAT, &far);
        depth_ = make_texture();
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, depth_.get());
        gl::TexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_DEPTH_COMPONENT32F, side, side, layout.layers);
        if (gl::GetError() != GL_NO_ERROR)
            throw GlError("VplShadowMaps: cannot allocate " + std::to_string(layout.layers) +
                          " layers of " + std::to_string(side) + "² texels (" +
                          std::to_string(count) + " maps of vpl.map_size " + std::to_string(size_) +
                          ", " + std::to_string(int64_t(side) * side * layout.layers * 8 >> 20) +
                          " MiB)");
        gl::BindFramebuffer(GL_FRAMEBUFFER, layered_.get());
        gl::FramebufferTexture(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, distance_.get(), 0);
        gl::FramebufferTexture(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, depth_.get(), 0);
        const GLenum status = gl::CheckFramebufferStatus(GL_FRAMEBUFFER);
        if (status != GL_FRAMEBUFFER_COMPLETE)
            throw GlError("VPL shadow-map framebuffer incomplete: " + std::to_string(status));
        capacity_ = layout.tiles * layout.tiles * layout.layers;
        layout_ = layout;
    }
    std::vector<glm::vec4> data;
    data.reserve(vpls.size() * 3 + 3);
    for (const Vpl& v : vpls) {
        data.emplace_back(v.position, float(layout_.tiles));
        data.emplace_back(v.normal, 0.0f);
        data.emplace_back(v.power, 0.0f);
    }
    if (data.empty()) data.resize(3, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, vpl_buffer_.get());
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(data.size() * sizeof(glm::vec4)),
                   data.data(), GL_DYNAMIC_DRAW);
    count_ = count;
    vpls_ = vpls;
    check_gl("VplShadowMaps::set_vpls");
}

namespace {

// The tangent frame of kVplMapGlsl's vpl_basis (the same sign rule), for the culling tests.
void vpl_basis(const glm::vec3& n, glm::vec3& t, glm::vec3& b) {
    const float s = n.z >= 0.0f ? 1.0f : -1.0f;
    const float a = -1.0f / (s + n.z);
    const float c = n.x * n.y * a;
    t = glm::vec3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    b = glm::vec3(c, s + n.y * n.y * a, -n.y);
}

}  // namespace

void VplShadowMaps::draw_culled(int first, int count, int faces) {
    // A run's box lies wholly outside face (sx, sy)'s octant when all eight corners are on the
    // negative side of one of its planes sx·x = 0, sy·y = 0, z = 0 (VPL frame): then so is every
    // vertex of every triangle in it, and the geometry shader would drop them all. The margin
    // keeps the CPU's rounding on the GPU's side of that test.
    const float margin = 1e-6f * far_;
    const size_t vpls = static_cast<size_t>(count);
    std::vector<glm::vec3> position(vpls), t(vpls), b(vpls), n(vpls);
    for (int v = 0; v < count; ++v) {
        position[size_t(v)] = vpls_[size_t(first + v)].position;
        n[size_t(v)] = vpls_[size_t(first + v)].normal;
        vpl_basis(n[size_t(v)], t[size_t(v)], b[size_t(v)]);
    }
    std::vector<uint32_t> list;
    struct Draw {
        size_t chunk;
        int offset, instances;
    };
    std::vector<Draw> draws;
    for (size_t ci = 0; ci < chunks_.size(); ++ci) {
        const Chunk& c = chunks_[ci];
        const glm::mat4 model = model_matrix(scene_.objects[c.object]);
        glm::vec3 corner[8];
        for (int k = 0; k < 8; ++k)
            corner[k] = glm::vec3(model * glm::vec4((k & 1) ? c.max.x : c.min.x,
                                                    (k & 2) ? c.max.y : c.min.y,
                                                    (k & 4) ? c.max.z : c.min.z, 1.0f));
        const int offset = int(list.size());
        for (int v = 0; v < count; ++v) {
            // Largest of x, −x, y, −y, z over the corners, in the VPL's frame.
            float hi[5] = {-1e30f, -1e30f, -1e30f, -1e30f, -1e30f};
            for (const glm::vec3& p : corner) {
                const glm::vec3 d = p - position[size_t(v)];
                const float x = glm::dot(d, t[size_t(v)]), y = glm::dot(d, b[size_t(v)]);
                hi[0] = std::max(hi[0], x), hi[1] = std::max(hi[1], -x);
                hi[2] = std::max(hi[2], y), hi[3] = std::max(hi[3], -y);
                hi[4] = std::max(hi[4], glm::dot(d, n[size_t(v)]));
            }
            if (hi[4] < -margin) continue;  // below the horizon: no face
            for (int f = 0; f < faces; ++f) {
                // Face bits as in kMapVertex: bit 0 flips x, bit 1 flips y.
                if (faces == 4 && (hi[(f & 1) ? 1 : 0] < -margin || hi[(f & 2) ? 3 : 2] < -margin))
                    continue;
                list.push_back(uint32_t(v * faces + f));
            }
        }
        const int instances = int(list.size()) - offset;
        if (instances > 0) draws.push_back({ci, offset, instances});
    }
    if (list.empty()) return;
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, instances_.get());
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(list.size() * sizeof(uint32_t)),
                   list.data(), GL_STREAM_DRAW);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, instances_.get());
    program_.set("listed", 1);
    size_t object = size_t(-1);
    for (const Draw& d : draws) {
        const Chunk& c = chunks_[d.chunk];
        if (c.object != object) {
            object = c.object;
            program_.set("model", model_matrix(scene_.objects[object]));
        }
        program_.set("list_offset", d.offset);
        meshes_.draw_instanced(c.object, c.first, c.count, d.instances);
        vertices_ += c.vertices * uint64_t(d.instances);
    }
}

void VplShadowMaps::render(int first, int count) {
    count = std::min(count, count_ - first);
    if (count <= 0) return;
    // Clear just these maps (the layered framebuffer would clear every layer; in an atlas the
    // scissor keeps the layer's other maps).
    const int tiles = layout_.tiles, per_layer = tiles * tiles;
    gl::BindFramebuffer(GL_FRAMEBUFFER, single_.get());
    const GLenum buffer = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &buffer);
    gl::DepthMask(GL_TRUE);
    gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    if (tiles > 1) {
        gl::Enable(GL_SCISSOR_TEST);
    } else {
        gl::Disable(GL_SCISSOR_TEST);
    }
    const float far[4] = {1e30f, 0.0f, 0.0f, 0.0f};
    for (int l = first; l < first + count; ++l) {
        const int layer = l / per_layer, tile = l % per_layer;
        gl::FramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, distance_.get(), 0,
                                    layer);
        gl::FramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, depth_.get(), 0, layer);
        if (tiles > 1) gl::Scissor((tile % tiles) * size_, (tile / tiles) * size_, size_, size_);
        gl::ClearBufferfv(GL_COLOR, 0, far);
        const float one = 1.0f;
        gl::ClearBufferfv(GL_DEPTH, 0, &one);
    }
    gl::Disable(GL_SCISSOR_TEST);
    gl::BindFramebuffer(GL_FRAMEBUFFER, layered_.get());
    gl::DrawBuffers(1, &buffer);
    gl::Viewport(0, 0, layout_.side(size_), layout_.side(size_));
    gl::Enable(GL_DEPTH_TEST);
    gl::DepthFunc(GL_LESS);
    gl::Disable(GL_BLEND);
    gl::Disable(GL_STENCIL_TEST);
    gl::Disable(GL_CULL_FACE);  // both sides occlude
    // Three octant/horizon planes; in an atlas four more keep each map inside its tile.
    const int planes = tiles > 1 ? 7 : 3;
    for (int c = 0; c < planes; ++c) gl::Enable(GL_CLIP_DISTANCE0 + GLenum(c));
    program_.use();
    bind_buffer();
    program_.set("first", first);
    program_.set("kind", int(kind_));
    program_.set("near_distance", near_);
    program_.set("far_distance", far_);
    const int faces = kind_ == VplMapKind::octahedral ? 4 : 1;
    if (!culling_) {
        program_.set("listed", 0);
        for (size_t i = 0; i < scene_.objects.size(); ++i) {
            program_.set("model", model_matrix(scene_.objects[i]));
            meshes_.draw_instanced(i, count * faces);
            vertices_ +=
                uint64_t(scene_.objects[i].mesh.positions.size()) * uint64_t(count * faces);
        }
    } else {
        draw_culled(first, count, faces);
    }
    for (int c = 0; c < planes; ++c) gl::Disable(GL_CLIP_DISTANCE0 + GLenum(c));
    // Let llvmpipe drain the map passes here: queuing two full passes of hundreds of layered,
    // instanced map draws without a finish corrupted its memory (a crash when the context was
    // destroyed at exit; VplGlTest.OctahedralMapVisibilityMatchesEmbreeRaysOnCornell renders all
    // 311 maps at 256² twice). The gather reads the maps next anyway.
    gl::Finish();
    check_gl("VplShadowMaps::render");
}

std::vector<float> VplShadowMaps::read_layer(int i) const {
    const int per_layer = layout_.tiles * layout_.tiles, tile = i % per_layer;
    gl::BindFramebuffer(GL_READ_FRAMEBUFFER, single_.get());
    gl::FramebufferTextureLayer(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, distance_.get(), 0,
                                i / per_layer);
    gl::ReadBuffer(GL_COLOR_ATTACHMENT0);
    std::vector<float> out(size_t(size_) * size_t(size_));
    gl::PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl::ReadPixels((tile % layout_.tiles) * size_, (tile / layout_.tiles) * size_, size_, size_,
                   GL_RED, GL_FLOAT, out.data());
    return out;
}

}  // namespace ag::gpu
