#include "render/gl_context.h"

#include <GL/osmesa.h>

#include <cstdlib>
#include <stdexcept>
#include <vector>

namespace dem::render {

struct GlContext::Impl {
  OSMesaContext context = nullptr;
  std::vector<unsigned char> token_buffer = std::vector<unsigned char>(4, 0);  // 1 x 1 RGBA
  ~Impl() {
    if (context) OSMesaDestroyContext(context);
  }
};

namespace {

OSMesaContext create(int profile, int major, int minor) {
  const int attributes[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 0,
                            OSMESA_PROFILE, profile, OSMESA_CONTEXT_MAJOR_VERSION, major,
                            OSMESA_CONTEXT_MINOR_VERSION, minor, 0};
  return OSMesaCreateContextAttribs(attributes, nullptr);
}

}  // namespace

GlContext::GlContext() : impl_(std::make_unique<Impl>()) {
  // Core 3.3 first; Mesa hands back its highest version of that profile. A compatibility context
  // of 3.3 is the fallback (older Mesa built without core support in OSMesa).
  impl_->context = create(OSMESA_CORE_PROFILE, 3, 3);
  if (!impl_->context) impl_->context = create(OSMESA_COMPAT_PROFILE, 3, 3);
  if (!impl_->context)
    throw std::runtime_error("render: OSMesa could not create an OpenGL 3.3 context (needs Mesa's "
                             "llvmpipe or softpipe, Debian package libosmesa6)");
  make_current();
  using GetString = const unsigned char* (*)(unsigned);
  auto get_string = reinterpret_cast<GetString>(proc("glGetString"));
  const auto* version = get_string ? get_string(0x1F02 /* GL_VERSION */) : nullptr;
  const auto* renderer = get_string ? get_string(0x1F01 /* GL_RENDERER */) : nullptr;
  description_ = std::string(version ? reinterpret_cast<const char*>(version) : "?") + ", " +
                 (renderer ? reinterpret_cast<const char*>(renderer) : "?");
  int major = version ? std::atoi(reinterpret_cast<const char*>(version)) : 0;
  int minor = version ? std::atoi(reinterpret_cast<const char*>(version) + 2) : 0;
  if (major < 3 || (major == 3 && minor < 3))
    throw std::runtime_error("render: OpenGL 3.3 needed, OSMesa gives " + description_);
}

GlContext::~GlContext() = default;

void GlContext::make_current() {
  if (!OSMesaMakeCurrent(impl_->context, impl_->token_buffer.data(), GL_UNSIGNED_BYTE, 1, 1))
    throw std::runtime_error("render: OSMesaMakeCurrent failed");
}

void GlContext::release() { OSMesaMakeCurrent(nullptr, nullptr, GL_UNSIGNED_BYTE, 0, 0); }

void* GlContext::proc(const char* name) const {
  return reinterpret_cast<void*>(OSMesaGetProcAddress(name));
}

}  // namespace dem::render
