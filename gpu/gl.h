// OpenGL 4.5 core entry points, loaded at run time from whichever context backend is current
// (OSMesa, EGL or GLFW). Only the Khronos core header is used, so no system GL header or loader
// library is needed and the three backends share one code path.
#pragma once

#include <GL/glcorearb.h>

#include <cstdio>
#include <stdexcept>
#include <string>

#define AG_GL_FUNCTIONS(X)                                       \
    X(PFNGLGETSTRINGPROC, GetString)                             \
    X(PFNGLGETINTEGERVPROC, GetIntegerv)                         \
    X(PFNGLGETERRORPROC, GetError)                               \
    X(PFNGLFINISHPROC, Finish)                                   \
    X(PFNGLFLUSHPROC, Flush)                                     \
    X(PFNGLENABLEPROC, Enable)                                   \
    X(PFNGLDISABLEPROC, Disable)                                 \
    X(PFNGLVIEWPORTPROC, Viewport)                               \
    X(PFNGLSCISSORPROC, Scissor)                                 \
    X(PFNGLCLEARPROC, Clear)                                     \
    X(PFNGLCLEARCOLORPROC, ClearColor)                           \
    X(PFNGLCLEARDEPTHPROC, ClearDepth)                           \
    X(PFNGLCLEARSTENCILPROC, ClearStencil)                       \
    X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv)                     \
    X(PFNGLDEPTHFUNCPROC, DepthFunc)                             \
    X(PFNGLCLIPCONTROLPROC, ClipControl)                         \
    X(PFNGLDEPTHMASKPROC, DepthMask)                             \
    X(PFNGLCOLORMASKPROC, ColorMask)                             \
    X(PFNGLSTENCILFUNCPROC, StencilFunc)                         \
    X(PFNGLSTENCILOPPROC, StencilOp)                             \
    X(PFNGLSTENCILOPSEPARATEPROC, StencilOpSeparate)             \
    X(PFNGLSTENCILMASKPROC, StencilMask)                         \
    X(PFNGLBLENDFUNCPROC, BlendFunc)                             \
    X(PFNGLBLENDEQUATIONPROC, BlendEquation)                     \
    X(PFNGLCULLFACEPROC, CullFace)                               \
    X(PFNGLPOLYGONOFFSETPROC, PolygonOffset)                     \
    X(PFNGLPIXELSTOREIPROC, PixelStorei)                         \
    X(PFNGLREADPIXELSPROC, ReadPixels)                           \
    X(PFNGLREADBUFFERPROC, ReadBuffer)                           \
    X(PFNGLDRAWBUFFERSPROC, DrawBuffers)                         \
    X(PFNGLDRAWARRAYSPROC, DrawArrays)                           \
    X(PFNGLDRAWELEMENTSPROC, DrawElements)                       \
    X(PFNGLCREATESHADERPROC, CreateShader)                       \
    X(PFNGLSHADERSOURCEPROC, ShaderSource)                       \
    X(PFNGLCOMPILESHADERPROC, CompileShader)                     \
    X(PFNGLGETSHADERIVPROC, GetShaderiv)                         \
    X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)               \
    X(PFNGLDELETESHADERPROC, DeleteShader)                       \
    X(PFNGLCREATEPROGRAMPROC, CreateProgram)                     \
    X(PFNGLATTACHSHADERPROC, AttachShader)                       \
    X(PFNGLLINKPROGRAMPROC, LinkProgram)                         \
    X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                       \
    X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)             \
    X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                     \
    X(PFNGLUSEPROGRAMPROC, UseProgram)                           \
    X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)           \
    X(PFNGLUNIFORM1IPROC, Uniform1i)                             \
    X(PFNGLUNIFORM1FPROC, Uniform1f)                             \
    X(PFNGLUNIFORM2FPROC, Uniform2f)                             \
    X(PFNGLUNIFORM2IPROC, Uniform2i)                             \
    X(PFNGLUNIFORM3FPROC, Uniform3f)                             \
    X(PFNGLUNIFORM4FPROC, Uniform4f)                             \
    X(PFNGLUNIFORM3FVPROC, Uniform3fv)                           \
    X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)               \
    X(PFNGLGENBUFFERSPROC, GenBuffers)                           \
    X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                     \
    X(PFNGLBINDBUFFERPROC, BindBuffer)                           \
    X(PFNGLBUFFERDATAPROC, BufferData)                           \
    X(PFNGLBUFFERSUBDATAPROC, BufferSubData)                     \
    X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays)                 \
    X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)           \
    X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                 \
    X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray) \
    X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)         \
    X(PFNGLGENTEXTURESPROC, GenTextures)                         \
    X(PFNGLDELETETEXTURESPROC, DeleteTextures)                   \
    X(PFNGLBINDTEXTUREPROC, BindTexture)                         \
    X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                     \
    X(PFNGLTEXIMAGE2DPROC, TexImage2D)                           \
    X(PFNGLTEXSTORAGE3DPROC, TexStorage3D)                       \
    X(PFNGLTEXSUBIMAGE2DPROC, TexSubImage2D)                     \
    X(PFNGLTEXPARAMETERIPROC, TexParameteri)                     \
    X(PFNGLGENERATEMIPMAPPROC, GenerateMipmap)                   \
    X(PFNGLGETTEXIMAGEPROC, GetTexImage)                         \
    X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers)                 \
    X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)           \
    X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                 \
    X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)       \
    X(PFNGLFRAMEBUFFERTEXTURELAYERPROC, FramebufferTextureLayer) \
    X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer) \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)   \
    X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers)               \
    X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)         \
    X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)               \
    X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage)         \
    X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer)                 \
    X(PFNGLGENQUERIESPROC, GenQueries)                           \
    X(PFNGLDELETEQUERIESPROC, DeleteQueries)                     \
    X(PFNGLBEGINQUERYPROC, BeginQuery)                           \
    X(PFNGLENDQUERYPROC, EndQuery)                               \
    X(PFNGLGETQUERYOBJECTUIVPROC, GetQueryObjectuiv)             \
    X(PFNGLGETQUERYOBJECTUI64VPROC, GetQueryObjectui64v)         \
    X(PFNGLQUERYCOUNTERPROC, QueryCounter)                       \
    X(PFNGLDISPATCHCOMPUTEPROC, DispatchCompute)                 \
    X(PFNGLDISPATCHCOMPUTEINDIRECTPROC, DispatchComputeIndirect) \
    X(PFNGLMEMORYBARRIERPROC, MemoryBarrier)                     \
    X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                   \
    X(PFNGLBINDBUFFERRANGEPROC, BindBufferRange)                 \
    X(PFNGLGETBUFFERSUBDATAPROC, GetBufferSubData)               \
    X(PFNGLCOPYBUFFERSUBDATAPROC, CopyBufferSubData)             \
    X(PFNGLCLEARBUFFERDATAPROC, ClearBufferData)                 \
    X(PFNGLCLEARBUFFERSUBDATAPROC, ClearBufferSubData)           \
    X(PFNGLMAPBUFFERRANGEPROC, MapBufferRange)                   \
    X(PFNGLUNMAPBUFFERPROC, UnmapBuffer)                         \
    X(PFNGLBINDIMAGETEXTUREPROC, BindImageTexture)               \
    X(PFNGLTEXIMAGE3DPROC, TexImage3D)                           \
    X(PFNGLTEXSUBIMAGE3DPROC, TexSubImage3D)                     \
    X(PFNGLTEXSTORAGE2DPROC, TexStorage2D)                       \
    X(PFNGLCLEARTEXIMAGEPROC, ClearTexImage)                     \
    X(PFNGLTEXPARAMETERFPROC, TexParameterf)                     \
    X(PFNGLTEXPARAMETERFVPROC, TexParameterfv)                   \
    X(PFNGLFRAMEBUFFERTEXTUREPROC, FramebufferTexture)           \
    X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced)         \
    X(PFNGLDRAWELEMENTSINSTANCEDPROC, DrawElementsInstanced)     \
    X(PFNGLVERTEXATTRIBDIVISORPROC, VertexAttribDivisor)         \
    X(PFNGLVERTEXATTRIBIPOINTERPROC, VertexAttribIPointer)       \
    X(PFNGLBLENDFUNCSEPARATEPROC, BlendFuncSeparate)             \
    X(PFNGLBLENDEQUATIONSEPARATEPROC, BlendEquationSeparate)     \
    X(PFNGLUNIFORM1UIPROC, Uniform1ui)                           \
    X(PFNGLUNIFORM3IPROC, Uniform3i)                             \
    X(PFNGLUNIFORM1FVPROC, Uniform1fv)                           \
    X(PFNGLUNIFORM2FVPROC, Uniform2fv)                           \
    X(PFNGLUNIFORM4FVPROC, Uniform4fv)                           \
    X(PFNGLUNIFORMMATRIX3FVPROC, UniformMatrix3fv)               \
    X(PFNGLGETINTEGERI_VPROC, GetIntegeri_v)                     \
    X(PFNGLGETPROGRAMRESOURCEINDEXPROC, GetProgramResourceIndex)

namespace ag::gpu::gl {

#define AG_GL_DECLARE(type, name) extern type name;
AG_GL_FUNCTIONS(AG_GL_DECLARE)
#undef AG_GL_DECLARE

// Loads every entry point through `get_proc` (the backend's GetProcAddress). Throws GlError
// naming the first missing function.
using GetProc = void* (*)(const char* name);
void load(GetProc get_proc);

}  // namespace ag::gpu::gl

namespace ag::gpu {

// A GL context could not be made or GL failed: the message says what and where.
class GlError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Throws GlError if glGetError reports an error, named (GL_OUT_OF_MEMORY with a hint), and
// `where`, the call site.
void check_gl(const char* where);

// Reads every pending GL error and returns them as "0x0501, 0x0506" ("" when none). Work that
// failed by throwing before its check_gl (an incomplete framebuffer, a refused size) may leave an
// error pending, and the next unit of work on the same context would then fail at its first
// check_gl; call this after catching such a failure (compare-methods between variants).
std::string take_gl_errors();

}  // namespace ag::gpu
