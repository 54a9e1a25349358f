// Render speed: 100,000 spheres in a box inside a cylinder of 100,000 triangles, 1920 x 1080,
// on Mesa's llvmpipe through OSMesa. Prints seconds per frame; writes the last frames as PNG.
//   render_bench [frames=5] [output folder=system temp]
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "render/render.h"

namespace dr = dem::render;

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  const std::filesystem::path folder = argc > 2 ? argv[2] : std::filesystem::temp_directory_path();

  // Spheres: a 125 x 32 x 25 lattice, jittered, in the lower half of the drum; coloured by a
  // made-up speed.
  std::vector<double> x, y, z, radius;
  std::vector<float> speed;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-0.0015, 0.0015);
  const double spacing = 0.0185;
  for (int i = 0; i < 125; ++i)
    for (int j = 0; j < 32; ++j)
      for (int k = 0; k < 25; ++k) {
        x.push_back(-1.147 + i * spacing + jitter(random));
        y.push_back(-0.287 + j * spacing + jitter(random));
        z.push_back(-0.52 + k * spacing + jitter(random));
        radius.push_back(0.0085 + 0.5 * jitter(random));
        speed.push_back(float(0.5 + 1.5 * k / 24.0 + 0.3 * std::sin(7 * x.back())));
      }

  // Cylinder along x, radius 0.62 m, 250 x 200 quads = 100,000 triangles, wear by angle.
  const int around = 250, along = 200;
  const double drum_radius = 0.62, half_length = 1.2;
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<float> wear;
  for (int a = 0; a <= along; ++a)
    for (int b = 0; b < around; ++b) {
      const double angle = 2 * std::numbers::pi * b / around;
      vertices.push_back({-half_length + 2 * half_length * a / along, drum_radius * std::cos(angle),
                          drum_radius * std::sin(angle)});
    }
  for (int a = 0; a < along; ++a)
    for (int b = 0; b < around; ++b) {
      const std::int32_t p = a * around + b, q = a * around + (b + 1) % around;
      // Outward normals: counter-clockwise seen from outside.
      triangles.push_back({p, q, p + around});
      triangles.push_back({q, q + around, p + around});
      const double angle = 2 * std::numbers::pi * (b + 0.5) / around;
      const float w = float(std::max(0.0, -std::sin(angle)) * (1 + 0.2 * std::cos(8.0 * a / along)));
      wear.push_back(w), wear.push_back(w);
    }

  dr::Frame frame;
  frame.camera = dr::fit_camera({-half_length, -drum_radius, -drum_radius}, {half_length, drum_radius, drum_radius},
                                "iso", 16.0 / 9.0);
  frame.particles.push_back({x, y, z, radius, speed});
  frame.meshes.push_back({vertices, triangles, wear});
  frame.particle_colours = dr::ColourMap{"viridis", 0.0, 2.5, "speed [m/s]"};
  frame.mesh_colours = dr::ColourMap{"coolwarm", 0.0, 1.2, "wear rate [mm/yr]"};
  frame.caption = "t = 1.250 s";

  std::printf("render_bench: %zu spheres, %zu triangles, %d x %d, %d samples\n", x.size(), triangles.size(),
              frame.width, frame.height, frame.samples);
  std::printf("backend: %s\n", dr::backend_description().c_str());
  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };

  struct Variant {
    const char* name;
    bool cutaway;
    float opacity;
  };
  for (const Variant& v : {Variant{"cutaway", true, 1.0f}, Variant{"translucent", false, 0.35f}}) {
    frame.meshes[0].cutaway = v.cutaway;
    frame.meshes[0].opacity = v.opacity;
    const std::string file = (folder / (std::string("render_bench_") + v.name + ".png")).string();
    dr::render_png(frame, file);  // warm-up: framebuffers sized, shaders compiled by llvmpipe
    double image_time = 0, png_time = 0;
    const std::clock_t cpu_start = std::clock();  // all threads: the work, whatever else runs
    for (int f = 0; f < frames; ++f) {
      const auto t0 = Clock::now();
      const dr::Image image = dr::render_image(frame);
      const auto t1 = Clock::now();
      dr::write_png(image, file);
      const auto t2 = Clock::now();
      image_time += seconds(t1 - t0), png_time += seconds(t2 - t1);
    }
    const double cpu = double(std::clock() - cpu_start) / CLOCKS_PER_SEC / frames;
    std::printf("%-12s render %.3f s/frame, + PNG %.3f s = %.3f s/frame (%d frames; CPU %.3f s/frame) -> %s\n",
                v.name, image_time / frames, png_time / frames, (image_time + png_time) / frames, frames, cpu,
                file.c_str());
  }
}
