#include "cpu/reference/light_tracer.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "cpu/media_tracking.h"
#include "shared/metrics.h"

namespace ag::cpu {

namespace {

constexpr uint64_t kChunk = 4096;  // light paths per work item
constexpr int kEmitDims = 5;       // cone choice, direction in it, point on an area light
constexpr int kQmcBounces = 16;    // bounces with Halton numbers (3 each), hashed after
constexpr uint64_t kLightKey = 0x6c62272e07bb0142ull;

bool is_delta(const Light& l) {
    return l.type == LightType::point || l.type == LightType::spot || l.type == LightType::sun;
}

}  // namespace

std::vector<BoundingSphere> specular_bounding_spheres(const Scene& scene) {
    std::vector<BoundingSphere> out;
    for (const Object& o : scene.objects) {
        if (o.material.type == MaterialType::diffuse || o.mesh.positions.empty()) continue;
        Bounds b;
        for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
        BoundingSphere s{b.center(), 0.0f};
        for (const glm::vec3& p : o.mesh.positions)
            s.radius = std::max(s.radius, glm::length(o.transform.apply_point(p) - s.center));
        s.radius *= 1.0f + 1e-4f;
        out.push_back(s);
    }
    return out;
}

AimedRay aimed_emission(const Scene& scene, const Light& l,
                        const std::vector<BoundingSphere>& bounds, const float u[5],
                        float epsilon) {
    AimedRay out;
    if (bounds.empty()) return out;
    if (l.type == LightType::sun) {
        // Parallel light: the union of the bounding spheres' discs across the sun's direction; a
        // point uniform on a disc picked by area, the density divided by the discs containing it
        // (overlaps count once), started outside the scene.
        glm::vec3 a, b;
        orthonormal_basis(l.direction, a, b);
        float area = 0.0f;
        thread_local std::vector<float> cumulative;
        cumulative.resize(bounds.size());
        for (size_t k = 0; k < bounds.size(); ++k) {
            area += std::numbers::pi_v<float> * bounds[k].radius * bounds[k].radius;
            cumulative[k] = area;
        }
        if (!(area > 0.0f)) return out;
        const float pick = u[0] * area;
        size_t chosen = 0;
        while (chosen + 1 < cumulative.size() && pick >= cumulative[chosen]) ++chosen;
        const BoundingSphere& s = bounds[chosen];
        const float r = s.radius * std::sqrt(u[1]);
        const float phi = 2.0f * std::numbers::pi_v<float> * u[2];
        const glm::vec3 p = s.center + r * (std::cos(phi) * a + std::sin(phi) * b);
        int containing = 0;
        for (const BoundingSphere& c : bounds) {
            const glm::vec3 d = p - c.center;
            const glm::vec3 across = d - glm::dot(d, l.direction) * l.direction;
            containing += glm::dot(across, across) <= c.radius * c.radius ? 1 : 0;
        }
        const glm::vec3 origin =
            p - (glm::dot(p - l.sun_center, l.direction) + 1.01f * l.sun_radius) * l.direction;
        out.ray = {origin, l.direction};
        out.power = l.irradiance * area / float(std::max(containing, 1));
        out.valid = true;
        return out;
    }
    glm::vec3 origin = l.position, nl(0.0f);
    if (l.is_area()) {
        const LightPoint at = sample_area_light(scene, l, u[3], u[4]);
        nl = at.normal;
        origin = at.position + epsilon * nl;
    }
    // Directions from the union of the cones around the bounding spheres: a cone by solid angle,
    // then uniform inside it; the density is (cones containing the direction) / ΣΩ.
    thread_local std::vector<glm::vec3> axis;
    thread_local std::vector<float> cos_max, cumulative;
    axis.resize(bounds.size());
    cos_max.resize(bounds.size());
    cumulative.resize(bounds.size());
    float total = 0.0f;
    for (size_t k = 0; k < bounds.size(); ++k) {
        const glm::vec3 to = bounds[k].center - origin;
        const float d = glm::length(to), r = bounds[k].radius;
        axis[k] = d > 0.0f ? to / d : glm::vec3(0.0f, 0.0f, 1.0f);
        cos_max[k] = d <= r ? -1.0f : std::sqrt(std::max(0.0f, 1.0f - (r * r) / (d * d)));
        total += 2.0f * std::numbers::pi_v<float> * (1.0f - cos_max[k]);
        cumulative[k] = total;
    }
    const float pick = u[0] * total;
    size_t chosen = 0;
    while (chosen + 1 < cumulative.size() && pick >= cumulative[chosen]) ++chosen;
    const glm::vec3 dir = cone_direction(axis[chosen], cos_max[chosen], u[1], u[2]);
    int containing = 0;
    for (size_t k = 0; k < axis.size(); ++k)
        containing += glm::dot(dir, axis[k]) >= cos_max[k] ? 1 : 0;
    const float inv_pdf = total / float(std::max(containing, 1));
    if (l.type == LightType::point || l.type == LightType::spot) {
        out.power = l.intensity * l.spot_factor(glm::dot(dir, l.direction)) * inv_pdf;
    } else {
        // dΦ = L cos θ dω dA; the point is uniform on the quad (pdf 1/A).
        const float cos_l = glm::dot(dir, nl);
        if (!(cos_l > 0.0f)) return out;
        out.power = l.radiance * cos_l * l.area() * inv_pdf;
    }
    out.ray = {origin, dir};
    out.valid = true;
    return out;
}

LightTracer::LightTracer(const Scene& scene, const RayTracer& rays,
                         const ReferenceSettings& settings, const PixelRegion& region)
    : scene_(scene),
      rays_(rays),
      seed_(settings.seed),
      max_depth_(std::max(1, settings.max_depth)),
      indirect_bounces_(settings.indirect_bounces),
      region_(region),
      bounds_(specular_bounding_spheres(scene)),
      halton_(kEmitDims + 3 * kQmcBounces, hash_u32(settings.seed + 0x78dde6e4u) | 1u) {
    const Camera& camera = scene.camera;
    forward_ = glm::normalize(camera.target - camera.eye);
    right_ = glm::normalize(glm::cross(forward_, camera.up));
    up_ = glm::cross(right_, forward_);
    tan_half_ = std::tan(glm::radians(camera.fov_y) * 0.5f);
    aspect_ = float(camera.width) / float(camera.height);
    const float pixel = 2.0f * tan_half_ / float(camera.height);  // square pixels
    pixel_area_ = pixel * pixel;

    std::vector<double> power(scene.lights.size(), 0.0);
    double sum = 0.0;
    for (size_t l = 0; l < scene.lights.size(); ++l) {
        const Light& light = scene.lights[l];
        if (!light.enabled || !is_delta(light)) continue;
        power[l] = std::max(0.0f, luminance(light.power()));
        sum += power[l];
    }
    if (!settings.light_tracing)
        skipped_ = "turned off";
    else if (settings.method != ReferenceMethod::path_tracing)
        skipped_ = "not path tracing";
    else if (!(sum > 0.0))
        skipped_ = "no point, spot or sun light";
    else if (bounds_.empty())
        skipped_ = "no mirror or glass";
    else if (has_media(scene))
        skipped_ =
            "participating media (light through mirrors and glass into media is not "
            "traced)";
    if (!skipped_.empty()) return;

    // Paths per pass: by default one per pixel of the whole image (not of the region: a tile's
    // splats must be the whole image's, so that tiles merge into it exactly).
    paths_per_pass_ = settings.light_paths > 0 ? uint64_t(settings.light_paths)
                                               : uint64_t(camera.width) * uint64_t(camera.height);
    uint64_t traced = 0;
    for (size_t l = 0; l < scene.lights.size(); ++l) {
        if (!(power[l] > 0.0)) continue;
        const uint64_t n =
            std::max<uint64_t>(1, uint64_t(std::llround(double(paths_per_pass_) * power[l] / sum)));
        for (uint64_t first = 0; first < n; first += kChunk)
            chunks_.push_back({int(l), first, std::min(kChunk, n - first), n});
        traced += n;
    }
    paths_per_pass_ = traced;  // after rounding per light
}

void LightTracer::connect(const glm::vec3& p, const glm::vec3& n, const glm::vec3& f_power,
                          FrameTerm term, std::vector<LightSplat>& out) const {
    // The pixel the camera sees p in, and the pixel value the path adds: the box-filtered pixel
    // is (1/A_pix) ∫ L dA_plane over the image plane at distance 1, and dA_plane =
    // cosθ_p dA / (d² cos³θ_cam), so a flux Φ arriving at p adds f Φ cosθ_p / (d² cos³θ_cam A_pix).
    const glm::vec3 v = p - scene_.camera.eye;
    const float z = glm::dot(v, forward_);
    if (!(z > 0.0f)) return;
    const float sx = glm::dot(v, right_) / z, sy = glm::dot(v, up_) / z;
    const float px = (sx / (tan_half_ * aspect_) + 1.0f) * 0.5f * float(scene_.camera.width);
    const float py = (1.0f - sy / tan_half_) * 0.5f * float(scene_.camera.height);
    if (!(px >= 0.0f) || !(py >= 0.0f)) return;
    const int ix = int(px) - region_.x, iy = int(py) - region_.y;
    if (ix < 0 || iy < 0 || ix >= region_.width || iy >= region_.height) return;
    const float d2 = glm::dot(v, v), d = std::sqrt(d2);
    const glm::vec3 to_eye = -v / d;
    const float cos_p = glm::dot(n, to_eye);
    if (!(cos_p > 0.0f)) return;
    const float cos_cam = z / d;
    const float eps = rays_.epsilon();
    if (rays_.occluded({p + eps * n, to_eye, 0.0f, d * (1.0f - 1e-5f)})) return;
    const float w = cos_p / (d2 * cos_cam * cos_cam * cos_cam * pixel_area_);
    out.push_back({uint32_t(iy) * uint32_t(region_.width) + uint32_t(ix), term, f_power * w});
}

void LightTracer::trace(int pass, size_t chunk, std::vector<LightSplat>& out) const {
    const Chunk& c = chunks_[chunk];
    const Light& light = scene_.lights[size_t(c.light)];
    const uint64_t key = mix64(uint64_t(seed_) * 0x100000001b3ull + uint64_t(c.light) + kLightKey);
    const float eps = rays_.epsilon();
    const float inv_count = 1.0f / float(c.per_pass);
    for (uint64_t i = c.first; i < c.first + c.count; ++i) {
        const Sampler s(halton_, key, uint64_t(pass) * c.per_pass + i);
        const float u[5] = {s.get(0), s.get(1), s.get(2), s.get(3), s.get(4)};
        const AimedRay a = aimed_emission(scene_, light, bounds_, u, eps);
        if (!a.valid) continue;
        Ray ray = a.ray;
        glm::vec3 power = a.power * inv_count;
        bool specular_seen = false;
        int diffuse_vertices = 0;  // diffuse vertices before the current one
        int dim = kEmitDims;
        for (int bounce = 0; bounce < max_depth_; ++bounce, dim += 3) {
            const RayHit hit = rays_.intersect(ray);
            if (!hit.hit) break;
            const Material& m = scene_.objects[size_t(hit.object)].material;
            if (m.type != MaterialType::diffuse) {
                specular_seen = true;
                ray = specular_bounce(m, hit, ray.direction, s.get(dim), eps);
                continue;
            }
            // The light's first segment ends on a diffuse surface: next-event estimation finds
            // that path and all that follow it.
            if (!specular_seen) break;
            if (glm::dot(ray.direction, hit.normal) >= 0.0f) break;  // back faces absorb
            if (indirect_bounces_ >= 0 && diffuse_vertices > indirect_bounces_) break;
            const glm::vec3 albedo =
                albedo_at(scene_.objects[size_t(hit.object)], hit.triangle, hit.barycentric);
            connect(hit.position, hit.normal, power * albedo / std::numbers::pi_v<float>,
                    diffuse_vertices == 0 ? FrameTerm::caustics : FrameTerm::indirect, out);
            ++diffuse_vertices;
            if (indirect_bounces_ >= 0 && diffuse_vertices > indirect_bounces_) break;
            // Russian roulette by albedo, as the photon tracer: survive with p = max ρ, carry ρ/p.
            const float p = std::min(1.0f, std::max({albedo.x, albedo.y, albedo.z}));
            if (!(p > 0.0f) || s.get(dim) >= p) break;
            power *= albedo / p;
            ray = {hit.position + eps * hit.normal,
                   cosine_direction(hit.normal, s.get(dim + 1), s.get(dim + 2))};
        }
    }
}

}  // namespace ag::cpu
