// The indirect term as a screen-space sum over virtual point lights with visibility (Barczak
// 2006 §4.3): E(x) = Σ_i Φ_i/π · G(x, i) · V(x, i), computed at the visible points of a G-buffer
// (frame size / vpl.resolution_divisor) and read by the frame per pixel. VPLs come from the
// selective photon tracer's groups (cpu::group_vpls), one slot per (light, group), so an edit
// that invalidates a group changes only its slot; or from the thesis's static random walks.
// A slot is refreshed when its VPLs change or a moved object may change what they see, at most
// vpl.updates_per_frame VPLs a frame, brightest × longest stale first (Barczak §4.6's shadow-map
// update priority), so the term is current ⌈N/K⌉ frames after an edit. Backends: `gl` re-renders
// a refreshed slot's shadow maps and sums every VPL per pixel in a shader each frame; `cpu`
// recomputes the slot's contribution with exact Embree visibility and keeps it until the next
// refresh.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "cpu/ray_tracer.h"
#include "cpu/vpl_shading.h"
#include "cpu/vpl_source.h"
#include "cpu/vpl_visibility.h"
#include "gpu/gl_objects.h"
#include "gpu/scene_meshes.h"
#include "gpu/vpl_gather.h"
#include "gpu/vpl_shadow_maps.h"
#include "shared/parallel.h"
#include "shared/pipeline/indirect_method.h"

namespace ag {

class VplMethod final : public IndirectMethod {
public:
    // `width` × `height`: the frame the term is composed into.
    VplMethod(const Scene& scene, const gpu::SceneMeshes& meshes, int width, int height);

    IndirectMethodKind kind() const override { return IndirectMethodKind::vpl; }
    void update(const IndirectInputs& in, PipelineStats& stats) override;
    void hand_over(cpu::PhotonSimulation& photons, PipelineStats& stats) override;
    void invalidate_all() override;
    void prime(cpu::PhotonSimulation& photons, uint64_t frame) override;
    gpu::IndirectTerm term() const override;
    bool settled() const override { return stale_vpls() == 0 && stale_slots() == 0; }
    uint64_t changes_seen() const override { return seen_sequence_; }

    // The VPLs the term shows now, slot by slot (for the VPL view and tests).
    std::vector<Vpl> vpls() const;
    int vpl_count() const;
    int stale_slots() const;
    int stale_vpls() const;  // VPLs of stale slots (their shown or pending set, the larger)
    // Σ over shown slots of what vpl.clamp removed / the unclamped energy (0 without a clamp).
    double clamp_bias() const;
    int term_width() const { return tw_; }
    int term_height() const { return th_; }
    // E (W/m², rows top-first) at the G-buffer points as shown now (read back on the GL backend).
    std::vector<glm::vec3> irradiance() const;
    VplBackend backend() const { return backend_; }
    const gpu::VplShadowMaps* shadow_maps() const { return maps_.get(); }
    const std::vector<cpu::SurfacePoint>& points() const { return points_; }

private:
    struct Slot {
        std::vector<Vpl> shown, next;  // `next`: the VPLs to show once it is updated
        bool has_next = false;
        bool shown_once = false;  // refreshed at least once (an empty set is then current)
        bool stale = false;
        uint64_t stale_since = 0;
        std::vector<glm::vec3> e;  // its contribution at every point
        double energy = 0.0, clamped = 0.0;
        double brightness = 0.0;    // max channel of Σ power (the priority's "intensity")
        int layer = 0, layers = 0;  // GL: its shadow-map layers [layer, layer + layers)
    };

    // Casts the G-buffer's camera rays; returns the points that differ from before.
    std::vector<size_t> make_points();
    // Re-shades every slot's shown VPLs at `changed` points only (a moved object uncovered or
    // covered them: their sum must be whole at once, not over frames).
    void reshade_points(const std::vector<size_t>& changed);
    // Marks a slot for recomputation (keeping how long it has been stale).
    void mark(Slot& s, uint64_t frame);
    void take_vpls(cpu::PhotonSimulation& photons, uint64_t frame);
    // Shows the slot's pending VPLs and recomputes what they give (CPU: its contribution; GL:
    // its VPL records and shadow maps).
    void refresh(Slot& s);
    // Refreshes these slots; GL: then uploads the VPL records and renders their maps.
    void refresh(const std::vector<size_t>& slots);
    void shade(Slot& s);
    // GL: gives every slot room for its VPLs (re-laying all out, and re-rendering all maps, when
    // one outgrows its room); returns true if the layout changed.
    bool layout();
    void render_maps(const Slot& s);
    void upload();
    void upload_points();
    // GL, vpl.tiles: rebuilds the tile lists (and with vpl.labels the F/P/N database) for the
    // VPL records and points now.
    void build_tiles();
    // Reads scene changes: true if an object moved (visibility may change for every VPL).
    bool read_changes();

    const Scene& scene_;
    VplBackend backend_;
    int width_, height_, tw_, th_;
    cpu::RayTracer rays_;
    ThreadPool pool_;
    std::vector<cpu::SurfacePoint> points_;  // [y * tw + x], y top-first; zero normal: none
    std::vector<Slot> slots_;
    std::vector<glm::vec3> sum_;
    gpu::Texture texture_;  // CPU backend: the uploaded sum
    std::unique_ptr<gpu::VplShadowMaps> maps_;
    std::unique_ptr<gpu::VplGather> gather_;
    std::vector<Vpl> records_;  // GL: one per shadow-map layer (unused layers: zero power)
    bool records_dirty_ = false;
    bool tiles_dirty_ = true;        // GL, vpl.tiles: records or points changed since build_tiles()
    std::vector<cpu::RayHit> hits_;  // the G-buffer rays' hits (vpl.labels: the points' patches)
    std::unique_ptr<cpu::VisibilityDatabase> database_;
    uint64_t revision_ = 1;
    uint64_t camera_version_ = 0;
    uint64_t seen_sequence_ = 0;
    uint64_t frame_ = 0;
    size_t round_robin_ = 0;  // full_budget: next slot
};

}  // namespace ag
