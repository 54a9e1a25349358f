// An OSMesa (off-screen Mesa) OpenGL context. This file and gl_context.cpp are the only ones that
// see <GL/osmesa.h>: it pulls in <GL/gl.h>, which clashes with <GL/glcorearb.h> used elsewhere.
#pragma once

#include <memory>
#include <string>

namespace dem::render {

class GlContext {
 public:
  /// Creates a core-profile context of OpenGL >= 3.3 (Mesa's llvmpipe gives 4.5), falling back to
  /// a compatibility profile; throws std::runtime_error when neither reaches 3.3.
  GlContext();
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// Binds the context to the calling thread; all drawing goes to framebuffer objects, so the
  /// window-system buffer is a token 1 x 1 pixel.
  void make_current();
  void release();
  /// Address of an OpenGL entry point, resolved through OSMesa's own dispatch so that a libGL
  /// loaded into the same process cannot capture the calls.
  void* proc(const char* name) const;
  const std::string& description() const { return description_; }  // "4.5 (Core Profile) ..."

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string description_;
};

}  // namespace dem::render
