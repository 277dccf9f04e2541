#include "gpu/caustics_renderer.h"

#include <chrono>
#include <cmath>

#include "shared/camera.h"

namespace ag::gpu {

namespace {

// A photon is splatted where it lands if it lies on the surface its pixel shows: not farther from
// the eye than that surface at the pixel's centre plus the depth one pixel's footprint spans there
// (side / cos θ = area / side). A depth test against the centre alone loses the photons on the far
// part of every pixel of a surface seen at a grazing angle: half of a low-resolution floor's.
const char* kSplatVertex = R"(
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 power;
uniform mat4 view_projection;
uniform vec3 eye;
uniform sampler2D position_map;  // the visible surface's world position per pixel (w = 1)
uniform sampler2D surface_map;   // its albedo and, in w, the world area of the pixel there
uniform float pixel_at_unit_distance;
uniform ivec2 size;
out vec3 v_power;
void main() {
    v_power = power;
    vec4 clip = view_projection * vec4(position, 1.0);
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume: not drawn
    if (clip.w <= 0.0) return;
    ivec2 pixel = ivec2(floor((clip.xy / clip.w * 0.5 + 0.5) * vec2(size)));
    if (any(lessThan(pixel, ivec2(0))) || any(greaterThanEqual(pixel, size))) return;
    vec4 seen = texelFetch(position_map, pixel, 0);
    if (seen.w <= 0.0) return;
    float d_seen = length(seen.xyz - eye), side = d_seen * pixel_at_unit_distance;
    float depth_span = texelFetch(surface_map, pixel, 0).w / side;
    if (length(position - eye) > d_seen + depth_span + 1e-4 * d_seen) return;
    gl_Position = vec4(clip.xy / clip.w, 0.0, 1.0);
}
)";
const char* kSplatFragment = R"(
in vec3 v_power;
out vec4 color;
void main() { color = vec4(v_power, 1.0); }
)";

const char* kQueryFragment = R"(
out vec4 color;
void main() { color = vec4(0.0); }
)";

// Eq. 12.1 as a scatter: each pixel q holding photons spreads their power over the pixels within
// its half-size h_q with weights t(i, j) = √(1 + 2h² − (i² + j²)) normalised over the pixels that
// receive caustics (diffuse surfaces), so no power is lost on glass, mirrors or the background
// next to a caustic (at low resolution a focus lies within k pixels of its lens's silhouette), and
// E = c / A_pixel (eq. 12.2), L = ρ/π · E. h_q is k (the thesis), or with `kernel_photons` > 0 the
// smallest window around q holding that many photons (a k-nearest-neighbour radius in pixels): a
// dense focus is not spread over (2k+1)² pixels, sparse photons keep the full kernel. Two passes
// in gather form: h_q and the normalisation W_q per photon pixel, then the sum at each pixel.
const char* kFilterCommon = R"(
uniform sampler2D splat;    // rgb: photon power; a: photon count
uniform sampler2D surface;  // rgb: albedo; a: the pixel's world area (0: receives nothing)
uniform int k;
uniform ivec2 size;
float cone(int i, int j, int h) { return sqrt(1.0 + 2.0 * float(h * h) - float(i * i + j * j)); }
bool inside(ivec2 q) { return q.x >= 0 && q.y >= 0 && q.x < size.x && q.y < size.y; }
)";

const std::string kFootprintFragment = std::string(kFilterCommon) + R"(
uniform int kernel_photons;
out vec4 color;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    color = vec4(0.0);
    if (texelFetch(splat, p, 0).a <= 0.0) return;
    int h = k;
    if (kernel_photons > 0 && k > 0) {
        // Grow the window ring by ring (max(|i|, |j|) = r) until it holds kernel_photons.
        float count = 0.0;
        for (int r = 0; r <= k; ++r) {
            for (int i = -r; i <= r; ++i)
                for (int j = -r; j <= r; j += (abs(i) == r || r == 0) ? 1 : 2 * r) {
                    ivec2 q = p + ivec2(i, j);
                    if (inside(q)) count += texelFetch(splat, q, 0).a;
                }
            if (count >= float(kernel_photons)) { h = r; break; }
        }
    }
    float w = 0.0;
    for (int j = -h; j <= h; ++j)
        for (int i = -h; i <= h; ++i) {
            ivec2 q = p + ivec2(i, j);
            if (inside(q) && texelFetch(surface, q, 0).a > 0.0) w += cone(i, j, h);
        }
    color = vec4(float(h), w, 0.0, 0.0);
}
)";

const std::string kFilterFragment = std::string(kFilterCommon) + R"(
uniform sampler2D footprint;  // per photon pixel: r = h, g = W (Σ of its weights that land)
uniform int block_level;      // mip level whose texels are 8×8-pixel blocks of the splats
out vec4 color;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 s = texelFetch(surface, p, 0);
    if (s.a <= 0.0) { color = vec4(0.0); return; }
    // Photons are sparse: if no 8×8 block the kernel touches holds one (their mean count, in
    // alpha, is 0), the result is exactly 0 and the kernel's fetches are skipped.
    if (block_level > 0) {
        ivec2 lo = max(p - ivec2(k), ivec2(0)) >> 3, hi = min(p + ivec2(k), size - 1) >> 3;
        float any = 0.0;
        for (int by = lo.y; by <= hi.y; ++by)
            for (int bx = lo.x; bx <= hi.x; ++bx) any += texelFetch(splat, ivec2(bx, by), block_level).a;
        if (any <= 0.0) { color = vec4(0.0); return; }
    }
    vec3 sum = vec3(0.0);
    for (int j = -k; j <= k; ++j)
        for (int i = -k; i <= k; ++i) {
            ivec2 q = p + ivec2(i, j);
            if (!inside(q)) continue;
            vec4 t = texelFetch(splat, q, 0);
            if (t.a <= 0.0) continue;
            vec2 f = texelFetch(footprint, q, 0).xy;
            int h = int(f.x + 0.5);
            if (max(abs(i), abs(j)) > h || f.y <= 0.0) continue;
            sum += cone(i, j, h) / f.y * t.rgb;
        }
    color = vec4(s.rgb / 3.14159265358979 * sum / s.a, 1.0);
}
)";

double elapsed_ms(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

CausticsRenderer::CausticsRenderer(const Scene& scene, const SceneMeshes& meshes, int width,
                                   int height, GBuffer* shared)
    : scene_(scene),
      width_(width),
      height_(height),
      own_g_buffer_(shared ? nullptr : std::make_unique<GBuffer>(scene, meshes, width, height)),
      g_buffer_(shared ? shared : own_g_buffer_.get()) {
    if (g_buffer_->width() != width || g_buffer_->height() != height)
        throw GlError("caustics: the shared G-buffer is not " + std::to_string(width) + "x" +
                      std::to_string(height));
    tile_ = scene.settings.caustics.tile_size;
    tiles_x_ = (width + tile_ - 1) / tile_;
    tiles_y_ = (height + tile_ - 1) / tile_;
    splat_ = Program("caustics splat", kSplatVertex, kSplatFragment);
    query_ = Program("caustics tile query", kFullScreenTriangleVertex, kQueryFragment);
    filter_ = Program("caustics filter", kFullScreenTriangleVertex, kFilterFragment);
    footprint_ = Program("caustics footprint", kFullScreenTriangleVertex, kFootprintFragment);
    splat_texture_ = make_float_texture(width, height, true);
    result_ = make_float_texture(width, height);
    footprint_texture_ = make_float_texture(width, height);
    splat_fbo_ =
        framebuffer_with({splat_texture_.get()}, g_buffer_->depth_stencil(), "caustics splat");
    result_fbo_ = framebuffer_with({result_.get()}, 0, "caustics result");
    footprint_fbo_ = framebuffer_with({footprint_texture_.get()}, 0, "caustics footprint");
    photon_vbo_ = make_buffer();
    photon_vao_ = make_vertex_array();
    gl::BindVertexArray(photon_vao_.get());
    gl::BindBuffer(GL_ARRAY_BUFFER, photon_vbo_.get());
    gl::EnableVertexAttribArray(0);
    gl::VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    gl::EnableVertexAttribArray(1);
    gl::VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                            reinterpret_cast<void*>(3 * sizeof(float)));
    empty_vao_ = make_vertex_array();
    gl::BindVertexArray(0);
    queries_.resize(size_t(tiles_x_) * size_t(tiles_y_));
    gl::GenQueries(GLsizei(queries_.size()), queries_.data());
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("CausticsRenderer");
}

CausticsRenderer::~CausticsRenderer() {
    if (!queries_.empty()) gl::DeleteQueries(GLsizei(queries_.size()), queries_.data());
}

void CausticsRenderer::render(const std::vector<glm::vec3>& positions,
                              const std::vector<glm::vec3>& powers, bool cull) {
    // No photons (a scene without mirrors or glass, or none traced yet): the term is zero
    // whatever the view. Drawing the scene for it cost as much as the frame's own G-buffer
    // (25 ms of a 50 ms settled frame on the conference room at 64²).
    if (positions.empty()) {
        if (!showing_none_) {
            gl::BindFramebuffer(GL_FRAMEBUFFER, result_fbo_.get());
            const GLenum one = GL_COLOR_ATTACHMENT0;
            gl::DrawBuffers(1, &one);
            const GLfloat zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
            gl::ClearBufferfv(GL_COLOR, 0, zero);
            gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
            ++revision_;
            last_inputs_ = Inputs{};
            showing_none_ = true;
        }
        tiles_filtered_ = 0;
        filter_ms_ = query_ms_ = 0.0;
        return;
    }
    // What this render draws from: the photons, the view the G-buffer is drawn from (its own,
    // about to be drawn, or the caller's, drawn this frame), the scene and the filter.
    std::vector<float> data;
    data.reserve(positions.size() * 6);
    for (size_t i = 0; i < positions.size(); ++i)
        data.insert(data.end(), {positions[i].x, positions[i].y, positions[i].z, powers[i].x,
                                 powers[i].y, powers[i].z});
    const glm::mat4 planned_vp = own_g_buffer_ ? own_g_buffer_->view().view_projection
                                               : g_buffer_->last_view().view_projection;
    {
        const CausticSettings& cs = scene_.settings.caustics;
        Inputs inputs{data, planned_vp, scene_.version, cs.kernel_k, cs.kernel_photons, cull};
        // The same inputs as the render before: the texture already holds this render's result
        // (the caustic photons of a settled scene stay as they were for every frame after their
        // last re-trace; drawing them again cost two_rooms at 96² 12 ms of a 20 ms frame).
        if (revision_ != 0 && !showing_none_ && inputs == last_inputs_) {
            tiles_filtered_ = 0;
            filter_ms_ = query_ms_ = 0.0;
            return;
        }
        ++revision_;
        last_inputs_ = std::move(inputs);
    }
    showing_none_ = false;
    // 1. The scene: depth and stencil cleared, positions, albedo and pixel areas (the G-buffer).
    //    Its own is drawn again only when the view or the scene changed since it was drawn: while
    //    the caustic photons are re-traced after an edit, a slice a frame, they are drawn over
    //    the same scene several times (two_rooms at 96²: 8-10 ms of a 15-24 ms drawing). The
    //    splats' stencil marks are cleared instead.
    if (own_g_buffer_) {
        const GBuffer::View planned = own_g_buffer_->view();
        const bool same = g_buffer_drawn_ && g_buffer_version_ == scene_.version &&
                          planned.view_projection == own_g_buffer_->last_view().view_projection &&
                          planned.camera.eye == own_g_buffer_->last_view().camera.eye;
        if (same) {
            gl::BindFramebuffer(GL_FRAMEBUFFER, splat_fbo_.get());
            gl::StencilMask(0xFF);
            gl::ClearStencil(0);
            gl::Clear(GL_STENCIL_BUFFER_BIT);
        } else {
            own_g_buffer_->render();
            g_buffer_drawn_ = true;
            g_buffer_version_ = scene_.version;
        }
    }
    const GBuffer::View& view = g_buffer_->last_view();
    const Camera& camera = view.camera;
    const glm::mat4& vp = view.view_projection;
    const GLuint position = g_buffer_->texture(GBufferTarget::position);
    const GLuint surface = g_buffer_->texture(GBufferTarget::surface);

    // 2. Photons as points, additive float RGB, each marking the stencil.
    // Its own state, whatever the caller's passes left: a kept G-buffer does not set it (the
    // viewer's clear colour filled the splats, and the caustics covered the image).
    gl::BindFramebuffer(GL_FRAMEBUFFER, splat_fbo_.get());
    const GLenum one = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &one);
    gl::Viewport(0, 0, width_, height_);
    gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl::ClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    gl::Clear(GL_COLOR_BUFFER_BIT);
    gl::DepthMask(GL_FALSE);
    gl::Disable(GL_DEPTH_TEST);  // visibility is decided per photon against the positions
    gl::Enable(GL_BLEND);
    gl::BlendFunc(GL_ONE, GL_ONE);
    gl::Enable(GL_STENCIL_TEST);
    gl::StencilFunc(GL_ALWAYS, 1, 0xFF);
    gl::StencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
    const std::vector<float>& data_drawn = last_inputs_.photons;
    if (!data_drawn.empty()) {
        splat_.use();
        splat_.set("view_projection", vp);
        splat_.set("eye", camera.eye);
        splat_.set("position_map", 0);
        splat_.set("surface_map", 1);
        splat_.set("pixel_at_unit_distance",
                   2.0f * std::tan(glm::radians(camera.fov_y) * 0.5f) / float(height_));
        gl::Uniform2i(splat_.location("size"), width_, height_);
        gl::ActiveTexture(GL_TEXTURE0);
        gl::BindTexture(GL_TEXTURE_2D, position);
        gl::ActiveTexture(GL_TEXTURE1);
        gl::BindTexture(GL_TEXTURE_2D, surface);
        gl::BindVertexArray(photon_vao_.get());
        gl::BindBuffer(GL_ARRAY_BUFFER, photon_vbo_.get());
        gl::BufferData(GL_ARRAY_BUFFER, GLsizeiptr(data_drawn.size() * sizeof(float)),
                       data_drawn.data(), GL_STREAM_DRAW);
        gl::DrawArrays(GL_POINTS, 0, GLsizei(positions.size()));
    }
    gl::Disable(GL_BLEND);
    gl::Disable(GL_DEPTH_TEST);

    // 3. One occlusion query per tile: does any pixel of it hold a photon?
    gl::Finish();
    auto t = std::chrono::steady_clock::now();
    std::vector<char> keep(queries_.size(), cull ? 0 : 1);
    if (cull) {
        gl::ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
        gl::StencilFunc(GL_EQUAL, 1, 0xFF);
        gl::StencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
        query_.use();
        gl::BindVertexArray(empty_vao_.get());
        for (int ty = 0; ty < tiles_y_; ++ty)
            for (int tx = 0; tx < tiles_x_; ++tx) {
                gl::Viewport(tx * tile_, ty * tile_, tile_, tile_);
                gl::BeginQuery(GL_ANY_SAMPLES_PASSED, queries_[size_t(ty * tiles_x_ + tx)]);
                gl::DrawArrays(GL_TRIANGLES, 0, 3);
                gl::EndQuery(GL_ANY_SAMPLES_PASSED);
            }
        gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        // A photon reaches k ≤ tile pixels: filter its tile and the 8 around it.
        for (int ty = 0; ty < tiles_y_; ++ty)
            for (int tx = 0; tx < tiles_x_; ++tx) {
                GLuint any = 0;
                gl::GetQueryObjectuiv(queries_[size_t(ty * tiles_x_ + tx)], GL_QUERY_RESULT, &any);
                if (!any) continue;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int x = tx + dx, y = ty + dy;
                        if (x >= 0 && y >= 0 && x < tiles_x_ && y < tiles_y_)
                            keep[size_t(y * tiles_x_ + x)] = 1;
                    }
            }
    }
    gl::Disable(GL_STENCIL_TEST);
    query_ms_ = elapsed_ms(t);

    // 4. The filter, on the kept tiles only. The splats' mip level 3 tells which 8×8 blocks hold
    //    photons (Mesa regenerates stale levels while the texture is attached: unbind first).
    t = std::chrono::steady_clock::now();
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, splat_texture_.get());
    gl::GenerateMipmap(GL_TEXTURE_2D);
    gl::Viewport(0, 0, width_, height_);
    gl::BindVertexArray(empty_vao_.get());
    auto over_kept_tiles = [&]() {
        int n = 0;
        for (int ty = 0; ty < tiles_y_; ++ty)
            for (int tx = 0; tx < tiles_x_; ++tx) {
                if (!keep[size_t(ty * tiles_x_ + tx)]) continue;
                ++n;
                gl::Viewport(tx * tile_, ty * tile_, tile_, tile_);
                gl::DrawArrays(GL_TRIANGLES, 0, 3);
            }
        gl::Viewport(0, 0, width_, height_);
        return n;
    };
    auto bind_common = [&](const Program& p) {
        p.use();
        p.set("splat", 0);
        p.set("surface", 1);
        p.set("k", scene_.settings.caustics.kernel_k);
        gl::Uniform2i(p.location("size"), width_, height_);
    };
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, splat_texture_.get());
    gl::ActiveTexture(GL_TEXTURE1);
    gl::BindTexture(GL_TEXTURE_2D, surface);
    // 4a. Each photon pixel's half-size and normalisation.
    gl::BindFramebuffer(GL_FRAMEBUFFER, footprint_fbo_.get());
    gl::DrawBuffers(1, &one);
    gl::Clear(GL_COLOR_BUFFER_BIT);
    bind_common(footprint_);
    footprint_.set("kernel_photons", scene_.settings.caustics.kernel_photons);
    over_kept_tiles();
    // 4b. The filter.
    gl::BindFramebuffer(GL_FRAMEBUFFER, result_fbo_.get());
    gl::DrawBuffers(1, &one);
    gl::Clear(GL_COLOR_BUFFER_BIT);
    bind_common(filter_);
    filter_.set("footprint", 2);
    // Level 3 is an exact 8×8 box only when both sides divide by 8.
    filter_.set("block_level", width_ % 8 == 0 && height_ % 8 == 0 ? 3 : 0);
    gl::ActiveTexture(GL_TEXTURE2);
    gl::BindTexture(GL_TEXTURE_2D, footprint_texture_.get());
    tiles_filtered_ = over_kept_tiles();
    gl::Finish();
    filter_ms_ = elapsed_ms(t);
    gl::BindTexture(GL_TEXTURE_2D, 0);
    gl::ActiveTexture(GL_TEXTURE1);
    gl::BindTexture(GL_TEXTURE_2D, 0);
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, 0);
    gl::BindVertexArray(0);
    gl::Enable(GL_DEPTH_TEST);
    gl::DepthMask(GL_TRUE);
    gl::DepthFunc(GL_LESS);
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("CausticsRenderer::render");
}

std::vector<glm::vec3> CausticsRenderer::read_radiance() const {
    const std::vector<float> rgba =
        read_rgba(result_fbo_.get(), GL_COLOR_ATTACHMENT0, 0, 0, width_, height_);
    std::vector<glm::vec3> out(size_t(width_) * size_t(height_));
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
            const float* p = &rgba[(size_t(height_ - 1 - y) * size_t(width_) + size_t(x)) * 4];
            out[size_t(y) * size_t(width_) + size_t(x)] = {p[0], p[1], p[2]};
        }
    return out;
}

std::vector<float> CausticsRenderer::read_pixel_area() const {
    const std::vector<glm::vec4> surface = g_buffer_->read(GBufferTarget::surface);
    std::vector<float> out(surface.size());
    for (size_t i = 0; i < surface.size(); ++i) out[i] = surface[i].w;
    return out;
}

}  // namespace ag::gpu
