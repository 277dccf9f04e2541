// OpenGL 4.5 core contexts. One GL code path, three backends chosen at run time: OSMesa (default,
// headless, Mesa llvmpipe, no GPU), EGL (headless on a GPU through the device platform, or
// surfaceless Mesa) and a GLFW window (the viewer). `automatic` tries EGL on a real GPU, then
// OSMesa.
#pragma once

#include <array>
#include <memory>
#include <stdexcept>
#include <string>

namespace ag::gpu {

enum class GlBackend { automatic, osmesa, egl, window };
inline constexpr std::array kGlBackendNames = {"auto", "osmesa", "egl", "window"};

class GlContext {
public:
    virtual ~GlContext() = default;
    virtual void make_current() = 0;
    virtual void swap_buffers() {}
    virtual bool should_close() const { return false; }
    virtual void* native_window() const { return nullptr; }  // GLFWwindow* for the window backend
    GlBackend backend() const { return backend_; }
    std::string renderer() const;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
    std::string version() const;   // GL_VERSION

protected:
    GlBackend backend_ = GlBackend::osmesa;
};

// Creates a context and loads the GL entry points. The window backend opens a window of the
// given size; the headless ones render into framebuffer objects only. Throws GlError saying
// which backend failed and why (e.g. "EGL: no display", "window: no DISPLAY").
std::unique_ptr<GlContext> make_gl_context(GlBackend backend, int width = 64, int height = 64,
                                           const std::string& title = "afterglow");

// Parses "auto|osmesa|egl|window"; throws std::invalid_argument listing the choices. Inline, so
// the command-line parser (and its fuzz target) needs no GL library.
inline GlBackend parse_gl_backend(const std::string& name) {
    for (size_t i = 0; i < kGlBackendNames.size(); ++i)
        if (name == kGlBackendNames[i]) return GlBackend(i);
    throw std::invalid_argument("unknown GL backend '" + name +
                                "' (expected auto, osmesa, egl or window)");
}

namespace detail {
std::unique_ptr<GlContext> make_osmesa_context();
std::unique_ptr<GlContext> make_egl_context(bool require_hardware);
std::unique_ptr<GlContext> make_window_context(int width, int height, const std::string& title);
}  // namespace detail

}  // namespace ag::gpu
