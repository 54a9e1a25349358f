// Candidate triangles near particles: Embree's BVH point queries (what the engine uses) against
// a uniform grid of triangle bounding boxes, on a triangulated drum of about 100,000 triangles
// with 100,000 particles near its surface. Prints queries per second and checks that both find
// the same triangles.
//
// Usage: bench_mesh_query [--triangles N] [--particles P]
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <unordered_map>
#include <vector>

#include "contact/mesh.h"
#include "core/particles.h"

namespace {

using dem::TriangleSurface;

/// Uniform grid over triangle bounding boxes; a query visits the cells its sphere's box touches.
class TriangleGrid {
 public:
  TriangleGrid(const TriangleSurface& s, double cell) : surface_(s), cell_(cell) {
    for (size_t t = 0; t < s.size(); ++t) {
      double lo[3], hi[3];
      bounds(t, lo, hi);
      for (long z = index(lo[2]); z <= index(hi[2]); ++z)
        for (long y = index(lo[1]); y <= index(hi[1]); ++y)
          for (long x = index(lo[0]); x <= index(hi[0]); ++x) cells_[key(x, y, z)].push_back(static_cast<std::int32_t>(t));
    }
  }
  void within(const double p[3], double r, std::vector<std::int32_t>& out) const {
    const size_t first = out.size();
    for (long z = index(p[2] - r); z <= index(p[2] + r); ++z)
      for (long y = index(p[1] - r); y <= index(p[1] + r); ++y)
        for (long x = index(p[0] - r); x <= index(p[0] + r); ++x) {
          const auto it = cells_.find(key(x, y, z));
          if (it == cells_.end()) continue;
          for (std::int32_t t : it->second) {
            const auto& tri = surface_.triangles[t];
            const dem::ClosestPoint cp = dem::closest_point_on_triangle(p, surface_.vertices[tri[0]].data(),
                                                                        surface_.vertices[tri[1]].data(), surface_.vertices[tri[2]].data());
            if (cp.distance2 <= r * r) out.push_back(t);
          }
        }
    std::sort(out.begin() + static_cast<long>(first), out.end());
    out.erase(std::unique(out.begin() + static_cast<long>(first), out.end()), out.end());
  }

 private:
  void bounds(size_t t, double lo[3], double hi[3]) const {
    for (int a = 0; a < 3; ++a) {
      lo[a] = hi[a] = surface_.vertices[surface_.triangles[t][0]][a];
      for (int k = 1; k < 3; ++k) {
        lo[a] = std::min(lo[a], surface_.vertices[surface_.triangles[t][k]][a]);
        hi[a] = std::max(hi[a], surface_.vertices[surface_.triangles[t][k]][a]);
      }
    }
  }
  long index(double v) const { return static_cast<long>(std::floor(v / cell_)); }
  static std::uint64_t key(long x, long y, long z) {
    return (static_cast<std::uint64_t>(x & 0x1fffff) << 42) | (static_cast<std::uint64_t>(y & 0x1fffff) << 21) |
           static_cast<std::uint64_t>(z & 0x1fffff);
  }
  const TriangleSurface& surface_;
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<std::int32_t>> cells_;
};

}  // namespace

int main(int argc, char** argv) {
  long triangles = 100000, particles = 100000;
  for (int k = 1; k + 1 < argc; k += 2) {
    if (!std::strcmp(argv[k], "--triangles")) triangles = std::stol(argv[k + 1]);
    if (!std::strcmp(argv[k], "--particles")) particles = std::stol(argv[k + 1]);
  }
  // Drum of radius 0.5 m, length 1 m: segments x rings quads.
  const int rings = static_cast<int>(std::sqrt(triangles / 2.0 / std::numbers::pi)) + 1;
  const int segments = static_cast<int>(triangles / 2 / rings);
  TriangleSurface surface;
  const double radius = 0.5, length = 1.0;
  for (int j = 0; j <= rings; ++j)
    for (int i = 0; i < segments; ++i) {
      const double a = 2 * std::numbers::pi * i / segments;
      surface.vertices.push_back({radius * std::cos(a), length * j / rings, radius * std::sin(a)});
    }
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < segments; ++i) {
      const int a = j * segments + i, b = j * segments + (i + 1) % segments;
      surface.triangles.push_back({a, b + segments, b});
      surface.triangles.push_back({a, a + segments, b + segments});
    }
  surface.build_topology();
  const dem::TriangleBvh bvh(surface);
  // Particles of radius 4 mm within a few radii of the wall; query radius r + skin.
  const double r = 0.004, reach = r + 0.001;
  dem::Random random(1);
  std::vector<std::array<double, 3>> points(static_cast<size_t>(particles));
  for (auto& p : points) {
    const double a = 2 * std::numbers::pi * random.uniform(), rho = radius - 0.012 * random.uniform();
    p = {rho * std::cos(a), length * random.uniform(), rho * std::sin(a)};
  }
  using Clock = std::chrono::steady_clock;
  std::vector<std::int32_t> found_bvh, found_grid;
  found_bvh.reserve(points.size() * 8), found_grid.reserve(points.size() * 8);
  const auto t0 = Clock::now();
  for (const auto& p : points) {
    const size_t first = found_bvh.size();
    bvh.within(p.data(), reach, found_bvh);
    std::sort(found_bvh.begin() + static_cast<long>(first), found_bvh.end());
  }
  const auto t1 = Clock::now();
  const TriangleGrid grid(surface, 2 * reach);
  const auto t2 = Clock::now();
  for (const auto& p : points) grid.within(p.data(), reach, found_grid);
  const auto t3 = Clock::now();
  const double s_bvh = std::chrono::duration<double>(t1 - t0).count(), s_grid = std::chrono::duration<double>(t3 - t2).count();
  const double s_build = std::chrono::duration<double>(t2 - t1).count();
  fmt::print("mesh query: {} triangles (edge {:.1f} mm), {} particles, query radius {:.1f} mm, one thread\n", surface.size(),
             1000 * 2 * std::numbers::pi * radius / segments, points.size(), 1000 * reach);
  fmt::print("  Embree BVH point query : {:.3f} s, {:.3g} queries/s\n", s_bvh, points.size() / s_bvh);
  fmt::print("  uniform grid           : {:.3f} s, {:.3g} queries/s (grid build {:.3f} s)\n", s_grid, points.size() / s_grid, s_build);
  fmt::print("  same candidates: {} ({} found)\n", found_bvh == found_grid ? "yes" : "NO", found_bvh.size());
  fmt::print("csv,mesh_query,{},{},{:.6g},{:.6g},{:.6g}\n", surface.size(), points.size(), points.size() / s_bvh,
             points.size() / s_grid, s_build);
  return found_bvh == found_grid ? 0 : 1;
}
