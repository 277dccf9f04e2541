#include "gpu/radiance_cache_splat.h"

#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <string>

#include "shared/camera.h"

namespace ag::gpu {

namespace {

constexpr int kRecordVec4s = 10;  // the record layout of kRecordsGlsl

// Per record, 10 vec4: position·R, normal·born, iim, temporal gradient, the rotation gradient's
// three channel columns, the translation gradient's.
const std::string kRecordsGlsl =
    "const float kMaxWardWeight = " + std::to_string(kMaxWardWeight) + R"(;
layout(std430, binding = 0) readonly buffer Records { vec4 rec[]; };
)";

const std::string kSplatVertex = kRecordsGlsl + R"(
uniform mat4 view_projection;
uniform float accuracy;
flat out int v_record;
void main() {
    int k = gl_InstanceID;
    vec4 pr = rec[10 * k];
    float radius = accuracy * pr.w;
    // The screen rectangle of the zone of influence's bounding cube; all of the screen if a
    // corner is behind the eye.
    vec2 lo = vec2(1e30), hi = vec2(-1e30);
    bool behind = false;
    for (int i = 0; i < 8; ++i) {
        vec3 s = vec3((i & 1) != 0 ? 1.0 : -1.0, (i & 2) != 0 ? 1.0 : -1.0, (i & 4) != 0 ? 1.0 : -1.0);
        vec4 h = view_projection * vec4(pr.xyz + radius * s, 1.0);
        if (h.w <= 1e-6) { behind = true; break; }
        lo = min(lo, h.xy / h.w);
        hi = max(hi, h.xy / h.w);
    }
    if (behind) { lo = vec2(-1.0); hi = vec2(1.0); }
    lo = clamp(lo, vec2(-1.0), vec2(1.0));
    hi = clamp(hi, vec2(-1.0), vec2(1.0));
    const vec2 corners[6] = vec2[6](vec2(0, 0), vec2(1, 0), vec2(1, 1), vec2(0, 0), vec2(1, 1), vec2(0, 1));
    gl_Position = vec4(mix(lo, hi, corners[gl_VertexID]), 0.0, 1.0);
    v_record = k;
}
)";

// Gautron Algorithm 3: Ward's weight (eq. 2.5) with the behind test, cut off at 1/a (eq. 2.6),
// the extrapolated E_k(p) (eq. 5.11); the same arithmetic as ag::ward_weight and ag::extrapolate.
const std::string kSplatFragment = kRecordsGlsl + R"(
uniform sampler2D positions;
uniform sampler2D normals;
uniform float accuracy;
uniform int frame;
flat in int v_record;
out vec4 color;
void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 p = texelFetch(positions, px, 0);
    if (p.a == 0.0) discard;
    vec3 n = texelFetch(normals, px, 0).xyz;
    int b = 10 * v_record;
    vec3 pk = rec[b].xyz;
    float r = rec[b].w;
    vec3 nk = rec[b + 1].xyz;
    vec3 d = p.xyz - pk;
    if (dot(d, 0.5 * (n + nk)) < -0.05 * r) discard;
    float angular = sqrt(max(0.0, 1.0 - dot(n, nk)));
    float e = length(d) / r + angular;
    float w = e > 1.0 / kMaxWardWeight ? 1.0 / e : kMaxWardWeight;
    if (w < 1.0 / accuracy) discard;
    vec3 axis = cross(nk, n);
    vec3 value = rec[b + 2].rgb + float(frame - int(rec[b + 1].w)) * rec[b + 3].rgb;
    value += vec3(dot(axis, rec[b + 4].xyz), dot(axis, rec[b + 5].xyz), dot(axis, rec[b + 6].xyz));
    value += vec3(dot(d, rec[b + 7].xyz), dot(d, rec[b + 8].xyz), dot(d, rec[b + 9].xyz));
#ifdef RECORD_VIEW
    // The record's own colour, brighter towards it (w/(1/a) grows from 1 at the rim).
    uint h = uint(v_record) * 2654435761u;
    vec3 c = vec3(float(h & 255u), float((h >> 8) & 255u), float((h >> 16) & 255u)) / 255.0;
    float near = clamp(0.25 * w * accuracy, 0.0, 1.0);
    value = length(d) < 0.02 * r ? vec3(40.0) : mix(0.3 * c, c, near);
#endif
    color = vec4(w * max(value, vec3(0.0)), w);
}
)";

const char* kGbufferFragment = R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
uniform int diffuse;
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;
void main() {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;
    out_position = vec4(v_world, diffuse != 0 ? 1.0 : 0.0);
    out_normal = vec4(n, 0.0);
}
)";

const char* kNormaliseFragment = R"(
uniform sampler2D sums;
out vec4 color;
void main() {
    vec4 s = texelFetch(sums, ivec2(gl_FragCoord.xy), 0);
    color = vec4(s.a > 0.0 ? s.rgb / s.a : vec3(0.0), 1.0);
}
)";

// Per tile, the smallest in-tile index of an uncovered pixel (atomicMin: the same whatever order
// fragments run in).
const char* kScanFragment = R"(
layout(std430, binding = 1) buffer Tiles { int first[]; };
uniform sampler2D sums;
uniform sampler2D positions;
uniform float accuracy;
uniform int tile;
uniform int tiles_x;
void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    if (texelFetch(positions, px, 0).a == 0.0) discard;
    if (texelFetch(sums, px, 0).a >= accuracy) discard;
    ivec2 t = px / tile;
    atomicMin(first[t.y * tiles_x + t.x], (px.y % tile) * tile + px.x % tile);
    discard;
}
)";

Texture float_target(int w, int h) { return make_float_texture(w, h); }

glm::mat4 camera_view_projection(const Scene& scene, int width, int height) {
    // As gpu::FrameRenderer draws the frame, so the splat's pixels are the frame's.
    const glm::mat4 projection = glm::infinitePerspective(
        glm::radians(scene.camera.fov_y), float(width) / float(height), 1e-3f * scene.diagonal());
    return projection * view_matrix(scene.camera);
}

}  // namespace

RadianceCacheSplat::RadianceCacheSplat(const Scene& scene, const SceneMeshes& meshes, int width,
                                       int height)
    : scene_(scene), meshes_(meshes), width_(width), height_(height) {
    gbuffer_ = Program("radiance cache g-buffer", kSceneVertex, kGbufferFragment);
    splat_ = Program("radiance cache splat", kSplatVertex, kSplatFragment);
    normalise_ = Program("radiance cache normalise", kFullScreenTriangleVertex, kNormaliseFragment);
    scan_ = Program("radiance cache scan", kFullScreenTriangleVertex, kScanFragment);
    view_program_ = Program("radiance cache record view", kSplatVertex,
                            "#define RECORD_VIEW\n" + kSplatFragment);
    position_ = float_target(width, height);
    normal_ = float_target(width, height);
    sums_ = float_target(width, height);
    term_ = float_target(width, height);
    view_ = float_target(width, height);
    view_sums_ = float_target(width, height);
    depth_ = make_renderbuffer();
    gl::BindRenderbuffer(GL_RENDERBUFFER, depth_.get());
    gl::RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
    gbuffer_fbo_ = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, gbuffer_fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, position_.get(),
                             0);
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, normal_.get(), 0);
    gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_.get());
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("radiance cache splat: g-buffer framebuffer incomplete");
    splat_fbo_ = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, splat_fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, sums_.get(), 0);
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("radiance cache splat: splat framebuffer incomplete");
    term_fbo_ = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, term_fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, term_.get(), 0);
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("radiance cache splat: term framebuffer incomplete");
    view_sums_fbo_ = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, view_sums_fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, view_sums_.get(),
                             0);
    view_fbo_ = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, view_fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, view_.get(), 0);
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("radiance cache splat: view framebuffer incomplete");
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    records_ = make_buffer();
    tiles_ = make_buffer();
    empty_ = make_vertex_array();
    clear();
    check_gl("RadianceCacheSplat");
}

void RadianceCacheSplat::render_gbuffer() {
    begin_scene_pass(gbuffer_fbo_.get(), 2, width_, height_, glm::vec4(0.0f));
    gbuffer_.use();
    gbuffer_.set("view_projection", camera_view_projection(scene_, width_, height_));
    for (size_t o = 0; o < scene_.objects.size(); ++o) {
        gbuffer_.set("model", model_matrix(scene_.objects[o]));
        gbuffer_.set("diffuse", scene_.objects[o].material.type == MaterialType::diffuse ? 1 : 0);
        meshes_.draw(o);
    }
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("RadianceCacheSplat::render_gbuffer");
}

std::vector<SplatPixel> RadianceCacheSplat::read_gbuffer() const {
    const std::vector<float> p =
        read_rgba(gbuffer_fbo_.get(), GL_COLOR_ATTACHMENT0, 0, 0, width_, height_);
    const std::vector<float> n =
        read_rgba(gbuffer_fbo_.get(), GL_COLOR_ATTACHMENT1, 0, 0, width_, height_);
    std::vector<SplatPixel> out(size_t(width_) * size_t(height_));
    for (size_t i = 0; i < out.size(); ++i) {
        out[i].position = glm::vec3(p[4 * i], p[4 * i + 1], p[4 * i + 2]);
        out[i].normal = glm::vec3(n[4 * i], n[4 * i + 1], n[4 * i + 2]);
        out[i].covered = p[4 * i + 3] != 0.0f;
    }
    return out;
}

void RadianceCacheSplat::clear() {
    gl::BindFramebuffer(GL_FRAMEBUFFER, splat_fbo_.get());
    const GLenum draw = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &draw);
    gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl::ClearColor(0, 0, 0, 0);
    gl::Clear(GL_COLOR_BUFFER_BIT);
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
}

void RadianceCacheSplat::render_record_view(const std::vector<IrradianceRecord>& records,
                                            float accuracy) {
    gl::BindFramebuffer(GL_FRAMEBUFFER, view_sums_fbo_.get());
    const GLenum draw = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &draw);
    gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl::ClearColor(0, 0, 0, 0);
    gl::Clear(GL_COLOR_BUFFER_BIT);
    draw_records(view_program_, view_sums_fbo_.get(), records, accuracy, 0);
    normalise_into(view_sums_.get(), view_fbo_.get());  // Σ w c / Σ w, as the term is
}

void RadianceCacheSplat::splat(const std::vector<IrradianceRecord>& records, float accuracy,
                               int frame) {
    last_splatted_ = int(records.size());
    draw_records(splat_, splat_fbo_.get(), records, accuracy, frame);
}

void RadianceCacheSplat::draw_records(const Program& program, GLuint framebuffer,
                                      const std::vector<IrradianceRecord>& records, float accuracy,
                                      int frame) {
    if (records.empty()) return;
    std::vector<glm::vec4> data(records.size() * kRecordVec4s);
    for (size_t k = 0; k < records.size(); ++k) {
        const IrradianceRecord& r = records[k];
        glm::vec4* d = &data[k * kRecordVec4s];
        d[0] = glm::vec4(r.position, r.harmonic_distance);
        d[1] = glm::vec4(r.normal, float(r.born));
        d[2] = glm::vec4(r.iim, 0.0f);
        d[3] = glm::vec4(r.temporal_gradient, 0.0f);
        for (int c = 0; c < 3; ++c) {
            d[4 + c] = glm::vec4(r.rotation_gradient[c], 0.0f);
            d[7 + c] = glm::vec4(r.translation_gradient[c], 0.0f);
        }
    }
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, records_.get());
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(data.size() * sizeof(glm::vec4)),
                   data.data(), GL_STREAM_DRAW);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, records_.get());

    gl::BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    const GLenum draw = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &draw);
    gl::Viewport(0, 0, width_, height_);
    gl::Disable(GL_DEPTH_TEST);
    gl::Disable(GL_CULL_FACE);
    gl::Disable(GL_STENCIL_TEST);
    gl::Enable(GL_BLEND);
    gl::BlendFunc(GL_ONE, GL_ONE);  // float additive blending: (Σ w E, Σ w)
    program.use();
    program.set("view_projection", camera_view_projection(scene_, width_, height_));
    program.set("accuracy", accuracy);
    program.set("frame", frame);
    program.set("positions", 0);
    program.set("normals", 1);
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, position_.get());
    gl::ActiveTexture(GL_TEXTURE1);
    gl::BindTexture(GL_TEXTURE_2D, normal_.get());
    gl::BindVertexArray(empty_.get());
    gl::DrawArraysInstanced(GL_TRIANGLES, 0, 6, GLsizei(records.size()));
    gl::BindVertexArray(0);
    gl::Disable(GL_BLEND);
    gl::BindTexture(GL_TEXTURE_2D, 0);
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, 0);
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("RadianceCacheSplat::draw_records");
}

std::vector<glm::vec4> RadianceCacheSplat::read_sums() const {
    const std::vector<float> s =
        read_rgba(splat_fbo_.get(), GL_COLOR_ATTACHMENT0, 0, 0, width_, height_);
    std::vector<glm::vec4> out(size_t(width_) * size_t(height_));
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = glm::vec4(s[4 * i], s[4 * i + 1], s[4 * i + 2], s[4 * i + 3]);
    return out;
}

std::vector<glm::vec3> RadianceCacheSplat::read_term() const {
    const std::vector<float> s =
        read_rgba(term_fbo_.get(), GL_COLOR_ATTACHMENT0, 0, 0, width_, height_);
    std::vector<glm::vec3> out(size_t(width_) * size_t(height_));
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = glm::vec3(s[4 * i], s[4 * i + 1], s[4 * i + 2]);
    return out;
}

void RadianceCacheSplat::normalise() { normalise_into(sums_.get(), term_fbo_.get()); }

void RadianceCacheSplat::normalise_into(GLuint sums, GLuint framebuffer) {
    gl::BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    const GLenum draw = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &draw);
    gl::Viewport(0, 0, width_, height_);
    gl::Disable(GL_DEPTH_TEST);
    gl::Disable(GL_BLEND);
    normalise_.use();
    normalise_.set("sums", 0);
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, sums);
    gl::BindVertexArray(empty_.get());
    gl::DrawArrays(GL_TRIANGLES, 0, 3);
    gl::BindVertexArray(0);
    gl::BindTexture(GL_TEXTURE_2D, 0);
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("RadianceCacheSplat::normalise");
}

std::vector<int> RadianceCacheSplat::uncovered_per_tile(float accuracy, int tile) {
    const int tiles_x = (width_ + tile - 1) / tile, tiles_y = (height_ + tile - 1) / tile;
    const std::vector<int> none(size_t(tiles_x) * size_t(tiles_y), std::numeric_limits<int>::max());
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, tiles_.get());
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(none.size() * sizeof(int)), none.data(),
                   GL_DYNAMIC_READ);
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, tiles_.get());
    // Drawn into the term framebuffer with colour writes off: the pass only writes the buffer.
    gl::BindFramebuffer(GL_FRAMEBUFFER, term_fbo_.get());
    gl::Viewport(0, 0, width_, height_);
    gl::Disable(GL_DEPTH_TEST);
    gl::Disable(GL_BLEND);
    gl::ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    scan_.use();
    scan_.set("sums", 0);
    scan_.set("positions", 1);
    scan_.set("accuracy", accuracy);
    scan_.set("tile", tile);
    scan_.set("tiles_x", tiles_x);
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, sums_.get());
    gl::ActiveTexture(GL_TEXTURE1);
    gl::BindTexture(GL_TEXTURE_2D, position_.get());
    gl::BindVertexArray(empty_.get());
    gl::DrawArrays(GL_TRIANGLES, 0, 3);
    gl::BindVertexArray(0);
    gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl::BindTexture(GL_TEXTURE_2D, 0);
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, 0);
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl::MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<int> first(none.size());
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, tiles_.get());
    gl::GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(first.size() * sizeof(int)),
                         first.data());
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    check_gl("RadianceCacheSplat::uncovered_per_tile");
    std::vector<int> out;
    for (int ty = 0; ty < tiles_y; ++ty)
        for (int tx = 0; tx < tiles_x; ++tx) {
            const int f = first[size_t(ty) * size_t(tiles_x) + size_t(tx)];
            if (f == std::numeric_limits<int>::max()) continue;
            const int x = tx * tile + f % tile, y = ty * tile + f / tile;
            out.push_back(y * width_ + x);
        }
    return out;
}

int RadianceCacheSplat::add_records_cpu_scan(std::vector<IrradianceRecord>& records,
                                             const std::vector<SplatPixel>& pixels, float accuracy,
                                             int frame, const MakeRecord& make, int max_new) {
    std::vector<glm::vec4> sums = read_sums();
    const size_t first = records.size();
    const int added = add_records_by_scan(records, pixels, accuracy, frame, sums, make, max_new);
    splat(std::vector<IrradianceRecord>(records.begin() + std::ptrdiff_t(first), records.end()),
          accuracy, frame);
    return added;
}

int RadianceCacheSplat::add_records_gpu_scan(std::vector<IrradianceRecord>& records,
                                             const std::vector<SplatPixel>& pixels, float accuracy,
                                             int frame, const MakeRecord& make, int max_new,
                                             int tile) {
    int added = 0;
    rounds_ = 0;
    const float cutoff = 1.0f / accuracy;
    std::vector<char> asked(pixels.size(), 0);
    while (added < max_new) {
        const std::vector<int> candidates = uncovered_per_tile(accuracy, tile);
        if (candidates.empty()) break;
        ++rounds_;
        std::vector<IrradianceRecord> round;
        for (int c : candidates) {
            if (added >= max_new) break;
            const SplatPixel& px = pixels[size_t(c)];
            if (asked[size_t(c)]) continue;  // its record does not cover it: never ask again
            float sum = 0.0f;
            for (const IrradianceRecord& r : round) {
                const float w = ward_weight(r, px.position, px.normal);
                if (w >= cutoff) sum += w;
            }
            // The GPU's sum at this pixel is below a, so this round's own records decide.
            if (sum >= accuracy) continue;
            round.push_back(make(px, size_t(c)));
            asked[size_t(c)] = 1;
            ++added;
        }
        splat(round, accuracy, frame);
        records.insert(records.end(), round.begin(), round.end());
        // A record that does not cover its own pixel (its normal or position differ from the
        // pixel's) would be asked for again and again: stop rather than loop.
        if (round.empty()) break;
    }
    return added;
}

}  // namespace ag::gpu
