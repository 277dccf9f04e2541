// Every tunable of the pipeline, one struct per stage, defaults in one place (Tungsten style).
// The scene file's "settings" block maps onto these with snake_case keys; visit_settings() is the
// single list of fields that parsing, printing and documentation walk.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace ag {

enum class GatherBackend { automatic, gl, cpu };
inline constexpr std::array kGatherBackendNames = {"auto", "gl", "cpu"};

// How the hemi-plane gather accounts for the part of the hemisphere the plane misses
// (Larsen ch. 11: renormalise; Gautron 2006 Table 4.1: stretch the border pixels).
// Where the indirect term comes from (DESIGN.md "Indirect methods on one scene graph"): each is an
// ag::IndirectMethod of the pipeline. `iim`: Larsen's lightmaps gathered from AIMs (ch. 8-11);
// `gpu_pm`: photons traced on the GPU, binned into screen tiles, cone-filtered (Jimenez Kwast
// 2016).
enum class IndirectMethodKind { iim, gpu_pm, vpl, irradiance_cache };
inline constexpr std::array kIndirectMethodNames = {"iim", "gpu_pm", "vpl", "irradiance_cache"};

// GPU photon mapping's radiance estimate: `standard`, eq. 5.6 (E = Σ Φ w / ((1 − 2/3k) π r²));
// `kwast`, with the thesis code's extra factors (×100 photon power, 1/π at the bounce, N·L at the
// estimate), for comparing with his numbers only.
enum class GpuPmEstimator { standard, kwast };
inline constexpr std::array kGpuPmEstimatorNames = {"standard", "kwast"};
// Tile binning: `scatter`, each photon writes itself into the tiles its disc covers; `brute`, the
// thesis's every-photon-against-every-tile test (§5.3.3.1), kept for comparison.
enum class GpuPmBinning { scatter, brute };
inline constexpr std::array kGpuPmBinningNames = {"scatter", "brute"};
// `vpl`: a screen-space sum over virtual point lights with visibility (Barczak 2006).

// Where the VPLs come from (Barczak 2006 §4.1): `photons`, the stored hits of the first
// vpl.photons_per_group photons of every QMC group of the selective photon tracer, so the set
// follows edits through group invalidation; `random_walk`, the thesis's static set of cosine
// random walks (power × BRDF / paths, at most vpl.walk_bounces bounces), traced once.
enum class VplSource { photons, random_walk };
inline constexpr std::array kVplSourceNames = {"photons", "random_walk"};
// `irradiance_cache`: Gautron 2006's splatted irradiance cache records (docs/irradiance_cache.md).

// What irradiance cache records gather: the AIMs (every bounce the photons carry) or the lights'
// direct light on the surfaces the rays hit (one bounce, as Gautron's records).
enum class RcSource { aim, direct };
inline constexpr std::array kRcSourceNames = {"aim", "direct"};
// How pixels Σ w < a are found: GPU tiles (no read-back of the splat buffer) or the thesis's CPU
// scan of the read-back buffer.
enum class RcScan { gpu, cpu };
inline constexpr std::array kRcScanNames = {"gpu", "cpu"};
// How records are gathered: stratified rays (E, R_k, gradients, reprojection) or the GL hemi-plane
// with its distance output (E and R_k only; the AIMs only).
enum class RcGather { rays, gl };
inline constexpr std::array kRcGatherNames = {"rays", "gl"};

// The part of the hemisphere the hemi-plane misses (Gautron 2006, Table 4.1): counted black
// (`none`), left out of the mean (`renormalize`, Larsen), or read from the border pixels stretched
// out to the horizon (`stretch`: each border pixel perpendicular to its edge and the corner pixels
// over the corner quadrants, the plane's clamp-to-edge; `stretch_radial`: the border point at the
// missing direction's own azimuth). docs/irradiance_cache.md compares the two stretches.
// `band` renders the missing band itself: a second view through a wider plane of half-width
// band_half_width at the same resolution, weighted only outside the first plane, its border
// stretched over what is left (≈1.3% at 8). The stretches assume the horizon looks like the
// plane's border; a surface facing out of an open room or towards a far bright room sees
// otherwise (docs/fidelity.md, "Session 14").
enum class BorderCorrection { none, renormalize, stretch, stretch_radial, band };
inline constexpr std::array kBorderCorrectionNames = {"none", "renormalize", "stretch",
                                                      "stretch_radial", "band"};

// What the CPU gather samples: `full`, cosine-weighted rays over the whole hemisphere (no plane,
// no correction: the exact gather of the AIMs); `plane`, only directions through the hemi-plane
// of half-width plane_half_width, the rest handled by border_correction exactly as the GL gather
// does (for comparing the two and for Gautron's Table 4.1). The GL gather is always `plane`.
enum class GatherHemisphere { full, plane };
inline constexpr std::array kGatherHemisphereNames = {"full", "plane"};

struct PhotonSettings {
    int groups = 77;               // QMC photon groups per light (Larsen ch. 9, Cornell: 77)
    int photons_per_group = 40;    // photons per group (Cornell: 40)
    int max_bounces = 12;          // hard cap after Russian roulette
    int verify_per_frame = 1;      // photons per group re-traced and compared each frame
    int retrace_budget = 4000;     // photons re-traced for invalid groups per frame
    float path_tolerance = 1e-4f;  // hit positions agree within this fraction of the scene diagonal
    // Progressive photon refinement (docs/fidelity.md, session 17): once the scene is static and
    // every group is traced, the simulation grows to this many complete photon sets (layers of
    // groups × photons_per_group photons per light, each its own QMC points), one layer at a time
    // with the retrace budget repairs leave; each photon then carries Φ / (G·P·sets of its
    // group). An edit re-traces the groups it touches with one set (the others keep theirs) and
    // growth starts again once settled. 1 = off. 16 by default since session 22 (issue #12: the
    // photon noise of one set kept the whole image 1-1.5% off pt on some seeds, docs/fidelity.md).
    int refine_layers = 16;
    // With refine_layers > 1: an invalidated group is re-traced with every photon set it holds
    // (its photons count L times against the retrace budget, no regrowth after the edit; the
    // hits whose paths did not change cancel in the AIM) instead of dropping back to one set and
    // growing again (a quicker first repair, then L − 1 more AIM and IIM updates). Which settles
    // sooner depends on the scene (docs/fidelity.md, session 19).
    bool retrace_all_sets = false;
};

struct LightmapSettings {
    float texel_size = 0.0f;     // world units per texel; 0 = longest scene extent / 10
    float crease_angle = 30.0f;  // degrees: adjacent faces closer than this share a surface
    float chart_cone = 30.0f;    // degrees: a chart's normals stay within this of its mean
    int gutter = 1;              // free texels around every chart in the atlas
    // Adaptive density (docs/fidelity.md): charts that touch dynamic objects get texel_size /
    // refine_factor, nearest first, while the atlas stays within refine_budget × the uniform one.
    // The defaults (×4, budget 10, tiles of 1 base texel, reach 1) are the tiled layout under
    // which issue #12's regions hold against pt (docs/fidelity.md, sessions 18 and 22).
    int refine_factor = 4;         // 1 = one texel size everywhere
    float refine_distance = 1.0f;  // contact: within this many base texels of a partner
    float refine_budget = 10.0f;   // at most this × the uniform layout's texels
    // Density within a chart: with refine_tile > 0 a chart that touches a partner is cut along
    // its base texel grid into tiles of refine_tile × refine_tile base texels; the tiles near the
    // contact become one chart of finer texels, the rest stays one chart at the base size (its
    // triangles split along the cut). 0 = whole charts only.
    int refine_tile = 1;
    // With refine_tile: the tiles within refine_reach × a partner's height above the chart (how
    // far it stands out along the chart's normal) get the finer texels too: the band where the
    // partner's occlusion of the hemisphere, so the indirect light, still changes fast (a box's
    // shadow reaching past the contact). Whether a chart is cut follows the contact alone.
    // 0 = the contact only.
    float refine_reach = 1.0f;
};

struct AimSettings {
    // N nearest photon hits per texel. The thesis's range is 50–500; 25 halves the disc's area at
    // the default photon count, which the contact regions need (the cube within 5% of pt on every
    // photon seed, docs/fidelity.md), at √2 the per-texel noise that the IIM's gathers average.
    int knn = 25;
    int surfaces_per_frame = 4;     // AIM rebuilds per frame, by Δf / area
    float delta_threshold = 1e-3f;  // rebuild when Δf / surface flux exceeds this
    // Divide each texel's kNN flux by the part of its disc that lies on its chart (the room's
    // creases and corners), not by the whole π r² (aim.h, docs/fidelity.md).
    bool boundary_correction = true;
    // Where the disc is cut by a chart edge, fit a density that varies linearly across the disc
    // and take its value at the texel centre, not the mean over the cut disc (whose centroid lies
    // inside the chart): the local-linear estimate (aim.cpp). Off by default: it removes the
    // rims' overshoot at the texel centres but the settled frame's regions read no better
    // (docs/fidelity.md, "The rims' overshoot").
    bool boundary_linear = false;
    // The direct part of the AIM from shadow rays to the lights, averaged over the texel's
    // footprint, and the kNN density estimate over the hits that made at least one bounce only
    // (Jensen's split of direct and indirect light). The kNN disc otherwise smears every hard
    // shadow of a point light across several texels: the floor in the Cornell cube's shadow reads
    // 1.3-3.9x the truth at the texel centres, and the lit floor beside it 0.5-0.9x
    // (docs/fidelity.md, "Exact direct light in the AIM").
    bool exact_direct = false;
    // Texel parts inside or under another object (the floor under a box: a ray along the normal
    // meets a back face first, or a face within kCoveredGap texels) receive no photons and no one
    // sees them. They are left out of the per-surface flux scale (Σ E·area over the open parts
    // equals the surface's photon flux) and wholly covered texels take their chart neighbours'
    // radiance, so the gathers' bilinear lookups beside a contact read no dark texel
    // (docs/fidelity.md, "Session 16").
    bool covered_texels = true;
    // With covered_texels and boundary_correction: the kNN disc is cut where it reaches covered
    // parts too (no photon can land there), as it is at the chart's edges. Off by default: the mean
    // over the cut disc is the density at its centroid, away from the contact, where the light
    // near a contact falls towards it, so the texels beside a box read high (Cornell's floor within
    // 28 mm of the cube 1.53 of pt, the cube 1.11; docs/fidelity.md, "Session 16").
    bool covered_disc = false;
};

struct GatherSettings {
    GatherBackend backend = GatherBackend::automatic;
    float plane_half_width = 2.0f;  // hemi-plane half-width a at unit distance (a=2: 83%)
    int plane_resolution = 32;      // pixels across the hemi-plane
    BorderCorrection border_correction = BorderCorrection::band;
    float band_half_width = 8.0f;  // border_correction=band: the second view's half-width
    int texels_per_frame = 20;     // IIM texels gathered per frame (thesis: ≤ 20)
    int blend_frames = 4;          // frames over which a new IIM fades in
    int cpu_rays = 256;            // rays per texel for the CPU gather backend
    // The CPU gather keeps each texel's rays' first hits (about 24 bytes a ray) while the
    // geometry they crossed stays put: after an AIM-only change (a light, an albedo, photons
    // moved elsewhere) a texel is re-read, not re-traced, and after a move only the rays that
    // hit the moved object or cross its new bounds are traced again. Same result as tracing
    // all of them. 0 = off; an atlas whose cache would exceed this many MiB is not cached.
    int ray_cache_mb = 512;
    GatherHemisphere hemisphere = GatherHemisphere::full;  // CPU gather: whole hemisphere or plane
    // Mirror/glass bounces a gather ray follows to the diffuse surface it reads (Fresnel-weighted
    // reflection and refraction); 0 = specular objects are black to the gather. The GL gather
    // hands texels whose hemi-plane shows a specular object to the CPU gather when this is > 0.
    int specular_bounces = 6;
    // Gathers averaged per settled texel: once nothing is queued, texels whose inputs have not
    // changed are gathered again at other points of their footprint with other ray sets and the
    // results averaged, so a static scene's IIM noise keeps falling; 1 = one gather per texel.
    int refine_passes = 16;
    float refine_footprint = 0.5f;  // share of the texel's footprint refinement passes spread over
};

// Scheduling by time, not by counts (DESIGN.md): with a frame-time target the pipeline measures
// what drawing and each unit of work cost and fills the rest of the frame in priority order; the
// per-frame counts above then only cap the work when `counts_cap` is set.
struct ScheduleSettings {
    float frame_ms = 0.0f;    // frame-time target; 0 = no target: the fixed per-frame counts
    bool counts_cap = false;  // with a target, also hold the fixed counts as upper limits
    // With a target, a frame still waits for its photon work at its end, as without one: offline
    // runs that count frames (tests, converge) then see each result in a frame that does not
    // depend on how fast the worker threads ran. Interactive runs leave it off (#11).
    bool wait_for_workers = false;
};

struct IndirectSettings {
    IndirectMethodKind method = IndirectMethodKind::iim;
};

// GPU photon mapping (Jimenez Kwast 2016): photon paths per frame, accumulated while nothing
// changes; the influence radius as a fraction of the scene's diagonal (his r is in scene units).
struct GpuPmSettings {
    int paths = 1000;           // photon paths per frame (thesis baseline: 1000)
    int frames = 64;            // frames accumulated while the scene is static, then settled
    float radius = 0.05f;       // photon influence radius / scene diagonal
    int bounces = 1;            // indirect bounces stored (thesis: 1)
    int low_res = 2;            // low-resolution pass: 1/low_res per axis; 1 = full resolution only
    float edge_normal = 0.99f;  // refine where normals differ more (dot below this)
    float edge_distance = 0.1f;  // ... or the low-res sample lies off the plane by this × radius
    GpuPmEstimator estimator = GpuPmEstimator::standard;
    GpuPmBinning binning = GpuPmBinning::scatter;
};

// How VPL visibility is found: `gl`, hemispherical shadow maps (gpu::VplShadowMaps) and a
// per-pixel sum in a shader, every frame; `cpu`, exact Embree shadow rays per point and VPL.
enum class VplBackend { gl, cpu };
inline constexpr std::array kVplBackendNames = {"gl", "cpu"};
// The shadow maps' parameterisation of the hemisphere (Barczak §4.2, Fig. 4-3).
enum class VplMapKind { octahedral, paraboloid };
inline constexpr std::array kVplMapKindNames = {"octahedral", "paraboloid"};

struct VplSettings {
    VplSource source = VplSource::photons;
    VplBackend backend = VplBackend::gl;
    VplMapKind map = VplMapKind::octahedral;
    int map_size = 128;           // shadow-map texels across (thesis: 512 with 25-100 lights)
    int photons_per_group = 4;    // photons of each group whose hits become VPLs (power × P/k)
    int walk_paths = 275;         // random_walk: paths per light (thesis Fig. 5-10: 275 indirect)
    int walk_bounces = 5;         // random_walk: VPLs stored along each path at most (thesis: 5)
    float clamp = 0.0f;           // 1/d² is clamped at 1/clamp² (world units); 0 = no clamp
    int updates_per_frame = 100;  // K: VPLs whose visibility is recomputed per frame (thesis: 100)
    int resolution_divisor = 4;   // the screen-space term is computed at frame size / this
    bool tiles = true;    // gl: per-tile VPL lists (only VPLs facing a tile's points; exact)
    bool labels = false;  // gl, tiles: F/P/N labels (cpu::VisibilityDatabase) in the tile lists
    int interleave = 1;  // gl, tiles: n × n interleaved sampling + geometry-aware filter (1 = off)
};

// Irradiance cache splatting and temporal radiance caching (Gautron 2006 ch. 4, 5).
struct RcSettings {
    RcSource source = RcSource::aim;
    RcScan scan = RcScan::gpu;
    RcGather gather = RcGather::rays;
    float accuracy = 0.3f;  // a: zone of influence a·R_k, new records where Σ w < a
    int theta_strata = 16;  // M × N stratified rays per record (Ward & Heckbert 1992)
    int phi_strata = 64;
    float min_radius = 0.01f;  // R_k clamped to [min, max] × scene diagonal
    float max_radius = 0.25f;
    int records_per_frame = 400;  // new or replaced records per frame (thesis: ≤ 100)
    int shadow_samples = 4;       // `direct`: shadow rays per area light at each ray's hit
    // Temporal caching (ch. 5): a record made at t0 lives while 1/(|τ−1|(t−t0)) ≥ 1/a^t and
    // t − t0 < δt_max; τ = E(t0+1)/E(t0) from the next frame's transforms. 0 = no temporal
    // caching: every edit drops the records it may affect.
    float temporal_accuracy = 0.05f;  // a^t
    int max_lifespan = 0;             // δt_max in frames (Cube in a Box: 20); 1 = per frame
};

struct CausticSettings {
    int photons = 10000;  // caustic photons per light (thesis: 10,000)
    int frames = 8;       // all photons re-traced over this many frames (thesis: 8)
    int kernel_k = 3;     // filter half-size k of eq. 12.1
    // Per photon pixel, the half-size shrinks to the smallest window (≤ k) holding this many
    // photons, so a dense focus keeps its size at low resolution; 0: always k, as in the thesis.
    int kernel_photons = 8;
    int tile_size = 32;  // screen tile edge for occlusion-query culling, pixels
};

// How the direct term finds each light sample's shadow: `shadow_volumes`, stencil shadow volumes
// (Larsen ch. 13: exact per sample); `vpl`, a hemispherical octahedral shadow map per sample
// (Barczak 2006 §4.2: an area light as many point lights, soft shadows; suns keep their volumes).
enum class DirectMethod { shadow_volumes, vpl };
inline constexpr std::array kDirectMethodNames = {"shadow_volumes", "vpl"};

struct DirectSettings {
    int area_light_samples = 16;  // point lights standing in for one quad light
    bool shadows = true;          // shadows at all (off: every sample lights everything it faces)
    DirectMethod method = DirectMethod::shadow_volumes;
    int map_size = 256;  // vpl: shadow-map texels across, per light sample (two for a point light)
    // While nothing changes, each frame moves the quad and mesh lights' samples within their
    // strata and the direct term averages this many frames (then it is kept); 1 = a fixed set.
    int accumulate_frames = 64;
};

struct SpecularSettings {
    int cube_map_size = 128;  // per face (thesis: 128²)
};

struct FrameSettings {
    // Progressive antialiasing: while nothing the frame depends on changes, each frame moves the
    // projection by a sub-pixel offset (a box filter over the pixel) and the displayed frame and
    // its terms are the running mean of this many frames (then kept); 1 = one sample at each
    // pixel's centre, every frame drawn anew.
    int accumulate_frames = 64;
};

struct Settings {
    PhotonSettings photons;
    LightmapSettings lightmap;
    AimSettings aim;
    GatherSettings gather;
    IndirectSettings indirect;
    GpuPmSettings gpu_pm;
    VplSettings vpl;
    RcSettings rc;
    ScheduleSettings schedule;
    CausticSettings caustics;
    DirectSettings direct;
    SpecularSettings specular;
    FrameSettings frame;
    uint32_t seed = 1;  // scrambling seed; same seed and settings give the same result
    int threads = 0;    // worker threads; 0 = all cores. Results never depend on it.
};

// Range-checked field descriptions for visitors.
template <class T>
struct Field {
    const char* name;
    T& value;
    double min, max;
    const char* help;
};
template <class E, size_t N>
struct EnumField {
    const char* name;
    E& value;
    const std::array<const char*, N>& names;
    const char* help;
};

// Calls v.section(name, help), then v.field(Field{...}) / v.field(EnumField{...}) for every
// setting, then v.end_section(). Settings may be const-cast only by readers (a visitor that reads
// never writes).
template <class Visitor>
void visit_settings(Settings& s, Visitor& v) {
    v.section("photons", "selective photon tracing, Larsen ch. 9");
    v.field(Field<int>{"groups", s.photons.groups, 1, 1e6, "QMC photon groups per light"});
    v.field(
        Field<int>{"photons_per_group", s.photons.photons_per_group, 1, 1e6, "photons per group"});
    v.field(Field<int>{"max_bounces", s.photons.max_bounces, 1, 1000,
                       "bounce cap after Russian roulette"});
    v.field(Field<int>{"verify_per_frame", s.photons.verify_per_frame, 0, 1e6,
                       "photons per group verified each frame"});
    v.field(Field<int>{"retrace_budget", s.photons.retrace_budget, 1, 1e9,
                       "photons re-traced per frame for invalid groups"});
    v.field(Field<float>{"path_tolerance", s.photons.path_tolerance, 0, 1,
                         "path agreement, fraction of scene diagonal"});
    v.field(Field<int>{"refine_layers", s.photons.refine_layers, 1, 64,
                       "photon sets a static, settled scene grows to (1 = off)"});
    v.field(Field<bool>{"retrace_all_sets", s.photons.retrace_all_sets, 0, 1,
                        "an invalidated group is re-traced with all its photon sets"});
    v.end_section();
    v.section("lightmap", "surfaces and charts, Larsen ch. 8");
    v.field(Field<float>{"texel_size", s.lightmap.texel_size, 0, 1e30,
                         "world units per texel; 0 = longest scene extent / 10"});
    v.field(Field<float>{"crease_angle", s.lightmap.crease_angle, 0, 180,
                         "degrees; adjacent faces closer than this share a surface"});
    v.field(Field<float>{"chart_cone", s.lightmap.chart_cone, 1, 60,
                         "degrees; chart normals stay within this of the chart axis"});
    v.field(Field<int>{"gutter", s.lightmap.gutter, 1, 16, "free texels around every chart"});
    v.field(Field<int>{"refine_factor", s.lightmap.refine_factor, 1, 16,
                       "texel subdivision on charts touching dynamic objects; 1 = uniform"});
    v.field(Field<float>{"refine_distance", s.lightmap.refine_distance, 0, 1e6,
                         "contact distance, in texels of texel_size"});
    v.field(Field<float>{"refine_budget", s.lightmap.refine_budget, 1, 1e6,
                         "atlas texels at most this times the uniform layout's"});
    v.field(Field<int>{"refine_tile", s.lightmap.refine_tile, 0, 1024,
                       "refine only the tiles of this many texels near a contact; 0 = whole "
                       "charts"});
    v.field(Field<float>{"refine_reach", s.lightmap.refine_reach, 0, 1e6,
                         "with refine_tile: tiles within this times a partner's height are "
                         "refined too; 0 = the contact only"});
    v.end_section();
    v.section("aim", "approximated illumination maps, Larsen ch. 10");
    v.field(Field<int>{"knn", s.aim.knn, 1, 10000, "nearest photon hits per texel"});
    v.field(Field<int>{"surfaces_per_frame", s.aim.surfaces_per_frame, 1, 1e6,
                       "AIM rebuilds per frame"});
    v.field(Field<float>{"delta_threshold", s.aim.delta_threshold, 0, 1e30,
                         "rebuild when delta_f / surface flux exceeds this"});
    v.field(Field<bool>{"boundary_correction", s.aim.boundary_correction, 0, 1,
                        "density over the part of the kNN disc on the texel's chart"});
    v.field(Field<bool>{"boundary_linear", s.aim.boundary_linear, 0, 1,
                        "at chart edges, a linear density fit read at the texel centre"});
    v.field(Field<bool>{"exact_direct", s.aim.exact_direct, 0, 1,
                        "direct light by shadow rays over each texel, photons for the rest"});
    v.field(Field<bool>{"covered_texels", s.aim.covered_texels, 0, 1,
                        "texel parts inside or under another object out of the flux scale"});
    v.field(Field<bool>{"covered_disc", s.aim.covered_disc, 0, 1,
                        "with covered_texels: the kNN disc cut at covered parts too"});
    v.end_section();
    v.section("gather", "hemi-plane final gathering into IIMs, Larsen ch. 11");
    v.field(EnumField<GatherBackend, 3>{"backend", s.gather.backend, kGatherBackendNames,
                                        "gather backend"});
    v.field(Field<float>{"plane_half_width", s.gather.plane_half_width, 0.1, 100,
                         "hemi-plane half-width at unit distance"});
    v.field(Field<int>{"plane_resolution", s.gather.plane_resolution, 2, 1024,
                       "pixels across the hemi-plane"});
    v.field(EnumField<BorderCorrection, kBorderCorrectionNames.size()>{
        "border_correction", s.gather.border_correction, kBorderCorrectionNames,
        "missing-hemisphere correction"});
    v.field(Field<float>{"band_half_width", s.gather.band_half_width, 0.2, 1000,
                         "border_correction=band: half-width of the wider second view"});
    v.field(Field<int>{"texels_per_frame", s.gather.texels_per_frame, 1, 1e6,
                       "IIM texels gathered per frame"});
    v.field(Field<int>{"blend_frames", s.gather.blend_frames, 1, 1000,
                       "frames over which a new IIM fades in"});
    v.field(Field<int>{"cpu_rays", s.gather.cpu_rays, 1, 1e6, "rays per texel, CPU gather"});
    v.field(Field<int>{"ray_cache_mb", s.gather.ray_cache_mb, 0, 1 << 20,
                       "CPU gather: MiB for texels' cached first hits; 0 = off"});
    v.field(EnumField<GatherHemisphere, 2>{"hemisphere", s.gather.hemisphere,
                                           kGatherHemisphereNames,
                                           "CPU gather: full hemisphere or the hemi-plane"});
    v.field(Field<int>{"specular_bounces", s.gather.specular_bounces, 0, 64,
                       "mirror/glass bounces a gather ray follows; 0 = specular is black"});
    v.field(Field<int>{"refine_passes", s.gather.refine_passes, 1, 4096,
                       "gathers averaged per settled texel (footprint, ray sets)"});
    v.field(Field<float>{"refine_footprint", s.gather.refine_footprint, 0, 1,
                         "share of the texel footprint refinement passes spread over; 0 = centre"});
    v.end_section();
    v.section("schedule", "scheduling by frame time (DESIGN.md)");
    v.field(Field<float>{"frame_ms", s.schedule.frame_ms, 0, 1e6,
                         "frame-time target in ms; 0 = fixed per-frame counts"});
    v.field(Field<bool>{"counts_cap", s.schedule.counts_cap, 0, 1,
                        "with a target, the fixed counts still cap the work"});
    v.field(Field<bool>{"wait_for_workers", s.schedule.wait_for_workers, 0, 1,
                        "with a target, a frame still waits for its photon work (frame counts "
                        "that do not depend on thread timing)"});
    v.end_section();
    v.section("indirect", "the indirect term: which method supplies it");
    v.field(EnumField<IndirectMethodKind, kIndirectMethodNames.size()>{
        "method", s.indirect.method, kIndirectMethodNames, "indirect method"});
    v.end_section();
    v.section("gpu_pm", "GPU photon mapping, Jimenez Kwast 2016 (--indirect gpu_pm)");
    v.field(Field<int>{"paths", s.gpu_pm.paths, 1, 1e7, "photon paths per frame"});
    v.field(Field<int>{"frames", s.gpu_pm.frames, 1, 1e6,
                       "frames of photons accumulated while the scene is static"});
    v.field(Field<float>{"radius", s.gpu_pm.radius, 1e-5, 10,
                         "photon influence radius as a fraction of the scene diagonal"});
    v.field(Field<int>{"bounces", s.gpu_pm.bounces, 1, 16, "indirect bounces stored"});
    v.field(Field<int>{"low_res", s.gpu_pm.low_res, 1, 8,
                       "low-resolution estimate at 1/low_res per axis; 1 = full resolution"});
    v.field(Field<float>{"edge_normal", s.gpu_pm.edge_normal, -1, 1,
                         "refine at full resolution where normals' dot is below this"});
    v.field(Field<float>{"edge_distance", s.gpu_pm.edge_distance, 0, 100,
                         "refine where a low-res sample lies off the plane by this x radius"});
    v.field(EnumField<GpuPmEstimator, kGpuPmEstimatorNames.size()>{
        "estimator", s.gpu_pm.estimator, kGpuPmEstimatorNames,
        "standard (eq. 5.6) or kwast (his code's extra factors)"});
    v.field(EnumField<GpuPmBinning, kGpuPmBinningNames.size()>{
        "binning", s.gpu_pm.binning, kGpuPmBinningNames,
        "scatter (photon writes its tiles) or brute (every photon against every tile)"});
    v.end_section();
    v.section("vpl", "virtual point lights with visibility, Barczak 2006");
    v.field(EnumField<VplSource, kVplSourceNames.size()>{"source", s.vpl.source, kVplSourceNames,
                                                         "where the VPLs come from"});
    v.field(EnumField<VplBackend, kVplBackendNames.size()>{"backend", s.vpl.backend,
                                                           kVplBackendNames, "visibility backend"});
    v.field(EnumField<VplMapKind, kVplMapKindNames.size()>{"map", s.vpl.map, kVplMapKindNames,
                                                           "shadow-map parameterisation"});
    v.field(Field<int>{"map_size", s.vpl.map_size, 8, 4096, "shadow-map texels across"});
    v.field(Field<int>{"photons_per_group", s.vpl.photons_per_group, 1, 1e6,
                       "photons of each QMC group whose hits become VPLs"});
    v.field(Field<int>{"walk_paths", s.vpl.walk_paths, 1, 1e7, "random_walk: paths per light"});
    v.field(Field<int>{"walk_bounces", s.vpl.walk_bounces, 1, 1000,
                       "random_walk: VPLs along each path at most"});
    v.field(Field<float>{"clamp", s.vpl.clamp, 0, 1e30,
                         "1/d^2 clamped at 1/clamp^2 (world units); 0 = off"});
    v.field(Field<int>{"updates_per_frame", s.vpl.updates_per_frame, 1, 1e7,
                       "VPLs whose visibility is recomputed per frame"});
    v.field(Field<int>{"resolution_divisor", s.vpl.resolution_divisor, 1, 64,
                       "screen-space term at frame size / this"});
    v.field(Field<bool>{"tiles", s.vpl.tiles, 0, 1, "gl: per-tile lists of the VPLs facing it"});
    v.field(Field<bool>{"labels", s.vpl.labels, 0, 1,
                        "gl, tiles: F/P/N visibility labels in the tile lists"});
    v.field(Field<int>{"interleave", s.vpl.interleave, 1, 4,
                       "gl, tiles: n x n interleaved sampling with a geometry-aware filter"});
    v.end_section();
    v.section("rc", "irradiance cache splatting and temporal caching, Gautron 2006");
    v.field(EnumField<RcSource, kRcSourceNames.size()>{"source", s.rc.source, kRcSourceNames,
                                                       "what records gather: aim or direct"});
    v.field(EnumField<RcScan, kRcScanNames.size()>{"scan", s.rc.scan, kRcScanNames,
                                                   "cache-miss scan: gpu tiles or cpu read-back"});
    v.field(EnumField<RcGather, kRcGatherNames.size()>{
        "gather", s.rc.gather, kRcGatherNames, "records by rays or the GL hemi-plane (aim only)"});
    v.field(Field<float>{"accuracy", s.rc.accuracy, 0.01, 1.0, "a: records cover a·R_k"});
    v.field(Field<int>{"theta_strata", s.rc.theta_strata, 1, 1024, "record rays: strata in θ"});
    v.field(Field<int>{"phi_strata", s.rc.phi_strata, 3, 4096, "record rays: strata in φ"});
    v.field(Field<float>{"min_radius", s.rc.min_radius, 0, 10, "R_k ≥ this × scene diagonal"});
    v.field(Field<float>{"max_radius", s.rc.max_radius, 0, 10, "R_k ≤ this × scene diagonal"});
    v.field(Field<int>{"records_per_frame", s.rc.records_per_frame, 1, 1e8,
                       "records made or replaced per frame"});
    v.field(Field<int>{"shadow_samples", s.rc.shadow_samples, 1, 4096,
                       "direct: shadow rays per area light per hit"});
    v.field(Field<float>{"temporal_accuracy", s.rc.temporal_accuracy, 1e-6, 1e6,
                         "a^t: temporal accuracy"});
    v.field(Field<int>{"max_lifespan", s.rc.max_lifespan, 0, 1e6,
                       "δt_max in frames; 0 = no temporal caching"});
    v.end_section();
    v.section("caustics", "caustic photons and screen-space filtering, Larsen ch. 12");
    v.field(Field<int>{"photons", s.caustics.photons, 0, 1e8, "caustic photons per light"});
    v.field(
        Field<int>{"frames", s.caustics.frames, 1, 1000, "frames to re-trace all caustic photons"});
    v.field(Field<int>{"kernel_k", s.caustics.kernel_k, 0, 32, "filter half-size k (eq. 12.1)"});
    v.field(Field<int>{"kernel_photons", s.caustics.kernel_photons, 0, 1000000,
                       "photons a pixel's filter window must hold before it stops shrinking"});
    v.field(Field<int>{"tile_size", s.caustics.tile_size, 4, 512,
                       "tile edge for occlusion-query culling"});
    v.end_section();
    v.section("direct", "direct light and shadow volumes, Larsen ch. 13");
    v.field(Field<int>{"area_light_samples", s.direct.area_light_samples, 1, 4096,
                       "point lights per quad light"});
    v.field(Field<bool>{"shadows", s.direct.shadows, 0, 1, "shadows (volumes or maps)"});
    v.field(EnumField<DirectMethod, kDirectMethodNames.size()>{
        "method", s.direct.method, kDirectMethodNames, "shadow_volumes | vpl (shadow maps)"});
    v.field(Field<int>{"map_size", s.direct.map_size, 8, 4096,
                       "vpl: shadow-map texels across per light sample"});
    v.field(Field<int>{"accumulate_frames", s.direct.accumulate_frames, 1, 65536,
                       "frames of moved area-light samples the direct term averages"});
    v.end_section();
    v.section("specular", "cube-map reflection and refraction, Larsen ch. 13");
    v.field(Field<int>{"cube_map_size", s.specular.cube_map_size, 8, 4096, "cube map face size"});
    v.end_section();
    v.section("frame", "the composed frame, Larsen ch. 13");
    v.field(Field<int>{"accumulate_frames", s.frame.accumulate_frames, 1, 65536,
                       "frames of sub-pixel offsets the displayed frame averages (antialiasing)"});
    v.end_section();
    v.section("", "");
    v.field(Field<uint32_t>{"seed", s.seed, 0, 4294967295.0, "scrambling seed"});
    v.field(Field<int>{"threads", s.threads, 0, 1024, "worker threads; 0 = all cores"});
    v.end_section();
}

// The effective texel size (resolves texel_size = 0).
float effective_texel_size(const Settings& settings, float longest_scene_extent);

// Settings as indented JSON text (for `afterglow info --settings` and docs).
std::string settings_to_json(const Settings& settings);

}  // namespace ag
