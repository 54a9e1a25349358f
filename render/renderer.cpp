// The OpenGL side: one OSMesa context for the process, framebuffers sized per frame, two programs.
#include <cstddef>
#include <mutex>
#include <stdexcept>
#include <string>

#include "render/gl_api.h"
#include "render/internal.h"
#include "render/shaders.h"

namespace dem::render {

void Gl::load(const GlContext& context) {
#define DEM_RENDER_GL_LOAD(type, name)                                                     \
  name = reinterpret_cast<type>(context.proc("gl" #name));                                 \
  if (!name) throw std::runtime_error("render: OpenGL function gl" #name " is missing");
  DEM_RENDER_GL_FUNCTIONS(DEM_RENDER_GL_LOAD)
#undef DEM_RENDER_GL_LOAD
}

namespace {

using detail::MeshVertex;
using detail::Scene;
using detail::SphereInstance;

class Renderer {
 public:
  Renderer() {
    gl_.load(context_);
    sphere_program_ = link(shaders::sphere_vertex, shaders::sphere_fragment, "sphere");
    mesh_program_ = link(shaders::mesh_vertex, shaders::mesh_fragment, "mesh");
    build_vertex_arrays();
    context_.release();
  }

  const std::string& description() const { return context_.description(); }

  Image render(const Frame& frame) {
    const Scene scene = detail::prepare_scene(frame);
    context_.make_current();
    struct Release {
      GlContext& context;
      ~Release() { context.release(); }
    } release{context_};

    ensure_framebuffers(frame.width, frame.height, frame.samples);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, render_fbo_);
    gl_.Viewport(0, 0, frame.width, frame.height);
    gl_.ClearColor(frame.background[0], frame.background[1], frame.background[2], 1.0f);
    gl_.ClearDepth(1.0);
    gl_.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    gl_.Enable(GL_DEPTH_TEST);
    gl_.DepthFunc(GL_LEQUAL);
    gl_.DepthMask(GL_TRUE);
    gl_.Disable(GL_BLEND);
    gl_.Disable(GL_CULL_FACE);

    // Opaque walls, then spheres, then blended walls far to near without writing depth.
    draw_mesh(scene, scene.opaque);
    draw_spheres(scene, frame.samples);
    gl_.Enable(GL_BLEND);
    gl_.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    gl_.DepthMask(GL_FALSE);
    draw_mesh(scene, scene.transparent);
    gl_.DepthMask(GL_TRUE);
    gl_.Disable(GL_BLEND);

    Image image = read_back(frame.width, frame.height);
    if (const GLenum error = gl_.GetError(); error != GL_NO_ERROR)
      throw std::runtime_error("render: OpenGL error " + std::to_string(error));
    detail::draw_overlays(frame, scene, image);
    return image;
  }

 private:
  GlContext context_;
  Gl gl_;
  GLuint sphere_program_ = 0, mesh_program_ = 0;
  GLuint arrays_[2] = {0, 0};         // sphere, mesh
  GLuint buffers_[3] = {0, 0, 0};     // quad corners, sphere instances, mesh vertices
  GLuint render_fbo_ = 0, resolve_fbo_ = 0;
  GLuint renderbuffers_[3] = {0, 0, 0};  // colour, depth (multisampled), resolved colour
  int fbo_width_ = 0, fbo_height_ = 0, fbo_samples_ = 0;

  GLuint compile(GLenum type, const std::string& source, const std::string& name) {
    const GLuint shader = gl_.CreateShader(type);
    const char* text = source.c_str();
    gl_.ShaderSource(shader, 1, &text, nullptr);
    gl_.CompileShader(shader);
    GLint ok = 0;
    gl_.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[4096] = {};
      gl_.GetShaderInfoLog(shader, sizeof log, nullptr, log);
      throw std::runtime_error("render: " + name + " shader does not compile: " + log);
    }
    return shader;
  }

  GLuint link(const char* vertex, const char* fragment, const std::string& name) {
    const GLuint program = gl_.CreateProgram();
    const GLuint vs = compile(GL_VERTEX_SHADER, vertex, name);
    const GLuint fs = compile(GL_FRAGMENT_SHADER,
                              std::string("#version 330 core\n") + shaders::lighting + fragment, name);
    gl_.AttachShader(program, vs);
    gl_.AttachShader(program, fs);
    gl_.LinkProgram(program);
    gl_.DeleteShader(vs);
    gl_.DeleteShader(fs);
    GLint ok = 0;
    gl_.GetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
      char log[4096] = {};
      gl_.GetProgramInfoLog(program, sizeof log, nullptr, log);
      throw std::runtime_error("render: " + name + " program does not link: " + log);
    }
    return program;
  }

  void build_vertex_arrays() {
    gl_.GenVertexArrays(2, arrays_);
    gl_.GenBuffers(3, buffers_);
    const float corners[] = {-1, -1, 1, -1, -1, 1, 1, 1};  // triangle strip
    // Spheres: a static quad, instanced with (centre, radius) and colour per sphere.
    gl_.BindVertexArray(arrays_[0]);
    gl_.BindBuffer(GL_ARRAY_BUFFER, buffers_[0]);
    gl_.BufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
    gl_.EnableVertexAttribArray(0);
    gl_.VertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
    gl_.BindBuffer(GL_ARRAY_BUFFER, buffers_[1]);
    gl_.EnableVertexAttribArray(1);
    gl_.VertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(SphereInstance),
                            reinterpret_cast<void*>(offsetof(SphereInstance, x)));
    gl_.VertexAttribDivisor(1, 1);
    gl_.EnableVertexAttribArray(2);
    gl_.VertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(SphereInstance),
                            reinterpret_cast<void*>(offsetof(SphereInstance, rgba)));
    gl_.VertexAttribDivisor(2, 1);
    // Triangles: position, face normal and colour per corner.
    gl_.BindVertexArray(arrays_[1]);
    gl_.BindBuffer(GL_ARRAY_BUFFER, buffers_[2]);
    gl_.EnableVertexAttribArray(0);
    gl_.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                            reinterpret_cast<void*>(offsetof(MeshVertex, x)));
    gl_.EnableVertexAttribArray(1);
    gl_.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                            reinterpret_cast<void*>(offsetof(MeshVertex, nx)));
    gl_.EnableVertexAttribArray(2);
    gl_.VertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(MeshVertex),
                            reinterpret_cast<void*>(offsetof(MeshVertex, rgba)));
    gl_.BindVertexArray(0);
  }

  void delete_framebuffers() {
    if (render_fbo_) gl_.DeleteFramebuffers(1, &render_fbo_);
    if (resolve_fbo_) gl_.DeleteFramebuffers(1, &resolve_fbo_);
    if (renderbuffers_[0]) gl_.DeleteRenderbuffers(3, renderbuffers_);
    render_fbo_ = resolve_fbo_ = 0;
    renderbuffers_[0] = renderbuffers_[1] = renderbuffers_[2] = 0;
  }

  // A multisampled colour + 32-bit float depth target, resolved into a single-sample one.
  void ensure_framebuffers(int width, int height, int samples) {
    if (width == fbo_width_ && height == fbo_height_ && samples == fbo_samples_) return;
    delete_framebuffers();
    const GLsizei count = samples > 1 ? samples : 0;
    gl_.GenRenderbuffers(3, renderbuffers_);
    gl_.GenFramebuffers(1, &render_fbo_);
    gl_.GenFramebuffers(1, &resolve_fbo_);
    auto storage = [&](GLuint renderbuffer, GLsizei n, GLenum format) {
      gl_.BindRenderbuffer(GL_RENDERBUFFER, renderbuffer);
      gl_.RenderbufferStorageMultisample(GL_RENDERBUFFER, n, format, width, height);
    };
    storage(renderbuffers_[0], count, GL_RGBA8);
    storage(renderbuffers_[1], count, GL_DEPTH_COMPONENT32F);
    storage(renderbuffers_[2], 0, GL_RGBA8);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, render_fbo_);
    gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, renderbuffers_[0]);
    gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, renderbuffers_[1]);
    check_complete("multisampled");
    gl_.BindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
    gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, renderbuffers_[2]);
    check_complete("resolve");
    fbo_width_ = width, fbo_height_ = height, fbo_samples_ = samples;
  }

  void check_complete(const char* which) {
    if (gl_.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      delete_framebuffers();
      fbo_width_ = fbo_height_ = fbo_samples_ = 0;
      throw std::runtime_error(std::string("render: the ") + which + " framebuffer is incomplete");
    }
  }

  void set_camera(GLuint program, const Scene& scene) {
    gl_.UseProgram(program);
    gl_.UniformMatrix4fv(gl_.GetUniformLocation(program, "view"), 1, GL_FALSE, scene.view.data());
    gl_.UniformMatrix4fv(gl_.GetUniformLocation(program, "projection"), 1, GL_FALSE,
                         scene.projection.data());
    gl_.Uniform1i(gl_.GetUniformLocation(program, "orthographic"), scene.orthographic);
  }

  void draw_spheres(const Scene& scene, int samples) {
    if (scene.spheres.empty()) return;
    set_camera(sphere_program_, scene);
    // With multisampling the rim's partial coverage becomes sample coverage; without it a pixel
    // is in when more than half covered.
    gl_.Uniform1f(gl_.GetUniformLocation(sphere_program_, "min_coverage"), samples > 1 ? 1e-3f : 0.5f);
    if (samples > 1) gl_.Enable(GL_SAMPLE_ALPHA_TO_COVERAGE);
    gl_.BindVertexArray(arrays_[0]);
    gl_.BindBuffer(GL_ARRAY_BUFFER, buffers_[1]);
    gl_.BufferData(GL_ARRAY_BUFFER, GLsizeiptr(scene.spheres.size() * sizeof(SphereInstance)),
                   scene.spheres.data(), GL_STREAM_DRAW);
    gl_.DrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(scene.spheres.size()));
    gl_.Disable(GL_SAMPLE_ALPHA_TO_COVERAGE);
  }

  void draw_mesh(const Scene& scene, const std::vector<MeshVertex>& vertices) {
    if (vertices.empty()) return;
    set_camera(mesh_program_, scene);
    gl_.BindVertexArray(arrays_[1]);
    gl_.BindBuffer(GL_ARRAY_BUFFER, buffers_[2]);
    gl_.BufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(MeshVertex)), vertices.data(),
                   GL_STREAM_DRAW);
    gl_.DrawArrays(GL_TRIANGLES, 0, GLsizei(vertices.size()));
  }

  // Resolve the samples, read RGB rows (OpenGL's are bottom up) into a top-down image.
  Image read_back(int width, int height) {
    gl_.BindFramebuffer(GL_READ_FRAMEBUFFER, render_fbo_);
    gl_.BindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
    gl_.BlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    gl_.BindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
    gl_.ReadBuffer(GL_COLOR_ATTACHMENT0);
    gl_.PixelStorei(GL_PACK_ALIGNMENT, 1);
    // RGBA is the renderbuffer's own layout, a plain copy for llvmpipe; RGB would go through its
    // slow format-conversion path.
    Image image{width, height, std::vector<std::uint8_t>(std::size_t(width) * height * 3)};
    std::vector<std::uint8_t> rgba(std::size_t(width) * height * 4);
    gl_.ReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    for (int row = 0; row < height; ++row) {
      const std::uint8_t* in = rgba.data() + std::size_t(height - 1 - row) * width * 4;
      std::uint8_t* out = image.rgb.data() + std::size_t(row) * width * 3;
      for (int column = 0; column < width; ++column, in += 4, out += 3) out[0] = in[0], out[1] = in[1], out[2] = in[2];
    }
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
    return image;
  }
};

std::mutex renderer_mutex;

/// The process's renderer, made on first use; the caller holds renderer_mutex. Never destroyed:
/// Mesa tears its state down in its own exit handler, and a static destructor that ran after it
/// would crash inside OSMesaMakeCurrent. The operating system reclaims the memory.
Renderer& renderer() {
  static Renderer* instance = nullptr;
  if (!instance) instance = new Renderer();
  return *instance;
}

}  // namespace

Image render_image(const Frame& frame) {
  std::lock_guard lock(renderer_mutex);
  return renderer().render(frame);
}

std::string backend_description() {
  std::lock_guard lock(renderer_mutex);
  return renderer().description();
}

void render_png(const Frame& frame, const std::string& path) {
  Image image;
  try {
    image = render_image(frame);
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(std::string(error.what()) + " (rendering " + path + ")");
  } catch (const std::exception& error) {
    throw std::runtime_error(std::string(error.what()) + " (rendering " + path + ")");
  }
  write_png(image, path);
}

}  // namespace dem::render
