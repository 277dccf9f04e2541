#include "gpu/gl_context.h"

#include <stdexcept>

#include "gpu/gl.h"

namespace ag::gpu {

std::string GlContext::renderer() const {
    const GLubyte* s = gl::GetString(GL_RENDERER);
    return s ? reinterpret_cast<const char*>(s) : "unknown";
}

std::string GlContext::version() const {
    const GLubyte* s = gl::GetString(GL_VERSION);
    return s ? reinterpret_cast<const char*>(s) : "unknown";
}

std::unique_ptr<GlContext> make_gl_context(GlBackend backend, int width, int height,
                                           const std::string& title) {
    switch (backend) {
        case GlBackend::osmesa:
            return detail::make_osmesa_context();
        case GlBackend::egl:
            return detail::make_egl_context(false);
        case GlBackend::window:
            return detail::make_window_context(width, height, title);
        case GlBackend::automatic:
            break;
    }
    try {
        return detail::make_egl_context(true);  // a real GPU, if there is one
    } catch (const GlError&) {
        return detail::make_osmesa_context();
    }
}

}  // namespace ag::gpu
