#include "gpu/frame_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <stdexcept>

#include "gpu/media_glsl.h"
#include "gpu/media_uniforms.h"
#include "shared/camera.h"
#include "shared/qmc.h"

namespace ag::gpu {

namespace {

constexpr int kLightMapUnit = 6;  // direct.method vpl: the light samples' shadow maps

// An image's rows run top-first, a GL texture's bottom-first: `rgba` becomes the image's rgb,
// rows turned over, with alpha(x, y) beside each pixel.
template <class Alpha>
void flip_to_rgba(const Image& image, Alpha alpha, std::vector<glm::vec4>& rgba) {
    rgba.resize(size_t(image.width) * size_t(image.height));
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            rgba[size_t(image.height - 1 - y) * size_t(image.width) + size_t(x)] =
                glm::vec4(image.rgb(x, y), alpha(x, y));
}

void upload_rgba(GLuint texture, int width, int height, const std::vector<glm::vec4>& rgba) {
    gl::BindTexture(GL_TEXTURE_2D, texture);
    gl::TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_FLOAT, rgba.data());
    gl::BindTexture(GL_TEXTURE_2D, 0);
}

// World media boxes the frame's direct light crosses (set_light_uniforms; scenes with more are
// refused by the FrameRenderer).
constexpr int kMaxFrameMediaBoxes = kMaxMediaBoxes;

const std::string kLightsGlsl = std::string(kMediaTransmittanceGlsl) + R"(
uniform int light_count;
uniform vec3 light_position[kMaxLightSamples];
uniform vec3 light_intensity[kMaxLightSamples];
uniform vec3 light_normal[kMaxLightSamples];
uniform int light_one_sided[kMaxLightSamples];
uniform int light_directional[kMaxLightSamples];
uniform vec2 light_cone[kMaxLightSamples];
const float kPi = 3.14159265358979;
// Radiance reflected by a Lambertian surface from point light i, unshadowed: ρ/π · I cosθ / d²
// (a spot's I times its falloff; a sun: ρ/π · E cosθ), attenuated by the media on the way.
vec3 direct_from(int i, vec3 p, vec3 n, vec3 albedo) {
    if (light_directional[i] != 0)
        return albedo / kPi * light_intensity[i] * max(dot(n, light_position[i]), 0.0) *
               media_transmittance(p, normalize(light_position[i]), 1e30);
    vec3 to_light = light_position[i] - p;
    float d2 = max(dot(to_light, to_light), 1e-12);
    vec3 l = to_light * inversesqrt(d2);
    float cos_s = max(dot(n, l), 0.0);
    float cos_l = light_one_sided[i] != 0 ? max(dot(light_normal[i], -l), 0.0) : 1.0;
    if (light_cone[i].x > -1.5) {  // spot: 1 inside the inner cone, linear in cosθ outside
        float c = dot(light_normal[i], -l);
        cos_l = c >= light_cone[i].y ? 1.0
              : clamp((c - light_cone[i].x) / max(light_cone[i].y - light_cone[i].x, 1e-6),
                      0.0, 1.0);
    }
    return albedo / kPi * light_intensity[i] * cos_s * cos_l / d2 *
           media_transmittance(p, l, sqrt(d2));
}
)";

// Mirrors and glass (Larsen ch. 13) through distance cube maps ("distance impostors", Szirmay-Kalos
// et al. 2005): each specular object's environment map holds, beside the radiance, the distance
// from the object's centre to what it shows, so a ray leaving any point of the object (not only
// the centre) finds the surface it meets by a search along it. Glass also holds a map of its own
// surface (outward normal, distance), so a ray refracted in is followed to where it leaves:
// refraction at both interfaces, with internal reflections, and a ball lens inverts the image.
const char* kSpecularGlsl = R"(
uniform samplerCube environment;  // rgb: radiance; a: distance from `centre` (1e30: nothing)
uniform samplerCube inner;        // glass: rgb its outward face normal; a: distance from `centre`
uniform vec3 centre;              // the cube maps' centre (world)
uniform float object_radius;      // bounding radius of the object around `centre`
uniform float scene_size;         // longer than any ray from the object to the scene
uniform int material;             // kMaterialDiffuse, kMaterialMirror or kMaterialGlass
uniform float ior;
uniform vec3 eye;
float fresnel(float cos_i, float eta) {
    float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) return 1.0;
    float cos_t = sqrt(1.0 - sin2_t);
    float rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}
// > 0 where x (relative to the centre) lies beyond the surface the map shows in its direction.
float beyond(samplerCube map, vec3 x) { return length(x) - textureLod(map, x, 0.0).a; }
// The first t in (0, t_max] where o + t·d (relative to the centre) crosses from inside the map's
// surface to beyond it: a linear search on steps spaced as (i/n)^spacing, then secant steps.
// −1 where it never does.
float trace_map(samplerCube map, vec3 o, vec3 d, float t_max, int steps, float spacing) {
    float a = 0.0, fa = 0.0;
    bool inside = false;
    for (int i = 1; i <= steps; ++i) {
        float t = t_max * pow(float(i) / float(steps), spacing);
        float f = beyond(map, o + t * d);
        if (f < 0.0) {
            inside = true;
            a = t;
            fa = f;
        } else if (inside) {
            float b = t, fb = f;
            for (int j = 0; j < 5; ++j) {
                float m = a + (b - a) * clamp(fa / (fa - fb), 0.02, 0.98);
                float fm = beyond(map, o + m * d);
                if (fm < 0.0) { a = m; fa = fm; } else { b = m; fb = fm; }
            }
            return 0.5 * (a + b);
        }
    }
    return -1.0;
}
// Radiance arriving at x (world) from direction d, from the environment map.
vec3 environment_radiance(vec3 x, vec3 d) {
    vec3 o = x - centre;
    float t = trace_map(environment, o, d, scene_size, 24, 2.0);
    return textureLod(environment, t > 0.0 ? o + t * d : d, 0.0).rgb;
}
// Radiance carried out of glass by a ray refracted in at p along d: at each exit the Fresnel
// share leaves (refracted), the rest is reflected inside and followed again (3 exits).
vec3 through_glass(vec3 p, vec3 d) {
    vec3 o = p - centre, sum = vec3(0.0);
    float weight = 1.0;
    for (int bounce = 0; bounce < 3 && weight > 1e-3; ++bounce) {
        float t = trace_map(inner, o, d, 2.0 * object_radius, 8, 1.0);
        vec3 n = t > 0.0 ? normalize(textureLod(inner, o + t * d, 0.0).rgb) : vec3(0.0);  // outward
        float cos_i = dot(d, n);
        if (t <= 0.0 || cos_i <= 0.0) {
            // No exit found (a grazing chord shorter than a step) or the map's face there does
            // not face the ray (not star-shaped): the ray leaves as it goes, not as black.
            sum += weight * environment_radiance(o + centre, d);
            break;
        }
        o += t * d;
        float f = fresnel(cos_i, ior);
        if (f < 1.0) sum += weight * (1.0 - f) * environment_radiance(o + centre, refract(d, -n, ior));
        weight *= f;
        d = reflect(d, -n);
    }
    return sum;
}
vec3 specular_radiance(vec3 p, vec3 n) {
    vec3 v = normalize(p - eye);
    vec3 nf = dot(v, n) < 0.0 ? n : -n;
    vec3 reflected = environment_radiance(p, reflect(v, nf));
    if (material == kMaterialMirror) return reflected;
    bool entering = dot(v, n) < 0.0;
    float eta = entering ? 1.0 / ior : ior;
    float f = fresnel(-dot(v, nf), eta);
    if (f >= 1.0) return reflected;
    vec3 t = refract(v, nf, eta);
    // Seen from inside the glass (the camera in it): one refraction, as no exit is to be found.
    vec3 refracted = entering ? through_glass(p, t) : environment_radiance(p, t);
    return f * reflected + (1.0 - f) * refracted;
}
)";

// G-buffer pass, diffuse objects: emission → direct, ρ·IIM → indirect, caustics. Mirrors and
// glass have their own program (below): llvmpipe runs the code of an untaken branch with an
// empty mask, so the cube-map searches in this shader cost every diffuse pixel 5× the frame.
const std::string kGbufferFragment = std::string(kAlbedoGlsl) + R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
uniform sampler2D iim;
uniform int iim_in_screen;  // 1: the indirect term is a screen-space image (IndirectSpace::screen)
uniform sampler2D caustics;
uniform int has_caustics;
uniform vec3 albedo;
uniform vec3 emission;
uniform vec2 screen;
layout(location = kFrameTermDirect) out vec4 out_direct;
layout(location = kFrameTermIndirect) out vec4 out_indirect;
layout(location = kFrameTermCaustics) out vec4 out_caustics;
layout(location = kFrameTermSpecular) out vec4 out_specular;
layout(location = kFrameTermVolume) out vec4 out_volume;  // no media in the GPU frame yet
#ifdef WRITE_SURFACE
// The surface the deferred direct-light passes shade: world position, unit normal, and the
// albedo with alpha 1 (a diffuse surface; mirrors, glass and the background leave alpha 0).
// Only in frames that draw the direct light anew: the two extra varyings cost llvmpipe's
// triangle setup a third of a settled frame of the conference room.
layout(location = kFrameTermCount + 0) out vec4 out_position;
layout(location = kFrameTermCount + 1) out vec4 out_normal;
layout(location = kFrameTermCount + 2) out vec4 out_albedo;
#endif
void main() {
#ifdef WRITE_SURFACE
    out_position = vec4(v_world, 1.0);
    out_normal = vec4(normalize(v_normal), 0.0);
    out_albedo = vec4(surface_albedo(albedo), 1.0);
#endif
    out_volume = vec4(0.0, 0.0, 0.0, 1.0);
    out_direct = vec4(emission, 1.0);
    // L_indirect = albedo × E/π, from the lightmap (IIM) or from a screen-space method's image.
    vec3 e = iim_in_screen != 0 ? texture(iim, gl_FragCoord.xy / screen).rgb : texture(iim, v_uv).rgb;
    out_indirect = vec4(surface_albedo(albedo) * e, 1.0);
    out_specular = vec4(0.0, 0.0, 0.0, 1.0);
    out_caustics = vec4(0.0, 0.0, 0.0, 1.0);
    if (has_caustics != 0) out_caustics.rgb = texture(caustics, gl_FragCoord.xy / screen).rgb;
}
)";

// G-buffer pass, mirrors and glass: their radiance through the cube maps → specular.
const std::string kGbufferSpecularFragment = std::string(kSpecularGlsl) + R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
layout(location = kFrameTermDirect) out vec4 out_direct;
layout(location = kFrameTermIndirect) out vec4 out_indirect;
layout(location = kFrameTermCaustics) out vec4 out_caustics;
layout(location = kFrameTermSpecular) out vec4 out_specular;
layout(location = kFrameTermVolume) out vec4 out_volume;  // no media in the GPU frame yet
layout(location = kFrameTermCount + 0) out vec4 out_position;
layout(location = kFrameTermCount + 1) out vec4 out_normal;
layout(location = kFrameTermCount + 2) out vec4 out_albedo;  // alpha 0: no direct light here
void main() {
    out_position = vec4(0.0);
    out_normal = vec4(0.0);
    out_albedo = vec4(0.0);
    out_volume = vec4(0.0, 0.0, 0.0, 1.0);
    out_direct = vec4(0.0, 0.0, 0.0, 1.0);
    out_indirect = vec4(0.0, 0.0, 0.0, 1.0);
    out_caustics = vec4(0.0, 0.0, 0.0, 1.0);
    out_specular = vec4(specular_radiance(v_world, normalize(v_normal)), 1.0);
}
)";

// One light sample, added where the stencil says the pixel is outside its shadow volumes.
const std::string kLightingFragment = std::string(kLightsGlsl) + kAlbedoGlsl + R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
uniform vec3 albedo;
uniform int light_index;
layout(location = 0) out vec4 out_direct;  // drawn with the direct term's image as the only buffer
void main() {
    out_direct =
        vec4(direct_from(light_index, v_world, normalize(v_normal), surface_albedo(albedo)), 0.0);
}
)";

// One light sample shadowed by its hemispherical shadow map (direct.method vpl, Barczak §4.2):
// layer `map_layer` about the sample's normal, or for a two-sided sample `map_layer` + 1 on the
// other side; −1: a sun, no map (drawn with the stencil of its shadow volumes).
const std::string kLightMapGlsl = std::string(kVplMapGlsl) + R"(
uniform sampler2DArray light_maps;
uniform int map_layer, map_layers, map_kind;
uniform float offset_scale, relative_bias;
// Whether the light sample's map sees the surface point p (normal n); always for a sun.
bool light_map_sees(vec3 p, vec3 n) {
    if (map_layer < 0) return true;
    int layer = map_layer;
    vec3 d = p - vpl_position(layer);
    if (map_layers == 2 && dot(d, vpl_normal(layer)) < 0.0) layer += 1;
    return vpl_map_visible(light_maps, layer, p, n, length(d), map_kind, offset_scale,
                           relative_bias);
}
)";
const std::string kLightingMappedFragment =
    std::string(kLightsGlsl) + kAlbedoGlsl + kLightMapGlsl + R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
uniform vec3 albedo;
uniform int light_index;
layout(location = 0) out vec4 out_direct;
void main() {
    vec3 n = normalize(v_normal);
    out_direct = light_map_sees(v_world, n)
                     ? vec4(direct_from(light_index, v_world, n, surface_albedo(albedo)), 0.0)
                     : vec4(0.0);
}
)";

// The same two passes deferred (the frame): one full-screen triangle per light sample shades the
// surface the G-buffer pass left in each pixel, with the same arithmetic as the forward passes
// above (which the cube maps still use), so a light costs a screen's pixels, not the scene's
// triangles again (the conference room's 277k triangles: four lights drew in 120 ms, now a few).
const char* kSurfaceGlsl = R"(
uniform sampler2D surface_position, surface_normal, surface_albedo_map;
// The G-buffer's surface at this pixel; false where it holds no diffuse surface.
bool surface_at(out vec3 p, out vec3 n, out vec3 albedo) {
    ivec2 q = ivec2(gl_FragCoord.xy);
    vec4 a = texelFetch(surface_albedo_map, q, 0);
    p = texelFetch(surface_position, q, 0).xyz;
    n = texelFetch(surface_normal, q, 0).xyz;
    albedo = a.rgb;
    return a.a > 0.5;
}
)";
const std::string kDeferredLightingFragment = std::string(kLightsGlsl) + kSurfaceGlsl + R"(
uniform int light_index;
layout(location = 0) out vec4 out_direct;
void main() {
    vec3 p, n, albedo;
    if (!surface_at(p, n, albedo)) discard;
    out_direct = vec4(direct_from(light_index, p, n, albedo), 0.0);
}
)";
const std::string kDeferredLightingMappedFragment =
    std::string(kLightsGlsl) + kSurfaceGlsl + kLightMapGlsl + R"(
uniform int light_index;
layout(location = 0) out vec4 out_direct;
void main() {
    vec3 p, n, albedo;
    if (!surface_at(p, n, albedo)) discard;
    out_direct = light_map_sees(p, n) ? vec4(direct_from(light_index, p, n, albedo), 0.0)
                                      : vec4(0.0);
}
)";

const char* kVolumeVertex = R"(
layout(location = 0) in vec4 position;
uniform mat4 view_projection;
void main() { gl_Position = view_projection * position; }
)";
const char* kVolumeFragment = R"(
out vec4 color;
void main() { color = vec4(0.0); }
)";

// What a mirror or glass object sees: the diffuse scene with emission, indirect light and the
// lights' shadowed direct light, and in alpha the distance from the cube map's centre. The direct
// light is rendered by the same passes as in the frame into a store per face (`direct`, layer
// `direct_layer`), read here texel for texel: the faces follow a converging indirect term every
// frame, and the direct light, the larger cost, only when the scene or the lights change.
const std::string kEnvironmentFragment = std::string(kAlbedoGlsl) + R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
uniform sampler2D iim;
uniform sampler2DArray direct;
uniform int direct_layer;
uniform vec3 albedo;
uniform vec3 emission;
uniform int diffuse;
uniform vec3 centre;
out vec4 color;
void main() {
    float distance = length(v_world - centre);
    if (diffuse == 0) { color = vec4(0.0, 0.0, 0.0, distance); return; }
    vec3 light = texelFetch(direct, ivec3(ivec2(gl_FragCoord.xy), direct_layer), 0).rgb;
    color = vec4(emission + surface_albedo(albedo) * texture(iim, v_uv).rgb + light, distance);
}
)";

// A glass object's own surface seen from its centre: outward face normal and distance.
const char* kInnerFragment = R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
uniform vec3 centre;
out vec4 color;
void main() { color = vec4(normalize(v_normal), length(v_world - centre)); }
)";

// Eq. 13.2 on the GPU: the displayed frame is the sum of the four terms.
const char* kComposeFragment = R"(
uniform sampler2D direct, indirect, specular, caustics, volume;
out vec4 color;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    color = vec4(texelFetch(direct, p, 0).rgb + texelFetch(indirect, p, 0).rgb +
                 texelFetch(specular, p, 0).rgb + texelFetch(caustics, p, 0).rgb +
                 texelFetch(volume, p, 0).rgb, 1.0);
}
)";

// A media method's `specular` term at the pixels it covers (alpha 1: the camera ray meets glass
// first) over the cube maps' (set_specular_through_glass); the other pixels keep theirs.
const char* kGlassSpecularFragment = R"(
uniform sampler2D through_glass;
layout(location = kFrameTermSpecular) out vec4 out_specular;
void main() {
    vec4 t = texelFetch(through_glass, ivec2(gl_FragCoord.xy), 0);
    if (t.a < 0.5) discard;
    out_specular = vec4(t.rgb, 1.0);
}
)";

// A media method's light on the surfaces, added into the indirect term by blending (dst + src;
// set_media_indirect).
const char* kAddIndirectFragment = R"(
uniform sampler2D media_indirect;
layout(location = kFrameTermIndirect) out vec4 out_indirect;
void main() {
    out_indirect = vec4(texelFetch(media_indirect, ivec2(gl_FragCoord.xy), 0).rgb, 0.0);
}
)";

// The camera ray's transmittance through the media up to the surface, multiplied into the
// surface's terms by blending (dst × src; set_volume): pt's components are attenuated so.
const char* kAttenuateFragment = R"(
uniform sampler2D transmittance;
layout(location = kFrameTermDirect) out vec4 out_direct;
layout(location = kFrameTermIndirect) out vec4 out_indirect;
layout(location = kFrameTermCaustics) out vec4 out_caustics;
layout(location = kFrameTermSpecular) out vec4 out_specular;
void main() {
    vec4 t = vec4(texelFetch(transmittance, ivec2(gl_FragCoord.xy), 0).rgb, 1.0);
    out_direct = t;
    out_indirect = t;
    out_caustics = t;
    out_specular = t;
}
)";

// The running mean of the terms: mix(mean, current, weight) per term, weight = 1/frames (the
// draw buffers choose which terms are written).
const char* kMeanFragment = R"(
uniform sampler2D mean_direct, mean_indirect, mean_caustics, mean_specular, mean_volume;
uniform sampler2D current_direct, current_indirect, current_caustics, current_specular,
    current_volume;
uniform float weight;
layout(location = kFrameTermDirect) out vec4 out_direct;
layout(location = kFrameTermIndirect) out vec4 out_indirect;
layout(location = kFrameTermCaustics) out vec4 out_caustics;
layout(location = kFrameTermSpecular) out vec4 out_specular;
layout(location = kFrameTermVolume) out vec4 out_volume;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    out_direct = mix(texelFetch(mean_direct, p, 0), texelFetch(current_direct, p, 0), weight);
    out_indirect =
        mix(texelFetch(mean_indirect, p, 0), texelFetch(current_indirect, p, 0), weight);
    out_caustics =
        mix(texelFetch(mean_caustics, p, 0), texelFetch(current_caustics, p, 0), weight);
    out_specular =
        mix(texelFetch(mean_specular, p, 0), texelFetch(current_specular, p, 0), weight);
    out_volume = mix(texelFetch(mean_volume, p, 0), texelFetch(current_volume, p, 0), weight);
}
)";

}  // namespace

glm::vec2 light_sample_jitter(int frame) {
    if (frame <= 0) return glm::vec2(0.5f);
    const auto k = uint64_t(frame);
    return glm::fract(glm::vec2(0.5f) +
                      glm::vec2(float(radical_inverse(2, k)), float(radical_inverse(3, k))));
}

glm::vec2 pixel_jitter(int frame) {
    if (frame <= 0) return glm::vec2(0.0f);
    const auto k = uint64_t(frame);
    return glm::fract(glm::vec2(0.5f) +
                      glm::vec2(float(radical_inverse(5, k)), float(radical_inverse(7, k)))) -
           glm::vec2(0.5f);
}

std::vector<LightSample> light_samples(const Scene& scene, glm::vec2 jitter) {
    std::vector<LightSample> out;
    for (const Light& l : scene.lights) {
        if (!l.enabled) continue;
        if (l.type == LightType::point) {
            out.push_back({l.position, l.intensity, glm::vec3(0.0f), false});
            continue;
        }
        if (l.type == LightType::spot) {
            out.push_back({l.position, l.intensity, l.direction, false, false,
                           glm::vec2(l.cos_outer(), l.cos_inner())});
            continue;
        }
        if (l.type == LightType::sun) {
            out.push_back({-l.direction, l.irradiance, glm::vec3(0.0f), false, true});
            continue;
        }
        const int n = quad_light_grid(scene.settings);
        if (l.type == LightType::mesh) {
            // n² points spread over the triangles by area (a rank-1 lattice: stratum j is the
            // strip u ∈ [j, j+1)/n² of the area CDF), each standing for A/n² of the surface;
            // lifted off it so its own mesh does not shadow it.
            const int count = n * n;
            const glm::vec3 intensity = l.radiance * (l.area() / float(count));
            const float lift = 1e-4f * scene.diagonal();
            for (int j = 0; j < count; ++j) {
                const LightPoint at =
                    sample_area_light(scene, l, (float(j) + jitter.x) / float(count),
                                      std::fmod(float(j) * 0.6180339887f + jitter.y, 1.0f));
                out.push_back({at.position + lift * at.normal, intensity, at.normal, true});
            }
            continue;
        }
        const glm::vec3 e1 = l.corners[1] - l.corners[0], e3 = l.corners[3] - l.corners[0];
        // Each cell of area A/n² emits I(ω) = L · (A/n²) · cosθ towards the front.
        const glm::vec3 intensity = l.radiance * (l.quad_area() / float(n * n));
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                out.push_back({l.corners[0] + (float(i) + jitter.x) / float(n) * e1 +
                                   (float(j) + jitter.y) / float(n) * e3,
                               intensity, l.quad_normal(), true});
    }
    // Never cut: the scene file was checked on load, but settings may have changed since.
    if (int(out.size()) > kMaxLightSamples) check_light_samples(scene);  // throws InputError
    return out;
}

FrameRenderer::FrameRenderer(const Scene& scene, const SceneMeshes& meshes, int width, int height)
    : scene_(scene), meshes_(meshes), width_(width), height_(height) {
    check_light_samples(scene);
    if (scene.media.size() > size_t(kMaxFrameMediaBoxes))
        throw std::invalid_argument(
            scene.path + ": \"media\" has " + std::to_string(scene.media.size()) +
            " boxes; the GPU frame shades at most " + std::to_string(kMaxFrameMediaBoxes));
    gbuffer_ = Program("frame g-buffer", kSceneVertex, kGbufferFragment);
    gbuffer_surface_ = Program("frame g-buffer with the surface", kSceneVertex,
                               "#define WRITE_SURFACE\n" + kGbufferFragment);
    gbuffer_specular_ =
        Program("frame g-buffer, mirrors and glass", kSceneVertex, kGbufferSpecularFragment);
    lighting_ = Program("frame lighting", kSceneVertex, kLightingFragment);
    lighting_mapped_ =
        Program("frame lighting, shadow maps", kSceneVertex, kLightingMappedFragment);
    lighting_deferred_ =
        Program("frame lighting, deferred", kFullScreenTriangleVertex, kDeferredLightingFragment);
    lighting_deferred_mapped_ = Program("frame lighting, deferred, shadow maps",
                                        kFullScreenTriangleVertex, kDeferredLightingMappedFragment);
    volume_ = Program("shadow volumes", kVolumeVertex, kVolumeFragment);
    environment_ = Program("cube-map environment", kSceneVertex, kEnvironmentFragment);
    inner_ = Program("glass inner map", kSceneVertex, kInnerFragment);

    fbo_ = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    for (size_t i = 0; i < aov_.size(); ++i) {
        aov_[i] = make_float_texture(width, height);
        gl::FramebufferTexture2D(GL_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + i), GL_TEXTURE_2D,
                                 aov_[i].get(), 0);
    }
    depth_stencil_ = make_renderbuffer();
    gl::BindRenderbuffer(GL_RENDERBUFFER, depth_stencil_.get());
    gl::RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH32F_STENCIL8, width, height);
    gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                                depth_stencil_.get());
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("frame: framebuffer incomplete");
    // The surface attachments after the terms, and the deferred lighting's framebuffer: the
    // direct term over the same depth and stencil (the G-buffer's textures are read, not drawn).
    for (size_t i = 0; i < surface_.size(); ++i) {
        surface_[i] = make_float_texture(width, height);
        gl::FramebufferTexture2D(GL_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + kFrameTermCount + i),
                                 GL_TEXTURE_2D, surface_[i].get(), 0);
    }
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("frame: framebuffer with surface attachments incomplete");
    lighting_fbo_ = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, lighting_fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                             aov_[size_t(FrameTerm::direct)].get(), 0);
    gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                                depth_stencil_.get());
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("frame: lighting framebuffer incomplete");

    compose_ = Program("frame compose", kFullScreenTriangleVertex, kComposeFragment);
    glass_specular_ =
        Program("frame specular through glass", kFullScreenTriangleVertex, kGlassSpecularFragment);
    glass_specular_texture_ = make_float_texture(width, height);
    attenuate_ =
        Program("frame media transmittance", kFullScreenTriangleVertex, kAttenuateFragment);
    transmittance_texture_ = make_float_texture(width, height);
    add_indirect_ =
        Program("frame media indirect", kFullScreenTriangleVertex, kAddIndirectFragment);
    media_indirect_texture_ = make_float_texture(width, height);
    frame_ = make_float_texture(width, height);
    compose_fbo_ = make_framebuffer();
    gl::BindFramebuffer(GL_FRAMEBUFFER, compose_fbo_.get());
    gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, frame_.get(), 0);
    if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("frame: compose framebuffer incomplete");
    empty_vao_ = make_vertex_array();

    for (const Object& o : scene.objects) {
        casters_.push_back(make_shadow_caster(o.mesh));
        Bounds b;
        for (const glm::vec3& p : o.mesh.positions) b.add(p);
        object_bounds_.push_back(b);
    }
    for (const Object& o : scene.objects)
        if (o.material.type == MaterialType::diffuse) diffuse_triangles_ += o.mesh.triangles.size();
    volume_vbo_ = make_buffer();
    volume_vao_ = make_vertex_array();
    gl::BindVertexArray(volume_vao_.get());
    gl::BindBuffer(GL_ARRAY_BUFFER, volume_vbo_.get());
    gl::EnableVertexAttribArray(0);
    gl::VertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 0, nullptr);
    gl::BindVertexArray(0);

    const int cube = scene.settings.specular.cube_map_size;
    auto make_cube = [&](GLenum filter) {
        Texture t = make_texture();
        gl::BindTexture(GL_TEXTURE_CUBE_MAP, t.get());
        for (int f = 0; f < 6; ++f)
            gl::TexImage2D(GLenum(GL_TEXTURE_CUBE_MAP_POSITIVE_X + f), 0, GL_RGBA32F, cube, cube, 0,
                           GL_RGBA, GL_FLOAT, nullptr);
        gl::TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GLint(filter));
        gl::TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAG_FILTER, GLint(filter));
        gl::TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        gl::TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        gl::TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
        return t;
    };
    gl::Enable(GL_TEXTURE_CUBE_MAP_SEAMLESS);  // no seams where a lookup crosses a face edge
    cube_maps_.resize(scene.objects.size());
    face_generation_.assign(scene.objects.size() * 6, 0);
    cube_direct_.resize(scene.objects.size());
    face_direct_generation_.assign(scene.objects.size() * 6, 0);
    inner_maps_.resize(scene.objects.size());
    cube_radii_.assign(scene.objects.size(), 0.0f);
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        const Object& obj = scene.objects[o];
        if (obj.material.type == MaterialType::diffuse) continue;
        cube_maps_[o] = make_cube(GL_LINEAR);
        cube_direct_[o] = make_texture();
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, cube_direct_[o].get());
        gl::TexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_RGBA32F, cube, cube, 6);
        gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        gl::TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, 0);
        // Nearest: a face's normal is not blended with its neighbours' (the references see facets).
        if (obj.material.type == MaterialType::glass) inner_maps_[o] = make_cube(GL_NEAREST);
        const glm::vec3 c = mesh_bounds(obj.mesh).center();
        for (const glm::vec3& p : obj.mesh.positions)
            cube_radii_[o] = std::max(cube_radii_[o], glm::length(p - c));
    }
    cube_depth_ = make_renderbuffer();
    gl::BindRenderbuffer(GL_RENDERBUFFER, cube_depth_.get());
    gl::RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH32F_STENCIL8, cube, cube);
    cube_fbo_ = make_framebuffer();
    near_ = 1e-3f * scene.diagonal();

    mean_program_ = Program("frame running mean", kFullScreenTriangleVertex, kMeanFragment);
    for (size_t i = 0; i < mean_.size(); ++i) {
        mean_fbo_[i] = make_framebuffer();
        gl::BindFramebuffer(GL_FRAMEBUFFER, mean_fbo_[i].get());
        for (size_t t = 0; t < kFrameTermCount; ++t) {
            mean_[i][t] = make_float_texture(width, height);
            gl::FramebufferTexture2D(GL_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + t),
                                     GL_TEXTURE_2D, mean_[i][t].get(), 0);
        }
        if (gl::CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            throw GlError("frame: running mean framebuffer incomplete");
    }
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("FrameRenderer");
}

void FrameRenderer::set_light_uniforms(const Program& p,
                                       const std::vector<LightSample>& lights) const {
    p.set("light_count", int(lights.size()));
    for (size_t i = 0; i < lights.size(); ++i) {
        const std::string k = "[" + std::to_string(i) + "]";
        p.set(("light_position" + k).c_str(), lights[i].position);
        p.set(("light_intensity" + k).c_str(), lights[i].intensity);
        p.set(("light_normal" + k).c_str(), lights[i].normal);
        p.set(("light_one_sided" + k).c_str(), lights[i].one_sided ? 1 : 0);
        p.set(("light_directional" + k).c_str(), lights[i].directional ? 1 : 0);
        p.set(("light_cone" + k).c_str(), lights[i].cone);
    }
    set_media_uniforms(p, scene_);  // at most kMaxFrameMediaBoxes: the constructor refuses more
}

glm::vec3 FrameRenderer::cube_centre(size_t object) const {
    const Object& o = scene_.objects[object];
    return o.transform.apply_point(mesh_bounds(o.mesh).center());
}

void FrameRenderer::render_cube_maps(GLuint iim, const std::vector<LightSample>& lights,
                                     const std::vector<int>& faces) {
    const int size = scene_.settings.specular.cube_map_size;
    // Face order +X −X +Y −Y +Z −Z with the GL cube-map conventions for up vectors.
    const glm::vec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    const glm::vec3 ups[6] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1},
                              {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
    // Infinite far plane, as in the frame: shadow volumes extruded to w = 0 are never clipped.
    const glm::mat4 projection = glm::infinitePerspective(glm::radians(90.0f), 1.0f, near_);
    update_light_maps(lights);  // binds its own framebuffer: before the faces' passes
    gl::BindFramebuffer(GL_FRAMEBUFFER, cube_fbo_.get());
    gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                                cube_depth_.get());
    const GLenum draw = GL_COLOR_ATTACHMENT0;
    const glm::vec4 cleared_distance(0, 0, 0, 1e30f);  // no surface: a lookup uses the direction
    for (int index : faces) {
        const size_t s = size_t(index / 6);
        const int f = index % 6;
        const glm::vec3 centre = cube_centre(s);
        const glm::mat4 view_projection =
            projection * glm::lookAt(centre, centre + dirs[f], ups[f]);
        const GLenum face = GLenum(GL_TEXTURE_CUBE_MAP_POSITIVE_X + f);
        if (inner_maps_[s]) {
            // The object's own surface (only it): its normals and distances.
            gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, face,
                                     inner_maps_[s].get(), 0);
            begin_scene_pass(cube_fbo_.get(), 1, size, size, glm::vec4(0, 0, 0, 0));
            inner_.use();
            inner_.set("view_projection", view_projection);
            inner_.set("centre", centre);
            inner_.set("model", model_matrix(scene_.objects[s]));
            meshes_.draw(s);
        }
        // Every object but this one, with the environment program: the depth of the direct
        // light's passes, then the face itself.
        auto draw_environment = [&] {
            environment_.use();
            environment_.set("iim", 0);
            environment_.set("direct", 1);
            environment_.set("direct_layer", f);
            environment_.set("centre", centre);
            environment_.set("view_projection", view_projection);
            gl::ActiveTexture(GL_TEXTURE0);
            gl::BindTexture(GL_TEXTURE_2D, iim);
            for (size_t o = 0; o < scene_.objects.size(); ++o) {
                if (o == s) continue;  // an object does not see itself in its own cube map
                const Object& obj = scene_.objects[o];
                environment_.set("model", model_matrix(obj));
                environment_.set("albedo", base_albedo(obj));
                meshes_.bind_albedo(environment_, o, kAlbedoUnit);
                environment_.set("emission", obj.material.emission);
                environment_.set("diffuse", obj.material.type == MaterialType::diffuse ? 1 : 0);
                meshes_.draw(o);
            }
        };
        uint64_t& stored = face_direct_generation_[size_t(index)];
        if (stored != direct_generation_) {
            // Direct light with the frame's shadow volumes (every object casts, this one too: a
            // mirror ball shows its own contact shadow), into the face's store over the depth of
            // what it sees.
            gl::FramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, cube_direct_[s].get(),
                                        0, f);
            begin_scene_pass(cube_fbo_.get(), 1, size, size, glm::vec4(0.0f));
            gl::ActiveTexture(GL_TEXTURE1);
            gl::BindTexture(GL_TEXTURE_2D_ARRAY, 0);  // not read while written
            gl::ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
            draw_environment();
            gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
            add_direct_light(lights, view_projection, draw);
            gl::BindFramebuffer(GL_FRAMEBUFFER, cube_fbo_.get());
            stored = direct_generation_;
        }
        gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, face, cube_maps_[s].get(),
                                 0);
        begin_scene_pass(cube_fbo_.get(), 1, size, size, cleared_distance);
        gl::ActiveTexture(GL_TEXTURE1);
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, cube_direct_[s].get());
        draw_environment();
        gl::ActiveTexture(GL_TEXTURE1);
        gl::BindTexture(GL_TEXTURE_2D_ARRAY, 0);
        gl::ActiveTexture(GL_TEXTURE0);
    }
    check_gl("FrameRenderer::render_cube_maps");
}

void FrameRenderer::draw_shadow_volumes(const LightSample& light,
                                        const glm::mat4& view_projection) {
    std::vector<glm::mat4> models;
    for (const Object& o : scene_.objects) models.push_back(model_matrix(o));
    // The weld depends only on where the open meshes (soup casters) are: a closed mover (Sponza's
    // block) leaves it as it is. Made again for every move, it cost Sponza's moving frames 2.3×
    // the draw time of the frames before the weld.
    bool soup_moved = models.size() != caster_models_.size();
    for (size_t o = 0; o < models.size() && !soup_moved; ++o)
        soup_moved = casters_[o].soup && models[o] != caster_models_[o];
    if (soup_moved) soup_weld_ = weld_soup_corners(casters_, models);
    caster_models_ = std::move(models);
    // Where every object is (the receivers): a planar soup with all of them in front of it,
    // seen from the light (a room's floor, walls and ceiling), casts nothing.
    std::vector<Bounds> receivers(object_bounds_.size());
    for (size_t o = 0; o < receivers.size(); ++o) {
        const Bounds& b = object_bounds_[o];
        if (b.empty()) continue;
        for (int k = 0; k < 8; ++k)
            receivers[o].add(glm::vec3(
                caster_models_[o] * glm::vec4(k & 1 ? b.max.x : b.min.x, k & 2 ? b.max.y : b.min.y,
                                              k & 4 ? b.max.z : b.min.z, 1.0f)));
    }
    std::vector<glm::vec4> triangles;
    append_shadow_volumes(casters_, caster_models_, soup_weld_,
                          glm::vec4(light.position, light.directional ? 0.0f : 1.0f), triangles,
                          &receivers);
    if (triangles.empty()) return;
    gl::BindBuffer(GL_ARRAY_BUFFER, volume_vbo_.get());
    gl::BufferData(GL_ARRAY_BUFFER, GLsizeiptr(triangles.size() * sizeof(glm::vec4)),
                   triangles.data(), GL_STREAM_DRAW);
    volume_.use();
    volume_.set("view_projection", view_projection);
    gl::BindVertexArray(volume_vao_.get());
    gl::DrawArrays(GL_TRIANGLES, 0, GLsizei(triangles.size()));
}

bool FrameRenderer::update_light_maps(const std::vector<LightSample>& lights) {
    const DirectSettings& direct = scene_.settings.direct;
    if (direct.method != DirectMethod::vpl || !direct.shadows) return false;
    if (!light_maps_ || light_maps_->size() != direct.map_size) {
        light_maps_ = std::make_unique<VplShadowMaps>(
            scene_, meshes_, direct.map_size, VplMapKind::octahedral, 1e-4f * scene_.diagonal());
        maps_valid_ = false;
    }
    if (maps_valid_ && mapped_version_ == scene_.version && mapped_lights_ == lights) return true;
    // A map's record: the sample's position and the normal its hemisphere is about (power unused).
    std::vector<Vpl> records;
    light_map_layer_.assign(lights.size(), -1);
    for (size_t i = 0; i < lights.size(); ++i) {
        const LightSample& l = lights[i];
        if (l.directional) continue;
        light_map_layer_[i] = int(records.size());
        const glm::vec3 up = l.one_sided || glm::length(l.normal) > 0.5f ? glm::normalize(l.normal)
                                                                         : glm::vec3(0, 1, 0);
        records.push_back({l.position, up, glm::vec3(0.0f)});
        if (!l.one_sided) records.push_back({l.position, -up, glm::vec3(0.0f)});
    }
    light_maps_->set_vpls(records);
    light_maps_->render_all();
    mapped_lights_ = lights;
    mapped_version_ = scene_.version;
    maps_valid_ = true;
    return true;
}

void FrameRenderer::add_direct_light(const std::vector<LightSample>& lights,
                                     const glm::mat4& view_projection, GLenum draw_buffer,
                                     bool deferred) {
    // With shadow maps they were rendered for these samples before the pass began.
    const bool mapped = light_maps_ && maps_valid_ &&
                        scene_.settings.direct.method == DirectMethod::vpl &&
                        scene_.settings.direct.shadows && mapped_lights_ == lights;
    if (deferred) {  // the direct term over the frame's depth and stencil
        gl::BindFramebuffer(GL_FRAMEBUFFER, lighting_fbo_.get());
        draw_buffer = GL_COLOR_ATTACHMENT0;
    }
    gl::DepthMask(GL_FALSE);
    gl::Enable(GL_STENCIL_TEST);
    gl::Enable(GL_DEPTH_CLAMP);
    for (size_t i = 0; i < lights.size(); ++i) {
        gl::Clear(GL_STENCIL_BUFFER_BIT);
        const int layer = mapped ? light_map_layer_[i] : -1;
        if (scene_.settings.direct.shadows && layer < 0) {
            gl::ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
            gl::DepthFunc(GL_LESS);
            gl::StencilFunc(GL_ALWAYS, 0, 0xFF);
            gl::StencilOpSeparate(GL_BACK, GL_KEEP, GL_INCR_WRAP, GL_KEEP);
            gl::StencilOpSeparate(GL_FRONT, GL_KEEP, GL_DECR_WRAP, GL_KEEP);
            draw_shadow_volumes(lights[i], view_projection);
            gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        }
        gl::DrawBuffers(1, &draw_buffer);
        gl::StencilFunc(GL_EQUAL, 0, 0xFF);
        gl::StencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
        gl::DepthFunc(GL_LEQUAL);
        gl::Enable(GL_BLEND);
        gl::BlendFunc(GL_ONE, GL_ONE);  // alpha + 0: a cube map's distances stay
        const Program& program = deferred
                                     ? (mapped ? lighting_deferred_mapped_ : lighting_deferred_)
                                     : (mapped ? lighting_mapped_ : lighting_);
        program.use();
        program.set("view_projection", view_projection);
        set_light_uniforms(program, {lights[i]});
        program.set("light_index", 0);
        if (mapped) {
            light_maps_->bind_buffer();
            gl::ActiveTexture(GL_TEXTURE0 + kLightMapUnit);
            gl::BindTexture(GL_TEXTURE_2D_ARRAY, light_maps_->texture());
            gl::ActiveTexture(GL_TEXTURE0);
            program.set("light_maps", int(kLightMapUnit));
            program.set("map_layer", layer);
            program.set("map_layers", lights[i].one_sided ? 1 : 2);
            program.set("map_kind", int(light_maps_->kind()));
            program.set("offset_scale", light_maps_->offset_scale());
            program.set("relative_bias", VplShadowMaps::kRelativeBias);
        }
        if (deferred) {
            // Every pixel the G-buffer pass left a diffuse surface in (the depth test is off:
            // the triangle lies at no depth; the stencil still says where the light is shadowed).
            constexpr int kSurfaceUnit = 3;  // position, normal, albedo on units 3, 4, 5
            static_assert(kSurfaceUnit + 2 < kLightMapUnit);
            const char* names[3] = {"surface_position", "surface_normal", "surface_albedo_map"};
            for (size_t t = 0; t < surface_.size(); ++t) {
                gl::ActiveTexture(GLenum(GL_TEXTURE0 + kSurfaceUnit + t));
                gl::BindTexture(GL_TEXTURE_2D, surface_[t].get());
                program.set(names[t], kSurfaceUnit + int(t));
            }
            gl::ActiveTexture(GL_TEXTURE0);
            gl::Disable(GL_DEPTH_TEST);
            gl::BindVertexArray(empty_vao_.get());
            gl::DrawArrays(GL_TRIANGLES, 0, 3);
            gl::Enable(GL_DEPTH_TEST);
        } else {
            for (size_t o = 0; o < scene_.objects.size(); ++o) {
                const Object& obj = scene_.objects[o];
                if (obj.material.type != MaterialType::diffuse) continue;
                program.set("model", model_matrix(obj));
                program.set("albedo", base_albedo(obj));
                meshes_.bind_albedo(program, o, kAlbedoUnit);
                meshes_.draw(o);
            }
        }
        gl::Disable(GL_BLEND);
    }
    if (deferred) {
        for (size_t t = 0; t < surface_.size(); ++t) {
            gl::ActiveTexture(GLenum(GL_TEXTURE0 + 3 + t));
            gl::BindTexture(GL_TEXTURE_2D, 0);
        }
        gl::ActiveTexture(GL_TEXTURE0);
        gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    }
    gl::Disable(GL_DEPTH_CLAMP);
    gl::Disable(GL_STENCIL_TEST);
    gl::DepthMask(GL_TRUE);
    gl::DepthFunc(GL_LESS);
}

void FrameRenderer::render(GLuint iim, GLuint caustics) {
    render(IndirectTerm{iim, IndirectSpace::lightmap}, caustics, 0);
}

std::vector<int> FrameRenderer::cube_faces_to_render(const IndirectTerm& indirect,
                                                     const std::vector<LightSample>& lights,
                                                     size_t relit_faces) {
    const CubeMapKey& k = cube_key_;
    // A new term texture (or none yet) is rendered whole at once; edits of the scene or the
    // lights, and new revisions of the term, move the generation on.
    const bool all = !k.valid || indirect.revision == 0 || k.texture != indirect.texture ||
                     k.space != indirect.space;
    const bool moved_on =
        k.scene_version != scene_.version || k.revision != indirect.revision || k.lights != lights;
    // The frame of an edit after frames without one draws the direct light anew for every light;
    // its faces wait for the frames after it (two_rooms' door at 96²: two faces drawn with the
    // moved door cost 14 ms of a 33 ms frame, on top of the direct light's 9 ms, and the frame
    // ran to 46 ms). In a run of edits every frame draws its share.
    const bool edited = k.valid && k.scene_version != scene_.version;
    const bool first_edit = edited && !last_edited_;
    last_edited_ = edited;
    cube_key_ = {scene_.version, indirect.revision, indirect.texture, indirect.space, lights, true};
    if (moved_on || all) ++generation_;
    // The direct light the faces' stores hold moves on with the scene and the light samples.
    if (!direct_key_.valid || direct_key_.scene_version != scene_.version ||
        direct_key_.lights != lights) {
        direct_key_ = {scene_.version, {}, 0, IndirectSpace::lightmap, lights, true};
        ++direct_generation_;
    }
    std::vector<int> faces;
    if (all) {
        for (size_t s = 0; s < cube_maps_.size(); ++s)
            if (cube_maps_[s])
                for (int f = 0; f < 6; ++f) faces.push_back(int(s) * 6 + f);
        for (int face : faces) {
            face_generation_[size_t(face)] = generation_;
            faces_relit_ += face_direct_generation_[size_t(face)] != direct_generation_ ? 1 : 0;
        }
        return faces;
    }
    // The faces that show an older state follow a share a frame, round robin, all within
    // kIndirectRefreshFrames frames: a converging IIM changes every frame, an edited scene
    // often, and the six faces per mirror or glass object cost more than the frame itself (the
    // reflections lag by a few frames; the frame rate holds).
    if (first_edit) return faces;
    std::vector<int> behind;
    for (size_t s = 0; s < cube_maps_.size(); ++s)
        if (cube_maps_[s])
            for (int f = 0; f < 6; ++f)
                if (face_generation_[s * 6 + size_t(f)] != generation_)
                    behind.push_back(int(s) * 6 + f);
    if (behind.empty()) return faces;
    size_t total = 0;
    for (const Texture& t : cube_maps_) total += t ? 6 : 0;
    const size_t share = (total + kIndirectRefreshFrames - 1) / kIndirectRefreshFrames;
    // Start after the face rendered last, so every face gets its turn.
    std::rotate(behind.begin(), std::upper_bound(behind.begin(), behind.end(), last_face_),
                behind.end());
    // A face whose direct light is out of date (after an edit) draws it for every light, the
    // cost of several faces that follow the indirect term alone: `relit_faces` a frame
    // (kRelitFacesPerFrame), so the frames after an edit keep their length (two_rooms at 96²,
    // two re-lit faces a frame: 21-34 ms of the frame's drawing for three frames).
    std::vector<int> taken;
    size_t relit = 0;
    for (int face : behind) {
        if (taken.size() >= share) break;
        const bool stale = face_direct_generation_[size_t(face)] != direct_generation_;
        if (stale && relit >= relit_faces) continue;
        relit += stale ? 1 : 0;
        taken.push_back(face);
    }
    behind = std::move(taken);
    faces_relit_ = relit;
    if (behind.empty()) return behind;
    for (int face : behind) face_generation_[size_t(face)] = generation_;
    last_face_ = behind.back();
    return behind;
}

size_t FrameRenderer::faces_to_relight() const {
    size_t n = 0;
    for (size_t s = 0; s < cube_maps_.size(); ++s)
        if (cube_maps_[s])
            for (size_t f = 0; f < 6; ++f)
                n += face_direct_generation_[s * 6 + f] != direct_generation_ ? 1 : 0;
    return n;
}

bool FrameRenderer::cube_maps_current() const {
    for (size_t s = 0; s < cube_maps_.size(); ++s)
        if (cube_maps_[s])
            for (int f = 0; f < 6; ++f)
                if (face_generation_[s * 6 + size_t(f)] != generation_) return false;
    return cube_key_.valid;
}

void FrameRenderer::render(const IndirectTerm& indirect, GLuint caustics,
                           uint64_t caustics_revision, size_t relit_faces) {
    const std::vector<LightSample> lights = light_samples(scene_);
    // Cube maps see the scene by its lightmaps; a screen-space term has none to give them. They
    // are kept while the scene, the term and the light samples stay as they were.
    const GLuint iim = indirect.texture;
    const bool in_screen = indirect.space == IndirectSpace::screen;
    faces_relit_ = 0;
    const std::vector<int> faces = cube_faces_to_render(indirect, lights, relit_faces);
    cube_faces_ms_ = 0.0;
    if (!faces.empty()) {
        const auto t = std::chrono::steady_clock::now();
        render_cube_maps(in_screen ? 0 : iim, lights, faces);
        if (faces_relit_ > 0) {  // timed for the scheduler, which plans for re-lit faces
            gl::Finish();
            cube_faces_ms_ =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t)
                    .count();
        }
    }

    // The running mean (progressive refinement while nothing changes). The direct term always
    // averages frames of moved area-light samples (direct.accumulate_frames); with
    // frame.accumulate_frames > 1 every term does, each frame also moved by a sub-pixel offset
    // (progressive antialiasing), so the displayed frame converges to the box-filtered image.
    const Settings& settings = scene_.settings;
    const DirectSettings& direct = settings.direct;
    // Everything the frame shows besides the direct term: the camera, the indirect term, the
    // caustics and the cube maps (a face rendered this frame, or faces still behind).
    MeanKey shown{scene_.version,           direct.area_light_samples,
                  direct.accumulate_frames, settings.frame.accumulate_frames,
                  direct.shadows,           true};
    shown.eye = scene_.camera.eye;
    shown.target = scene_.camera.target;
    shown.up = scene_.camera.up;
    shown.fov_y = scene_.camera.fov_y;
    shown.indirect = indirect.texture;
    shown.space = indirect.space;
    shown.indirect_revision = indirect.revision;
    shown.caustics = caustics;
    shown.caustics_revision = caustics_revision;
    shown.cube_generation = generation_;
    shown.cube_current = cube_maps_current();
    const bool shown_still = shown == shown_key_ && faces.empty();
    shown_key_ = shown;
    // Every term is accumulated (with sub-pixel offsets) only while all of it stands still since
    // the frame before; while anything changes (an IIM converging, caustics re-traced, cube maps
    // catching up), frames are drawn at the pixel centres and only the direct term averages its
    // light samples, as without frame accumulation, so area lights' penumbrae converge even
    // while the indirect term does not. A term whose changes are not tracked (revision 0) may
    // change any frame: then the frame is never accumulated.
    const bool all_terms = settings.frame.accumulate_frames > 1 && indirect.revision != 0 &&
                           (!caustics || caustics_revision != 0) && shown_still;
    MeanKey key = shown;
    if (!all_terms) {  // the direct term alone: its inputs (and the view, which edits may skip)
        key = MeanKey{scene_.version,           direct.area_light_samples,
                      direct.accumulate_frames, settings.frame.accumulate_frames,
                      direct.shadows,           false};
        key.eye = shown.eye;
        key.target = shown.target;
        key.up = shown.up;
        key.fov_y = shown.fov_y;
    }
    if (!(key == mean_key_)) {
        mean_key_ = key;
        mean_frames_ = 0;
    }
    // Without an enabled quad or mesh light every frame would draw the same light samples.
    const bool area = std::any_of(scene_.lights.begin(), scene_.lights.end(),
                                  [](const Light& l) { return l.enabled && l.is_area(); });
    const int direct_limit = area && direct.accumulate_frames > 1 ? direct.accumulate_frames : 1;
    const int limit =
        all_terms ? std::max(settings.frame.accumulate_frames, direct_limit) : direct_limit;
    const bool accumulating = all_terms || direct.accumulate_frames > 1;
    const bool fresh = !accumulating || mean_frames_ < limit;
    // While frame accumulation waits for the frame to stand still, the mean is not complete.
    const bool frame_accumulation = settings.frame.accumulate_frames > 1 &&
                                    indirect.revision != 0 && (!caustics || caustics_revision != 0);
    mean_complete_ = (!accumulating || !fresh || mean_frames_ + 1 >= limit) &&
                     (all_terms || !frame_accumulation);
    // Every term is kept as it is: the term attachments and the frame already hold the mean.
    drew_ = !(all_terms && !fresh);
    drew_direct_ = drew_ && fresh;
    if (!drew_) return;

    // Frame k of the mean: the light samples at jitter k (frame 0 at their centres) and, with all
    // terms accumulated, the pixels sampled at offset k (frame 0 at their centres). The offset
    // moves the projection, so every term (rasterised coverage, shading, shadows) is sampled at
    // the same point of the pixel; screen-space images (caustics, a screen-space indirect term)
    // are read at the pixel they were made for.
    const int k = mean_frames_;
    Camera camera = scene_.camera;
    camera.width = width_;
    camera.height = height_;
    // Infinite far plane: shadow volumes extruded to w = 0 are never clipped.
    glm::mat4 projection =
        glm::infinitePerspective(glm::radians(camera.fov_y), float(width_) / float(height_), near_);
    if (all_terms) {
        const glm::vec2 offset = pixel_jitter(k);
        projection =
            glm::translate(glm::mat4(1.0f), glm::vec3(2.0f * offset.x / float(width_),
                                                      2.0f * offset.y / float(height_), 0.0f)) *
            projection;
    }
    const glm::mat4 view_projection = projection * view_matrix(camera);

    const GLenum all[kFrameTermCount] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1,
                                         GL_COLOR_ATTACHMENT2, GL_COLOR_ATTACHMENT3,
                                         GL_COLOR_ATTACHMENT4};
    // This frame's light samples (moved within their strata while the direct term accumulates)
    // and, with direct.method vpl, their shadow maps, rendered before the frame's passes.
    const bool move_lights = area && direct.accumulate_frames > 1 && k > 0;
    const std::vector<LightSample> frame_lights =
        move_lights ? light_samples(scene_, light_sample_jitter(k)) : lights;
    if (fresh) update_light_maps(frame_lights);
    // The surface attachments only for a frame that draws the direct light anew (writing them
    // costs a frame of the conference room at 64² a third more).
    const bool deferred =
        direct_pass_ == DirectPass::deferred ||
        (direct_pass_ == DirectPass::automatic &&
         frame_lights.size() * diffuse_triangles_ > size_t(width_) * size_t(height_));
    const bool surface = fresh && deferred;
    begin_scene_pass(fbo_.get(), kFrameTermCount + (surface ? int(surface_.size()) : 0), width_,
                     height_, glm::vec4(0, 0, 0, 1));
    if (surface) {
        const GLfloat none[4] = {0.0f, 0.0f, 0.0f, 0.0f};  // no surface: alpha 0
        for (size_t t = 0; t < surface_.size(); ++t)
            gl::ClearBufferfv(GL_COLOR, GLint(kFrameTermCount + t), none);
    }

    // 1. G-buffer: depth, emission, indirect, specular, caustics (and the surface for the
    //    deferred direct light).
    const Program& gbuffer = surface ? gbuffer_surface_ : gbuffer_;
    gbuffer.use();
    gbuffer.set("view_projection", view_projection);
    gbuffer.set("iim", 0);
    gbuffer.set("iim_in_screen", in_screen ? 1 : 0);
    gbuffer.set("caustics", 1);
    gbuffer.set("has_caustics", caustics ? 1 : 0);
    gbuffer.set("screen", glm::vec2(float(width_), float(height_)));
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, iim);
    gl::ActiveTexture(GL_TEXTURE1);
    gl::BindTexture(GL_TEXTURE_2D, caustics);
    for (size_t o = 0; o < scene_.objects.size(); ++o) {
        const Object& obj = scene_.objects[o];
        if (obj.material.type != MaterialType::diffuse) continue;
        gbuffer.set("model", model_matrix(obj));
        gbuffer.set("albedo", base_albedo(obj));
        meshes_.bind_albedo(gbuffer, o, kAlbedoUnit);
        gbuffer.set("emission", obj.material.emission);
        meshes_.draw(o);
    }
    gbuffer_specular_.use();
    gbuffer_specular_.set("view_projection", view_projection);
    gbuffer_specular_.set("environment", 2);
    gbuffer_specular_.set("inner", 3);
    gbuffer_specular_.set("scene_size", 2.0f * scene_.diagonal());
    gbuffer_specular_.set("eye", camera.eye);
    for (size_t o = 0; o < scene_.objects.size(); ++o) {
        const Object& obj = scene_.objects[o];
        if (obj.material.type == MaterialType::diffuse) continue;
        gbuffer_specular_.set("model", model_matrix(obj));
        gbuffer_specular_.set("material", int(obj.material.type));
        gbuffer_specular_.set("ior", obj.material.ior);
        gbuffer_specular_.set("centre", cube_centre(o));
        gbuffer_specular_.set("object_radius", cube_radii_[o]);
        gl::ActiveTexture(GL_TEXTURE2);
        gl::BindTexture(GL_TEXTURE_CUBE_MAP, cube_maps_[o].get());
        gl::ActiveTexture(GL_TEXTURE3);
        gl::BindTexture(GL_TEXTURE_CUBE_MAP, inner_maps_[o] ? inner_maps_[o].get() : 0);
        meshes_.draw(o);
    }

    // 2. Per light: shadow volumes into the stencil (depth-fail), then add its light where the
    //    count is zero (eq. 13.2). While the scene stands still, each frame moves the area
    //    lights' samples within their strata and the direct term is the mean over the frames:
    //    n² samples a frame, n²·k after k frames; once the mean is complete, it is kept.
    if (fresh)
        add_direct_light(frame_lights, view_projection,
                         GLenum(GL_COLOR_ATTACHMENT0 + kFrameTermDirect), deferred);
    if (accumulating)
        accumulate(fresh, all_terms);
    else
        mean_frames_ = 1;
    gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    gl::DrawBuffers(kFrameTermCount, all);
    compose();
    gl::BindVertexArray(0);
    gl::BindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("FrameRenderer::render");
}

void FrameRenderer::accumulate(bool fresh, bool all_terms) {
    gl::Disable(GL_DEPTH_TEST);
    gl::Disable(GL_BLEND);
    gl::Disable(GL_STENCIL_TEST);
    gl::Viewport(0, 0, width_, height_);
    mean_program_.use();
    for (FrameTerm t : kFrameTerms) {
        mean_program_.set((std::string("mean_") + frame_term_name(t)).c_str(), int(t));
        mean_program_.set((std::string("current_") + frame_term_name(t)).c_str(),
                          int(kFrameTermCount) + int(t));
    }
    gl::BindVertexArray(empty_vao_.get());
    // Which terms are written: all of them, or the direct term alone (the others stay as drawn).
    GLenum buffers[kFrameTermCount];
    for (size_t t = 0; t < kFrameTermCount; ++t)
        buffers[t] = all_terms || t == size_t(FrameTerm::direct) ? GLenum(GL_COLOR_ATTACHMENT0 + t)
                                                                 : GLenum(GL_NONE);
    using Textures = std::array<GLuint, kFrameTermCount>;
    auto pass = [&](GLuint framebuffer, const Textures& mean, const Textures& current,
                    float weight) {
        gl::BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
        gl::DrawBuffers(GLsizei(kFrameTermCount), buffers);
        for (size_t t = 0; t < kFrameTermCount; ++t) {
            gl::ActiveTexture(GLenum(GL_TEXTURE0 + t));
            gl::BindTexture(GL_TEXTURE_2D, mean[t]);
            gl::ActiveTexture(GLenum(GL_TEXTURE0 + kFrameTermCount + t));
            gl::BindTexture(GL_TEXTURE_2D, current[t]);
        }
        mean_program_.set("weight", weight);
        gl::DrawArrays(GL_TRIANGLES, 0, 3);
    };
    auto textures = [](const std::array<Texture, kFrameTermCount>& from) {
        Textures out;
        for (size_t t = 0; t < kFrameTermCount; ++t) out[t] = from[t].get();
        return out;
    };
    const Textures this_frame = textures(aov_);
    if (fresh) {
        ++mean_frames_;
        const int next = 1 - mean_current_;
        // The first frame replaces the mean (never read: it may hold an older scene's), and the
        // term attachments already hold it.
        const Textures mean =
            mean_frames_ == 1 ? this_frame : textures(mean_[size_t(mean_current_)]);
        pass(mean_fbo_[size_t(next)].get(), mean, this_frame, 1.0f / float(mean_frames_));
        mean_current_ = next;
    }
    if (!fresh || mean_frames_ > 1) {
        const Textures mean = textures(mean_[size_t(mean_current_)]);
        pass(fbo_.get(), mean, mean, 0.0f);
    }
    for (size_t t = 0; t < 2 * kFrameTermCount; ++t) {
        gl::ActiveTexture(GLenum(GL_TEXTURE0 + t));
        gl::BindTexture(GL_TEXTURE_2D, 0);
    }
    gl::ActiveTexture(GL_TEXTURE0);
    gl::Enable(GL_DEPTH_TEST);
}

void FrameRenderer::set_volume(const Image& volume, const Image& transmittance) {
    volume_rgba_.clear();
    transmittance_rgba_.clear();
    const auto frame_sized = [&](const Image& image) {
        if (image.width != width_ || image.height != height_)
            throw std::invalid_argument("FrameRenderer::set_volume: the image is not frame-sized");
    };
    if (!transmittance.pixels.empty()) {
        frame_sized(transmittance);
        flip_to_rgba(
            transmittance, [](int, int) { return 1.0f; }, transmittance_rgba_);
        upload_rgba(transmittance_texture_.get(), width_, height_, transmittance_rgba_);
    }
    if (volume.pixels.empty()) return;
    frame_sized(volume);
    flip_to_rgba(
        volume, [](int, int) { return 1.0f; }, volume_rgba_);
}

void FrameRenderer::set_media_indirect(const Image& indirect) {
    media_indirect_rgba_.clear();
    if (indirect.pixels.empty()) return;
    if (indirect.width != width_ || indirect.height != height_)
        throw std::invalid_argument(
            "FrameRenderer::set_media_indirect: the image is not frame-sized");
    flip_to_rgba(
        indirect, [](int, int) { return 0.0f; }, media_indirect_rgba_);
    upload_rgba(media_indirect_texture_.get(), width_, height_, media_indirect_rgba_);
}

void FrameRenderer::set_specular_through_glass(const Image& specular,
                                               const std::vector<uint8_t>& covered) {
    glass_specular_rgba_.clear();
    if (specular.pixels.empty()) return;
    if (specular.width != width_ || specular.height != height_ ||
        covered.size() != size_t(width_) * size_t(height_))
        throw std::invalid_argument(
            "FrameRenderer::set_specular_through_glass: the image is not frame-sized");
    flip_to_rgba(
        specular,
        [&](int x, int y) { return covered[size_t(y) * size_t(width_) + size_t(x)] ? 1.0f : 0.0f; },
        glass_specular_rgba_);
    upload_rgba(glass_specular_texture_.get(), width_, height_, glass_specular_rgba_);
}

void FrameRenderer::draw_full_screen(const Program& program, const char* sampler, GLuint texture,
                                     const std::array<bool, kFrameTermCount>& terms) {
    gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    GLenum buffers[kFrameTermCount];
    for (size_t t = 0; t < kFrameTermCount; ++t)
        buffers[t] = terms[t] ? GLenum(GL_COLOR_ATTACHMENT0 + t) : GLenum(GL_NONE);
    gl::DrawBuffers(GLsizei(kFrameTermCount), buffers);
    gl::Viewport(0, 0, width_, height_);
    gl::Disable(GL_DEPTH_TEST);
    gl::Disable(GL_STENCIL_TEST);
    program.use();
    gl::ActiveTexture(GL_TEXTURE0);
    gl::BindTexture(GL_TEXTURE_2D, texture);
    program.set(sampler, 0);
    gl::BindVertexArray(empty_vao_.get());
    gl::DrawArrays(GL_TRIANGLES, 0, 3);
    gl::Enable(GL_DEPTH_TEST);
    for (size_t t = 0; t < kFrameTermCount; ++t) buffers[t] = GLenum(GL_COLOR_ATTACHMENT0 + t);
    gl::DrawBuffers(GLsizei(kFrameTermCount), buffers);
}

void FrameRenderer::compose() {
    // The G-buffer pass wrote a zero volume term; a media method's replaces it.
    if (!volume_rgba_.empty()) {
        upload_rgba(aov_[size_t(FrameTerm::volume)].get(), width_, height_, volume_rgba_);
    }
    // The light the fog scatters onto the surfaces, into the indirect term after the running
    // mean (it is the same every frame until the method runs again) and before the dimming.
    if (!media_indirect_rgba_.empty()) {
        gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
        GLenum buffers[kFrameTermCount];
        for (size_t t = 0; t < kFrameTermCount; ++t)
            buffers[t] = t == size_t(FrameTerm::indirect) ? GLenum(GL_COLOR_ATTACHMENT0 + t)
                                                          : GLenum(GL_NONE);
        gl::DrawBuffers(GLsizei(kFrameTermCount), buffers);
        gl::Viewport(0, 0, width_, height_);
        gl::Disable(GL_DEPTH_TEST);
        gl::Disable(GL_STENCIL_TEST);
        gl::Enable(GL_BLEND);
        gl::BlendEquation(GL_FUNC_ADD);
        gl::BlendFunc(GL_ONE, GL_ONE);  // dst + the fog's light
        add_indirect_.use();
        gl::ActiveTexture(GL_TEXTURE0);
        gl::BindTexture(GL_TEXTURE_2D, media_indirect_texture_.get());
        add_indirect_.set("media_indirect", 0);
        gl::BindVertexArray(empty_vao_.get());
        gl::DrawArrays(GL_TRIANGLES, 0, 3);
        gl::Disable(GL_BLEND);
        gl::Enable(GL_DEPTH_TEST);
        for (size_t t = 0; t < kFrameTermCount; ++t) buffers[t] = GLenum(GL_COLOR_ATTACHMENT0 + t);
        gl::DrawBuffers(GLsizei(kFrameTermCount), buffers);
    }
    // The surface's terms dimmed by the media in front of it, after the running mean (which
    // keeps them undimmed; the transmittance is the same every frame until the method runs
    // again); the volume term is not (it is what the media add on the way).
    if (!transmittance_rgba_.empty()) {
        std::array<bool, kFrameTermCount> terms;
        terms.fill(true);
        terms[size_t(FrameTerm::volume)] = false;
        gl::Enable(GL_BLEND);
        gl::BlendEquation(GL_FUNC_ADD);
        gl::BlendFuncSeparate(GL_ZERO, GL_SRC_COLOR, GL_ZERO, GL_ONE);  // dst × transmittance
        draw_full_screen(attenuate_, "transmittance", transmittance_texture_.get(), terms);
        gl::Disable(GL_BLEND);
    }
    // Where a media method traced what the camera sees through glass, its term replaces the
    // cube maps' (straight through both interfaces, no media), after the running mean: it is
    // the same every frame until the method runs again.
    if (!glass_specular_rgba_.empty()) {
        std::array<bool, kFrameTermCount> terms{};
        terms[size_t(FrameTerm::specular)] = true;
        gl::Disable(GL_BLEND);
        draw_full_screen(glass_specular_, "through_glass", glass_specular_texture_.get(), terms);
    }
    gl::BindFramebuffer(GL_FRAMEBUFFER, compose_fbo_.get());
    const GLenum draw = GL_COLOR_ATTACHMENT0;
    gl::DrawBuffers(1, &draw);
    gl::Viewport(0, 0, width_, height_);
    gl::Disable(GL_DEPTH_TEST);
    gl::Disable(GL_BLEND);
    compose_.use();
    for (FrameTerm t : kFrameTerms) {
        gl::ActiveTexture(GLenum(GL_TEXTURE0 + int(t)));
        gl::BindTexture(GL_TEXTURE_2D, aov_[size_t(t)].get());
        compose_.set(frame_term_name(t), int(t));
    }
    gl::BindVertexArray(empty_vao_.get());
    gl::DrawArrays(GL_TRIANGLES, 0, 3);
    gl::Enable(GL_DEPTH_TEST);
    gl::ActiveTexture(GL_TEXTURE0);
}

FrameImages FrameRenderer::read_back() const {
    auto to_image = [&](GLuint fbo, GLenum attachment) {
        const std::vector<float> rgba = read_rgba(fbo, attachment, 0, 0, width_, height_);
        Image img(width_, height_);
        for (int y = 0; y < height_; ++y)
            for (int x = 0; x < width_; ++x) {
                const float* p = &rgba[(size_t(height_ - 1 - y) * size_t(width_) + size_t(x)) *
                                       4];  // GL rows bottom-up
                img.set_rgb(x, y, {p[0], p[1], p[2]});
            }
        return img;
    };
    FrameImages out;
    out.frame = to_image(compose_fbo_.get(), GL_COLOR_ATTACHMENT0);
    for (size_t a = 0; a < aov_.size(); ++a)
        out.aov[a] = to_image(fbo_.get(), GLenum(GL_COLOR_ATTACHMENT0 + a));
    return out;
}

}  // namespace ag::gpu
