// The indirect term by radiance cache splatting and temporal radiance caching (Gautron 2006
// ch. 4, 5; docs/irradiance_cache.md): irradiance records gathered by ray casting from the AIMs or
// from direct light (cpu::IrradianceGather), splatted on the GPU into a screen-space term
// (gpu::RadianceCacheSplat), new records where the splat leaves pixels uncovered. Records are
// view-independent and kept across frames: with temporal caching each lives for the frames its
// reprojected change rate τ allows and is then replaced in place.
#pragma once

#include <memory>
#include <vector>

#include "cpu/irradiance_gather.h"
#include "cpu/ray_tracer.h"
#include "gpu/hemi_plane_gather.h"
#include "gpu/lightmap_texture.h"
#include "gpu/radiance_cache_splat.h"
#include "gpu/scene_meshes.h"
#include "shared/parallel.h"
#include "shared/pipeline/indirect_method.h"

namespace ag {

struct IrradianceCacheStats {
    int records = 0;            // in the cache after the frame
    int added = 0;              // new records this frame (cache misses)
    int replaced = 0;           // expired records recomputed in place
    int dropped = 0;            // records removed by edits
    int deleted = 0;            // expired records no pixel used any more, deleted
    int expired_pending = 0;    // expired records left for later frames (budget)
    uint64_t records_made = 0;  // every record ever computed (added + replaced)
    double splat_ms = 0.0, scan_ms = 0.0, gather_ms = 0.0;
    bool uncovered_left = false;  // the scan stopped at its budget
};

class IrradianceCacheMethod final : public IndirectMethod {
public:
    // `aim_values` (atlas-sized) are the AIMs as handed over (rc.source aim); the term is
    // width × height, the frame's size.
    IrradianceCacheMethod(const Scene& scene, const gpu::SceneMeshes& meshes,
                          const std::vector<glm::vec3>& aim_values, int width, int height);

    IndirectMethodKind kind() const override { return IndirectMethodKind::irradiance_cache; }
    void update(const IndirectInputs& in, PipelineStats& stats) override;
    void hand_over(cpu::PhotonSimulation& photons, PipelineStats& stats) override;
    void invalidate_all() override { records_.clear(); }
    void prime(cpu::PhotonSimulation& photons, uint64_t frame) override;
    gpu::IndirectTerm term() const override;
    bool settled() const override;
    uint64_t changes_seen() const override { return seen_sequence_; }

    // The scene one frame ahead (the edit script run ahead; Gautron's "predefined animation"),
    // or null: then records near an object that moves expire at once.
    bool wants_lookahead() const override { return scene_.settings.rc.max_lifespan > 0; }
    void set_lookahead(const Scene* next) override { lookahead_ = next; }

    const std::vector<IrradianceRecord>& records() const { return records_; }
    const IrradianceCacheStats& last_stats() const { return stats_; }
    const gpu::RadianceCacheSplat& splat() const { return splat_; }
    // The viewer's picture of the records and their zones (gpu::RadianceCacheSplat).
    GLuint render_record_view() {
        splat_.render_record_view(records_, scene_.settings.rc.accuracy);
        return splat_.record_view();
    }
    // Reprojected E(t+1)/π and the record it was made for, for every record made by the last
    // update() with a look-ahead (Table 5.1's error is measured against a gather at t+1).
    struct Prediction {
        IrradianceRecord record;
        glm::vec3 predicted{0.0f};
        uint32_t key = 0;  // the gather's jitter key, so a gather at t+1 repeats its strata
    };
    const std::vector<Prediction>& last_predictions() const { return predictions_; }
    cpu::RecordRadiance radiance_source(const Scene& scene, const cpu::RayTracer& rays) const;
    cpu::RecordGatherOptions gather_options() const;

private:
    IrradianceRecord make_record(const GatherPoint& at, int frame);
    IrradianceRecord plane_record(const GatherPoint& at);
    void read_changes();
    void run(int frame, int budget, bool everything);

    const Scene& scene_;
    const std::vector<glm::vec3>& aim_;
    gpu::RadianceCacheSplat splat_;
    cpu::RayTracer rays_;
    ThreadPool pool_{1};  // beside the photon work, like the IIM's CPU gather
    cpu::IrradianceGather gather_;
    // rc.gather = gl: the AIMs as a texture and a hemi-plane gather with the distance output.
    std::unique_ptr<gpu::LightmapTexture> aim_texture_;
    std::unique_ptr<gpu::HemiPlaneGather> plane_;
    bool aim_texture_stale_ = true;
    std::vector<IrradianceRecord> records_;
    std::vector<Prediction> predictions_;
    const Scene* lookahead_ = nullptr;
    uint64_t seen_sequence_ = 0, version_ = 0, revision_ = 1;
    bool aim_stale_ = false;
    PipelineMode mode_ = PipelineMode::selective;
    IrradianceCacheStats stats_;
};

}  // namespace ag
