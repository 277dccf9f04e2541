#include "cpu/irradiance_gather.h"

#include <algorithm>
#include <cmath>
#include <limits>
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
        // The albedo there, its texture included (pt's albedo at a hit).
        const glm::vec3 albedo =
            albedo_at(scene.objects[size_t(hit.object)], hit.triangle, hit.barycentric);
        // A fixed lattice rotation: the hit points of one record already vary.
        const glm::vec3 e =
            direct_irradiance(scene, rays, hit.position, hit.normal, shadow_samples, 0.5f, 0.5f);
        return albedo * e * float(std::numbers::inv_pi);
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
                                              const RecordGatherOptions& options,
                                              std::vector<RecordSample>* samples) const {
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
    if (samples) samples->assign(l.size(), RecordSample{});
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
            if (samples && hit.hit) {
                const Transform& tr = scene_.objects[size_t(hit.object)].transform;
                const glm::quat to_local = glm::inverse(tr.rotation);
                const Material& mat = scene_.objects[size_t(hit.object)].material;
                (*samples)[at] = {
                    radiance_jk,
                    hit.t,
                    hit.object,
                    to_local * (hit.position - tr.translation),
                    to_local * hit.normal,
                    mat.type == MaterialType::diffuse && glm::dot(d, hit.normal) < 0.0f,
                    hit.triangle,
                    hit.barycentric};
            }
            sum += radiance_jk;
            // Ward & Heckbert eq. 8: tilting n towards azimuth u raises cos θ of this sample by
            // sin θ per radian, i.e. its cosine-weighted share by tan θ; the tilt is a rotation
            // about n × u, the axis n_k × n of the extrapolation.
            const float tan_t = cos_t > 1e-4f ? sin_t / cos_t : 1e4f;
            const glm::vec3 axis = glm::cross(n, u);
            for (int c = 0; c < 3; ++c) rotation[c] += tan_t * radiance_jk[c] * axis;
        }
    const float count = float(m) * float(n_phi);
    IrradianceRecord rec;
    rec.position = point.position;
    rec.normal = n;
    rec.iim = sum / count;
    rec.rotation_gradient = rotation / count;
    const double harmonic = inverse_distances > 0.0 ? count / inverse_distances : 1e30;
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

glm::vec3 reproject_record(const IrradianceRecord& record, const std::vector<RecordSample>& samples,
                           const std::vector<Transform>& now, const std::vector<Transform>& next,
                           int theta, int phi, const RecordRadiance* next_radiance) {
    const int m = std::max(1, theta), n_phi = std::max(3, phi);
    const glm::vec3 n = record.normal;
    glm::vec3 t, b;
    orthonormal_basis(n, t, b);
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<float> depth(samples.size(), inf);
    std::vector<glm::vec3> value(samples.size(), glm::vec3(0.0f));
    for (size_t i = 0; i < samples.size(); ++i) {
        const RecordSample& s = samples[i];
        if (s.object < 0) {
            // The ray left the scene: the sky stays where it is, behind everything.
            if (depth[i] == inf) depth[i] = std::numeric_limits<float>::max();
            continue;
        }
        const Transform& to = next[size_t(s.object)];
        const Transform& from = now[size_t(s.object)];
        // The hit's radiance at t0+1: shaded again where it lands, or carried.
        auto radiance_next = [&](const glm::vec3& x) {
            if (!next_radiance || !s.shaded) return s.radiance;
            RayHit hit;
            hit.hit = true;
            hit.object = s.object;
            hit.triangle = s.triangle;
            hit.barycentric = s.barycentric;
            hit.position = x;
            hit.normal = glm::normalize(to.rotation * s.local_normal);  // rigid transforms
            return (*next_radiance)(hit);
        };
        if (to.translation == from.translation && to.rotation == from.rotation) {
            if (s.distance < depth[i]) {
                depth[i] = s.distance;
                value[i] = radiance_next(to.apply_point(s.local));
            }
            continue;
        }
        const glm::vec3 x = to.apply_point(s.local);
        const glm::vec3 d = x - record.position;
        const float dist = glm::length(d);
        if (dist <= 0.0f) continue;
        const glm::vec3 w = d / dist;
        const float cos_t = glm::dot(w, n);
        if (cos_t <= 0.0f) continue;
        const float sin2 = std::max(0.0f, 1.0f - cos_t * cos_t);
        float phi_angle = std::atan2(glm::dot(w, b), glm::dot(w, t));
        if (phi_angle < 0.0f) phi_angle += 2.0f * std::numbers::pi_v<float>;
        const int j = std::min(m - 1, int(sin2 * float(m)));
        const int k =
            std::min(n_phi - 1, int(phi_angle / (2.0f * std::numbers::pi_v<float>)*float(n_phi)));
        const size_t at = size_t(j) * size_t(n_phi) + size_t(k);
        if (dist < depth[at]) {  // the Z-test of the point splat
            depth[at] = dist;
            value[at] = radiance_next(x);
        }
    }
    glm::vec3 sum(0.0f);
    for (int j = 0; j < m; ++j)
        for (int k = 0; k < n_phi; ++k) {
            const size_t at = size_t(j) * size_t(n_phi) + size_t(k);
            if (std::isfinite(depth[at])) {
                sum += value[at];
                continue;
            }
            // A hole: what moved away uncovered what lay behind it, so the farthest neighbour
            // that received a sample of geometry (Gautron's background fill; the sky only when
            // no neighbour shows geometry, else the edge of an approaching object turns black).
            float farthest = -1.0f;
            glm::vec3 fill(0.0f);
            const int nj[4] = {j - 1, j + 1, j, j},
                      nk[4] = {k, k, (k + 1) % n_phi, (k + n_phi - 1) % n_phi};
            for (int q = 0; q < 4; ++q) {
                if (nj[q] < 0 || nj[q] >= m) continue;
                const size_t o = size_t(nj[q]) * size_t(n_phi) + size_t(nk[q]);
                const float d = depth[o] == std::numeric_limits<float>::max() ? 0.0f : depth[o];
                if (std::isfinite(d) && d > farthest) {
                    farthest = d;
                    fill = value[o];
                }
            }
            sum += fill;
        }
    return sum / (float(m) * float(n_phi));
}

int record_lifespan(const glm::vec3& now, const glm::vec3& next, float temporal_accuracy,
                    int max_lifespan) {
    auto lum = [](const glm::vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; };
    const float e0 = lum(now), e1 = lum(next);
    int frames = std::max(1, max_lifespan);
    if (e0 > 0.0f) {
        const float change = std::abs(e1 / e0 - 1.0f);  // |τ − 1|
        if (change > 0.0f) frames = std::min(frames, std::max(1, int(temporal_accuracy / change)));
    } else if (e1 > 0.0f) {
        frames = 1;  // from black to lit: no ratio, expire at once
    }
    return frames;
}

}  // namespace ag::cpu
