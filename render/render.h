// Headless renders of particles and wall meshes to PNG with OSMesa (Mesa's llvmpipe on the CPU):
// no DISPLAY, no GPU. The library takes plain arrays and includes nothing from the engine.
//
// Spheres are ray-cast impostors (one quad each; the fragment shader intersects the ray with the
// sphere, so silhouettes, shading and depth are exact, also where spheres cut walls or each
// other); spheres hidden behind nearer ones are culled on the CPU first. Walls are flat-shaded,
// lit on both sides, optionally translucent or cut away. 4x multisampling with alpha-to-coverage
// smooths both. A 1920 x 1080 frame of 100k spheres and 100k triangles takes about half a
// second on two cores (bench/render_bench.cpp).
//
//   dem::render::Frame frame;
//   frame.camera = dem::render::fit_camera(lo, hi, "iso", 16.0 / 9.0);
//   frame.particles.push_back({x, y, z, radius, speed});
//   frame.particle_colours = dem::render::ColourMap{"viridis", 0.0, 2.0, "speed [m/s]"};
//   frame.caption = "t = 1.250 s";
//   dem::render::render_png(frame, "out/frame_0001.png");
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace dem::render {

/// Pinhole or orthographic camera, world coordinates [m].
struct Camera {
  Eigen::Vector3d eye{0, -1, 0};
  Eigen::Vector3d target{0, 0, 0};
  Eigen::Vector3d up{0, 0, 1};  // need not be orthogonal to the view direction
  double fov_deg = 35;          // vertical field of view of the perspective camera
  bool orthographic = false;
  double ortho_height = 1;      // [m] height of the view when orthographic
};

/// Spheres as struct-of-arrays columns; all spans of one layer have the same length.
/// The spans only borrow: the arrays must outlive the render call.
struct ParticleLayer {
  std::span<const double> x{}, y{}, z{};  // [m] centres
  std::span<const double> radius{};   // [m]
  std::span<const float> value{};     // field to colour by (speed, size, material id, ...); empty -> `colour`
  std::array<float, 3> colour{0.80f, 0.55f, 0.25f};  // RGB in [0, 1], used without `value`
};

/// Triangle mesh; counter-clockwise winding seen from outside (the side the normal points to).
struct MeshLayer {
  std::span<const std::array<double, 3>> vertices{};         // [m]
  std::span<const std::array<std::int32_t, 3>> triangles{};  // indices into `vertices`
  std::span<const float> triangle_value{};  // per-triangle field (pressure, wear rate); empty -> `colour`
  std::array<float, 3> colour{0.72f, 0.74f, 0.77f};
  float opacity = 1.0f;  // < 1: blended, sorted back to front
  bool cutaway = false;  // hide triangles whose front faces the camera, so the inside shows
};

/// Maps a field to colour; values outside [min, max] clamp, NaN is drawn grey.
struct ColourMap {
  std::string name = "viridis";  // see colour_map_names()
  double min = std::numeric_limits<double>::quiet_NaN();  // NaN: range of the data in this frame
  double max = std::numeric_limits<double>::quiet_NaN();
  std::string label;  // title of the colour bar, with units: "speed [m/s]"
};

/// One picture: what to draw and how.
struct Frame {
  int width = 1920, height = 1080;  // [px]
  Camera camera;
  std::vector<ParticleLayer> particles;
  std::vector<MeshLayer> meshes;
  std::optional<ColourMap> particle_colours;  // empty: each layer's plain colour
  std::optional<ColourMap> mesh_colours;
  // Text (caption, colour-bar labels, scale bar) is set in DejaVu Sans from Debian's
  // fonts-dejavu-core, or in the TrueType font named by $DEMDESIGN_FONT.
  std::string caption;    // top left, e.g. "t = 1.250 s"; UTF-8
  bool scale_bar = true;  // a round length; perspective cameras measure it at the target depth
  std::array<float, 3> background{1.0f, 1.0f, 1.0f};
  int samples = 4;        // multisample anti-aliasing: 1 (off), 2 or 4
  bool cull_hidden = true;  // skip spheres that nearer spheres hide; conservative, same picture
};

/// 8-bit RGB pixels, rows top to bottom.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // (height x width x 3)
  const std::uint8_t* pixel(int column, int row) const { return &rgb[3 * (std::size_t(row) * width + column)]; }
  std::uint8_t* pixel(int column, int row) { return &rgb[3 * (std::size_t(row) * width + column)]; }
};

/// Renders `frame` into an image. Throws std::invalid_argument for inconsistent input and
/// std::runtime_error when no OpenGL 3.3 context can be created.
Image render_image(const Frame& frame);

/// Renders `frame` and writes it as PNG. Throws std::runtime_error naming `path` when rendering
/// or writing fails, std::invalid_argument (also naming `path`) for inconsistent input.
void render_png(const Frame& frame, const std::string& path);

/// The OpenGL implementation in use, e.g. "4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6,
/// 256 bits)"; creates the context if needed.
std::string backend_description();

/// A camera that shows the whole box [bbox_min, bbox_max] in an image of width/height `aspect`.
/// Presets: "side" looks along +y (x right, z up), "front" looks along -x (y right, z up),
/// "top" looks down along -z (x right, y up), "iso" looks along (-1, 1, -1) (x to the right and
/// towards the viewer, y into the picture, z up).
Camera fit_camera(const Eigen::Vector3d& bbox_min, const Eigen::Vector3d& bbox_max,
                  const std::string& preset, double aspect, bool orthographic = false);

/// Colour of `name` at t in [0, 1] (clamped), linear interpolation between the table's entries.
/// t = 0 gives the first entry exactly and t = 1 the last. Throws std::invalid_argument for an
/// unknown name.
std::array<float, 3> colour_at(const std::string& name, double t);
std::vector<std::string> colour_map_names();

/// PNG files (libpng). write_png throws std::runtime_error naming the path; read_png returns any
/// PNG as 8-bit RGB.
void write_png(const Image& image, const std::string& path);
Image read_png(const std::string& path);

}  // namespace dem::render
