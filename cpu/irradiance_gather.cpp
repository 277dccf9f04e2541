#include "cpu/irradiance_gather.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "cpu/reference/reference.h"
#include "cpu/sampling.h"
#include "shared/lightmap_sample.h"
#include "shared/qmc.h"

namespace ag::cpu {

RecordRadiance aim_radiance_source(const Scene& scene, const std::vector<glm::vec3>& aim) {
    return [&scene, &aim](const RayHit& hit) {
        return sample_lightmap(scene.atlas, aim, hit.object, hit.triangle, hit.barycentric);
    };
}

RecordRadiance direct_radiance_source(const Scene& scene, const RayTracer& rays,
                                      int shadow_samples) {
    return [&scene, &rays, shadow_samples](const RayHit& hit) {
        const Material& m = scene.objects[size_t(hit.object)].material;
        // A fixed lattice rotation: the hit points of one record already vary.
        const glm::vec3 e =
            direct_irradiance(scene, rays, hit.position, hit.normal, shadow_samples, 0.5f, 0.5f);
        return m.albedo * e * float(std::numbers::inv_pi);
    };
}

IrradianceGather::IrradianceGather(const Scene& scene, const RayTracer& rays, ThreadPool& pool)
    : scene_(scene), rays_(rays), pool_(pool) {}

std::vector<IrradianceRecord> IrradianceGather::gather(const std::vector<GatherPoint>& points,
                                                       const RecordRadiance& radiance,
                                                       const RecordGatherOptions& options) {
    std::vector<IrradianceRecord> out(points.size());
    pool_.parallel_for(
        points.size(), [&](size_t i) { out[i] = gather_one(points[i], radiance, options); }, 1);
    stats_.records = int(points.size());
    stats_.rays = uint64_t(points.size()) * uint64_t(options.theta) * uint64_t(options.phi);
    return out;
}

IrradianceRecord IrradianceGather::gather_one(const GatherPoint& point,
                                              const RecordRadiance& radiance,
                                              const RecordGatherOptions& options) const {
    const int m = std::max(1, options.theta), n_phi = std::max(3, options.phi);
    const glm::vec3 n = glm::normalize(point.normal);
    glm::vec3 t, b;
    orthonormal_basis(n, t, b);
    const glm::vec3 origin = point.position + rays_.epsilon() * n;
    const float two_pi = 2.0f * std::numbers::pi_v<float>;
    auto azimuth = [&](float phi) { return std::cos(phi) * t + std::sin(phi) * b; };

    std::vector<glm::vec3> l(size_t(m) * size_t(n_phi));
    std::vector<float> dist(l.size());
    glm::vec3 sum(0.0f);
    double inverse_distances = 0.0;
    glm::mat3 rotation(0.0f);
    uint32_t h = hash_u32(options.seed * 0x9e3779b9u ^ hash_u32(point.key + 0x7f4a7c15u));
    for (int k = 0; k < n_phi; ++k)
        for (int j = 0; j < m; ++j) {
            h = hash_u32(h + 0x6a09e667u);
            const float u1 = to_unit_float(h);
            h = hash_u32(h + 0xbb67ae85u);
            const float u2 = to_unit_float(h);
            const float sin2 = (float(j) + u1) / float(m);
            const float sin_t = std::sqrt(sin2), cos_t = std::sqrt(std::max(0.0f, 1.0f - sin2));
            const float phi = two_pi * (float(k) + u2) / float(n_phi);
            const glm::vec3 u = azimuth(phi);
            const glm::vec3 d = sin_t * u + cos_t * n;
            const RayHit hit = rays_.intersect({origin, d, 0.0f, 1e30f});
            glm::vec3 radiance_jk(0.0f);
            float r = std::numeric_limits<float>::infinity();
            if (hit.hit) {
                r = hit.t;
                const Material& mat = scene_.objects[size_t(hit.object)].material;
                if (mat.type == MaterialType::diffuse && glm::dot(d, hit.normal) < 0.0f)
                    radiance_jk = radiance(hit);
                inverse_distances += 1.0 / std::max(hit.t, 1e-6f);
            }
            const size_t at = size_t(j) * size_t(n_phi) + size_t(k);
            l[at] = radiance_jk;
            dist[at] = r;
            sum += radiance_jk;
            // Ward & Heckbert eq. 8: tilting n towards azimuth u raises cos θ of this sample by
            // sin θ per radian, i.e. its cosine-weighted share by tan θ; the tilt is a rotation
            // about n × u, the axis n_k × n of the extrapolation.
            const float tan_t = cos_t > 1e-4f ? sin_t / cos_t : 1e4f;
            const glm::vec3 axis = glm::cross(n, u);
            for (int c = 0; c < 3; ++c) rotation[c] += tan_t * radiance_jk[c] * axis;
        }
    const float samples = float(m) * float(n_phi);
    IrradianceRecord rec;
    rec.position = point.position;
    rec.normal = n;
    rec.iim = sum / samples;
    rec.rotation_gradient = rotation / samples;
    const double harmonic = inverse_distances > 0.0 ? samples / inverse_distances : 1e30;
    rec.harmonic_distance =
        float(std::clamp(harmonic, double(options.min_distance), double(options.max_distance)));

    // Translation gradient (Křivánek, Gautron et al. 2005, eq. for cosine-weighted strata; Ward &
    // Heckbert 1992 eq. 11): the walls between strata move as the point does, by the distance to
    // the nearer of the two surfaces they separate. E here is π·iim, so everything carries 1/π.
    glm::mat3 translation(0.0f);
    for (int k = 0; k < n_phi; ++k) {
        const int k_prev = (k + n_phi - 1) % n_phi;
        const glm::vec3 u_k = azimuth(two_pi * (float(k) + 0.5f) / float(n_phi));
        const glm::vec3 v_k =
            azimuth(two_pi * float(k) / float(n_phi) + 0.5f * std::numbers::pi_v<float>);
        glm::vec3 radial(0.0f), tangential(0.0f);
        for (int j = 0; j < m; ++j) {
            const size_t at = size_t(j) * size_t(n_phi) + size_t(k);
            const float sin_minus = std::sqrt(float(j) / float(m)),
                        sin_plus = std::sqrt(float(j + 1) / float(m));
            if (j > 0) {
                const size_t below = at - size_t(n_phi);
                const float r = std::min(dist[at], dist[below]);
                const float cos2 = 1.0f - sin_minus * sin_minus;
                if (std::isfinite(r)) radial += sin_minus * cos2 / r * (l[at] - l[below]);
            }
            const size_t side = size_t(j) * size_t(n_phi) + size_t(k_prev);
            const float r = std::min(dist[at], dist[side]);
            if (std::isfinite(r)) tangential += (sin_plus - sin_minus) / r * (l[at] - l[side]);
        }
        radial *= two_pi / float(n_phi);
        for (int c = 0; c < 3; ++c) translation[c] += radial[c] * u_k + tangential[c] * v_k;
    }
    rec.translation_gradient = translation * float(std::numbers::inv_pi);
    return rec;
}

}  // namespace ag::cpu
