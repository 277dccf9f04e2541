#include "gpu/media_view.h"

#include <algorithm>
#include <string>

#include "gpu/media_ray_step.h"

namespace ag::gpu {

namespace {

const char* kViewCompute = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer Rays { vec4 rays[]; };  // in: direction, max distance; out: L
layout(std430, binding = 1) readonly buffer Optics { vec4 optics[]; };  // n, σ_s, σ_t, 0
layout(std430, binding = 2) readonly buffer Light { vec4 light[]; };    // fluence, flow
uniform int pixel_count;
uniform vec3 eye;
uniform ivec3 size;
uniform vec3 grid_min;
uniform vec3 voxel;
uniform float step;  // world units
uniform float phase_k;
uniform int max_steps;

const float kPi = 3.14159265358979;

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
    vec3 d = rays[id].xyz;
    float max_distance = rays[id].w;
    // Into the grid's box.
    vec3 grid_max = grid_min + vec3(size) * voxel;
    vec3 inv = 1.0 / d;
    vec3 ta = (grid_min - eye) * inv, tb = (grid_max - eye) * inv;
    float t0 = max(max(min(ta.x, tb.x), min(ta.y, tb.y)), max(min(ta.z, tb.z), 0.0));
    float t1 = min(min(max(ta.x, tb.x), max(ta.y, tb.y)), max(ta.z, tb.z));
    vec3 radiance = vec3(0.0);
    if (t0 < t1 && t0 < max_distance) {
        vec3 x = eye + t0 * d;
        vec3 g = clamp((x - grid_min) / voxel, vec3(1e-4), vec3(size) - 1e-4);
        float travelled = t0;
        float n = index_at(g);
        vec3 v = n * d;
        float transmittance = 1.0;
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
            float denom = 1.0 - phase_k * c;
            float phase = (1.0 - phase_k * phase_k) / (4.0 * kPi * denom * denom);
            // ∫ T σ_s p φ over the segment with σ constant: T (1 − e^{−σ_t ℓ}) / σ_t.
            float sigma_t = o.z;
            float through = sigma_t > 1e-6 ? (1.0 - exp(-sigma_t * seg)) / sigma_t : seg;
            radiance += vec3(transmittance * through * o.y * phase * l.x);
            transmittance *= exp(-sigma_t * seg);
            travelled += seg;
            if (travelled >= max_distance) break;
            x = x1;
            v = v1;
            n = n1;
            g = (x - grid_min) / voxel;
            if (any(lessThan(g, vec3(0.0))) || any(greaterThanEqual(g, vec3(size)))) break;
        }
    }
    rays[id] = vec4(radiance, 0.0);
}
)";

}  // namespace

MediaView::MediaView()
    : program_("media view march", std::string(kViewCompute) + kMediaRayStep + kViewMarch) {}

Image MediaView::render(const MediaGrid& grid, const std::vector<float>& fluence,
                        const std::vector<glm::vec3>& flow, const Camera& camera,
                        const MediaViewSettings& settings,
                        const std::vector<float>& max_distance) const {
    const size_t voxels = grid.voxel_count();
    const size_t pixels = size_t(camera.width) * size_t(camera.height);
    std::vector<glm::vec4> rays(pixels), optics(voxels), light(voxels);
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const size_t i = size_t(y) * size_t(camera.width) + size_t(x);
            rays[i] = glm::vec4(camera_ray_direction(camera, float(x) + 0.5f, float(y) + 0.5f),
                                max_distance.empty() ? 1e30f : max_distance[i]);
        }
    for (size_t i = 0; i < voxels; ++i) {
        optics[i] = glm::vec4(grid.n[i], grid.sigma_s[i], grid.sigma_t[i], 0.0f);
        light[i] = glm::vec4(fluence[i], flow[i]);
    }
    const auto upload = [](const std::vector<glm::vec4>& data, GLuint binding) {
        Buffer b = make_buffer();
        gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, b.get());
        gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(data.size() * sizeof(glm::vec4)),
                       data.data(), GL_DYNAMIC_COPY);
        gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, b.get());
        return b;
    };
    const Buffer ray_buffer = upload(rays, 0);
    const Buffer optics_buffer = upload(optics, 1);
    const Buffer light_buffer = upload(light, 2);
    const glm::vec3 voxel = grid.voxel_size();
    program_.use();
    program_.set("pixel_count", int(pixels));
    program_.set("eye", camera.eye);
    program_.set("size", grid.size);
    program_.set("grid_min", grid.bounds.min);
    program_.set("voxel", voxel);
    program_.set("step", settings.step * std::min({voxel.x, voxel.y, voxel.z}));
    program_.set("phase_k", settings.phase_k);
    program_.set("max_steps",
                 int(4.0f * float(grid.size.x + grid.size.y + grid.size.z) / settings.step));
    gl::DispatchCompute(GLuint((pixels + 63) / 64), 1, 1);
    gl::MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, ray_buffer.get());
    gl::GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(pixels * sizeof(glm::vec4)),
                         rays.data());
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    check_gl("MediaView::render");
    Image image(camera.width, camera.height);
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x)
            image.set_rgb(x, y, glm::vec3(rays[size_t(y) * size_t(camera.width) + size_t(x)]));
    return image;
}

}  // namespace ag::gpu
