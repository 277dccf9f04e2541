// Hemi-plane final gathering (Larsen ch. 11): from a texel's centre, looking along its normal,
// render the scene textured with AIM radiance onto one enlarged plane, weight every pixel by
// eq. 11.2, F(x,y) = ΔA / (π (x² + y² + 1)²), and sum by mipmap reduction in float. Many texels
// are gathered per pass: each owns an R×R tile of one framebuffer and a single mipmap pass leaves
// every tile's mean at level log2(R). The part of the hemisphere the plane misses is corrected by
// Larsen's renormalisation or Gautron's border stretch (Gautron 2006, Table 4.1), or rendered
// through a second, wider plane (`band`).
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "gpu/lightmap_texture.h"
#include "gpu/scene_meshes.h"
#include "shared/gather.h"
#include "shared/scene.h"

namespace ag::gpu {

// Per-pixel weights of an R×R hemi-plane of half-width a (at unit distance), row-major from the
// plane's (−a, −a) corner. Exact per pixel (integrated, not point-sampled); `correction` adds the
// missing hemisphere as in settings. Sum: coverage for none and band, 1 for renormalize and
// the stretches.
std::vector<float> hemi_plane_weights(int resolution, float half_width,
                                      BorderCorrection correction);

// border_correction=band: the weights of the second, wider view (half-width band_half_width, the
// same resolution): each pixel's cosine-weighted solid angle outside the first plane [-a, a]²,
// its border stretched to the horizon. Sum: 1 − coverage(half_width).
std::vector<float> hemi_band_weights(int resolution, float half_width, float band_half_width);

// Cosine-weighted fraction of the hemisphere a square of half-width a at unit distance covers:
// (4/π)·s·atan(s), s = a/√(1+a²).
double hemi_plane_coverage(float half_width);

class HemiPlaneGather final : public Gatherer {
public:
    // Up to `tiles` texels are gathered per pass (rounded up to a square of tiles).
    // `aim`, if given, is the AIM texture gather(texels) reads, chart-aware. With `distances`, a
    // second layer array takes weight/distance per pixel and every result carries the harmonic
    // mean distance (GatherResult::harmonic_distance: the irradiance cache's R_k).
    HemiPlaneGather(const Scene& scene, const SceneMeshes& meshes, int tiles = 256,
                    const LightmapTexture* aim = nullptr, bool distances = false);

    GatherBackend backend() const override { return GatherBackend::gl; }
    // Texels whose plane shows a mirror or glass come back with sees_specular set when
    // settings.gather.specular_bounces > 0 (ag::SpecularRoutedGather hands them to the rays).
    std::vector<GatherResult> gather(const std::vector<int>& texels) override;

    // Gathers the given texel records (indices into scene.atlas.texels) with the AIM texture
    // (atlas-sized RGBA32F). With `chart_texture` (LightmapTexture::charts()) the AIM is read
    // chart-aware, exactly like the CPU gather; without it, by plain bilinear filtering of the
    // dilated atlas. Results in the same order.
    std::vector<GatherResult> gather(const std::vector<int>& texels, GLuint aim_texture,
                                     GLuint chart_texture = 0);
    // The same at arbitrary points, with the AIM texture given at construction.
    std::vector<GatherResult> gather_points(const std::vector<GatherPoint>& points) override;

    int resolution() const { return resolution_; }
    int tiles_per_pass() const { return layers_; }
    // Limits a pass to `n` texels (1 = unbatched, for benchmarks); 0 = all tiles.
    void set_max_per_pass(int n) { max_per_pass_ = n; }

private:
    // The views of one gather: world-space centre (before the offset) and normal per texel.
    std::vector<GatherResult> gather_views(const std::vector<GatherPoint>& views,
                                           GLuint aim_texture, GLuint chart_texture);

    const Scene& scene_;
    const SceneMeshes& meshes_;
    const LightmapTexture* aim_;
    int resolution_, tiles_x_, level_, layers_;
    int max_per_pass_ = 0;
    float specular_tag_ = 0.0f;  // alpha per unit weight of mirror/glass pixels; 0 = not tagged
    bool distances_ = false;
    bool band_ = false;        // a second view per texel renders the band beyond the plane
    double weight_sum_ = 1.0;  // Σ w of the weight tables (the coverage, or 1 when corrected)
    Program program_;
    // With band_, layer layers_ + k holds texel k's band view (weights band_weights_).
    Texture color_, weights_, band_weights_, distance_;
    Renderbuffer depth_;
    Framebuffer fbo_;
};

}  // namespace ag::gpu
