#include "cpu/reference/path_tracer.h"

#include <algorithm>
#include <numbers>

#include "shared/camera.h"

namespace ag::cpu {

namespace {

// Sample dimensions: 2 for the pixel position, then per vertex: diffuse or phase direction (2),
// glass Fresnel choice, Russian roulette, light lattice rotation (2). With media, one more per
// vertex for its free-flight distance, after the first kQmcVertices vertices' own. The first
// kQmcVertices vertices use Halton numbers, deeper ones hashed numbers. Without media the layout
// (and so every image) is what it was before media existed.
constexpr int kPixelDims = 2, kVertexDims = 6, kQmcVertices = 5;
constexpr int kRouletteDepth = 3;           // vertices before Russian roulette starts
constexpr int kHashedMediumDims = 1 << 20;  // free-flight dimensions of deep vertices: hashed

}  // namespace

PathTracer::PathTracer(const Scene& scene, const RayTracer& rays, const ReferenceSettings& settings)
    : scene_(scene),
      rays_(rays),
      max_depth_(std::max(1, settings.max_depth)),
      indirect_bounces_(settings.indirect_bounces),
      volume_bounces_(std::max(0, settings.volume_bounces)),
      seed_(settings.seed),
      media_(scene),
      media_dims_(media_.empty() ? 0 : kQmcVertices),
      halton_(kPixelDims + kVertexDims * kQmcVertices + media_dims_, hash_u32(settings.seed) | 1u),
      object_lights_(object_lights(scene)) {}

int PathTracer::vertex_dim(int depth) const {
    return kPixelDims + kVertexDims * depth + (depth >= kQmcVertices ? media_dims_ : 0);
}

int PathTracer::medium_dim(int depth) const {
    return depth < kQmcVertices ? kPixelDims + kVertexDims * kQmcVertices + depth
                                : kHashedMediumDims + depth;
}

ComponentRadiance PathTracer::sample(int x, int y, uint64_t index) const {
    const Camera& camera = scene_.camera;
    const Sampler s(halton_, pixel_key(seed_, x, y), index);
    Ray ray{camera.eye, camera_ray_direction(camera, float(x) + s.get(0), float(y) + s.get(1))};
    const float eps = rays_.epsilon();

    ComponentRadiance out;
    glm::vec3 throughput(1.0f);
    bool specular_pixel = false;   // the camera ray met a mirror or glass first
    bool volume_pixel = false;     // the camera ray scattered in a medium before any surface
    bool diffuse_seen = false;     // some diffuse (or medium) vertex on the path so far
    bool diffuse_after_x = false;  // a diffuse vertex after the first one, x
    bool after_specular = false;   // the ray leaves a specular vertex
    int diffuse_vertices = 0;      // diffuse vertices so far, x included
    bool specular_only = false;    // --indirect-bounces reached: end at the next diffuse vertex
    int inside = -1;               // the glass object the ray travels in, or -1
    int volume_vertices = 0;       // scattering events in media so far
    // Light reaching the camera through a specular chain that NEE cannot sample.
    const auto routed = [&] {
        return volume_pixel      ? FrameTerm::volume
               : specular_pixel  ? FrameTerm::specular
               : diffuse_after_x ? FrameTerm::indirect
                                 : FrameTerm::caustics;
    };
    // Russian roulette after vertex `depth`.
    const auto survives = [&](int depth, int dim) {
        if (depth + 1 < kRouletteDepth) return true;
        // Survive in proportion to the throughput (capped below 1 so mirror loops end).
        const float p = std::min(0.95f, std::max({throughput.x, throughput.y, throughput.z}));
        if (!(p > 0.0f) || s.get(dim + 3) >= p) return false;
        throughput /= p;
        return true;
    };
    for (int depth = 0; depth < max_depth_; ++depth) {
        const int dim = vertex_dim(depth);
        const RayHit hit = rays_.intersect(ray);

        if (!media_.empty()) {
            // Delta tracking up to the surface: a real collision makes this vertex a scattering
            // event in the medium instead (the integral of Pfeuti eq. 2.5, sampled by free flight).
            HashedStream more(mix64(mix64(s.key() ^ mix64(s.index())) + uint64_t(depth)));
            const std::optional<MediumCollision> collision = media_.sample_collision(
                ray, hit.hit ? hit.t : 1e30f, inside, s.get(medium_dim(depth)), more);
            if (collision) {
                if (volume_vertices >= volume_bounces_) break;
                ++volume_vertices;
                if (depth == 0) volume_pixel = true;
                const Medium& m = *collision->medium;
                const glm::vec3 p = ray.origin + collision->t * ray.direction;
                const FrameTerm here = volume_pixel     ? FrameTerm::volume
                                       : specular_pixel ? FrameTerm::specular
                                                        : FrameTerm::indirect;
                // Collision probability σ_t/majorant against weight σ_t/majorant: the scattering
                // share σ_s/σ_t is what remains (the same at every point of a perturbed medium).
                throughput *= m.albedo();
                out[here] +=
                    throughput * direct_inscattering(scene_, rays_, p, ray.direction, m.phase_k, 1,
                                                     s.get(dim + 4), s.get(dim + 5), media_, more);
                if (depth > 0) diffuse_after_x = true;
                diffuse_seen = true;
                after_specular = false;
                // Phase sampling: p / pdf = 1.
                ray = {p, sample_schlick(ray.direction, m.phase_k, s.get(dim), s.get(dim + 1))};
                if (!survives(depth, dim)) break;
                continue;
            }
        }

        // Quad lights are not geometry: a ray finds one only to complete L S+ D ... paths that
        // next-event estimation cannot sample (it stops at specular vertices). Lights stay
        // invisible to the camera and to purely specular chains from it, as in the GPU frame.
        if (after_specular && diffuse_seen) {
            const glm::vec3 le = quad_light_radiance(scene_, ray, hit.hit ? hit.t : 1e30f);
            out[routed()] += throughput * le;
        }
        if (!hit.hit) break;

        const Material& m = scene_.objects[size_t(hit.object)].material;
        if (depth == 0) specular_pixel = m.type != MaterialType::diffuse;
        const FrameTerm here = volume_pixel     ? FrameTerm::volume
                               : specular_pixel ? FrameTerm::specular
                               : depth == 0     ? FrameTerm::direct
                                                : FrameTerm::indirect;
        const bool front = glm::dot(ray.direction, hit.normal) < 0.0f;
        if (front && object_lights_[size_t(hit.object)] >= 0 && depth > 0) {
            // A mesh light after a diffuse vertex was counted by next-event estimation there;
            // after a specular one it completes a path NEE cannot sample (as quad lights above).
            if (after_specular) out[diffuse_seen ? routed() : here] += throughput * m.emission;
        } else if (front) {
            out[here] += throughput * m.emission;
        }

        if (m.type == MaterialType::diffuse) {
            // Lightmaps cover front faces only; light reaching a back face is absorbed (as in the
            // photon tracer), so it is black.
            if (!front || specular_only) break;
            const glm::vec3 albedo =
                albedo_at(scene_.objects[size_t(hit.object)], hit.triangle, hit.barycentric);
            glm::vec3 e;
            if (media_.empty()) {
                e = direct_irradiance(scene_, rays_, hit.position, hit.normal, 1, s.get(dim + 4),
                                      s.get(dim + 5));
            } else {
                HashedStream more(mix64(mix64(s.key() ^ mix64(s.index())) + uint64_t(depth)) ^
                                  0x5851f42d4c957f2dull);
                e = direct_irradiance(scene_, rays_, hit.position, hit.normal, 1, s.get(dim + 4),
                                      s.get(dim + 5), &media_, &more);
            }
            out[here] += throughput * albedo / std::numbers::pi_v<float> * e;
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
            // Refracted into glass: its own medium (if any) until it refracts out.
            if (m.type == MaterialType::glass)
                inside = glm::dot(ray.direction, hit.normal) < 0.0f ? hit.object : -1;
        }

        if (!survives(depth, dim)) break;
    }
    return out;
}

}  // namespace ag::cpu
