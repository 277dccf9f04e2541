#include "gpu/media_view.h"

#include <algorithm>
#include <string>

#include "gpu/media_ray_step.h"
#include "shared/media.h"

namespace ag::gpu {

namespace {

const char* kViewCompute = R"(
layout(local_size_x = 64) in;
// Per ray, three vec4. In: origin, max distance; direction, split; n_leave, 0, 0, 0.
// Out: radiance, transmittance; end point, ended (1: left the glass or the grid); n v at the end.
layout(std430, binding = 0) buffer Rays { vec4 rays[]; };
layout(std430, binding = 1) readonly buffer Optics { vec4 optics[]; };  // n, σ_s, σ_t, 0
layout(std430, binding = 2) readonly buffer Light { vec4 light[]; };    // fluence, flow
uniform int pixel_count;
uniform ivec3 size;
uniform vec3 grid_min;
uniform vec3 voxel;
uniform float step;  // world units
uniform int max_steps;
// Schlick k for the spread of the photons' directions (schlick_spread_table): entry i at
// R = 1 − (i / (kSpreadEntries − 1))²; entry 0 alone without the spread (his phase).
const int kSpreadEntries = SPREAD_ENTRIES;
uniform float spread_k[kSpreadEntries];
uniform int use_spread;

const float kPi = 3.14159265358979;

// The phase's k for light of mean resultant length r (|flow| / fluence).
float phase_k_for(float r) {
    if (use_spread == 0) return spread_k[0];
    float s = sqrt(clamp(1.0 - r, 0.0, 1.0)) * float(kSpreadEntries - 1);
    int i = min(int(s), kSpreadEntries - 2);
    return mix(spread_k[i], spread_k[i + 1], s - float(i));
}

int cell_index(ivec3 c) { return (c.z * size.y + c.y) * size.x + c.x; }

// Trilinear reads, voxel centres at i + 0.5, clamped at the border (his grids are 3D textures).
vec4 tri_optics(vec3 g) {
    vec3 p = g - 0.5;
    ivec3 i0 = ivec3(floor(p));
    vec3 f = p - vec3(i0);
    vec4 r = vec4(0.0);
    for (int k = 0; k < 8; ++k) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        vec3 w = mix(1.0 - f, f, vec3(o));
        r += w.x * w.y * w.z * optics[cell_index(clamp(i0 + o, ivec3(0), size - 1))];
    }
    return r;
}
vec4 tri_light(vec3 g) {
    vec3 p = g - 0.5;
    ivec3 i0 = ivec3(floor(p));
    vec3 f = p - vec3(i0);
    vec4 r = vec4(0.0);
    for (int k = 0; k < 8; ++k) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        vec3 w = mix(1.0 - f, f, vec3(o));
        r += w.x * w.y * w.z * light[cell_index(clamp(i0 + o, ivec3(0), size - 1))];
    }
    return r;
}
float index_at(vec3 g) { return tri_optics(g).x; }
vec3 index_gradient(vec3 g) {
    vec3 d;
    d.x = index_at(g + vec3(0.5, 0, 0)) - index_at(g - vec3(0.5, 0, 0));
    d.y = index_at(g + vec3(0, 0.5, 0)) - index_at(g - vec3(0, 0.5, 0));
    d.z = index_at(g + vec3(0, 0, 0.5)) - index_at(g - vec3(0, 0, 0.5));
    return d / voxel;
}
)";

// The ray step (gpu/media_ray_step.h) comes between the two halves.
const char* kViewMarch = R"(

void main() {
    int id = int(gl_GlobalInvocationID.x);
    if (id >= pixel_count) return;
    vec3 eye = rays[3 * id].xyz;
    float max_distance = rays[3 * id].w;
    vec3 d = rays[3 * id + 1].xyz;
    // Light scattered before `split` along the ray is not counted (it is another term's), its
    // extinction is.
    float split = rays[3 * id + 1].w;
    // > 0: end where the ray, having reached an index of n_leave (inside the glass), is back
    // in air (n = 1 beyond the smoothed border): where it leaves the object bent.
    float n_leave = rays[3 * id + 2].x;
    // Into the grid's box.
    vec3 grid_max = grid_min + vec3(size) * voxel;
    vec3 inv = 1.0 / d;
    vec3 ta = (grid_min - eye) * inv, tb = (grid_max - eye) * inv;
    float t0 = max(max(min(ta.x, tb.x), min(ta.y, tb.y)), max(min(ta.z, tb.z), 0.0));
    float t1 = min(min(max(ta.x, tb.x), max(ta.y, tb.y)), max(ta.z, tb.z));
    vec3 radiance = vec3(0.0);
    float transmittance = 1.0;
    vec3 x = eye;
    vec3 v = d;
    float ended = 0.0;
    if (t0 < t1 && t0 < max_distance) {
        x = eye + t0 * d;
        vec3 g = clamp((x - grid_min) / voxel, vec3(1e-4), vec3(size) - 1e-4);
        float travelled = t0;
        float n = index_at(g);
        v = n * d;
        bool in_glass = false;
        for (int i = 0; i < max_steps; ++i) {
            vec3 x1 = x, v1 = v;
            float n1 = n;
            ray_step(x1, v1, n1, step);  // eqs. 2.10/2.11
            float seg = length(x1 - x);
            vec3 along = (x1 - x) / seg;
            if (travelled + seg > max_distance) {
                seg = max_distance - travelled;
                x1 = x + seg * along;
            }
            vec3 gm = 0.5 * (g + (x1 - grid_min) / voxel);
            vec4 o = tri_optics(gm);
            vec4 l = tri_light(gm);
            float flow_length = length(l.yzw);
            float c = flow_length > 0.0 ? dot(l.yzw / flow_length, -along) : 0.0;
            float phase_k = phase_k_for(l.x > 0.0 ? flow_length / l.x : 1.0);
            float denom = 1.0 - phase_k * c;
            float phase = (1.0 - phase_k * phase_k) / (4.0 * kPi * denom * denom);
            // ∫ T σ_s p φ over the segment with σ constant: T (1 − e^{−σ_t ℓ}) / σ_t.
            float sigma_t = o.z;
            float before = clamp(split - travelled, 0.0, seg);  // the part before the split
            float counted = seg - before;
            float through =
                sigma_t > 1e-6 ? (1.0 - exp(-sigma_t * counted)) / sigma_t : counted;
            radiance += vec3(transmittance * exp(-sigma_t * before) * through * o.y * phase * l.x);
            transmittance *= exp(-sigma_t * seg);
            travelled += seg;
            if (travelled >= max_distance) break;
            x = x1;
            v = v1;
            n = n1;
            g = (x - grid_min) / voxel;
            if (any(lessThan(g, vec3(0.0))) || any(greaterThanEqual(g, vec3(size)))) {
                ended = 1.0;
                break;
            }
            if (n_leave > 0.0) {
                in_glass = in_glass || n >= n_leave;
                if (in_glass && n < 1.0 + 1e-5) {
                    ended = 1.0;
                    break;
                }
            }
        }
    }
    rays[3 * id] = vec4(radiance, transmittance);
    rays[3 * id + 1] = vec4(x, ended);
    rays[3 * id + 2] = vec4(v, 0.0);
}
)";

}  // namespace

namespace {
constexpr int kSpreadEntries = 129;
}  // namespace

MediaView::MediaView()
    : program_("media view march", "#define SPREAD_ENTRIES " + std::to_string(kSpreadEntries) +
                                       "\n" + kViewCompute + kMediaRayStep + kViewMarch) {}

std::vector<MediaViewEnd> MediaView::march(const MediaGrid& grid, const std::vector<float>& fluence,
                                           const std::vector<glm::vec3>& flow,
                                           const std::vector<MediaViewRay>& rays,
                                           const MediaViewSettings& settings) const {
    const size_t voxels = grid.voxel_count();
    std::vector<glm::vec4> data(3 * rays.size()), optics(voxels), light(voxels);
    for (size_t i = 0; i < rays.size(); ++i) {
        data[3 * i] = glm::vec4(rays[i].origin, rays[i].max_distance);
        data[3 * i + 1] = glm::vec4(rays[i].direction, rays[i].split);
        data[3 * i + 2] = glm::vec4(rays[i].n_leave, 0.0f, 0.0f, 0.0f);
    }
    std::vector<MediaViewEnd> out(rays.size());
    if (rays.empty()) return out;
    for (size_t i = 0; i < voxels; ++i) {
        optics[i] = glm::vec4(grid.n[i], grid.sigma_s[i], grid.sigma_t[i], 0.0f);
        light[i] = glm::vec4(fluence[i], flow[i]);
    }
    const auto upload = [](const std::vector<glm::vec4>& values, GLuint binding) {
        Buffer b = make_buffer();
        gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, b.get());
        gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(values.size() * sizeof(glm::vec4)),
                       values.data(), GL_DYNAMIC_COPY);
        gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, b.get());
        return b;
    };
    const Buffer ray_buffer = upload(data, 0);
    const Buffer optics_buffer = upload(optics, 1);
    const Buffer light_buffer = upload(light, 2);
    const glm::vec3 voxel = grid.voxel_size();
    program_.use();
    program_.set("pixel_count", int(rays.size()));
    program_.set("size", grid.size);
    program_.set("grid_min", grid.bounds.min);
    program_.set("voxel", voxel);
    program_.set("step", settings.step * std::min({voxel.x, voxel.y, voxel.z}));
    const std::vector<float> spread = schlick_spread_table(settings.phase_k, kSpreadEntries);
    gl::Uniform1fv(program_.location("spread_k"), kSpreadEntries, spread.data());
    program_.set("use_spread", settings.phase_spread ? 1 : 0);
    program_.set("max_steps",
                 int(4.0f * float(grid.size.x + grid.size.y + grid.size.z) / settings.step));
    gl::DispatchCompute(GLuint((rays.size() + 63) / 64), 1, 1);
    gl::MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, ray_buffer.get());
    gl::GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(data.size() * sizeof(glm::vec4)),
                         data.data());
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    check_gl("MediaView::march");
    for (size_t i = 0; i < rays.size(); ++i) {
        out[i].radiance = glm::vec3(data[3 * i]);
        out[i].transmittance = data[3 * i].w;
        out[i].position = glm::vec3(data[3 * i + 1]);
        out[i].ended = data[3 * i + 1].w > 0.5f;
        out[i].direction = glm::normalize(glm::vec3(data[3 * i + 2]));
    }
    return out;
}

Image MediaView::render(const MediaGrid& grid, const std::vector<float>& fluence,
                        const std::vector<glm::vec3>& flow, const Camera& camera,
                        const MediaViewSettings& settings,
                        const std::vector<float>& max_distance) const {
    const size_t pixels = size_t(camera.width) * size_t(camera.height);
    std::vector<MediaViewRay> rays(pixels);
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const size_t i = size_t(y) * size_t(camera.width) + size_t(x);
            rays[i].origin = camera.eye;
            rays[i].direction = camera_ray_direction(camera, float(x) + 0.5f, float(y) + 0.5f);
            rays[i].max_distance = max_distance.empty() ? 1e30f : max_distance[i];
        }
    const std::vector<MediaViewEnd> ends = march(grid, fluence, flow, rays, settings);
    Image image(camera.width, camera.height);
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x)
            image.set_rgb(x, y, ends[size_t(y) * size_t(camera.width) + size_t(x)].radiance);
    return image;
}

}  // namespace ag::gpu
