#include "cpu/photon_tracer.h"

#include <algorithm>
#include <cmath>

#include "cpu/sampling.h"

namespace ag::cpu {

namespace {

constexpr int kQmcBounces = 16;
// Per photon: the 2D emission point, then Halton dimensions 1.. (quad position, two bounces).
constexpr int kTabulated = 1 + 2 + 3 * 2 + 1;

}  // namespace

glm::vec2 hilbert_point(double t) {
    constexpr int kOrder = 16;
    constexpr uint32_t kSide = 1u << kOrder;
    const double scaled = std::clamp(t, 0.0, 1.0) * double(uint64_t(kSide) * kSide);
    uint64_t d = std::min<uint64_t>(uint64_t(scaled), uint64_t(kSide) * kSide - 1);
    uint32_t x = 0, y = 0;
    for (uint32_t s = 1; s < kSide; s <<= 1) {  // Hilbert index -> cell (classic d2xy)
        const uint32_t rx = 1u & uint32_t(d / 2), ry = 1u & uint32_t(d ^ rx);
        if (ry == 0) {
            if (rx == 1) {
                x = s - 1 - x;
                y = s - 1 - y;
            }
            std::swap(x, y);
        }
        x += s * rx;
        y += s * ry;
        d /= 4;
    }
    return {(float(x) + 0.5f) / float(kSide), (float(y) + 0.5f) / float(kSide)};
}

PhotonTracer::PhotonTracer(const Scene& scene, const RayTracer& rays) : scene_(scene), rays_(rays) {
    refresh();
}

void PhotonTracer::refresh() {
    const PhotonSettings& s = scene_.settings.photons;
    groups_ = s.groups;
    per_group_ = s.photons_per_group;
    max_bounces_ = s.max_bounces;
    media_ = std::make_unique<MediaTracker>(scene_);
    // Halton dimensions for emission and the first bounces; deeper bounces (rare after Russian
    // roulette, and their stratification no longer matters) use hashed numbers.
    dimensions_ = 3 + 3 * std::min(max_bounces_, kQmcBounces);
    const size_t table_size = size_t(groups_) * size_t(per_group_) * kTabulated;
    if (halton_.size() != scene_.lights.size() ||
        (!halton_.empty() && halton_[0].dimensions() != dimensions_) ||
        (!tables_.empty() && tables_[0].size() != table_size)) {
        halton_.clear();
        tables_.clear();
        for (size_t l = 0; l < scene_.lights.size(); ++l) {
            halton_.emplace_back(dimensions_,
                                 hash_u32(scene_.settings.seed * 7919u + uint32_t(l)) | 1u);
            // Every photon is re-traced again and again with the same numbers: tabulate the
            // emission point and the first bounces' numbers once (a light's photons are fixed).
            const Halton& h = halton_.back();
            std::vector<float> table(table_size);
            for (int g = 0; g < groups_; ++g)
                for (int i = 0; i < per_group_; ++i) {
                    const uint64_t k = uint64_t(g) * uint64_t(per_group_) + uint64_t(i);
                    float* row = &table[k * kTabulated];
                    const glm::vec2 point =
                        hilbert_point((double(g) + h.sample(uint64_t(i), 0)) / double(groups_));
                    row[0] = point.x;
                    row[1] = point.y;
                    for (int d = 1; d + 1 < kTabulated && d < dimensions_; ++d)
                        row[d + 1] = float(h.sample(k, d));
                }
            tables_.push_back(std::move(table));
        }
    }
}

glm::vec3 PhotonTracer::photon_power(int light) const {
    const Light& l = scene_.lights[size_t(light)];
    if (!l.enabled) return glm::vec3(0.0f);
    return l.power() / float(double(groups_) * double(per_group_));
}

float PhotonTracer::sample(int light, uint64_t k, int dim) const {
    if (dim + 1 < kTabulated && dim < dimensions_ && k < uint64_t(groups_) * uint64_t(per_group_))
        return tables_[size_t(light)][k * kTabulated + size_t(dim) + 1];
    if (dim < dimensions_) return float(halton_[size_t(light)].sample(k, dim));
    const uint32_t h = hash_u32(hash_u32(uint32_t(k) ^ hash_u32(uint32_t(k >> 32) + 0x9e3779b9u)) +
                                uint32_t(dim) * 0x85ebca6bu + scene_.settings.seed +
                                uint32_t(light) * 0xc2b2ae35u);
    return to_unit_float(h);
}

PathEnds PhotonTracer::trace(int light, int group, int index, std::vector<TracedVertex>& out,
                             int layer) const {
    const Light& l = scene_.lights[size_t(light)];
    const uint64_t k =
        (uint64_t(layer) * uint64_t(groups_) + uint64_t(group)) * uint64_t(per_group_) +
        uint64_t(index);
    // Group g owns stratum [g/G, (g+1)/G) of the Hilbert parameter; photon i takes the i-th
    // point of a 1D QMC sequence inside it, so a group's photons leave in similar directions
    // (layer L: the points L·P.. of that sequence).
    glm::vec2 s;
    if (layer == 0) {
        const float* row = &tables_[size_t(light)][k * kTabulated];
        s = glm::vec2(row[0], row[1]);
    } else {
        const uint64_t i = uint64_t(layer) * uint64_t(per_group_) + uint64_t(index);
        s = hilbert_point((double(group) + halton_[size_t(light)].sample(i, 0)) / double(groups_));
    }

    // A sun's group strata lie on its disc (the Hilbert point), its direction is fixed.
    const glm::vec2 other(sample(light, k, 1), sample(light, k, 2));
    const bool sun = l.type == LightType::sun;
    const EmissionRay emitted =
        emission_ray(scene_, l, sun ? other : s, sun ? s : other, rays_.epsilon());
    Ray ray = emitted.ray;
    glm::vec3 power = photon_power(light) * emitted.weight;
    const float eps = rays_.epsilon();
    PathEnds ends;
    ends.origin = ray.origin;
    int inside = -1;  // the glass object the photon is in (its interior medium), or none
    // Ratio tracking's numbers in perturbed media (closed form in homogeneous ones).
    HashedStream more(mix64((uint64_t(light) << 32) ^ k ^ (uint64_t(scene_.settings.seed) << 48) ^
                            0x70686f746f6e73ull));

    for (int bounce = 0; bounce < max_bounces_; ++bounce) {
        ray.tmin = 0.0f;
        ray.tmax = 1e30f;
        const RayHit hit = rays_.intersect(ray);
        if (!hit.hit) {
            ends.escape = ray.direction;
            return ends;
        }
        // Beer–Lambert along the segment through the media it crosses (the glass's interior
        // medium inside it), as the caustic photons and pt's shadow rays.
        if (!media_->empty()) power *= media_->transmittance(ray, hit.t, inside, more);
        const Object& object = scene_.objects[size_t(hit.object)];
        const Material& m = object.material;
        const bool front = glm::dot(ray.direction, hit.normal) < 0.0f;
        const glm::vec3 facing = front ? hit.normal : -hit.normal;  // towards the incoming side

        TracedVertex v;
        v.object = hit.object;
        v.surface = scene_.triangle_surface[size_t(hit.object)][size_t(hit.triangle)];
        v.position = hit.position;
        v.local_position = glm::conjugate(object.transform.rotation) *
                           (hit.position - object.transform.translation);
        v.normal = facing;
        v.power = power;
        v.bounce = uint8_t(std::min(bounce, 255));
        const int dim = 3 + 3 * bounce;

        if (m.type == MaterialType::diffuse) {
            // Lightmaps cover the front of a surface; light reaching a back face is absorbed
            // (walls lit from both sides need thickness).
            v.stored = front;
            const glm::vec3 albedo = albedo_at(object, hit.triangle, hit.barycentric);
            v.albedo = albedo;
            out.push_back(v);
            if (!front) return ends;
            // Russian roulette by albedo (Jensen): survive with p = max ρ, carry ρ/p.
            const float p = std::min(1.0f, std::max({albedo.x, albedo.y, albedo.z}));
            if (p <= 0.0f || sample(light, k, dim) >= p) return ends;
            power *= albedo / p;
            ray.origin = hit.position + eps * facing;
            ray.direction =
                cosine_direction(facing, sample(light, k, dim + 1), sample(light, k, dim + 2));
        } else {  // mirror or glass: reflect, or refract by Fresnel, without storing
            out.push_back(v);
            const float u = m.type == MaterialType::glass ? sample(light, k, dim) : 0.0f;
            const glm::vec3 before = ray.direction;
            ray = specular_bounce(m, hit, ray.direction, u, eps);
            // Through the surface (the same side of it as before): into or out of the glass.
            if (m.type == MaterialType::glass && (glm::dot(ray.direction, hit.normal) < 0.0f) ==
                                                     (glm::dot(before, hit.normal) < 0.0f))
                inside = front ? hit.object : -1;
        }
    }
    return ends;
}

}  // namespace ag::cpu
