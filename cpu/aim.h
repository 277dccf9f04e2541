// Approximated illumination maps (Larsen ch. 10): per texel, an N-nearest-neighbour density
// estimate over the photon hits of the texel's own surface, E = ΣΦ / (π r² f), stored as the
// diffusely reflected radiance L = ρ/π · E in the shared atlas layout. f is the fraction of the
// disc that lies on the surface's chart (the kNN estimate's boundary bias, which otherwise
// halves the estimate along chart edges: the room's creases and corners). Surfaces are rebuilt
// in order of Δf / area, above a threshold, under a per-frame budget. With aim.exact_direct the
// direct part comes from shadow rays over each texel and the kNN estimate counts bounced hits only.
// Texel parts inside or under another object (aim.covered_texels) hold no photons: they are left
// out of the flux scale (and with aim.covered_disc out of the kNN disc), and wholly covered texels
// take their neighbours' value.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <optional>
#include <vector>

#include "cpu/photon_map.h"
#include "cpu/ray_tracer.h"
#include "shared/mesh.h"
#include "shared/parallel.h"
#include "shared/scene.h"

namespace ag::cpu {

class Aim {
public:
    Aim(const Scene& scene, ThreadPool& pool);

    // Rebuilds the most-changed surfaces (Δf / area, above aim.delta_threshold relative to the
    // surface's flux) up to aim.surfaces_per_frame. Resets those surfaces' Δf. Returns texels
    // rebuilt; `surfaces_rebuilt` receives the surface count.
    int update(PhotonMaps& maps, int* surfaces_rebuilt = nullptr);
    // The same under explicit budgets: at most `max_surfaces` surfaces, and no further surface
    // once `max_texels` texels are rebuilt (at least one surface when any is due).
    int update(PhotonMaps& maps, int max_surfaces, int max_texels, int* surfaces_rebuilt);
    // Rebuilds surfaces in turn, whatever changed, from where the last call stopped, until
    // `max_texels` texels are rebuilt (at least one surface): brute force under a budget.
    int rebuild_round_robin(PhotonMaps& maps, int max_texels, int* surfaces_rebuilt);
    // Rebuilds every surface.
    int rebuild_all(PhotonMaps& maps);
    // Rebuilds one surface's texels from its hits and resets its Δf.
    int rebuild_surface(PhotonMaps& maps, int surface);

    // The hits added or removed since the surface's AIM was built, those that came back as they
    // were cancelled: their positions, and the Σ |energy| of the net changes in `energy`. None
    // where the changes overflowed (anything may have changed).
    static std::optional<std::vector<glm::vec3>> net_changes(const SurfaceHits& s,
                                                             double* energy = nullptr);

    // Per atlas texel (width × height, row-major): reflected radiance and irradiance.
    const std::vector<glm::vec3>& radiance() const { return radiance_; }
    const std::vector<glm::vec3>& irradiance() const { return irradiance_; }
    // Atlas texel indices (y·width + x) changed since the last call, for uploads.
    std::vector<int> take_dirty_texels();
    // Per texel record: its indirect irradiance estimate (energy of the hits that made at least
    // one bounce: the light a final gather there collects) as last built, −1 = never built; and
    // 5% of its surface's mean estimate then (the floor of a relative change). The IIM compares a
    // texel's estimate now with the one it had when the texel was last gathered.
    const std::vector<float>& indirect_estimates() const { return indirect_; }
    const std::vector<float>& indirect_floors() const { return indirect_floor_; }

    // The part of a texel's kNN disc that lies on its chart: its area and first and second
    // moments, in units of the disc (radius 1, area 1), and the tangent frame they are in.
    struct DiscPart {
        double area = 1.0;             // fraction of the disc on the chart
        glm::dvec2 first{0.0};         // ∫ u du over that part
        glm::dmat2 second{0.0};        // ∫ u uᵀ du over that part
        glm::vec3 b1{0.0f}, b2{0.0f};  // tangent axes of u
        uint64_t on = ~uint64_t(0);    // which of the disc's sample points count (bit i: point i)
    };
    // aim.covered_texels: per texel record, the share of its footprint (its parts on the chart,
    // in kCoverageSubdivision² cells) that is not inside or under another object, as of the last
    // rebuild (1 before the first). Empty when off.
    const std::vector<float>& open_fraction() const { return open_fraction_; }

private:
    // Estimates the surface's texels from its hits (all of them without `changed`; with it, only
    // those whose last kNN disc reaches one of the changed positions), rescales the surface to
    // its flux and writes radiance, irradiance and the indirect estimate of every texel. Resets
    // Δf and the change list. Returns the texels estimated.
    int estimate_surface(PhotonMaps& maps, int surface, const std::vector<glm::vec3>* changed);
    glm::vec3 albedo_of(int surface) const;

    // The part of the disc of radius `radius` around texel record `record`, in its tangent
    // plane, on the surface (its chart). Deterministic: a fixed pattern of points.
    DiscPart disc_on_surface(int record, double radius) const;
    // aim.exact_direct: the direct irradiance from the lights averaged over texel record
    // `record`'s footprint (a 4 × 4 grid of its points on the chart; points inside another
    // solid, such as the floor under a box, are left out), with hard shadows from every object.
    glm::vec3 direct_over_texel(int record) const;
    // aim.covered_texels: brings the covered cells up to date with the objects' placements (all
    // of them on the first call; after a move, the cells of the moved objects and those whose
    // normal ray crosses a moved object's old or new bounds) and marks the surfaces whose cells
    // changed, to be estimated again. Called before every rebuild.
    void sync_covered();
    // Tests the cells of chart `chart` (all, or those whose ray crosses one of `boxes`); returns
    // whether any changed.
    bool test_covered(int chart, const std::vector<Bounds>* boxes);

    const Scene& scene_;
    ThreadPool& pool_;
    std::vector<uint16_t> coverage_;  // texel_coverage_masks: which parts of texels are on charts
    std::vector<std::vector<int>> surface_texels_;  // per surface: indices into atlas.texels
    std::vector<glm::vec3> radiance_, irradiance_;
    std::vector<float> indirect_;        // per record: indirect irradiance (energy), −1 = never
    std::vector<float> indirect_floor_;  // per record: 5% of its surface's mean indirect_
    // Per atlas texel record: the mean of its object's albedo texture over the texel (1 without
    // one), so that the AIM's radiance is the texel's mean exitant radiance.
    std::vector<glm::vec3> texture_mean_;
    std::vector<int> dirty_;
    size_t round_robin_ = 0;  // next surface for rebuild_round_robin
    std::vector<char> dirty_flag_;
    // Per record, as last estimated: E and its bounced part before the surface's flux scale, and
    // the squared distance to the k-th nearest hit (infinite with fewer hits: any change
    // reaches it). Per surface: built at least once, and the albedo it was built with.
    std::vector<glm::vec3> raw_e_, raw_indirect_;
    std::vector<float> reach2_;
    std::vector<char> built_;
    std::vector<glm::vec3> built_albedo_;
    // aim.exact_direct: shadow rays for the direct part; aim.covered_texels: the covered test.
    std::unique_ptr<RayTracer> rays_;
    // aim.covered_texels (empty when off). Atlas-sized: the cells of each texel that are covered,
    // and those on the chart and not covered (what the kNN disc may count with covered_disc).
    std::vector<uint16_t> covered_, open_;
    std::vector<float> open_fraction_;   // per record, see open_fraction()
    std::vector<char> open_record_;      // per record: some part of it is open
    std::vector<char> covered_changed_;  // per surface: cells changed since its last estimate
    std::vector<Transform> covered_transforms_;  // per object: placement the cells were tested at
    std::vector<Bounds> covered_bounds_;         // per object: its world bounds then
    // Per chart, from the first test: the cells each of its triangles places (the first triangle
    // holding a cell's centre, in chart order), packed as (texel within the chart's rectangle)·16
    // + cell, and where each triangle's run starts. A re-test after a move skips the triangles
    // whose rays cannot reach a moved object's bounds without walking their cells again.
    std::vector<std::vector<uint32_t>> cell_claims_, claim_begin_;
    std::vector<uint64_t> disc_on_;  // per record: DiscPart::on of its last estimate
};

}  // namespace ag::cpu
