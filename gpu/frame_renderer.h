// The composed frame (Larsen ch. 13, eq. 13.2): L = L_indirect + L_caustics + L_specular
// + Σ_lights L_direct(i)·shadow(i). Each term is rendered into its own float attachment, so the
// component images (thesis Fig. 13.1) sum exactly to the frame. Direct light is shaded per pixel
// for every point light (quad lights as a grid of point lights) with hard shadows from stencil
// shadow volumes; indirect light is IIM × albedo; mirrors and glass trace through dynamic
// distance cube maps (both glass interfaces; the cube maps hold shadowed direct light).
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "gpu/gl_objects.h"
#include "gpu/scene_meshes.h"
#include "gpu/shadow_volumes.h"
#include "gpu/vpl_shadow_maps.h"
#include "shared/frame_terms.h"
#include "shared/host_device_shared.h"
#include "shared/image.h"
#include "shared/scene.h"

namespace ag::gpu {

// A point light standing in for a light or a piece of a quad light: intensity I (W/sr) towards
// directions in front of `normal` (one-sided, scaled by the cosine) or everywhere.
// A sun is a directional sample: `position` holds the unit direction towards it, `intensity` its
// irradiance E, and there is no 1/d². A spot scales I by its falloff around `normal` (its axis).
struct LightSample {
    glm::vec3 position{0.0f};
    glm::vec3 intensity{0.0f};
    glm::vec3 normal{0.0f};
    bool one_sided = false;
    bool directional = false;
    glm::vec2 cone{-2.0f, -1.0f};  // spot: (cos outer, cos inner); a cone of every direction else
    bool operator==(const LightSample&) const = default;
};

// The enabled lights as point samples (quad lights: an n×n grid, n² ≈ area_light_samples; mesh
// lights: n² strata of a rank-1 lattice over their area); at most kMaxLightSamples (scene files
// needing more are rejected on load; an InputError otherwise). `jitter` ∈ [0,1)² places each
// area-light sample within its stratum (0.5, 0.5: the centres).
std::vector<LightSample> light_samples(const Scene& scene, glm::vec2 jitter = glm::vec2(0.5f));
// Where frame k of an accumulation puts its samples within their strata: the centres for k = 0,
// then the Halton points (bases 2, 3) shifted by one half, so the frames fill each stratum evenly.
glm::vec2 light_sample_jitter(int frame);
// Where frame k of an accumulation samples each pixel, in pixels from its centre, in
// [−0.5, 0.5)²: the centre for k = 0, then the Halton points in bases 5 and 7 shifted by one
// half (other bases than the light samples', so the pair of offsets fills pixel × light
// jointly, not along a diagonal). Their mean is a box filter over the pixel, the references'.
glm::vec2 pixel_jitter(int frame);

// Where an indirect method's term lives (DESIGN.md "Indirect methods on one scene graph"): an
// atlas-sized lightmap read at each surface point (the IIM), or a frame-sized image read at each
// pixel. Both hold E_indirect/π; the frame multiplies by the albedo.
enum class IndirectSpace { lightmap, screen };
struct IndirectTerm {
    GLuint texture = 0;
    IndirectSpace space = IndirectSpace::lightmap;
    // Changes whenever the texture's contents do; 0 = not tracked (then the renderer treats the
    // term as changed every frame). Lets the cube maps be kept while nothing they see changes.
    uint64_t revision = 0;
};

struct FrameImages {
    Image frame;
    std::array<Image, kFrameTermCount> aov;  // indexed by FrameTerm
};

class FrameRenderer {
public:
    FrameRenderer(const Scene& scene, const SceneMeshes& meshes, int width, int height);

    // Renders the current scene. `iim` and `caustics` are GL textures (atlas-sized IIM;
    // screen-sized caustic radiance, or 0 for none).
    void render(GLuint iim, GLuint caustics = 0);
    // The same with the indirect term in lightmap or screen space. `caustics_revision` changes
    // whenever the caustic texture's contents do; 0 = not tracked (changed every frame).
    // `relit_faces`: at most this many cube-map faces draw their direct light again in this
    // render (kRelitFacesPerFrame; 0 in a frame that has other drawing to catch up on).
    void render(const IndirectTerm& indirect, GLuint caustics = 0, uint64_t caustics_revision = 0,
                size_t relit_faces = kRelitFacesPerFrame);
    FrameImages read_back() const;  // rows top-first, linear radiance
    // The `volume` term from a media method (rows top-first, width × height), composed into
    // every later frame; an empty image sets it back to zero (the frame has no media of its own).
    // `transmittance` (the same size, or empty for none): each pixel's camera-ray transmittance
    // up to the surface it meets, which attenuates the other four terms, as in pt's components
    // (the term through glass, set_specular_through_glass, carries its own).
    void set_volume(const Image& volume, const Image& transmittance = Image());
    // Light a media method adds to the `indirect` term (rows top-first, width × height): what
    // the fog scatters onto the surface each pixel shows, added in every later frame after the
    // running mean and before set_volume's transmittance dims it; an empty image adds nothing.
    void set_media_indirect(const Image& indirect);
    // A media method's `specular` term (rows top-first, width × height) at the pixels where
    // `covered` (row-major, top-first) is set — those whose camera ray meets glass first, traced
    // through the smoothed index and the fog — in place of the cube maps' term there, in every
    // later frame; an empty image sets it back to the cube maps' everywhere.
    void set_specular_through_glass(const Image& specular, const std::vector<uint8_t>& covered);

    int width() const { return width_; }
    int height() const { return height_; }
    GLuint framebuffer() const { return fbo_.get(); }
    GLuint aov_texture(FrameTerm t) const { return aov_[size_t(t)].get(); }
    GLuint frame_texture() const { return frame_.get(); }  // the composed L, for display
    // Whether every cube-map face shows the scene, lights and indirect term of the last render
    // (they follow changes a share of faces a frame).
    bool cube_maps_current() const;
    // When the scene, the lights or the indirect term's revision change, the cube-map faces
    // showing an older state are rendered again round robin, all of them within this many
    // frames: a converging IIM changes every frame, an edited scene often, and the six faces
    // per mirror or glass object cost more than the frame itself. The frame of an edit after
    // frames without one renders none (it draws every light's direct light anew). A face keeps
    // the direct light it sees and draws it again only after an edit or a change of the light
    // samples, one such face a frame (kRelitFacesPerFrame): after an edit the faces follow
    // within max(kIndirectRefreshFrames, 6 × mirror and glass objects) + 1 frames. A new term
    // texture is rendered whole at once.
    static constexpr size_t kIndirectRefreshFrames = 4;
    static constexpr size_t kRelitFacesPerFrame = 1;
    size_t faces_relit() const { return faces_relit_; }  // by the last render
    // What the last render's cube-map faces took (ms, after glFinish) where it re-lit any; 0
    // otherwise.
    double cube_faces_ms() const { return cube_faces_ms_; }
    // Cube-map faces whose stored direct light is older than the last render's scene and
    // light samples (they wait for their turn to draw it again).
    size_t faces_to_relight() const;
    // Frames in the running mean the last render showed (1: that frame alone), and whether the
    // mean is complete (as many frames as the settings ask; later renders keep it as it is).
    int accumulated_frames() const { return mean_frames_; }
    bool accumulation_complete() const { return mean_complete_; }
    // Whether the last render() drew the frame's passes; false when the accumulated mean was
    // complete and kept as it was (a frame that costs next to nothing to draw).
    bool drew() const { return drew_; }
    // Whether it drew the direct light anew (shadow volumes or maps for every light): the frame
    // after an edit always does, a frame of a complete direct mean does not. It costs several
    // times a frame that does not (the conference room at 64²: 154 ms against 50 ms).
    bool drew_direct() const { return drew_direct_; }
    // How the frame draws the direct light: deferred, one full-screen pass per light sample over
    // the G-buffer's surface, or forward, every diffuse object again per light sample (as the
    // cube maps are); the same arithmetic at the same fragments. `automatic` defers where the
    // forward passes would rasterise more triangles than the frame has pixels (light samples ×
    // diffuse triangles > pixels): an edit's frame of the conference room at 64² draws in 35 ms
    // deferred against 121 ms forward, of bumpy_133k_box at 96² in 19 against 27 ms, while
    // Cornell and two_rooms at 96² draw 4–6% faster forward (`afterglow bench frame`).
    enum class DirectPass { automatic, deferred, forward };
    void set_direct_pass(DirectPass pass) { direct_pass_ = pass; }

private:
    // Renders the listed faces (object × 6 + face, GL face order).
    void render_cube_maps(GLuint iim, const std::vector<LightSample>& lights,
                          const std::vector<int>& faces);
    // The faces to render for this scene version, term and lights: all of them for a new term
    // texture, else a share of those behind (kIndirectRefreshFrames), else none.
    std::vector<int> cube_faces_to_render(const IndirectTerm& indirect,
                                          const std::vector<LightSample>& lights,
                                          size_t relit_faces);
    glm::vec3 cube_centre(size_t object) const;  // where its cube maps are rendered from (world)
    // Adds each light's direct light on the diffuse objects into `draw_buffer` of the bound
    // framebuffer, outside its shadow volumes (the depth buffer must hold the scene): forward,
    // drawing the objects again per light (the cube maps), or `deferred`, one full-screen pass
    // per light over the surface the frame's G-buffer pass left (into the direct term; the
    // frame's framebuffer is bound again after).
    void add_direct_light(const std::vector<LightSample>& lights, const glm::mat4& view_projection,
                          GLenum draw_buffer, bool deferred = false);
    void draw_shadow_volumes(const LightSample& light, const glm::mat4& view_projection);
    // direct.method vpl (Barczak §4.2): renders a hemispherical shadow map for each light sample
    // that is not a sun (one about a one-sided sample's normal, two back to back for a point
    // light) unless the maps already show these samples in this scene version. Call outside a
    // scene pass: it binds its own framebuffer. Returns whether the samples have maps.
    bool update_light_maps(const std::vector<LightSample>& lights);
    void set_light_uniforms(const Program& p, const std::vector<LightSample>& lights) const;
    // Progressive accumulation: this frame's terms (the direct one alone, or all of them)
    // averaged into the running mean of the frames since the last restart, which then replaces
    // them in the term attachments. With `fresh` false nothing new was drawn and the mean is
    // copied back as it is.
    void accumulate(bool fresh, bool all_terms);

    const Scene& scene_;
    const SceneMeshes& meshes_;
    int width_, height_;
    Program gbuffer_, gbuffer_specular_, lighting_, volume_, environment_, inner_;
    Program gbuffer_surface_, lighting_deferred_, lighting_deferred_mapped_;
    // The G-buffer's surface (attachments kFrameTermCount…: world position, unit normal, albedo
    // with alpha 1 where a diffuse surface is) and the deferred lighting's framebuffer.
    std::array<Texture, 3> surface_;
    Framebuffer lighting_fbo_;
    void compose();
    // One full-screen pass of `program` over the frame's framebuffer, into the terms `terms`
    // selects, reading `texture` at unit 0 as `sampler`; blending as the caller set it, depth and
    // stencil tests off during the pass (depth on after), every term drawn to again after.
    void draw_full_screen(const Program& program, const char* sampler, GLuint texture,
                          const std::array<bool, kFrameTermCount>& terms);

    std::array<Texture, kFrameTermCount> aov_;  // indexed by FrameTerm
    std::vector<glm::vec4> volume_rgba_;        // set_volume's term, rows bottom-first
    // set_volume's transmittance (rows bottom-first; empty: none), its texture and the pass that
    // multiplies the terms by it.
    std::vector<glm::vec4> transmittance_rgba_;
    Texture transmittance_texture_;
    Program attenuate_;
    // set_media_indirect's term (rows bottom-first; empty: none), its texture and the pass that
    // adds it.
    std::vector<glm::vec4> media_indirect_rgba_;
    Texture media_indirect_texture_;
    Program add_indirect_;
    // set_specular_through_glass's term (alpha: covered), rows bottom-first, and its texture.
    std::vector<glm::vec4> glass_specular_rgba_;
    Texture glass_specular_texture_;
    Program glass_specular_;
    Texture frame_;
    Framebuffer compose_fbo_;
    VertexArray empty_vao_;
    Program compose_;
    Renderbuffer depth_stencil_;
    Framebuffer fbo_;
    std::vector<ShadowCaster> casters_;
    std::vector<glm::mat4> caster_models_;  // where the objects were at the last volumes drawn
    SoupWeld soup_weld_;                    // made where the soup casters are in caster_models_
    std::vector<Bounds> object_bounds_;     // per object, its mesh's bounds (object space)
    // direct.method vpl: the light samples' shadow maps (made on first use) and what they show.
    std::unique_ptr<VplShadowMaps> light_maps_;
    std::vector<LightSample> mapped_lights_;
    std::vector<int> light_map_layer_;  // per light sample: its first layer, −1 for a sun
    uint64_t mapped_version_ = 0;
    bool maps_valid_ = false;
    Program lighting_mapped_;
    Buffer volume_vbo_;
    VertexArray volume_vao_;
    // Cube maps, one per specular object (index by object; empty for diffuse objects).
    std::vector<Texture> cube_maps_;
    // Glass only: its own surface seen from the centre (outward normal, distance).
    std::vector<Texture> inner_maps_;
    std::vector<float> cube_radii_;  // bounding radius around the centre
    Renderbuffer cube_depth_;
    struct CubeMapKey {
        uint64_t scene_version = 0, revision = 0;
        GLuint texture = 0;
        IndirectSpace space = IndirectSpace::lightmap;
        std::vector<LightSample> lights;
        bool valid = false;
    } cube_key_;
    uint64_t generation_ = 0;                // moves on with every change of what the cube maps see
    std::vector<uint64_t> face_generation_;  // per object × 6 faces: the generation shown
    // Per specular object, the direct light each face sees (6 layers, the faces' order), and
    // per face the generation of the scene and light samples it holds: the faces follow the
    // indirect term every frame and draw the direct light (shadow volumes, a pass per light)
    // only when it changed (two_rooms' mirror ball at 128²: 8.6 of a face's 9.9 ms).
    std::vector<Texture> cube_direct_;
    std::vector<uint64_t> face_direct_generation_;
    CubeMapKey direct_key_;  // the scene version and light samples of direct_generation_
    uint64_t direct_generation_ = 0;
    int last_face_ = -1;        // the face the round robin rendered last
    bool last_edited_ = false;  // the last render's scene version was new
    Framebuffer cube_fbo_;
    float near_ = 1.0f;

    // The running mean of the terms (ping-pong: one read, one written; one texture per term) and
    // what it is the mean of: the frames drawn since anything in MeanKey last changed.
    std::array<std::array<Texture, kFrameTermCount>, 2> mean_;
    std::array<Framebuffer, 2> mean_fbo_;
    int mean_current_ = 0;
    Program mean_program_;
    // What restarts the mean. Always: the scene version (every edit: objects, materials, lights,
    // camera, settings through the edit API) and the settings read here. With all terms
    // accumulated (frame.accumulate_frames > 1, and only from the second frame in which all of
    // `shown_key_` stood still) also the camera, the indirect term (texture, space, revision),
    // the caustic texture and its revision, and the cube maps (a face rendered, or faces still
    // behind): whatever changes the frame's content.
    struct MeanKey {
        uint64_t scene_version = 0;
        int area_light_samples = 0, direct_frames = 0, frame_frames = 0;
        bool shadows = false, all_terms = false;
        glm::vec3 eye{0.0f}, target{0.0f}, up{0.0f};
        float fov_y = 0.0f;
        GLuint indirect = 0, caustics = 0;
        IndirectSpace space = IndirectSpace::lightmap;
        uint64_t indirect_revision = 0, caustics_revision = 0, cube_generation = 0;
        bool cube_current = false;
        bool operator==(const MeanKey&) const = default;
    } mean_key_, shown_key_;
    int mean_frames_ = 0;  // frames in the mean
    bool mean_complete_ = false;
    bool drew_ = false;
    bool drew_direct_ = false;
    size_t faces_relit_ = 0;
    double cube_faces_ms_ = 0.0;
    DirectPass direct_pass_ = DirectPass::automatic;
    size_t diffuse_triangles_ = 0;  // of the diffuse objects, which the forward passes draw
};

}  // namespace ag::gpu
