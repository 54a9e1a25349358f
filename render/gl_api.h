// The OpenGL entry points the renderer uses, loaded through OSMesa into one table.
#pragma once

#include <GL/glcorearb.h>

#include "render/gl_context.h"

namespace dem::render {

#define DEM_RENDER_GL_FUNCTIONS(X)                                                            \
  X(PFNGLGETSTRINGPROC, GetString) X(PFNGLGETERRORPROC, GetError)                             \
  X(PFNGLGETINTEGERVPROC, GetIntegerv) X(PFNGLENABLEPROC, Enable) X(PFNGLDISABLEPROC, Disable) \
  X(PFNGLVIEWPORTPROC, Viewport) X(PFNGLCLEARCOLORPROC, ClearColor)                           \
  X(PFNGLCLEARDEPTHPROC, ClearDepth) X(PFNGLCLEARPROC, Clear) X(PFNGLDEPTHMASKPROC, DepthMask) \
  X(PFNGLDEPTHFUNCPROC, DepthFunc) X(PFNGLCULLFACEPROC, CullFace)                              \
  X(PFNGLFRONTFACEPROC, FrontFace) X(PFNGLBLENDFUNCPROC, BlendFunc)                            \
  X(PFNGLREADPIXELSPROC, ReadPixels) X(PFNGLPIXELSTOREIPROC, PixelStorei)                      \
  X(PFNGLFINISHPROC, Finish) X(PFNGLREADBUFFERPROC, ReadBuffer)                                \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers)                                                 \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                                           \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                                                 \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer)                                 \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)                                   \
  X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers)                                               \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)                                         \
  X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)                                               \
  X(PFNGLRENDERBUFFERSTORAGEMULTISAMPLEPROC, RenderbufferStorageMultisample)                   \
  X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer) X(PFNGLDRAWBUFFERSPROC, DrawBuffers)            \
  X(PFNGLCREATESHADERPROC, CreateShader) X(PFNGLSHADERSOURCEPROC, ShaderSource)                \
  X(PFNGLCOMPILESHADERPROC, CompileShader) X(PFNGLGETSHADERIVPROC, GetShaderiv)                \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog) X(PFNGLDELETESHADERPROC, DeleteShader)        \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram) X(PFNGLATTACHSHADERPROC, AttachShader)              \
  X(PFNGLLINKPROGRAMPROC, LinkProgram) X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                  \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog) X(PFNGLDELETEPROGRAMPROC, DeleteProgram)    \
  X(PFNGLUSEPROGRAMPROC, UseProgram) X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)        \
  X(PFNGLUNIFORM1IPROC, Uniform1i) X(PFNGLUNIFORM1FPROC, Uniform1f)                            \
  X(PFNGLUNIFORM3FPROC, Uniform3f) X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)              \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays) X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)    \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays) X(PFNGLGENBUFFERSPROC, GenBuffers)        \
  X(PFNGLBINDBUFFERPROC, BindBuffer) X(PFNGLBUFFERDATAPROC, BufferData)                        \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                                                     \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)                                 \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)                                         \
  X(PFNGLVERTEXATTRIBDIVISORPROC, VertexAttribDivisor) X(PFNGLDRAWARRAYSPROC, DrawArrays)      \
  X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced)

/// Function table: gl.Clear(...) instead of glClear(...).
struct Gl {
#define DEM_RENDER_GL_MEMBER(type, name) type name = nullptr;
  DEM_RENDER_GL_FUNCTIONS(DEM_RENDER_GL_MEMBER)
#undef DEM_RENDER_GL_MEMBER

  /// Loads every entry; throws std::runtime_error naming the first one missing.
  void load(const GlContext& context);
};

}  // namespace dem::render
