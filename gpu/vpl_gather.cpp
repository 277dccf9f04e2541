#include "gpu/vpl_gather.h"

#include <algorithm>
#include <glm/gtc/constants.hpp>

#include "gpu/gl.h"

namespace ag::gpu {

namespace {
const char* const kGatherFragment = R"(
uniform sampler2D positions, normals;
uniform sampler2DArray maps;
uniform int count, kind, visibility, labelled;
uniform int tiled, interleave, tile_size, tiles_x;
layout(std430, binding = 1) readonly buffer Labels { uint labels[]; };
layout(std430, binding = 2) readonly buffer TileOffsets { uint tile_offsets[]; };
layout(std430, binding = 3) readonly buffer TileEntries { uint tile_entries[]; };
uniform float clamp2, scale, offset_scale, relative_bias;
layout(location = 0) out vec4 out_e;
// VPL i's irradiance at x (normal n) up to 1/π; `lookup`: read its shadow map.
vec3 contribution(int i, vec3 x, vec3 n, bool lookup) {
    vec3 d = vpl_position(i) - x;
    float d2 = dot(d, d);
    if (d2 <= 0.0) return vec3(0.0);
    float inv = inversesqrt(d2);
    float cos_x = dot(n, d) * inv, cos_l = -dot(vpl_normal(i), d) * inv;
    if (cos_x <= 0.0 || cos_l <= 0.0) return vec3(0.0);
    if (visibility != 0 && lookup &&
        !vpl_map_visible(maps, i, x, n, d2 * inv, kind, offset_scale, relative_bias))
        return vec3(0.0);
    return vpl_power(i) * (cos_x * cos_l / max(d2, clamp2));
}
void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 xw = texelFetch(positions, px, 0);
    vec3 x = xw.xyz;
    int patch_base = int(xw.w) * count;
    vec3 n = texelFetch(normals, px, 0).xyz;
    out_e = vec4(0.0, 0.0, 0.0, 1.0);
    if (n == vec3(0.0)) return;
    vec3 e = vec3(0.0);
    if (tiled != 0) {
        // This tile's list of the pixel's interleave class; the top bit asks for a lookup.
        ivec2 t = px / tile_size;
        int cls = (px.x % interleave) + interleave * (px.y % interleave);
        int slot = (t.y * tiles_x + t.x) * interleave * interleave + cls;
        uint end = tile_offsets[slot + 1];
        for (uint j = tile_offsets[slot]; j < end; ++j) {
            uint entry = tile_entries[j];
            e += contribution(int(entry & 0x7fffffffu), x, n, (entry >> 31) != 0u);
        }
    } else {
        for (int i = 0; i < count; ++i) {
            uint label = labelled != 0 ? labels[patch_base + i] : 1u;
            if (label >= 2u) continue;
            e += contribution(i, x, n, label == 1u);
        }
    }
    out_e.rgb = e * scale;
}
)";

// Interleaved sampling's reconstruction: per class, the mean of its partial sums over the
// (2n−1)² neighbours on the pixel's surface; classes no neighbour holds are made up by scaling.
const char* const kFilterFragment = R"(
uniform sampler2D positions, normals, partial;
uniform int interleave, wide;
layout(location = 0) out vec4 out_e;
void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(partial, 0);
    // wide: the (2n−1)² window around the pixel; narrow: the n × n window starting n/2 before
    // it (each class once).
    int lo = wide != 0 ? 1 - interleave : -(interleave / 2);
    int hi = wide != 0 ? interleave - 1 : interleave - 1 - interleave / 2;
    vec3 x = texelFetch(positions, px, 0).xyz;
    vec3 n = texelFetch(normals, px, 0).xyz;
    out_e = vec4(0.0, 0.0, 0.0, 1.0);
    if (n == vec3(0.0)) return;
    vec3 acc[16];
    float cnt[16];
    int nn = interleave * interleave;
    for (int c = 0; c < 16; ++c) {
        acc[c] = vec3(0.0);
        cnt[c] = 0.0;
    }
    for (int dy = lo; dy <= hi; ++dy)
        for (int dx = lo; dx <= hi; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
            vec3 nq = texelFetch(normals, q, 0).xyz;
            if (dot(n, nq) < 0.9) continue;
            vec3 d = texelFetch(positions, q, 0).xyz - x;
            if (abs(dot(n, d)) > 0.1 * length(d)) continue;
            int c = (q.x % interleave) + interleave * (q.y % interleave);
            acc[c] += texelFetch(partial, q, 0).rgb;
            cnt[c] += 1.0;
        }
    vec3 e = vec3(0.0);
    int have = 0;
    for (int c = 0; c < nn; ++c)
        if (cnt[c] > 0.0) {
            e += acc[c] / cnt[c];
            ++have;
        }
    out_e.rgb = e * (float(nn) / float(max(have, 1)));
}
)";

// VPL i's interleave class: a fixed hash, so a class is a random-like share of the VPLs
// whatever order the sources list them in.
int vpl_class(size_t i, int classes) {
    uint32_t h = uint32_t(i) * 2654435761u;
    h ^= h >> 16;
    return int(h % uint32_t(classes));
}
}  // namespace

VplGather::VplGather(int width, int height)
    : width_(width),
      height_(height),
      program_("vpl gather", kFullScreenTriangleVertex, std::string(kVplMapGlsl) + kGatherFragment),
      filter_("vpl interleave filter", kFullScreenTriangleVertex, kFilterFragment),
      fbo_(make_framebuffer()),
      partial_fbo_(make_framebuffer()),
      labels_(make_buffer()),
      tile_offsets_(make_buffer()),
      tile_entries_(make_buffer()),
      empty_vao_(make_vertex_array()) {
    positions_ = make_float_texture(width, height);
    normals_ = make_float_texture(width, height);
    output_ = make_float_texture(width, height);
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, output_.get(), 0);
    partial_ = make_float_texture(width, height);
    gl::BindFramebuffer(GL_FRAMEBUFFER, partial_fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, partial_.get(),
                             0);
    check_gl("VplGather");
}

void VplGather::set_points(const std::vector<glm::vec3>& positions,
                           const std::vector<glm::vec3>& normals, const std::vector<int>& patches) {
    auto upload = [&](const Texture& t, const std::vector<glm::vec3>& v) {
        std::vector<float> rgba(v.size() * 4, 0.0f);
        for (size_t i = 0; i < v.size(); ++i) {
            for (int c = 0; c < 3; ++c) rgba[4 * i + size_t(c)] = v[i][c];
            // Patch indices ride in alpha (exact in float up to 2^24).
            if (&v == &positions && i < patches.size()) rgba[4 * i + 3] = float(patches[i]);
        }
        gl::BindTexture(GL_TEXTURE_2D, t.get());
        gl::TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_, height_, GL_RGBA, GL_FLOAT, rgba.data());
    };
    upload(positions_, positions);
    upload(normals_, normals);
    cpu_positions_ = positions;
    cpu_normals_ = normals;
    cpu_patches_ = patches;
    check_gl("VplGather::set_points");
}

void VplGather::set_tiles(const std::vector<Vpl>& vpls, int interleave,
                          const std::vector<uint32_t>* labels, bool wide_filter) {
    interleave_ = std::clamp(interleave, 1, 4);
    wide_filter_ = wide_filter;
    tile_ = interleave_ == 3 ? 6 : kTile;
    tiles_x_ = (width_ + tile_ - 1) / tile_;
    const int tiles_y = (height_ + tile_ - 1) / tile_;
    const int classes = interleave_ * interleave_;
    const size_t count = vpls.size();
    std::vector<int> cls(count);
    for (size_t i = 0; i < count; ++i) cls[i] = vpl_class(i, classes);
    std::vector<uint32_t> offsets(size_t(tiles_x_) * size_t(tiles_y) * size_t(classes) + 1, 0);
    std::vector<uint32_t> entries;
    std::vector<std::vector<uint32_t>> by_class(static_cast<size_t>(classes));
    tile_counts_ = {};
    std::vector<size_t> inside;
    for (int ty = 0; ty < tiles_y; ++ty)
        for (int tx = 0; tx < tiles_x_; ++tx) {
            inside.clear();
            for (int y = ty * tile_; y < std::min(height_, (ty + 1) * tile_); ++y)
                for (int x = tx * tile_; x < std::min(width_, (tx + 1) * tile_); ++x) {
                    const size_t p = size_t(y) * size_t(width_) + size_t(x);
                    if (p < cpu_normals_.size() && cpu_normals_[p] != glm::vec3(0.0f))
                        inside.push_back(p);
                }
            for (auto& b : by_class) b.clear();
            for (size_t i = 0; i < count; ++i) {
                const Vpl& v = vpls[i];
                if (v.power == glm::vec3(0.0f)) continue;
                ++tile_counts_.pairs;
                bool lit = false, lookup = false;
                for (size_t p : inside) {
                    const glm::vec3 d = v.position - cpu_positions_[p];
                    if (glm::dot(cpu_normals_[p], d) <= 0.0f || glm::dot(v.normal, d) >= 0.0f)
                        continue;  // one of the cosines is not positive: no light here
                    uint32_t label = 1;
                    if (labels) {
                        const size_t patch = p < cpu_patches_.size() ? size_t(cpu_patches_[p]) : 0;
                        label = (*labels)[patch * count + i];
                    }
                    if (label >= 2u) continue;  // fully occluded (or behind) at this patch
                    lit = true;
                    if (label == 1u) {
                        lookup = true;
                        break;  // listed with a lookup: nothing more to learn
                    }
                }
                if (!lit) continue;
                ++tile_counts_.entries;
                tile_counts_.lookups += lookup ? 1 : 0;
                by_class[size_t(cls[i])].push_back(uint32_t(i) | (lookup ? 0x80000000u : 0u));
            }
            const size_t base = (size_t(ty) * size_t(tiles_x_) + size_t(tx)) * size_t(classes);
            for (int c = 0; c < classes; ++c) {
                offsets[base + size_t(c)] = uint32_t(entries.size());
                entries.insert(entries.end(), by_class[size_t(c)].begin(),
                               by_class[size_t(c)].end());
            }
            offsets[base + size_t(classes)] = uint32_t(entries.size());
            for (size_t p : inside) {
                const int x = int(p % size_t(width_)), y = int(p / size_t(width_));
                const int c = (x % interleave_) + interleave_ * (y % interleave_);
                for (uint32_t j = offsets[base + size_t(c)]; j < offsets[base + size_t(c) + 1];
                     ++j) {
                    ++tile_counts_.evaluations;
                    tile_counts_.evaluated_lookups += (entries[j] >> 31) != 0u ? 1 : 0;
                }
            }
        }
    if (entries.empty()) entries.push_back(0);
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, tile_offsets_.get());
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(offsets.size() * sizeof(uint32_t)),
                   offsets.data(), GL_DYNAMIC_DRAW);
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, tile_entries_.get());
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(entries.size() * sizeof(uint32_t)),
                   entries.data(), GL_DYNAMIC_DRAW);
    tiled_ = true;
    check_gl("VplGather::set_tiles");
}

void VplGather::clear_tiles() {
    tiled_ = false;
    interleave_ = 1;
}

void VplGather::set_labels(const std::vector<uint32_t>& labels) {
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, labels_.get());
    const std::vector<uint32_t> one(1, 1u);
    const std::vector<uint32_t>& data = labels.empty() ? one : labels;
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(data.size() * sizeof(uint32_t)),
                   data.data(), GL_STATIC_DRAW);
    check_gl("VplGather::set_labels");
}

void VplGather::shade(const VplShadowMaps& maps, float clamp, float scale, bool visibility,
                      bool labelled) {
    const bool interleaved = tiled_ && interleave_ > 1;
    gl::BindFramebuffer(GL_FRAMEBUFFER, interleaved ? partial_fbo_.get() : fbo_.get());
    const GLenum buffer = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &buffer);
    gl::Viewport(0, 0, width_, height_);
    gl::Disable(GL_DEPTH_TEST);
    gl::Disable(GL_BLEND);
    gl::Disable(GL_STENCIL_TEST);
    gl::Disable(GL_CULL_FACE);
    program_.use();
    maps.bind_buffer();
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, positions_.get());
    gl::ActiveTexture(GL_TEXTURE1);
    gl::BindTexture(GL_TEXTURE_2D, normals_.get());
    gl::ActiveTexture(GL_TEXTURE2);
    gl::BindTexture(GL_TEXTURE_2D_ARRAY, maps.texture());
    gl::ActiveTexture(GL_TEXTURE0);
    program_.set("positions", 0);
    program_.set("normals", 1);
    program_.set("maps", 2);
    program_.set("count", maps.count());
    program_.set("kind", int(maps.kind()));
    program_.set("visibility", visibility && maps.count() > 0 ? 1 : 0);
    program_.set("labelled", labelled ? 1 : 0);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, labels_.get());
    program_.set("tiled", tiled_ ? 1 : 0);
    program_.set("interleave", interleave_);
    program_.set("tile_size", tile_);
    program_.set("tiles_x", tiles_x_);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, tile_offsets_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, tile_entries_.get());
    program_.set("clamp2", clamp * clamp);
    program_.set("scale", scale * glm::one_over_pi<float>());
    program_.set("offset_scale", maps.offset_scale());
    program_.set("relative_bias", VplShadowMaps::kRelativeBias);
    gl::BindVertexArray(empty_vao_.get());
    gl::DrawArrays(GL_TRIANGLES, 0, 3);
    if (interleaved) {
        gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
        gl::DrawBuffers(1, &buffer);
        filter_.use();
        gl::ActiveTexture(GL_TEXTURE0);
        gl::BindTexture(GL_TEXTURE_2D, positions_.get());
        gl::ActiveTexture(GL_TEXTURE1);
        gl::BindTexture(GL_TEXTURE_2D, normals_.get());
        gl::ActiveTexture(GL_TEXTURE2);
        gl::BindTexture(GL_TEXTURE_2D, partial_.get());
        gl::ActiveTexture(GL_TEXTURE0);
        filter_.set("positions", 0);
        filter_.set("normals", 1);
        filter_.set("partial", 2);
        filter_.set("interleave", interleave_);
        filter_.set("wide", wide_filter_ ? 1 : 0);
        gl::DrawArrays(GL_TRIANGLES, 0, 3);
    }
    check_gl("VplGather::shade");
}

std::vector<glm::vec3> VplGather::read_back() const {
    const std::vector<float> rgba =
        read_rgba(fbo_.get(), GL_COLOR_ATTACHMENT0, 0, 0, width_, height_);
    std::vector<glm::vec3> out(size_t(width_) * size_t(height_));
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = {rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]};
    return out;
}

}  // namespace ag::gpu
