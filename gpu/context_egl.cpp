// EGL backend: headless GL 4.5 core on a GPU (EGL_EXT_platform_device) or, when no hardware device
// is asked for, Mesa's surfaceless platform.
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstring>
#include <string>
#include <vector>

#include "gpu/gl_context.h"

namespace ag::gpu {

void throw_gl_error(const std::string& message);
void load_gl(void* (*get_proc)(const char*));

namespace {

bool has_extension(const char* list, const char* name) {
    if (!list) return false;
    const size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)); p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    return false;
}

class EglContext final : public GlContext {
public:
    explicit EglContext(bool require_hardware) {
        backend_ = GlBackend::egl;
        const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
        auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
            eglGetProcAddress("eglGetPlatformDisplayEXT"));
        if (has_extension(client_ext, "EGL_EXT_platform_device") && get_platform_display) {
            auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(
                eglGetProcAddress("eglQueryDevicesEXT"));
            auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
                eglGetProcAddress("eglQueryDeviceStringEXT"));
            EGLDeviceEXT devices[16];
            EGLint count = 0;
            if (query_devices && query_devices(16, devices, &count))
                for (EGLint i = 0; i < count && display_ == EGL_NO_DISPLAY; ++i) {
                    const char* ext = query_device_string
                                          ? query_device_string(devices[i], EGL_EXTENSIONS)
                                          : nullptr;
                    // Mesa's software device advertises EGL_MESA_device_software.
                    if (require_hardware && has_extension(ext, "EGL_MESA_device_software"))
                        continue;
                    EGLDisplay d =
                        get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
                    if (d != EGL_NO_DISPLAY && try_initialize(d)) display_ = d;
                }
        }
        if (display_ == EGL_NO_DISPLAY && require_hardware)
            throw_gl_error("EGL: no hardware GPU device found (EGL_EXT_platform_device)");
        if (display_ == EGL_NO_DISPLAY &&
            has_extension(client_ext, "EGL_MESA_platform_surfaceless") && get_platform_display) {
            EGLDisplay d =
                get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
            if (d != EGL_NO_DISPLAY && try_initialize(d)) display_ = d;
        }
        if (display_ == EGL_NO_DISPLAY) throw_gl_error("EGL: no display could be initialised");
        if (!eglBindAPI(EGL_OPENGL_API)) throw_gl_error("EGL: the OpenGL API is not available");
        const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLConfig config = nullptr;
        EGLint configs = 0;
        eglChooseConfig(display_, config_attribs, &config, 1, &configs);
        const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                          4,
                                          EGL_CONTEXT_MINOR_VERSION,
                                          5,
                                          EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                          EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                          EGL_NONE};
        context_ = eglCreateContext(display_, configs > 0 ? config : EGL_NO_CONFIG_KHR,
                                    EGL_NO_CONTEXT, context_attribs);
        if (context_ == EGL_NO_CONTEXT) throw_gl_error("EGL: cannot create a GL 4.5 core context");
        make_current();
    }
    ~EglContext() override {
        eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
        eglTerminate(display_);
    }
    void make_current() override {
        if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
            throw_gl_error("EGL: cannot make the context current (no surfaceless support?)");
    }

private:
    static bool try_initialize(EGLDisplay d) {
        EGLint major = 0, minor = 0;
        return eglInitialize(d, &major, &minor) == EGL_TRUE;
    }
    EGLDisplay display_ = EGL_NO_DISPLAY;
    EGLContext context_ = EGL_NO_CONTEXT;
};

void* get_proc(const char* name) { return reinterpret_cast<void*>(eglGetProcAddress(name)); }

}  // namespace

namespace detail {
std::unique_ptr<GlContext> make_egl_context(bool require_hardware) {
    auto context = std::make_unique<EglContext>(require_hardware);
    load_gl(get_proc);
    return context;
}
}  // namespace detail

}  // namespace ag::gpu
