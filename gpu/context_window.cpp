// GLFW window backend (the interactive viewer): GL 4.5 core in a window on the X display.
#include <GLFW/glfw3.h>

#include <string>

#include "gpu/gl_context.h"

namespace ag::gpu {

void throw_gl_error(const std::string& message);
void load_gl(void* (*get_proc)(const char*));

namespace {

class WindowContext final : public GlContext {
public:
    WindowContext(int width, int height, const std::string& title) {
        backend_ = GlBackend::window;
        if (!glfwInit())
            throw_gl_error(
                "window: GLFW cannot start (no DISPLAY? run under xvfb-run -a; headless commands "
                "take --gl osmesa)");
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        glfwWindowHint(GLFW_STENCIL_BITS, 8);
        window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (!window_) {
            glfwTerminate();
            throw_gl_error("window: cannot open a GL 4.5 core window");
        }
        make_current();
    }
    ~WindowContext() override {
        glfwDestroyWindow(window_);
        glfwTerminate();
    }
    void make_current() override { glfwMakeContextCurrent(window_); }
    void swap_buffers() override { glfwSwapBuffers(window_); }
    bool should_close() const override { return glfwWindowShouldClose(window_); }
    void* native_window() const override { return window_; }

private:
    GLFWwindow* window_ = nullptr;
};

void* get_proc(const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); }

}  // namespace

namespace detail {
std::unique_ptr<GlContext> make_window_context(int width, int height, const std::string& title) {
    auto context = std::make_unique<WindowContext>(width, height, title);
    load_gl(get_proc);
    return context;
}
}  // namespace detail

}  // namespace ag::gpu
