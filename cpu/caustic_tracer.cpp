#include "cpu/caustic_tracer.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "cpu/media_tracking.h"
#include "cpu/sampling.h"
#include "shared/qmc.h"

namespace ag::cpu {

namespace {
constexpr int kMaxSpecularBounces = 12;

}  // namespace

CausticTracer::CausticTracer(const Scene& scene, ThreadPool& pool) : scene_(scene), pool_(pool) {
    rays_ = std::make_unique<RayTracer>(scene_);
    photons_.assign(scene_.lights.size() * size_t(scene_.settings.caustics.photons),
                    CausticPhoton{});
    for (size_t l = 0; l < scene_.lights.size(); ++l)
        halton_.emplace_back(5 + kMaxSpecularBounces,
                             hash_u32(scene_.settings.seed * 31337u + uint32_t(l)) | 1u);
}

namespace {

// An object's bounding sphere in world space (rigid transforms keep the radius).
void bounding_sphere(const Object& obj, glm::vec3& centre, float& radius) {
    const glm::vec3 c_local = mesh_bounds(obj.mesh).center();
    radius = 0.0f;
    for (const glm::vec3& p : obj.mesh.positions)
        radius = std::max(radius, glm::length(p - c_local));
    centre = obj.transform.apply_point(c_local);
}

}  // namespace

std::vector<CausticTracer::Cone> CausticTracer::cones(const glm::vec3& from) const {
    std::vector<Cone> out;
    for (int o = 0; o < int(scene_.objects.size()); ++o) {
        const Object& obj = scene_.objects[size_t(o)];
        if (obj.material.type == MaterialType::diffuse) continue;
        glm::vec3 c;
        float r = 0.0f;
        bounding_sphere(obj, c, r);
        const float d = glm::length(c - from);
        if (d <= r * 1.0001f) continue;  // the light is inside the bound: no cone (documented)
        const double sin_a = double(r) / double(d),
                     cos_a = std::sqrt(std::max(0.0, 1.0 - sin_a * sin_a));
        const double one_minus_cos = sin_a * sin_a / (1.0 + cos_a);  // no cancellation
        out.push_back({o, c, one_minus_cos, float(2.0 * std::numbers::pi * one_minus_cos)});
    }
    return out;
}

std::vector<CausticTracer::Cone> CausticTracer::discs() const {
    std::vector<Cone> out;
    for (int o = 0; o < int(scene_.objects.size()); ++o) {
        const Object& obj = scene_.objects[size_t(o)];
        if (obj.material.type == MaterialType::diffuse) continue;
        glm::vec3 c;
        float r = 0.0f;
        bounding_sphere(obj, c, r);
        out.push_back({o, c, double(r), std::numbers::pi_v<float> * r * r});
    }
    return out;
}

CausticPhoton CausticTracer::trace_photon(int light, int index, const std::vector<Cone>& cone_cache,
                                          const MediaTracker& media, bool& hit_specular) const {
    hit_specular = false;
    const Light& l = scene_.lights[size_t(light)];
    if (!l.enabled) return {};
    const glm::vec3 centre = l.center();
    if (cone_cache.empty()) return {};
    const Halton& halton = halton_[size_t(light)];
    const uint64_t k = uint64_t(index);

    // Pick a cone in proportion to its solid angle, then a direction uniformly inside it.
    float total = 0.0f;
    for (const Cone& c : cone_cache) total += c.solid_angle;
    float pick = float(halton.sample(k, 0)) * total;
    const Cone* cone = &cone_cache.back();
    for (const Cone& c : cone_cache) {
        if (pick < c.solid_angle) {
            cone = &c;
            break;
        }
        pick -= c.solid_angle;
    }
    Ray ray;
    ray.origin = centre;
    glm::vec3 power;
    const int n = scene_.settings.caustics.photons;
    glm::vec3 light_normal(0.0f);
    if (l.type == LightType::sun) {
        // Parallel light: a point uniform on the chosen disc across the sun's direction, started
        // outside the scene. Discs that overlap there share the photon (density / their count).
        glm::vec3 u, v;
        orthonormal_basis(l.direction, u, v);
        const float radius = float(std::sqrt(halton.sample(k, 1))) * float(cone->one_minus_cos);
        const float phi = 2.0f * std::numbers::pi_v<float> * float(halton.sample(k, 2));
        const glm::vec3 p = cone->centre + radius * (std::cos(phi) * u + std::sin(phi) * v);
        int containing = 0;
        for (const Cone& c : cone_cache) {
            const glm::vec3 d = p - c.centre;
            const glm::vec3 across = d - glm::dot(d, l.direction) * l.direction;
            containing += glm::dot(across, across) <= float(c.one_minus_cos * c.one_minus_cos);
        }
        ray.origin =
            p - (glm::dot(p - l.sun_center, l.direction) + 1.01f * l.sun_radius) * l.direction;
        ray.direction = l.direction;
        power = l.irradiance * total / float(std::max(containing, 1)) / float(n);
    } else {
        if (l.is_area()) {
            const LightPoint at = sample_area_light(scene_, l, float(halton.sample(k, 3)),
                                                    float(halton.sample(k, 4)));
            light_normal = at.normal;
            ray.origin = at.position + rays_->epsilon() * at.normal;
        }
        const glm::vec3 axis = glm::normalize(cone->centre - ray.origin);
        // Uniform in the cone's solid angle: 1 − cosθ = u (1 − cos α); sinθ from it without
        // cancellation.
        const double x = halton.sample(k, 1) * cone->one_minus_cos;
        const float cos_t = float(1.0 - x), sin_t = float(std::sqrt(std::max(0.0, x * (2.0 - x))));
        const float phi = 2.0f * std::numbers::pi_v<float> * float(halton.sample(k, 2));
        glm::vec3 u, v;
        orthonormal_basis(axis, u, v);
        ray.direction =
            glm::normalize(cos_t * axis + sin_t * (std::cos(phi) * u + std::sin(phi) * v));
        if (l.type == LightType::point || l.type == LightType::spot) {
            // The flux into all cones, shared by n photons (a spot's by its falloff).
            power = l.intensity * l.spot_factor(glm::dot(ray.direction, l.direction)) * total /
                    float(n);
        } else {
            const float cos_l = glm::dot(light_normal, ray.direction);
            if (cos_l <= 0.0f) return {};
            power = l.radiance * l.area() * cos_l * total / float(n);
        }
    }

    const float eps = rays_->epsilon();
    bool specular_seen = false;
    int inside = -1;  // the glass object the photon is in (its interior medium), or none
    // Ratio tracking's numbers in perturbed media (closed form in homogeneous ones).
    HashedStream more(mix64((uint64_t(light) << 32) ^ k ^ (uint64_t(scene_.settings.seed) << 48)));
    for (int bounce = 0; bounce <= kMaxSpecularBounces; ++bounce) {
        ray.tmin = 0.0f;
        ray.tmax = 1e30f;
        const RayHit hit = rays_->intersect(ray);
        if (!hit.hit) return {};
        // Beer–Lambert along the segment through the media it crosses (Pfeuti's surface caustic
        // seen through fog; the glass's interior medium inside it).
        if (!media.empty()) {
            power *= media.transmittance(ray, hit.t, inside, more);
            if (power == glm::vec3(0.0f)) return {};
        }
        const Material& m = scene_.objects[size_t(hit.object)].material;
        const bool front = glm::dot(ray.direction, hit.normal) < 0.0f;
        const glm::vec3 facing = front ? hit.normal : -hit.normal;
        if (m.type == MaterialType::diffuse) {
            if (!specular_seen || !front) return {};  // not an L S+ D path, or a back face
            return CausticPhoton{hit.position, power, facing, frame_};
        }
        if (bounce == 0) hit_specular = true;
        specular_seen = true;
        const float fresnel_u =
            m.type == MaterialType::glass
                ? float(halton.sample(k, 5 + std::min(bounce, kMaxSpecularBounces - 1)))
                : 0.0f;
        const glm::vec3 before = ray.direction;
        ray = specular_bounce(m, hit, ray.direction, fresnel_u, eps);
        // Through the surface (the same side of it as before): into or out of the glass.
        if (m.type == MaterialType::glass &&
            (glm::dot(ray.direction, hit.normal) < 0.0f) == (glm::dot(before, hit.normal) < 0.0f))
            inside = front ? hit.object : -1;
    }
    return {};
}

CausticStats CausticTracer::trace_slice(int slice, int slices) {
    rays_->update(scene_);
    const int n = scene_.settings.caustics.photons;
    std::vector<int> jobs;  // global slot = light * n + index
    for (int l = 0; l < int(scene_.lights.size()); ++l)
        for (int i = slice; i < n; i += slices) jobs.push_back(l * n + i);
    std::vector<std::vector<Cone>> light_cones;  // the specular objects as seen from each light now
    for (const Light& l : scene_.lights)
        light_cones.push_back(l.type == LightType::sun ? discs() : cones(l.center()));
    std::vector<char> specular(jobs.size(), 0);
    const MediaTracker media(scene_);
    pool_.parallel_for(
        jobs.size(),
        [&](size_t j) {
            bool hit = false;
            const int light = jobs[j] / n;
            photons_[size_t(jobs[j])] =
                trace_photon(light, jobs[j] % n, light_cones[size_t(light)], media, hit);
            specular[j] = hit;
        },
        64);
    CausticStats stats;
    stats.traced = int(jobs.size());
    for (size_t j = 0; j < jobs.size(); ++j) {
        stats.hit_specular += specular[j];
        stats.stored += photons_[size_t(jobs[j])].power != glm::vec3(0.0f) ? 1 : 0;
    }
    return stats;
}

CausticStats CausticTracer::frame() {
    ++frame_;
    const int slices = scene_.settings.caustics.frames;
    return trace_slice(int((frame_ - 1) % uint32_t(slices)), slices);
}

CausticStats CausticTracer::trace_all() {
    ++frame_;
    return trace_slice(0, 1);
}

}  // namespace ag::cpu
