// Headless renders: checked by image size, pixel coverage bands, positions and colours, never
// byte for byte. Each test renders with DISPLAY unset (OSMesa needs no X server).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

#include "render/render.h"

namespace dr = dem::render;

// For sanitizer builds (DEMDESIGN_SANITIZE): Mesa keeps a few hundred bytes until the process
// ends, which LeakSanitizer would report as ours.
extern "C" const char* __lsan_default_suppressions() { return "leak:libOSMesa.so\n"; }

namespace {

class Render : public ::testing::Test {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    unsetenv("WAYLAND_DISPLAY");
    directory_ = std::filesystem::temp_directory_path() /
                 ("demdesign_render_" + std::to_string(::getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }
  std::string path(const std::string& name) const { return (directory_ / name).string(); }

  std::filesystem::path directory_;
};

/// One sphere as a layer; the arrays live in the struct so the spans stay valid.
struct Spheres {
  std::vector<double> x, y, z, r;
  std::vector<float> value;
  void add(double px, double py, double pz, double radius, float v = 0) {
    x.push_back(px), y.push_back(py), z.push_back(pz), r.push_back(radius), value.push_back(v);
  }
  dr::ParticleLayer layer(std::array<float, 3> colour, bool with_value = false) const {
    dr::ParticleLayer l{x, y, z, r, {}, colour};
    if (with_value) l.value = value;
    return l;
  }
};

/// Plain scene: white background, no caption or scale bar, so every dark pixel is geometry.
dr::Frame plain_frame(int width, int height) {
  dr::Frame frame;
  frame.width = width, frame.height = height;
  frame.scale_bar = false;
  return frame;
}

/// Side view (looking along +y, x right, z up) of an orthographic camera centred on the origin.
dr::Camera ortho_side(double height) {
  dr::Camera camera;
  camera.eye = {0, -5, 0};
  camera.target = {0, 0, 0};
  camera.orthographic = true;
  camera.ortho_height = height;
  return camera;
}

bool is_background(const std::uint8_t* p) { return p[0] > 245 && p[1] > 245 && p[2] > 245; }

struct Coverage {
  double area = 0, x = 0, y = 0;  // [px], centroid [px] (pixel centres at +0.5)
};

/// Pixels at least half covered by a red object on white: green below mid-grey.
Coverage red_coverage(const dr::Image& image) {
  Coverage c;
  for (int row = 0; row < image.height; ++row)
    for (int column = 0; column < image.width; ++column)
      if (image.pixel(column, row)[1] < 128) c.area += 1, c.x += column + 0.5, c.y += row + 0.5;
  if (c.area > 0) c.x /= c.area, c.y /= c.area;
  return c;
}

/// Pixels of a clearly red hue, whatever lies around them (grey walls included).
int red_pixels(const dr::Image& image) {
  int n = 0;
  for (int row = 0; row < image.height; ++row)
    for (int column = 0; column < image.width; ++column) {
      const auto* p = image.pixel(column, row);
      n += p[0] > p[1] + 40 && p[0] > p[2] + 40;
    }
  return n;
}

/// Direction of a colour, to compare hues independently of shading.
std::array<double, 3> direction(double r, double g, double b) {
  const double n = std::sqrt(r * r + g * g + b * b);
  return {r / n, g / n, b / n};
}

double angle_between(std::array<double, 3> a, std::array<double, 3> b) {
  return std::acos(std::clamp(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], -1.0, 1.0));
}

}  // namespace

TEST_F(Render, WritesPngOfRequestedSizeWithoutDisplay) {
  ASSERT_EQ(std::getenv("DISPLAY"), nullptr);
  Spheres s;
  s.add(0, 0, 0, 0.1);
  for (auto [width, height] : {std::pair{320, 200}, std::pair{257, 131}}) {
    dr::Frame frame;  // with caption and scale bar: the font path is exercised too
    frame.width = width, frame.height = height;
    frame.camera = dr::fit_camera({-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1}, "iso", double(width) / height);
    frame.particles.push_back(s.layer({0.2f, 0.4f, 0.8f}));
    frame.caption = "t = 1.250 s";
    const std::string file = path("size_" + std::to_string(width) + ".png");
    dr::render_png(frame, file);
    const dr::Image image = dr::read_png(file);
    EXPECT_EQ(image.width, width);
    EXPECT_EQ(image.height, height);
    EXPECT_EQ(image.rgb.size(), std::size_t(width) * height * 3);
  }
}

TEST_F(Render, OrthographicSphereCoversItsProjectedDiscAtItsPosition) {
  // Radius 0.2 m in a view 1 m high on 400 px: 80 px radius, centre 0.1 m right and 0.05 m up.
  const int size = 400;
  const double ppm = size / 1.0, radius = 0.2;
  Spheres s;
  s.add(0.1, 0.3, 0.05, radius);
  for (int samples : {1, 4}) {
    dr::Frame frame = plain_frame(size, size);
    frame.samples = samples;
    frame.camera = ortho_side(1.0);
    frame.particles.push_back(s.layer({1, 0, 0}));
    const std::string file = path("sphere.png");
    dr::render_png(frame, file);
    const dr::Image image = dr::read_png(file);
    const Coverage c = red_coverage(image);
    const double expected = std::numbers::pi * std::pow(radius * ppm, 2);
    EXPECT_NEAR(c.area / expected, 1.0, 0.05) << "samples " << samples;
    EXPECT_NEAR(c.x, size / 2.0 + 0.1 * ppm, 1.0);
    EXPECT_NEAR(c.y, size / 2.0 - 0.05 * ppm, 1.0);

    // Shaded, not a flat disc: the centre is brighter than anywhere near the rim.
    const int cx = int(c.x), cy = int(c.y), rim = int(0.92 * radius * ppm);
    const int centre_red = image.pixel(cx, cy)[0];
    EXPECT_GT(centre_red, 180);
    for (auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, -1}}) {
      const double n = std::hypot(dx, dy);
      const auto* p = image.pixel(cx + int(dx * rim / n), cy + int(dy * rim / n));
      EXPECT_LT(p[0] + 20, centre_red) << "rim toward (" << dx << ", " << dy << ")";
    }
  }
}

TEST_F(Render, PerspectiveSphereCoversItsSilhouette) {
  // Sphere at the target, eye at distance d: silhouette radius f r / sqrt(d^2 - r^2) pixels.
  const int width = 480, height = 360;
  const double d = 3.0, radius = 0.25, fov = 30;
  Spheres s;
  s.add(0, 0, 0, radius);
  dr::Frame frame = plain_frame(width, height);
  frame.camera.eye = {0, -d, 0};
  frame.camera.fov_deg = fov;
  frame.particles.push_back(s.layer({1, 0, 0}));
  const dr::Image image = dr::render_image(frame);
  const double focal = 0.5 * height / std::tan(0.5 * fov * std::numbers::pi / 180);
  const double rho = focal * radius / std::sqrt(d * d - radius * radius);
  const Coverage c = red_coverage(image);
  EXPECT_NEAR(c.area / (std::numbers::pi * rho * rho), 1.0, 0.05);
  EXPECT_NEAR(c.x, width / 2.0, 1.0);
  EXPECT_NEAR(c.y, height / 2.0, 1.0);
}

TEST_F(Render, ColourMapEndsAreItsFirstAndLastColours) {
  EXPECT_EQ(dr::colour_at("viridis", 0), (std::array<float, 3>{0.267004f, 0.004874f, 0.329415f}));
  EXPECT_EQ(dr::colour_at("viridis", 1), (std::array<float, 3>{0.993248f, 0.906157f, 0.143936f}));
  EXPECT_EQ(dr::colour_at("viridis", -3), dr::colour_at("viridis", 0));  // clamped
  EXPECT_EQ(dr::colour_at("viridis", 7), dr::colour_at("viridis", 1));
  for (const std::string& name : dr::colour_map_names()) EXPECT_NO_THROW(dr::colour_at(name, 0.5));
  EXPECT_THROW(dr::colour_at("no-such-map", 0.5), std::invalid_argument);
}

TEST_F(Render, ParticlesColouredByValueShowTheMapEnds) {
  // Three spheres valued 2, 5 and 8 on a map from 2 to 8: the outer two take the map's ends.
  Spheres s;
  s.add(-0.3, 0, 0, 0.1, 2.0f);
  s.add(0.0, 0, 0, 0.1, 5.0f);
  s.add(0.3, 0, 0, 0.1, 8.0f);
  const int size = 300;
  dr::Frame frame = plain_frame(size, size);
  frame.camera = ortho_side(1.0);
  frame.particles.push_back(s.layer({1, 1, 1}, true));
  frame.particle_colours = dr::ColourMap{"viridis", 2.0, 8.0, "speed [m/s]"};
  const dr::Image image = dr::render_image(frame);
  for (auto [x, t] : {std::pair{-0.3, 0.0}, {0.3, 1.0}}) {
    const auto* p = image.pixel(int(size / 2 + x * size), size / 2);
    const auto expected = dr::colour_at("viridis", t);
    const double angle = angle_between(direction(p[0], p[1], p[2]), direction(expected[0], expected[1], expected[2]));
    EXPECT_LT(angle, 0.08) << "t = " << t << ": pixel " << int(p[0]) << " " << int(p[1]) << " " << int(p[2]);
  }
  // The colour bar at the right shows both ends of the map.
  bool first = false, last = false;
  for (int row = 0; row < size; ++row)
    for (int column = size * 3 / 4; column < size; ++column) {
      const auto* p = image.pixel(column, row);
      auto near = [&](std::array<float, 3> c) {
        return std::abs(p[0] - 255 * c[0]) < 4 && std::abs(p[1] - 255 * c[1]) < 4 && std::abs(p[2] - 255 * c[2]) < 4;
      };
      first |= near(dr::colour_at("viridis", 0));
      last |= near(dr::colour_at("viridis", 1));
    }
  EXPECT_TRUE(first);
  EXPECT_TRUE(last);
}

namespace {

/// Axis-aligned box [-h, h]^3 as 12 triangles, counter-clockwise seen from outside.
struct Box {
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  explicit Box(double h) {
    for (int i = 0; i < 8; ++i) vertices.push_back({i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h});
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) triangles.push_back({q[0], q[1], q[2]}), triangles.push_back({q[0], q[2], q[3]});
  }
};

}  // namespace

TEST_F(Render, CutawayHidesWallsFacingTheCamera) {
  // A red sphere inside a closed grey box: hidden by the walls, seen once they are cut away.
  const Box box(0.4);
  Spheres s;
  s.add(0, 0, 0, 0.2);
  const int size = 200;
  const double disc = std::numbers::pi * std::pow(0.2 * size, 2);
  for (bool ortho : {true, false}) {
    dr::Frame frame = plain_frame(size, size);
    frame.camera = ortho ? ortho_side(1.0) : dr::fit_camera({-0.4, -0.4, -0.4}, {0.4, 0.4, 0.4}, "iso", 1.0);
    frame.particles.push_back(s.layer({1, 0, 0}));
    frame.meshes.push_back({.vertices = box.vertices, .triangles = box.triangles});
    EXPECT_EQ(red_pixels(dr::render_image(frame)), 0) << "closed box, ortho " << ortho;

    frame.meshes[0].cutaway = true;
    const dr::Image cut = dr::render_image(frame);
    EXPECT_GT(red_pixels(cut), ortho ? 0.9 * disc : 0.1 * disc) << "ortho " << ortho;
    // The far walls are still drawn: grey, not background, beside the sphere.
    EXPECT_FALSE(is_background(cut.pixel(size / 2 + int(0.3 * size), size / 2))) << "ortho " << ortho;

    // Translucent walls show the sphere, tinted.
    frame.meshes[0].cutaway = false;
    frame.meshes[0].opacity = 0.3f;
    EXPECT_GT(red_pixels(dr::render_image(frame)), 0.1 * disc) << "translucent, ortho " << ortho;
  }
}

TEST_F(Render, WallsColouredByTriangleValue) {
  // A square facing the camera, two triangles valued at the map's ends.
  const std::vector<std::array<double, 3>> vertices{{-0.4, 0, -0.4}, {0.4, 0, -0.4}, {0.4, 0, 0.4}, {-0.4, 0, 0.4}};
  const std::vector<std::array<std::int32_t, 3>> triangles{{0, 1, 2}, {0, 2, 3}};  // lower right, upper left
  const std::vector<float> pressure{1e5f, 0.0f};
  dr::Frame frame = plain_frame(200, 200);
  frame.camera = ortho_side(1.0);
  frame.meshes.push_back({vertices, triangles, pressure});
  frame.mesh_colours = dr::ColourMap{"coolwarm", 0, 1e5, "pressure [Pa]"};
  const dr::Image image = dr::render_image(frame);
  for (auto [column, row, t] : {std::tuple{140, 140, 1.0}, {60, 60, 0.0}}) {
    const auto* p = image.pixel(column, row);
    const auto c = dr::colour_at("coolwarm", t);
    EXPECT_LT(angle_between(direction(p[0], p[1], p[2]), direction(c[0], c[1], c[2])), 0.08) << "t = " << t;
  }
}

TEST_F(Render, FitCameraKeepsTheBoxInView) {
  // Spheres at the corners of a flat box: every preset shows them all, none touching the border.
  const Eigen::Vector3d lo(-1, -0.3, 0), hi(2, 0.5, 0.4);
  Spheres s;
  for (int i = 0; i < 8; ++i)
    s.add(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z(), 0.02);
  for (const char* preset : {"side", "front", "top", "iso"})
    for (bool ortho : {false, true}) {
      dr::Frame frame = plain_frame(320, 180);
      frame.camera = dr::fit_camera(lo, hi, preset, 320.0 / 180.0, ortho);
      frame.particles.push_back(s.layer({1, 0, 0}));
      const dr::Image image = dr::render_image(frame);
      int lo_x = image.width, hi_x = -1, lo_y = image.height, hi_y = -1;
      for (int row = 0; row < image.height; ++row)
        for (int column = 0; column < image.width; ++column)
          if (!is_background(image.pixel(column, row)))
            lo_x = std::min(lo_x, column), hi_x = std::max(hi_x, column), lo_y = std::min(lo_y, row),
            hi_y = std::max(hi_y, row);
      const std::string what = std::string(preset) + (ortho ? " ortho" : " perspective");
      ASSERT_GE(hi_x, 0) << what;
      EXPECT_GT(lo_x, 0) << what;
      EXPECT_GT(lo_y, 0) << what;
      EXPECT_LT(hi_x, image.width - 1) << what;
      EXPECT_LT(hi_y, image.height - 1) << what;
      // Fitted, not lost in the middle: the spheres span most of the limiting dimension.
      EXPECT_GT(std::max(double(hi_x - lo_x) / image.width, double(hi_y - lo_y) / image.height), 0.6) << what;
    }
  EXPECT_THROW(dr::fit_camera(lo, hi, "diagonal", 1.0), std::invalid_argument);
}

TEST_F(Render, CullingHiddenSpheresLeavesThePictureUnchanged) {
  // A dense bed, 30 x 30 x 12 spheres: most are hidden, and culling them must not show.
  Spheres s;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j)
      for (int k = 0; k < 12; ++k) s.add(0.021 * i, 0.021 * j + 0.003 * (k % 2), 0.02 * k, 0.01 + 0.001 * ((i + j + k) % 3), float(k));
  for (bool ortho : {false, true}) {
    dr::Frame frame = plain_frame(480, 320);
    frame.camera = dr::fit_camera({0, 0, 0}, {0.63, 0.63, 0.24}, "iso", 1.5, ortho);
    frame.particles.push_back(s.layer({1, 1, 1}, true));
    frame.particle_colours = dr::ColourMap{"viridis", 0, 11, ""};
    frame.cull_hidden = false;
    const dr::Image all = dr::render_image(frame);
    frame.cull_hidden = true;
    const dr::Image culled = dr::render_image(frame);
    int differ = 0;
    for (std::size_t i = 0; i < all.rgb.size(); i += 3)
      differ += std::abs(all.rgb[i] - culled.rgb[i]) > 3 || std::abs(all.rgb[i + 1] - culled.rgb[i + 1]) > 3 ||
                std::abs(all.rgb[i + 2] - culled.rgb[i + 2]) > 3;
    EXPECT_LT(differ, 10) << "ortho " << ortho;  // a few pixels of depth-test ties at most
  }
}

TEST_F(Render, FailuresNameThePath) {
  dr::Frame frame = plain_frame(64, 48);
  const std::string missing = path("no/such/folder/frame.png");
  try {
    dr::render_png(frame, missing);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(missing), std::string::npos) << error.what();
  }
  Spheres s;
  s.add(0, 0, 0, 0.1);
  frame.particles.push_back(s.layer({1, 0, 0}));
  frame.particles[0].radius = {};  // lengths disagree
  EXPECT_THROW(dr::render_png(frame, path("bad.png")), std::invalid_argument);
  EXPECT_THROW(dr::read_png(path("absent.png")), std::runtime_error);
}
