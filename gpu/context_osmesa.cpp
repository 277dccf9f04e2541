// OSMesa backend: Mesa's off-screen llvmpipe, GL 4.5 core without any GPU or display.
// Kept in its own file: GL/osmesa.h pulls in the system GL header.
#include <GL/osmesa.h>

#include <vector>

#include "gpu/gl_context.h"

namespace ag::gpu {

void throw_gl_error(const std::string& message);  // defined below (gl.h cannot be included here)

namespace {

class OsmesaContext final : public GlContext {
public:
    OsmesaContext() {
        backend_ = GlBackend::osmesa;
        const int attribs[] = {OSMESA_FORMAT,
                               OSMESA_RGBA,
                               OSMESA_DEPTH_BITS,
                               24,
                               OSMESA_STENCIL_BITS,
                               8,
                               OSMESA_PROFILE,
                               OSMESA_CORE_PROFILE,
                               OSMESA_CONTEXT_MAJOR_VERSION,
                               4,
                               OSMESA_CONTEXT_MINOR_VERSION,
                               5,
                               0};
        context_ = OSMesaCreateContextAttribs(attribs, nullptr);
        if (!context_)
            throw_gl_error(
                "OSMesa: cannot create a GL 4.5 core context (is libosmesa6 installed?)");
        buffer_.resize(4 * 4 * 4);  // we draw into framebuffer objects; the default one is a stub
        make_current();
    }
    ~OsmesaContext() override { OSMesaDestroyContext(context_); }
    void make_current() override {
        if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, 4, 4))
            throw_gl_error("OSMesa: cannot make the context current");
    }

private:
    OSMesaContext context_ = nullptr;
    std::vector<unsigned char> buffer_;
};

void* get_proc(const char* name) { return reinterpret_cast<void*>(OSMesaGetProcAddress(name)); }

}  // namespace

void load_gl(void* (*get_proc)(const char*));

namespace detail {
std::unique_ptr<GlContext> make_osmesa_context() {
    auto context = std::make_unique<OsmesaContext>();
    load_gl(get_proc);
    return context;
}
}  // namespace detail

}  // namespace ag::gpu
