// Pfeuti's reference pipeline (2009, ch. 3.1) end to end — voxelisation through the ray tracer,
// the smoothed index grid, the photon plane of the scene's point light, curved photon marching
// and the view march on the GPU — and his adaptive pipeline (ch. 3.2). Joins cpu/ (voxeliser) and
// gpu/ (marchers), so it lives here.
#pragma once

#include <string>

#include "gpu/media_marcher.h"
#include "shared/image.h"
#include "shared/scene.h"

namespace ag {

// His adaptive pipeline (ch. 3.2): pilot photons on a jittered square grid of the photon plane,
// marched into a coarse grid that keeps where on the plane each voxel's photons came from;
// voxels of high gradient or low fluence mark circles on a 2D density over the plane; the
// photons follow that density (each weighted by 1/density, so the sum stays unbiased); the
// deposits are reconstructed per voxel from a mipmap pyramid at min(centre-surround, weight)
// level. Point and spot lights only (the photon plane, or the sphere of directions).
struct MediaAdaptiveSettings {
    bool enabled = false;
    int pilot_side = 64;  // pilots = side², the density's cells side × side (his 64² = 4096)
    int coarse = 16;      // region-detection grid along the longest side (his 16³)
    // Region selection on the coarse grid (his two thresholds, Listing B.1), relative to the mean
    // fluence F̄ of the coarse voxels photons reached, so that they hold for any light: a voxel
    // is sampled tightly where |∇F| × coarse voxel ≥ gradient × F̄, or where 0 < F ≤ shadow × F̄.
    float gradient = 0.5f;
    float shadow = 0.2f;
    float background = 0.1f;  // density of unselected cells, relative to the densest cell
    // For a light inside the grid (photons over the sphere of directions; not his, docs/media.md
    // "A light inside the grid"): the thresholds and the filter see fluence × r², r the distance
    // to the light, so that the light's own 1/r² falloff is neither an edge, nor a shadow, nor
    // blurred; and the photons are a uniform Hammersley set at the density's floor plus a set
    // through the cells whose excess over the floor is above dense_cut of the peak's (a
    // two-level density). False: his pipeline there too. On a photon plane, his pipeline.
    bool free_space = true;
    bool stratified = true;
    float dense_cut = 0.1f;
    // Photon-weight filter: level ⌊w / Δweight⌋ with w = 1/(N p) his photon weight (N photons,
    // p the density at the photon's origin, mean 1): level k where the photons are as sparse as
    // 1/(k Δweight) uniform ones or sparser (2e-5: level 1 below 50,000-photon density).
    // For a 64-voxel grid; scaled by 64 / (voxels along the longest side).
    float delta_weight = 2e-5f;
    int max_level = 4;  // highest mipmap level read
    // The weight level read continuously (not his; docs/media.md "Session 14"): w / Δweight in
    // place of ⌊w / Δweight⌋, a fractional level blending the two mipmap levels around it. His
    // integer level left the filter nearly off where w sat between Δweight and 2 Δweight
    // (fog_sphere_point at 50,000 photons: 0.62 of uniform's photons, now 0.29). False: his.
    bool fractional_level = true;
    // The photon density read bilinearly between the cells' centres (not his; docs/media.md
    // "Session 15"): the importance-sampled photons' weights 1/(N p) no longer jump at every
    // cell edge, which cost the Hammersley points their advantage over a smooth field
    // (media_noise_cube_point at 200,000 photons, 8 seeds: 0.53 of uniform's photons, now
    // 0.47). On a photon plane, and for his pipeline round a light inside the grid (the
    // two-level sets keep their cells). False: his piecewise-constant cells.
    bool bilinear_density = true;
    // Significance stop (not his; docs/media.md "The filter beside a caustic's focus"): a voxel
    // climbs from mipmap level l to l + 1 only while |c(l+1) − c(l)| is within this many standard
    // errors, each level's relative error 1/√(photons crossing its voxel); 0: off (his filter).
    float significance = 3.0f;
    bool reconstruct = true;  // false: the raw importance-sampled deposits (for the bias tests)
    uint32_t seed = 0;        // pilot jitter and the rotation of the Hammersley points
};

struct MediaMethodSettings {
    int grid = 64;              // voxels along the longest side of the grid's box
    int width = 0, height = 0;  // the volume image; 0: the scene camera's resolution
    int photons = 122000;       // on the photon plane (his Table 4.1 count)
    float march_step = 0.25f;   // photon step, voxels
    float view_step = 0.5f;     // view-ray step, voxels
    bool phase_spread = true;   // the view's phase broadened by the photons' spread (ours)
    gpu::MediaDeposit deposit = gpu::MediaDeposit::track_length;
    bool octree = true;  // his octree step lengths in the photon march (track length only)
    MediaAdaptiveSettings adaptive;  // `photons` then counts the importance-sampled photons
    // The order of the uniform photons of a point light (his Table 4.1); Hammersley by default.
    PlaneSampling sampling = PlaneSampling::hammersley;
    // Light the scene's opaque surfaces send into the media (not his: his photons stop at the
    // grid): photons leaving the grid go on from the surface they meet — mirrored by a mirror,
    // cosine-distributed by a diffuse surface, carrying its grey albedo — and are marched again,
    // up to this many times. The reference pipeline only (the adaptive one ignores it).
    int surface_bounces = 2;
    uint32_t seed = 0;  // the bounced photons' directions
    // Also what the camera sees through glass (MediaMethodResult::specular).
    bool through_glass = true;
    // The light the fog scatters onto the surfaces the camera sees (MediaMethodResult::indirect,
    // view_fog_on_surfaces): view-march rays per pixel over the surface's hemisphere (cosine-
    // distributed, a Hammersley set rotated per pixel); 0: none. Their step, in voxels.
    int fog_on_surfaces_rays = 32;
    float fog_on_surfaces_step = 1.0f;
    // Photons from the scene's emissive surfaces (mesh lights and lamps that are no light; not
    // his): at least this many, more where their power over the light's asks for more to keep
    // the photons' powers alike; 0: none.
    int emissive_photons = 4096;
};

// Seconds per pass, as his Tables 4.2–4.4 list them (no copy: the grids are SSBOs). The octree
// is built on the CPU once for the grids and kept for every march on them (pilots, photons, each
// surface bounce).
struct MediaMethodTiming {
    double voxelisation = 0.0, smoothing = 0.0, octree = 0.0, photon_generation = 0.0,
           photon_marching = 0.0, viewing = 0.0;
    // The adaptive pipeline's passes (zero for the reference pipeline).
    double pilot_generation = 0.0, pilot_marching = 0.0, distribution = 0.0, reconstruction = 0.0;
    double total() const {
        return voxelisation + smoothing + octree + photon_generation + photon_marching + viewing +
               pilot_generation + pilot_marching + distribution + reconstruction;
    }
};

struct MediaMethodResult {
    Image volume;  // the `volume` frame term: single scattering before the first surface
    // Per pixel of `volume`, the camera ray's transmittance up to that surface (the view
    // march's): what the frame's other terms are attenuated by, as pt's are.
    Image transmittance;
    // The `specular` frame term at the pixels whose camera ray meets glass first (black
    // elsewhere; view_through_glass), where settings.through_glass.
    Image specular;
    std::vector<uint8_t> glass;  // per pixel of `specular` (row-major): 1 where it is the term
    // Per pixel, the light the fog scatters onto the diffuse surface the camera ray meets,
    // reflected towards the camera (view_fog_on_surfaces): part of the frame's `indirect` term
    // (pt files it there), not yet dimmed by the camera ray's transmittance.
    Image indirect;
    MediaMethodTiming timing;
    glm::ivec3 grid{0};
    size_t photons_marched = 0;    // photons of the plane that meet the grid
    size_t pilots_marched = 0;     // adaptive: pilot photons that meet the grid
    size_t photons_bounced = 0;    // photons sent on from surfaces (all bounces)
    double power_deposited = 0.0;  // Σ over voxels of fluence × voxel volume (before filtering),
                                   // the light's photons only
    double power_bounced = 0.0;    // the same for the photons from surfaces (surface_bounces)
    size_t photons_emissive = 0;   // photons of emissive surfaces that meet the grid
    double power_emissive = 0.0;   // the same sum for them (emissive_photons)
    std::vector<double> density;   // adaptive: the photon density over the plane (side², mean 1)
    std::vector<uint8_t> levels;   // adaptive: the mipmap level each voxel read
    MediaGrid grids;               // n (smoothed), σ_s, σ_t, for slice views
    std::vector<float> fluence;    // per voxel, as deposited (reconstructed, adaptive)
    std::vector<glm::vec3> flow;   // per voxel, fluence × photon direction
    glm::vec3 tint{1.0f};          // the light's colour over its grey intensity
};

// The grid covers the scene's media boxes and glass objects; light comes from the first enabled
// point or spot light (spot cones ignored), else the first quad light. Needs a current GL
// context. Throws std::invalid_argument naming scene.path where the scene has no media or glass,
// or no such light.
// `with_view` false skips the view march (the grids only; `volume` stays empty).
MediaMethodResult render_media(const Scene& scene, const MediaMethodSettings& settings,
                               bool with_view = true);

// A slice of `field` through voxel layer `layer` across `axis` (as grid_slice; a layer out of
// range clamps) over the max of the field in the slice (levels over the highest level; n − 1
// over its max, so air is black), fitted into a width × height image with its aspect kept,
// nearest voxel, black around it. An empty field (no levels outside the adaptive pipeline) gives
// black.
Image media_slice_view(const MediaMethodResult& media, MediaField field, int axis, int layer,
                       int width, int height);

// The view march alone (ch. 3.1.6) through `grids` lit as `media` holds them, for `camera` at
// its resolution: what a camera move needs (the photons stay as they are). Needs a GL context.
// `transmittance`, where given, gets each pixel's transmittance up to the first surface.
Image view_media(const Scene& scene, const MediaMethodResult& media, const Camera& camera,
                 const MediaMethodSettings& settings, Image* transmittance = nullptr);

// The light the media scatter onto the surfaces the camera sees (not his: his view march ends
// at the first surface): at the diffuse front face each pixel's straight camera ray meets, the
// single-scattered radiance arriving over its hemisphere, gathered by settings.
// fog_on_surfaces_rays view-march rays (the volume term's march and phase, from the surface up
// to the next surface a straight ray meets) in cosine-distributed directions, so that
// albedo/π · E = albedo / N · Σ L_k; times the light's colour. What pt files under `indirect`
// for the paths whose first vertex after the visible surface scatters in a medium, with the
// light the surfaces send into the fog (surface_bounces) included. Black where the ray meets no
// diffuse front face, or with no rays. Needs a GL context.
Image view_fog_on_surfaces(const Scene& scene, const MediaMethodResult& media, const Camera& camera,
                           const MediaMethodSettings& settings);

// What the camera sees through the glass (his viewing pass behind the refractive object,
// ch. 3.1.6): at each pixel whose camera ray meets glass first, the Fresnel reflection there, and
// the view march on through the smoothed index, bent (eqs. 2.10/2.11), scattering single light
// inside the glass and behind it, until the ray is back in air; from there straight on (n = 1) to
// the surface the bent ray meets, traced (his environment map holds only a distant scene; ours is
// the scene itself), which shows its emission and direct light; the Fresnel transmittance where
// the ray leaves the glass. Mirrors and glass behind the glass show black. Needs a GL context.
// `glass`, where given, gets 1 at those pixels and 0 elsewhere (row-major, top row first).
Image view_through_glass(const Scene& scene, const MediaMethodResult& media, const Camera& camera,
                         const MediaMethodSettings& settings,
                         std::vector<uint8_t>* glass = nullptr);

}  // namespace ag
