// The viewport of `afterglow view`: shows the composed frame or one term of eq. 13.2 (the
// pipeline's AOV textures), or draws diagnostic views of its own (AIM or IIM on the scene,
// surfaces in unique colours), with points over it (photons, gather centres, lights) and the
// selection tinted; then puts the result in the window with exposure and the sRGB curve.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "gpu/gl_objects.h"
#include "gpu/scene_meshes.h"
#include "shared/image.h"
#include "shared/scene.h"
#include "tools/afterglow/view_state.h"

namespace ag::cli {

struct ViewPoint {
    glm::vec3 position{0.0f};  // world space
    glm::vec3 color{1.0f};     // linear, drawn as is (no exposure)
};

// A rectangle of the window's framebuffer, GL convention (origin bottom-left).
struct ViewRect {
    int x = 0, y = 0, width = 0, height = 0;
};

class ViewRenderer {
public:
    // `width`×`height` is the frame size (the pipeline's).
    ViewRenderer(const Scene& scene, const gpu::SceneMeshes& meshes, int width, int height);

    // Draws `mode` into the display texture. `source` is the pipeline's texture for the mode: the
    // frame or the term's AOV (screen-sized), or the AIM / IIM atlas; unused for surfaces.
    // `points` are depth-tested against the scene, `markers` drawn on top; `highlight` is an
    // object to tint (−1 for none).
    void render(ViewMode mode, GLuint source, const std::vector<ViewPoint>& points,
                const std::vector<ViewPoint>& markers, float point_size, int highlight);
    // Shows the display texture in `rect` of the window's default framebuffer.
    void present(const ViewRect& rect, float exposure);
    // The display texture, linear, top row first (what F12 writes).
    Image read_back() const;
    // The window's back buffer as shown (panel included), decoded to linear.
    static Image read_window(int width, int height);

private:
    void draw_scene(int mode);
    void draw_points(const std::vector<ViewPoint>& points, float size);

    const Scene& scene_;
    const gpu::SceneMeshes& meshes_;
    int width_, height_;
    float near_ = 1.0f;
    glm::mat4 view_projection_{1.0f};
    gpu::Program scene_program_, copy_program_, points_program_, present_program_;
    gpu::Texture display_, surface_ids_;
    gpu::Renderbuffer depth_;
    gpu::Framebuffer fbo_;
    gpu::VertexArray empty_vao_, points_vao_;
    gpu::Buffer points_vbo_;
    std::vector<int> triangle_offset_;  // per object: first triangle in surface_ids_
};

}  // namespace ag::cli
