#include "gpu/gl_objects.h"

#include <atomic>
#include <cassert>
#include <string>

#include "shared/host_device_shared.h"

namespace ag::gpu {

Buffer make_buffer() {
    GLuint id = 0;
    gl::GenBuffers(1, &id);
    return Buffer(id);
}
Texture make_texture() {
    GLuint id = 0;
    gl::GenTextures(1, &id);
    return Texture(id);
}
Framebuffer make_framebuffer() {
    GLuint id = 0;
    gl::GenFramebuffers(1, &id);
    return Framebuffer(id);
}
Renderbuffer make_renderbuffer() {
    GLuint id = 0;
    gl::GenRenderbuffers(1, &id);
    return Renderbuffer(id);
}
VertexArray make_vertex_array() {
    GLuint id = 0;
    gl::GenVertexArrays(1, &id);
    return VertexArray(id);
}

namespace {
GLuint compile(const std::string& name, GLenum type, const std::string& source) {
    const GLuint s = gl::CreateShader(type);
    // Every shader sees the constants shared with C++; `#line 1` keeps log line numbers those of
    // `source`.
    const std::string full =
        std::string("#version 450 core\n") + kHostDeviceSharedGlsl + "\n#line 1\n" + source;
    const char* text = full.c_str();
    gl::ShaderSource(s, 1, &text, nullptr);
    gl::CompileShader(s);
    GLint ok = 0;
    gl::GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096];
        gl::GetShaderInfoLog(s, sizeof log, nullptr, log);
        gl::DeleteShader(s);
        throw GlError("shader '" + name +
                      (type == GL_VERTEX_SHADER     ? "' (vertex)"
                       : type == GL_COMPUTE_SHADER  ? "' (compute)"
                       : type == GL_GEOMETRY_SHADER ? "' (geometry)"
                                                    : "' (fragment)") +
                      " does not compile:\n" + log);
    }
    return s;
}
}  // namespace

Program::Program(const std::string& name, const std::string& vertex, const std::string& fragment)
    : Program(name, vertex, "", fragment) {}

Program::Program(const std::string& name, const std::string& vertex, const std::string& geometry,
                 const std::string& fragment) {
    std::vector<GLuint> shaders = {compile(name, GL_VERTEX_SHADER, vertex)};
    if (!geometry.empty()) shaders.push_back(compile(name, GL_GEOMETRY_SHADER, geometry));
    shaders.push_back(compile(name, GL_FRAGMENT_SHADER, fragment));
    link(name, shaders);
}

Program Program::compute(const std::string& name, const std::string& source) {
    Program p;
    p.link(name, {compile(name, GL_COMPUTE_SHADER, source)});
    return p;
}

void Program::link(const std::string& name, const std::vector<GLuint>& shaders) {
    id_ = Handle<detail::delete_program>(gl::CreateProgram());
    for (const GLuint s : shaders) gl::AttachShader(id_.get(), s);
    gl::LinkProgram(id_.get());
    for (const GLuint s : shaders) gl::DeleteShader(s);
    GLint ok = 0;
    gl::GetProgramiv(id_.get(), GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096];
        gl::GetProgramInfoLog(id_.get(), sizeof log, nullptr, log);
        throw GlError("program '" + name + "' does not link:\n" + log);
    }
}

Buffer make_storage_buffer(size_t bytes, const void* data) {
    Buffer b = make_buffer();
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, b.get());
    gl::BufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes), data, GL_DYNAMIC_COPY);
    if (!data && bytes > 0)
        gl::ClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT,
                            nullptr);
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    check_gl("make_storage_buffer");
    return b;
}

namespace {
std::atomic<uint64_t> readbacks{0};
}  // namespace

uint64_t readback_count() { return readbacks.load(); }

std::vector<uint8_t> read_buffer(GLuint buffer, size_t bytes) {
    ++readbacks;
    std::vector<uint8_t> out(bytes);
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
    if (bytes > 0) gl::GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(bytes), out.data());
    gl::BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    check_gl("read_buffer");
    return out;
}

void dispatch_compute(GLuint groups) {
    if (groups == 0) return;
    const GLuint x = groups < 65535u ? groups : 65535u;
    gl::DispatchCompute(x, (groups + x - 1) / x, 1);
    gl::MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                      GL_BUFFER_UPDATE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                      GL_ATOMIC_COUNTER_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
}

Program::Program(const std::string& name, const std::string& compute) {
    link(name, {compile(name, GL_COMPUTE_SHADER, compute)});
}

Texture make_float_texture(int width, int height, bool mip, const float* rgba) {
    Texture t = make_texture();
    gl::BindTexture(GL_TEXTURE_2D, t.get());
    gl::TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, width, height, 0, GL_RGBA, GL_FLOAT, rgba);
    if (mip) {
        int w = width, h = height;
        for (int level = 1; w > 1 || h > 1; ++level) {
            w = std::max(1, w / 2);
            h = std::max(1, h / 2);
            gl::TexImage2D(GL_TEXTURE_2D, level, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
        }
    }
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER,
                      mip ? GL_NEAREST_MIPMAP_NEAREST : GL_NEAREST);
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    const std::string where = "make_float_texture (" + std::to_string(width) + " x " +
                              std::to_string(height) + " RGBA32F, " +
                              std::to_string((int64_t(width) * height * 16 + (1 << 20) - 1) >> 20) +
                              " MiB)";
    check_gl(where.c_str());
    return t;
}

void begin_scene_pass(GLuint framebuffer, int buffers, int width, int height,
                      const glm::vec4& clear) {
    gl::BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    const GLenum all[8] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                           GL_COLOR_ATTACHMENT3, GL_COLOR_ATTACHMENT4, GL_COLOR_ATTACHMENT5,
                           GL_COLOR_ATTACHMENT6, GL_COLOR_ATTACHMENT7};
    assert(buffers >= 1 && buffers <= 8);
    gl::DrawBuffers(buffers, all);
    gl::Viewport(0, 0, width, height);
    gl::ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl::DepthMask(GL_TRUE);
    gl::StencilMask(0xFF);
    gl::ClearColor(clear.r, clear.g, clear.b, clear.a);
    gl::ClearDepth(1.0);
    gl::ClearStencil(0);
    gl::Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
    gl::Enable(GL_DEPTH_TEST);
    gl::DepthFunc(GL_LESS);
    gl::Disable(GL_BLEND);
    gl::Disable(GL_STENCIL_TEST);
    gl::Disable(GL_CULL_FACE);
}

std::vector<float> read_rgba(GLuint framebuffer, GLenum attachment, int x, int y, int width,
                             int height) {
    ++readbacks;
    std::vector<float> out(size_t(width) * size_t(height) * 4);
    gl::BindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer);
    gl::ReadBuffer(attachment);
    gl::PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl::ReadPixels(x, y, width, height, GL_RGBA, GL_FLOAT, out.data());
    check_gl("read_rgba");
    return out;
}

}  // namespace ag::gpu
