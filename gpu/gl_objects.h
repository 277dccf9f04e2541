// RAII handles for GL objects and small helpers (programs, float textures, framebuffers).
#pragma once

#include <cstdint>
#include <cstring>
#include <glm/glm.hpp>
#include <string>
#include <utility>
#include <vector>

#include "gpu/gl.h"

namespace ag::gpu {

// A move-only GL name with its deleter.
template <void (*Delete)(GLuint)>
class Handle {
public:
    Handle() = default;
    explicit Handle(GLuint id) : id_(id) {}
    ~Handle() { reset(); }
    Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
    Handle& operator=(Handle&& o) noexcept {
        if (this != &o) {
            reset();
            id_ = std::exchange(o.id_, 0);
        }
        return *this;
    }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    GLuint get() const { return id_; }
    explicit operator bool() const { return id_ != 0; }
    void reset() {
        if (id_) Delete(id_);
        id_ = 0;
    }

private:
    GLuint id_ = 0;
};

namespace detail {
inline void delete_buffer(GLuint id) { gl::DeleteBuffers(1, &id); }
inline void delete_texture(GLuint id) { gl::DeleteTextures(1, &id); }
inline void delete_framebuffer(GLuint id) { gl::DeleteFramebuffers(1, &id); }
inline void delete_renderbuffer(GLuint id) { gl::DeleteRenderbuffers(1, &id); }
inline void delete_vertex_array(GLuint id) { gl::DeleteVertexArrays(1, &id); }
inline void delete_program(GLuint id) { gl::DeleteProgram(id); }
}  // namespace detail

using Buffer = Handle<detail::delete_buffer>;
using Texture = Handle<detail::delete_texture>;
using Framebuffer = Handle<detail::delete_framebuffer>;
using Renderbuffer = Handle<detail::delete_renderbuffer>;
using VertexArray = Handle<detail::delete_vertex_array>;

Buffer make_buffer();
Texture make_texture();
Framebuffer make_framebuffer();
Renderbuffer make_renderbuffer();
VertexArray make_vertex_array();

// Vertex shader of a full-screen pass: draw 3 vertices with an empty VAO; the triangle covers
// the viewport, so fragment shaders address pixels by gl_FragCoord.
inline constexpr const char* kFullScreenTriangleVertex = R"(
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}
)";

// A linked program with uniform setters. Compile/link errors throw GlError with the log and
// the shader's name.
class Program {
public:
    Program() = default;
    Program(const std::string& name, const std::string& vertex, const std::string& fragment);
    // A compute program (GLSL 4.50 with the shared constants prepended, like the others).
    static Program compute(const std::string& name, const std::string& source);
    // With a geometry stage between them (layered rendering: gl_Layer); "" = none.
    Program(const std::string& name, const std::string& vertex, const std::string& geometry,
            const std::string& fragment);
    Program(const std::string& name, const std::string& compute);  // a compute program
    void use() const { gl::UseProgram(id_.get()); }
    explicit operator bool() const { return bool(id_); }
    GLint location(const char* uniform) const { return gl::GetUniformLocation(id_.get(), uniform); }
    void set(const char* u, int v) const { gl::Uniform1i(location(u), v); }
    void set(const char* u, unsigned v) const { gl::Uniform1ui(location(u), v); }
    void set(const char* u, float v) const { gl::Uniform1f(location(u), v); }
    void set(const char* u, const glm::vec2& v) const { gl::Uniform2f(location(u), v.x, v.y); }
    void set(const char* u, const glm::vec3& v) const { gl::Uniform3f(location(u), v.x, v.y, v.z); }
    void set(const char* u, const glm::ivec3& v) const {
        gl::Uniform3i(location(u), v.x, v.y, v.z);
    }
    void set(const char* u, const glm::vec4& v) const {
        gl::Uniform4f(location(u), v.x, v.y, v.z, v.w);
    }
    void set(const char* u, const glm::mat4& m) const {
        gl::UniformMatrix4fv(location(u), 1, GL_FALSE, &m[0][0]);
    }

private:
    void link(const std::string& name, const std::vector<GLuint>& shaders);
    Handle<detail::delete_program> id_;
};

// A shader storage buffer of `bytes` (contents from `data`, or zero), usage DYNAMIC_COPY.
Buffer make_storage_buffer(size_t bytes, const void* data = nullptr);
// Reads `bytes` from the start of a buffer back (for tests and diagnostics, never per frame).
std::vector<uint8_t> read_buffer(GLuint buffer, size_t bytes);
// How many times read_buffer and read_rgba have read GPU data back (tests check a frame adds 0).
uint64_t readback_count();
template <class T>
std::vector<T> read_buffer_as(GLuint buffer, size_t count) {
    const std::vector<uint8_t> bytes = read_buffer(buffer, count * sizeof(T));
    std::vector<T> out(count);
    std::memcpy(out.data(), bytes.data(), bytes.size());
    return out;
}
// Dispatches `groups` work groups of the bound compute program, at most 65535 per dimension
// (the rest spill into y), followed by a storage and image barrier.
void dispatch_compute(GLuint groups);

// RGBA32F texture of w × h (nearest filtering, clamped); `mip` allocates a full mip chain.
Texture make_float_texture(int width, int height, bool mip = false, const float* rgba = nullptr);

// Starts a scene pass into `framebuffer`: color attachments 0..buffers-1 drawn, full viewport,
// every mask on, colour/depth/stencil cleared (to `clear`, 1, 0), depth test LESS, no blending,
// stencil test or culling.
void begin_scene_pass(GLuint framebuffer, int buffers, int width, int height,
                      const glm::vec4& clear);

// Reads an RGBA32F framebuffer attachment back (rows bottom-up, as GL stores them).
std::vector<float> read_rgba(GLuint framebuffer, GLenum attachment, int x, int y, int width,
                             int height);

}  // namespace ag::gpu
