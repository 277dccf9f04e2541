#include "gpu/gl.h"

namespace ag::gpu::gl {

#define AG_GL_DEFINE(type, name) type name = nullptr;
AG_GL_FUNCTIONS(AG_GL_DEFINE)
#undef AG_GL_DEFINE

void load(GetProc get_proc) {
#define AG_GL_LOAD(type, name)                           \
    name = reinterpret_cast<type>(get_proc("gl" #name)); \
    if (!name) throw GlError("OpenGL entry point gl" #name " is missing from the context");
    AG_GL_FUNCTIONS(AG_GL_LOAD)
#undef AG_GL_LOAD
}

}  // namespace ag::gpu::gl

namespace ag::gpu {

namespace {

const char* gl_error_name(GLenum e) {
    switch (e) {
        case GL_INVALID_ENUM:
            return "GL_INVALID_ENUM";
        case GL_INVALID_VALUE:
            return "GL_INVALID_VALUE";
        case GL_INVALID_OPERATION:
            return "GL_INVALID_OPERATION";
        case GL_STACK_OVERFLOW:
            return "GL_STACK_OVERFLOW";
        case GL_STACK_UNDERFLOW:
            return "GL_STACK_UNDERFLOW";
        case GL_OUT_OF_MEMORY:
            return "GL_OUT_OF_MEMORY: the GL implementation could not allocate it; a smaller "
                   "image, atlas or map needs less";
        case GL_INVALID_FRAMEBUFFER_OPERATION:
            return "GL_INVALID_FRAMEBUFFER_OPERATION";
        default:
            return "unknown";
    }
}

}  // namespace

void check_gl(const char* where) {
    const GLenum e = gl::GetError();
    if (e != GL_NO_ERROR)
        throw GlError(std::string("OpenGL error 0x") +
                      [&] {
                          char buf[16];
                          std::snprintf(buf, sizeof buf, "%04x", unsigned(e));
                          return std::string(buf);
                      }() +
                      " (" + gl_error_name(e) + ") in " + where);
}

std::string take_gl_errors() {
    // An implementation holds at most one error per kind (Mesa holds one); a lost context may
    // report forever, so the loop is bounded.
    std::string errors;
    for (int i = 0; i < 16; ++i) {
        const GLenum e = gl::GetError();
        if (e == GL_NO_ERROR) break;
        char buf[16];
        std::snprintf(buf, sizeof buf, "0x%04x", unsigned(e));
        errors += (errors.empty() ? "" : ", ") + std::string(buf);
    }
    return errors;
}

}  // namespace ag::gpu

namespace ag::gpu {

// For backends whose headers clash with gl.h (they include the system GL header).
void throw_gl_error(const std::string& message) { throw GlError(message); }
void load_gl(void* (*get_proc)(const char*)) { gl::load(get_proc); }

}  // namespace ag::gpu
