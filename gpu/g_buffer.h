// The G-buffer shared by the screen-space passes (caustics, Larsen ch. 12; the photon tiles and
// cone filter of Jimenez Kwast 2016 §5.2, Fig. 5.2): one scene pass writing, per pixel, the world
// position, the surface (albedo and the world area the pixel covers, eq. 12.2), the world normal
// with the linear view depth, and the ids (object, material, material type), over one
// depth-stencil buffer that later passes may attach to mark pixels.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "gpu/scene_meshes.h"
#include "shared/camera.h"
#include "shared/scene.h"

namespace ag::gpu {

// Attachment order of the G-buffer framebuffer (GL_COLOR_ATTACHMENT0 + value).
enum class GBufferTarget : int {
    position = 0,  // world xyz; w = 1 where a surface is seen, 0 on the background
    surface =
        1,       // albedo rgb (0 on mirrors and glass); a = the pixel's world area (0: not diffuse)
    normal = 2,  // world unit normal facing the eye; w = view depth (distance along −z)
    ids = 3,     // r = object index, g = material id, b = MaterialType; a = 1 where covered
};
inline constexpr int kGBufferTargets = 4;

// Material ids: objects with equal materials (type, albedo, ior, emission) share the id of the
// first such object, so an edge test by id does not flag two objects of one material.
std::vector<int> material_ids(const Scene& scene);

class GBuffer {
public:
    GBuffer(const Scene& scene, const SceneMeshes& meshes, int width, int height);

    // The scene's camera resized to this buffer, its near and far planes and view-projection.
    struct View {
        Camera camera;
        float near_plane = 0.0f, far_plane = 0.0f;
        glm::mat4 view{1.0f}, projection{1.0f}, view_projection{1.0f};
    };
    View view() const;
    // The same for any scene and buffer size.
    static View view_of(const Scene& scene, int width, int height);

    // Clears colour, depth (1) and stencil (0) and draws every object of the scene as it stands.
    void render();

    int width() const { return width_; }
    int height() const { return height_; }
    GLuint texture(GBufferTarget t) const { return targets_[size_t(t)].get(); }
    GLuint depth_stencil() const { return depth_stencil_.get(); }  // DEPTH32F_STENCIL8
    GLuint framebuffer() const { return fbo_.get(); }
    const View& last_view() const { return last_view_; }  // the view of the last render

    // For tests: one target read back, rows top-first.
    std::vector<glm::vec4> read(GBufferTarget t) const;

private:
    const Scene& scene_;
    const SceneMeshes& meshes_;
    int width_, height_;
    Program program_;
    std::array<Texture, kGBufferTargets> targets_;
    Renderbuffer depth_stencil_;
    Framebuffer fbo_;
    View last_view_;
};

// A framebuffer over `colors` (attachments 0..n-1) and optionally a depth-stencil renderbuffer;
// throws GlError naming `what` if incomplete.
Framebuffer framebuffer_with(const std::vector<GLuint>& colors, GLuint depth_stencil,
                             const char* what);

}  // namespace ag::gpu
