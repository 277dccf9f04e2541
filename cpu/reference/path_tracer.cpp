#include "cpu/reference/path_tracer.h"

#include <algorithm>
#include <numbers>

#include "shared/camera.h"

namespace ag::cpu {

namespace {

// Sample dimensions: 2 for the pixel position, then per vertex: diffuse direction (2), glass
// Fresnel choice, Russian roulette, quad-light lattice rotation (2). The first kQmcVertices
// vertices use Halton numbers, deeper ones hashed numbers.
constexpr int kPixelDims = 2, kVertexDims = 6, kQmcVertices = 5;
constexpr int kRouletteDepth = 3;  // vertices before Russian roulette starts

}  // namespace

PathTracer::PathTracer(const Scene& scene, const RayTracer& rays, const ReferenceSettings& settings)
    : scene_(scene),
      rays_(rays),
      max_depth_(std::max(1, settings.max_depth)),
      indirect_bounces_(settings.indirect_bounces),
      seed_(settings.seed),
      halton_(kPixelDims + kVertexDims * kQmcVertices, hash_u32(settings.seed) | 1u),
      object_lights_(object_lights(scene)) {}

ComponentRadiance PathTracer::sample(int x, int y, uint64_t index) const {
    const Camera& camera = scene_.camera;
    const Sampler s(halton_, pixel_key(seed_, x, y), index);
    Ray ray{camera.eye, camera_ray_direction(camera, float(x) + s.get(0), float(y) + s.get(1))};
    const float eps = rays_.epsilon();

    ComponentRadiance out;
    glm::vec3 throughput(1.0f);
    bool specular_pixel = false;   // the camera ray met a mirror or glass first
    bool diffuse_seen = false;     // some diffuse vertex on the path so far
    bool diffuse_after_x = false;  // a diffuse vertex after the first one, x
    bool after_specular = false;   // the ray leaves a specular vertex
    int diffuse_vertices = 0;      // diffuse vertices so far, x included
    bool specular_only = false;    // --indirect-bounces reached: end at the next diffuse vertex
    for (int depth = 0; depth < max_depth_; ++depth) {
        const int dim = kPixelDims + kVertexDims * depth;
        const RayHit hit = rays_.intersect(ray);

        // Quad lights are not geometry: a ray finds one only to complete L S+ D ... paths that
        // next-event estimation cannot sample (it stops at specular vertices). Lights stay
        // invisible to the camera and to purely specular chains from it, as in the GPU frame.
        if (after_specular && diffuse_seen) {
            const glm::vec3 le = quad_light_radiance(scene_, ray, hit.hit ? hit.t : 1e30f);
            const FrameTerm c = specular_pixel    ? FrameTerm::specular
                                : diffuse_after_x ? FrameTerm::indirect
                                                  : FrameTerm::caustics;
            out[c] += throughput * le;
        }
        if (!hit.hit) break;

        const Material& m = scene_.objects[size_t(hit.object)].material;
        if (depth == 0) specular_pixel = m.type != MaterialType::diffuse;
        const FrameTerm here = specular_pixel ? FrameTerm::specular
                               : depth == 0   ? FrameTerm::direct
                                              : FrameTerm::indirect;
        const bool front = glm::dot(ray.direction, hit.normal) < 0.0f;
        if (front && object_lights_[size_t(hit.object)] >= 0 && depth > 0) {
            // A mesh light after a diffuse vertex was counted by next-event estimation there;
            // after a specular one it completes a path NEE cannot sample (as quad lights above).
            if (after_specular)
                out[diffuse_seen ? (specular_pixel    ? FrameTerm::specular
                                    : diffuse_after_x ? FrameTerm::indirect
                                                      : FrameTerm::caustics)
                                 : here] += throughput * m.emission;
        } else if (front) {
            out[here] += throughput * m.emission;
        }

        if (m.type == MaterialType::diffuse) {
            // Lightmaps cover front faces only; light reaching a back face is absorbed (as in the
            // photon tracer), so it is black.
            if (!front || specular_only) break;
            const glm::vec3 albedo =
                albedo_at(scene_.objects[size_t(hit.object)], hit.triangle, hit.barycentric);
            out[here] += throughput * albedo / std::numbers::pi_v<float> *
                         direct_irradiance(scene_, rays_, hit.position, hit.normal, 1,
                                           s.get(dim + 4), s.get(dim + 5));
            if (depth > 0) diffuse_after_x = true;
            diffuse_seen = true;
            // Light arriving at the k-th diffuse vertex after x has made k bounces to reach x.
            // After the last bounce allowed has had its next-event estimate the path goes on
            // through mirrors and glass only, to find the lights they show (L S+ D paths).
            if (indirect_bounces_ >= 0 && ++diffuse_vertices > indirect_bounces_)
                specular_only = true;
            after_specular = false;
            // Cosine sampling makes BRDF · cos / pdf = ρ.
            throughput *= albedo;
            ray = {hit.position + eps * hit.normal,
                   cosine_direction(hit.normal, s.get(dim), s.get(dim + 1))};
        } else {
            ray = specular_bounce(m, hit, ray.direction, s.get(dim + 2), eps);
            after_specular = true;
        }

        if (depth + 1 >= kRouletteDepth) {
            // Survive in proportion to the throughput (capped below 1 so mirror loops end).
            const float p = std::min(0.95f, std::max({throughput.x, throughput.y, throughput.z}));
            if (!(p > 0.0f) || s.get(dim + 3) >= p) break;
            throughput /= p;
        }
    }
    return out;
}

}  // namespace ag::cpu
