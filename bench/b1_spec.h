// Benchmark B1 "box settle": the specification shared by bench_b1_settle (one process) and
// bench_b3_domain (split over MPI ranks): sizes, the case and the jittered lattice. The full
// specification is in the header comment of b1_settle.cpp.
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "case/spec.h"
#include "core/particles.h"

namespace bench::b1 {

inline constexpr double kSpacing = 0.005;      // [m] lattice spacing S
inline constexpr double kJitter = 0.0004;      // [m] lateral jitter amplitude
inline constexpr std::uint64_t kSeed = 20240601;

struct Size {
  int nx, ny, nz;
  double lx, ly;           // [m]
  std::int64_t phase1, phase2;  // steps
  long n() const { return static_cast<long>(nx) * ny * nz; }
};

inline Size size_for(long n) {
  if (n == 20000) return {25, 25, 32, 0.125, 0.125, 20000, 4000};
  if (n == 100000) return {50, 50, 40, 0.25, 0.25, 20000, 1000};
  // Scaling series (not in the spec): the 20k bed's 32 layers on a wider square footprint,
  // n = NX x NX x 32 with NX = round(sqrt(n / 32)); the box grows with the lattice.
  if (n >= 2000 && n <= 4000000) {
    const int nx = static_cast<int>(std::lround(std::sqrt(static_cast<double>(n) / 32.0)));
    const double l = nx * kSpacing;
    return {nx, nx, 32, l, l, 20000, 4000};
  }
  throw std::runtime_error(fmt::format("--n {}: the spec's sizes are 20000 and 100000; the scaling series takes 2000-4000000", n));
}

/// The case as YAML; particle positions are filled in afterwards (one placeholder here).
inline std::string case_yaml(const Size& b) {
  return fmt::format(R"(title: B1 box settle
simulation:
  duration: 1.0
  time_step: 1.5e-5
  unsafe_time_step: warn
  gravity: [0, 0, -9.81]
  skin: 0.001
  seed: {seed}
materials:
  m:
    density: 2500
    youngs_modulus: 5.0e7
    poisson_ratio: 0.25
    restitution: 0.5
    friction: 0.5
contact:
  normal: hertz
  damping: {{model: restitution, end_of_contact: tension}}
  tangential: mindlin
  rolling: none
walls:
  - {{name: floor, plane: {{point: [0, 0, 0], normal: [0, 0, 1]}}, material: m}}
  - {{name: x0, plane: {{point: [0, 0, 0], normal: [1, 0, 0]}}, material: m}}
  - {{name: x1, plane: {{point: [{lx}, 0, 0], normal: [-1, 0, 0]}}, material: m}}
  - {{name: y0, plane: {{point: [0, 0, 0], normal: [0, 1, 0]}}, material: m}}
  - {{name: y1, plane: {{point: [0, {ly}, 0], normal: [0, -1, 0]}}, material: m}}
particles:
  - material: m
    diameter: 0.004
    positions: [[0.0025, 0.0025, 0.0025]]
)",
                     fmt::arg("seed", kSeed), fmt::arg("lx", b.lx), fmt::arg("ly", b.ly));
}

/// Lattice centres in id order (i fastest, then j, then k), jitter jx then jy per particle.
inline std::vector<dem::Vec3> lattice(const Size& b) {
  std::vector<dem::Vec3> out;
  out.reserve(static_cast<size_t>(b.n()));
  dem::Random random(kSeed);
  for (int k = 0; k < b.nz; ++k)
    for (int j = 0; j < b.ny; ++j)
      for (int i = 0; i < b.nx; ++i) {
        const double jx = kJitter * (2.0 * random.uniform() - 1.0);
        const double jy = kJitter * (2.0 * random.uniform() - 1.0);
        out.emplace_back((i + 0.5) * kSpacing + jx, (j + 0.5) * kSpacing + jy, (k + 0.5) * kSpacing);
      }
  return out;
}


}  // namespace bench::b1
