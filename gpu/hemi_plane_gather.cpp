#include "gpu/hemi_plane_gather.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <numbers>
#include <string>

#include "gpu/lightmap_texture.h"
#include "gpu/media_glsl.h"
#include "gpu/media_uniforms.h"

namespace ag::gpu {

namespace {

constexpr int kMaxFramebufferSide = 2048;  // 2048² RGBA32F with mips: ~85 MiB

const char* kVertex = R"(
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;
layout(location = 3) in float chart;
uniform mat4 model, view_projection;
out vec2 v_uv;
out vec3 v_world;
flat out float v_chart;
void main() {
    v_uv = uv;
    v_chart = chart;
    vec4 world = model * vec4(position, 1.0);
    v_world = world.xyz;
    gl_Position = view_projection * world;
}
)";

// rgb: weight × AIM radiance; alpha: weight if the pixel shows a back face (texel behind or
// inside geometry), so after the reduction alpha is the share of such pixels. With the distance
// output bound (attachment 1): r = weight / distance of every pixel that shows geometry (any face,
// any material), so after the reduction r is Σ w/d and the harmonic mean distance Σw / Σ w/d.
const std::string kFragment = std::string(kChartLightmapGlsl) + kMediaTransmittanceGlsl + R"(
in vec2 v_uv;
in vec3 v_world;
flat in float v_chart;
uniform vec3 eye;
layout(location = 1) out vec4 inverse_distance;
uniform sampler2D aim;
uniform sampler2D charts;
uniform int use_charts;
uniform sampler2D weights;
uniform ivec2 tile_origin;
uniform int specular;
uniform float specular_tag;
layout(location = 0) out vec4 color;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy) - tile_origin;
    float w = texelFetch(weights, p, 0).r;
    inverse_distance = vec4(w / max(distance(v_world, eye), 1e-6), 0.0, 0.0, 0.0);
    // A mirror or glass pixel adds w × specular_tag to alpha, more than 1 even for the smallest
    // pixel weight, so a tile's alpha above 1 says the view met one (back faces add at most 1).
    if (specular != 0 && specular_tag > 0.0) { color = vec4(0.0, 0.0, 0.0, w * specular_tag); return; }
    if (!gl_FrontFacing) { color = vec4(0.0, 0.0, 0.0, w); return; }
    vec3 radiance = specular != 0 ? vec3(0.0) : (use_charts != 0 ? chart_lightmap(aim, charts, v_uv, v_chart)
                                                    : texture(aim, v_uv).rgb);
    if (media_count > 0) {
        float d = distance(v_world, eye);
        radiance *= media_transmittance(eye, (v_world - eye) / max(d, 1e-12), d);
    }
    color = vec4(w * radiance, 0.0);
}
)";

// ∫∫ over [x0,x1]×[y0,y1] of 1/(π(x²+y²+1)²): the cosine-weighted solid angle of a rectangle
// at unit distance, by 8×8 Gauss-free midpoint subdivision (exact enough: the integrand is smooth).
double pixel_weight(double x0, double x1, double y0, double y1) {
    constexpr int kSub = 8;
    double sum = 0.0;
    for (int j = 0; j < kSub; ++j)
        for (int i = 0; i < kSub; ++i) {
            const double x = x0 + (i + 0.5) * (x1 - x0) / kSub,
                         y = y0 + (j + 0.5) * (y1 - y0) / kSub;
            const double d = x * x + y * y + 1.0;
            sum += 1.0 / (std::numbers::pi * d * d);
        }
    return sum * (x1 - x0) * (y1 - y0) / (kSub * kSub);
}

// The same in closed form from the origin's corner: ∫₀^X∫₀^Y dx dy / (π(x²+y²+1)²) =
// (X/√(1+X²)·atan(Y/√(1+X²)) + Y/√(1+Y²)·atan(X/√(1+Y²))) / 2π, the form factor of a parallel
// rectangle with a corner above the point; odd in X and in Y, so any rectangle follows by
// inclusion and exclusion, unbounded ones (the stretched strips) with a limit of ±kFar.
double corner_weight(double x, double y) {
    const double sx = std::sqrt(1.0 + x * x), sy = std::sqrt(1.0 + y * y);
    return (x / sx * std::atan(y / sx) + y / sy * std::atan(x / sy)) / (2.0 * std::numbers::pi);
}
double rectangle_weight(double x0, double x1, double y0, double y1) {
    return corner_weight(x1, y1) - corner_weight(x0, y1) - corner_weight(x1, y0) +
           corner_weight(x0, y0);
}

// Gautron's border pixels "virtually stretched to fill the remaining solid angle": each border
// pixel of an r×r plane of half-width a reaches out to the horizon perpendicular to its edge
// (x ≥ a over its own y range), and each corner pixel also takes the quadrant beyond its corner,
// so a missing direction reads the plane point nearest to it in plane coordinates (clamp-to-edge).
void add_border_stretch(std::vector<double>& w, int r, double a) {
    constexpr double kFar = 1e7;  // the horizon, in plane coordinates
    const double step = 2.0 * a / r;
    for (int k = 0; k < r; ++k) {
        const double lo = -a + k * step, hi = lo + step;
        w[size_t(k) * r] += rectangle_weight(-kFar, -a, lo, hi);                // left column
        w[size_t(k) * r + size_t(r - 1)] += rectangle_weight(a, kFar, lo, hi);  // right
        w[size_t(k)] += rectangle_weight(lo, hi, -kFar, -a);                    // bottom row
        w[size_t(r - 1) * r + size_t(k)] += rectangle_weight(lo, hi, a, kFar);  // top
    }
    const double quadrant = rectangle_weight(a, kFar, a, kFar);
    for (const size_t corner :
         {size_t(0), size_t(r - 1), size_t(r - 1) * r, size_t(r - 1) * r + size_t(r - 1)})
        w[corner] += quadrant;
}

}  // namespace

std::vector<float> hemi_band_weights(int resolution, float half_width, float band_half_width) {
    const int r = resolution;
    const double a = half_width, b = std::max(band_half_width, half_width), step = 2.0 * b / r;
    std::vector<double> w(size_t(r) * size_t(r));
    for (int j = 0; j < r; ++j)
        for (int i = 0; i < r; ++i) {
            const double x0 = -b + i * step, y0 = -b + j * step, x1 = x0 + step, y1 = y0 + step;
            // The pixel's cosine-weighted solid angle less its overlap with the first plane.
            const double ox0 = std::max(x0, -a), ox1 = std::min(x1, a), oy0 = std::max(y0, -a),
                         oy1 = std::min(y1, a);
            const double overlap =
                ox0 < ox1 && oy0 < oy1 ? rectangle_weight(ox0, ox1, oy0, oy1) : 0.0;
            // A pixel all but covered keeps no rounding residue: the smallest weight sets the
            // specular tag (alpha per unit weight), which a residue of 1e-17 would blow up.
            const double whole = rectangle_weight(x0, x1, y0, y1), rest = whole - overlap;
            w[size_t(j) * r + size_t(i)] = rest > 1e-9 * whole ? rest : 0.0;
        }
    add_border_stretch(w, r, b);
    return std::vector<float>(w.begin(), w.end());
}

double hemi_plane_coverage(float half_width) {
    const double a = half_width, s = a / std::sqrt(1.0 + a * a);
    return 4.0 / std::numbers::pi * s * std::atan(s);
}

std::vector<float> hemi_plane_weights(int resolution, float half_width,
                                      BorderCorrection correction) {
    const int r = resolution;
    const double a = half_width, step = 2.0 * a / r;
    std::vector<double> w(size_t(r) * size_t(r));
    double sum = 0.0;
    for (int j = 0; j < r; ++j)
        for (int i = 0; i < r; ++i) {
            const double x0 = -a + i * step, y0 = -a + j * step;
            w[size_t(j) * r + size_t(i)] = pixel_weight(x0, x0 + step, y0, y0 + step);
            sum += w[size_t(j) * r + size_t(i)];
        }
    if (correction == BorderCorrection::renormalize) {
        for (double& v : w) v /= sum;  // Larsen: scale up by the covered fraction
    } else if (correction == BorderCorrection::stretch) {
        add_border_stretch(w, r, a);
    } else if (correction == BorderCorrection::stretch_radial) {
        // Directions beyond the plane are pushed radially (same azimuth) onto the
        // border pixel they would leave through; integrate their cosine-weighted solid angle.
        constexpr int kPhi = 1024;
        for (int k = 0; k < kPhi; ++k) {
            const double phi = (k + 0.5) * 2.0 * std::numbers::pi / kPhi;
            const double cx = std::cos(phi), cy = std::sin(phi);
            // Where the azimuth leaves the square: t = a / max(|cx|, |cy|).
            const double t = a / std::max(std::abs(cx), std::abs(cy));
            const double theta_edge = std::atan(t);
            // Cosine-weighted measure of θ ∈ [θ_edge, π/2] at this azimuth: ∫ cos sin dθ dφ / π.
            const double measure = 0.5 * std::cos(theta_edge) * std::cos(theta_edge) *
                                   (2.0 * std::numbers::pi / kPhi) / std::numbers::pi;
            const double bx = std::clamp(t * cx, -a, a), by = std::clamp(t * cy, -a, a);
            const int i = std::clamp(int((bx + a) / step), 0, r - 1),
                      j = std::clamp(int((by + a) / step), 0, r - 1);
            w[size_t(j) * r + size_t(i)] += measure;
        }
    }
    return std::vector<float>(w.begin(), w.end());
}

HemiPlaneGather::HemiPlaneGather(const Scene& scene, const SceneMeshes& meshes, int tiles,
                                 const LightmapTexture* aim, bool distances)
    : scene_(scene), meshes_(meshes), aim_(aim), distances_(distances) {
    resolution_ = 1;
    while (resolution_ < scene.settings.gather.plane_resolution) resolution_ *= 2;  // mip alignment
    level_ = 0;
    while ((1 << level_) < resolution_) ++level_;
    // Each texel's hemi-plane is one layer of an R×R 2D-array texture, drawn at the viewport
    // origin: rasterisation is then the same for a texel in any batch and at any place in it (at
    // a tile offset inside one big framebuffer, a GPU snaps vertices differently), and each
    // layer's mip chain reduces that layer alone. The layers of one pass are bounded like the
    // tiles of a (tiles_x·R)² framebuffer were: at R = 1024, 256 layers would be 4 GiB.
    GLint max_texture = 0, max_layers = 0;
    gl::GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture);
    gl::GetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    const int max_side = std::min(kMaxFramebufferSide, std::max(int(max_texture), resolution_));
    tiles_x_ = std::clamp(int(std::ceil(std::sqrt(double(tiles)))), 1,
                          std::max(1, max_side / resolution_));
    layers_ = std::min(tiles_x_ * tiles_x_, std::max(1, int(max_layers)));
    program_ = Program("hemi-plane gather", kVertex, kFragment);
    band_ = scene.settings.gather.border_correction == BorderCorrection::band;
    const int views = band_ ? 2 * layers_ : layers_;
    color_ = make_texture();
    gl::BindTexture(GL_TEXTURE_2D_ARRAY, color_.get());
    gl::TexStorage3D(GL_TEXTURE_2D_ARRAY, level_ + 1, GL_RGBA32F, resolution_, resolution_, views);
    gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
    gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl::BindTexture(GL_TEXTURE_2D_ARRAY, 0);
    if (distances_) {
        distance_ = make_texture();
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, distance_.get());
        gl::TexStorage3D(GL_TEXTURE_2D_ARRAY, level_ + 1, GL_RGBA32F, resolution_, resolution_,
                         views);
        gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
        gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, 0);
    }
    const GatherSettings& gs = scene.settings.gather;
    std::vector<float> w =
        hemi_plane_weights(resolution_, gs.plane_half_width, gs.border_correction);
    auto weight_texture = [&](const std::vector<float>& table) {
        std::vector<float> rgba(table.size() * 4, 0.0f);
        for (size_t i = 0; i < table.size(); ++i) rgba[4 * i] = table[i];
        return make_float_texture(resolution_, resolution_, false, rgba.data());
    };
    weights_ = weight_texture(w);
    if (band_) {
        const std::vector<float> band =
            hemi_band_weights(resolution_, gs.plane_half_width, gs.band_half_width);
        band_weights_ = weight_texture(band);
        w.insert(w.end(), band.begin(), band.end());
    }
    weight_sum_ = 0.0;
    for (float v : w) weight_sum_ += v;
    if (gs.specular_bounces > 0) {
        float smallest = 1.0f;
        for (float v : w)
            if (v > 0.0f) smallest = std::min(smallest, v);
        specular_tag_ = 4.0f / smallest;
    }
    depth_ = make_renderbuffer();
    gl::BindRenderbuffer(GL_RENDERBUFFER, depth_.get());
    gl::RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, resolution_, resolution_);
    fbo_ = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    gl::FramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, color_.get(), 0, 0);
    if (distances_)
        gl::FramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, distance_.get(), 0, 0);
    gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_.get());
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("hemi-plane gather: framebuffer incomplete");
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("HemiPlaneGather");
}

std::vector<GatherResult> HemiPlaneGather::gather(const std::vector<int>& texels) {
    if (!aim_)
        throw GlError(
            "HemiPlaneGather: gather(texels) needs the AIM texture given at construction");
    return gather(texels, aim_->id(), aim_->charts());
}

std::vector<GatherResult> HemiPlaneGather::gather_points(const std::vector<GatherPoint>& points) {
    if (!aim_)
        throw GlError(
            "HemiPlaneGather: gather_points(points) needs the AIM texture given at construction");
    return gather_views(points, aim_->id(), aim_->charts());
}

std::vector<GatherResult> HemiPlaneGather::gather(const std::vector<int>& texels,
                                                  GLuint aim_texture, GLuint chart_texture) {
    std::vector<GatherPoint> views(texels.size());
    for (size_t k = 0; k < texels.size(); ++k) {
        const TexelRecord& t = scene_.atlas.texels[size_t(texels[k])];
        const Object& owner = scene_.objects[size_t(t.object)];
        views[k] = {owner.transform.apply_point(t.position),
                    owner.transform.apply_vector(t.normal)};
    }
    return gather_views(views, aim_texture, chart_texture);
}

std::vector<GatherResult> HemiPlaneGather::gather_views(const std::vector<GatherPoint>& texels,
                                                        GLuint aim_texture, GLuint chart_texture) {
    std::vector<GatherResult> out(texels.size());
    const int per_pass = max_per_pass_ > 0 ? std::min(max_per_pass_, layers_) : layers_;
    const float a = scene_.settings.gather.plane_half_width;
    const float diagonal = scene_.diagonal();
    // A gather at the edge of a wall sees the adjacent wall at distances far below the texel
    // size, so the near plane must be tiny: reversed-Z with a float depth buffer keeps the
    // precision (depth 1 at the near plane, 0 at the far one).
    const float near_plane = 1e-7f * diagonal, far_plane = 4.0f * diagonal;
    const float offset = 2e-5f * diagonal;  // leave the surface, stay inside thin gaps

    gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    const GLenum draw[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    gl::DrawBuffers(distances_ ? 2 : 1, draw);
    gl::Enable(GL_DEPTH_TEST);
    gl::DepthFunc(GL_GREATER);
    gl::ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    gl::Disable(GL_CULL_FACE);
    gl::Disable(GL_BLEND);
    gl::Disable(GL_STENCIL_TEST);
    program_.use();
    program_.set("aim", 0);
    program_.set("weights", 1);
    program_.set("charts", 2);
    program_.set("use_charts", chart_texture ? 1 : 0);
    program_.set("specular_tag", specular_tag_);
    set_media_uniforms(program_, scene_);  // the frame refuses more than kMaxMediaBoxes
    // The plane [-a, a]² at unit distance is the frustum's cross-section: symmetric, aspect 1.
    glm::mat4 reverse(1.0f);
    reverse[2][2] = -1.0f;
    reverse[3][2] = 1.0f;  // z' = w − z
    auto plane_projection = [&](float half) {
        return reverse * glm::frustumRH_ZO(-half * near_plane, half * near_plane,
                                           -half * near_plane, half * near_plane, near_plane,
                                           far_plane);
    };
    const glm::mat4 projection = plane_projection(a);
    const glm::mat4 band_projection =
        plane_projection(std::max(a, scene_.settings.gather.band_half_width));

    for (size_t first = 0; first < texels.size(); first += size_t(per_pass)) {
        const size_t count = std::min(texels.size() - first, size_t(per_pass));
        // Bound every pass: the reduction below binds the tile texture on its own unit.
        gl::ActiveTexture(GL_TEXTURE0);
        gl::BindTexture(GL_TEXTURE_2D, aim_texture);
        gl::ActiveTexture(GL_TEXTURE1);
        gl::BindTexture(GL_TEXTURE_2D, weights_.get());
        gl::ActiveTexture(GL_TEXTURE2);
        gl::BindTexture(GL_TEXTURE_2D, chart_texture);
        gl::Viewport(0, 0, resolution_, resolution_);
        gl::ClearColor(0, 0, 0, 0);
        gl::ClearDepth(0.0);
        gl::Uniform2i(program_.location("tile_origin"), 0, 0);
        // The plane of every texel into layers 0..count-1, then with band_ the wider view of
        // every texel into layers layers_..layers_+count-1.
        for (int view_set = 0; view_set < (band_ ? 2 : 1); ++view_set) {
            if (view_set == 1) {
                gl::ActiveTexture(GL_TEXTURE1);
                gl::BindTexture(GL_TEXTURE_2D, band_weights_.get());
            }
            const glm::mat4& proj = view_set == 0 ? projection : band_projection;
            for (size_t k = 0; k < count; ++k) {
                const GatherPoint& at = texels[first + k];
                const glm::vec3 n = glm::normalize(at.normal);
                const glm::vec3 p = at.position + offset * n;
                const glm::vec3 helper =
                    std::abs(n.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
                const glm::mat4 view =
                    glm::lookAt(p, p + n, glm::normalize(glm::cross(glm::cross(n, helper), n)));
                const glm::mat4 vp = proj * view;
                const GLint layer = GLint(k) + (view_set == 1 ? GLint(layers_) : 0);
                gl::FramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, color_.get(), 0,
                                            layer);
                if (distances_)
                    gl::FramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1,
                                                distance_.get(), 0, layer);
                gl::Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
                program_.set("view_projection", vp);
                program_.set("eye", p);
                for (size_t o = 0; o < scene_.objects.size(); ++o) {
                    program_.set("model", model_matrix(scene_.objects[o]));
                    program_.set("specular",
                                 scene_.objects[o].material.type == MaterialType::diffuse ? 0 : 1);
                    meshes_.draw(o);
                }
            }
        }
        // One reduction for the whole batch: level log2(R) of each layer holds its texel's mean.
        // Mesa 22.3 (llvmpipe) regenerates stale levels if the texture is still attached to the
        // bound framebuffer: unbind it first.
        gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
        gl::ActiveTexture(GL_TEXTURE3);
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, color_.get());
        gl::GenerateMipmap(GL_TEXTURE_2D_ARRAY);
        const size_t views = band_ ? 2 * size_t(layers_) : size_t(layers_);
        std::vector<float> means(views * 4);
        gl::GetTexImage(GL_TEXTURE_2D_ARRAY, level_, GL_RGBA, GL_FLOAT, means.data());
        std::vector<float> inverse(distances_ ? views * 4 : 0);
        if (distances_) {
            gl::BindTexture(GL_TEXTURE_2D_ARRAY, distance_.get());
            gl::GenerateMipmap(GL_TEXTURE_2D_ARRAY);
            gl::GetTexImage(GL_TEXTURE_2D_ARRAY, level_, GL_RGBA, GL_FLOAT, inverse.data());
        }
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, 0);  // never leave the target bound for sampling
        gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
        const float pixels = float(resolution_) * float(resolution_);
        for (size_t k = 0; k < count; ++k) {
            // Layer k, plus layer layers_ + k with the band: the two views' weights partition
            // the hemisphere, so their sums add.
            glm::vec4 m(means[4 * k], means[4 * k + 1], means[4 * k + 2], means[4 * k + 3]);
            float inv = distances_ ? inverse[4 * k] : 0.0f;
            if (band_) {
                const size_t b = 4 * (size_t(layers_) + k);
                m += glm::vec4(means[b], means[b + 1], means[b + 2], means[b + 3]);
                if (distances_) inv += inverse[b];
            }
            out[first + k].iim = pixels * glm::vec3(m);
            if (distances_) {
                // Σ w / Σ w/d over the whole (corrected) view; nothing seen: infinitely far.
                const double sum = double(pixels) * double(inv);
                out[first + k].harmonic_distance =
                    sum > 0.0 ? float(weight_sum_ / sum) : std::numeric_limits<float>::infinity();
            }
            const float alpha = pixels * m[3];
            if (specular_tag_ > 0.0f && alpha > 2.0f) {
                out[first + k].sees_specular = true;  // alpha holds the tag: no back share
                out[first + k].back_fraction = 0.0f;
            } else {
                out[first + k].back_fraction = alpha;
            }
        }
    }
    gl::BindTexture(GL_TEXTURE_2D, 0);
    gl::ActiveTexture(GL_TEXTURE0);
    gl::ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
    gl::DepthFunc(GL_LESS);
    gl::ClearDepth(1.0);
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("HemiPlaneGather::gather");
    return out;
}

}  // namespace ag::gpu
