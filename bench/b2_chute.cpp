// Benchmark B2 "mesh chute": spheres fed at 30,000 per second into an STL chute (a 35 degree
// trough ending in a spoon) flow down it and leave off the spoon lip. After a fill phase that
// brings the flow to a steady state, a timed phase is stepped on; the figure of merit is particle
// time steps per second of that timed stepping (no output inside it).
//
// Specification (copied from the team's benchmark spec; the program reads no files but the STL
// it writes itself):
//   Common: SI units, gravity 9.81 m/s^2 along -z, spheres only, velocity Verlet, no global
//     damping, no cohesion. Contact law: Hertz normal + Mindlin tangential with history +
//     restitution damping, tension allowed (LIGGGHTS `gran model hertz tangential history`,
//     no force limiting) + constant directional torque rolling friction (LIGGGHTS
//     `rolling_friction cdt`), i.e.
//     contact: {normal: hertz, damping: {model: restitution, end_of_contact: tension},
//               tangential: mindlin, rolling: cdt}.
//   Geometry (metres; x down the chute, y across, z up): a trough with a flat floor 0.30 m wide
//     (y in [-0.15, 0.15]) and two side walls 0.15 m high standing perpendicular to the floor.
//     Floor centre-line: straight 1.0 m at 35 degrees below horizontal from (x, z) = (0, 0) to
//     (0.81915, -0.57358), then a "spoon", a circular arc of radius 0.5 m, concave up, turning
//     the slope from 35 to 10 degrees, ending at (1.01912, -0.65640). The upper end is closed by
//     a back plate (0.30 x 0.15 m) normal to the chute axis; the lower end is open.
//     Triangulation: 40 segments along the straight part and 10 along the spoon; 12 strips
//     across the floor and 6 up each wall; every quad split in 2: 2,400 triangles + 144 of the
//     back plate = 2,544 triangles (ASCII STL, written by write_chute_stl below; LIGGGHTS reads
//     the same file).
//   Particles: monodisperse d = 8 mm (R = 4 mm), density 2500 kg/m^3 (m = 6.702e-4 kg).
//   Materials: particles and chute E = 5.0e7 Pa, nu = 0.25; restitution 0.5 (particle-particle
//     and particle-wall); friction 0.5 particle-particle, 0.4 particle-wall; rolling friction
//     0.05 both.
//   Time step: dt = 3.0e-5 s (given explicitly; 19.6 % of the Rayleigh time).
//   Feed: 30,000 particles/s, inserted every 500 steps (450 a batch) at random non-overlapping
//     positions entirely inside the box x in [0.10, 0.30], y in [-0.12, 0.12], z in [0.02, 0.12],
//     initial velocity (1.0, 0, -0.5) m/s.
//   Domain: x in [-0.02, 1.06], y in [-0.16, 0.16], z in [-0.70, 0.20]; particles leaving it are
//     deleted (the outflow off the spoon lip).
//   Wall model: per-triangle records (normal and shear impulse, friction work, impacts and impact
//     energy), which demdesign always keeps (LIGGGHTS: `mesh/surface/stress ... wear finnie`).
//   Neighbour skin: 2 mm.
//   Fill: 30,000 steps (0.9 s) from an empty chute to steady flow. Timed run: 3,000 steps
//     (0.09 s) continuing with the feed on.
//   Figures: particle-steps/s = mean particle count x timed steps / loop seconds (the clock runs
//     only around dem::step; the samples are taken with it stopped); the mean particle count is
//     over samples every 500 steps of the timed phase, start and end included (as over the
//     LIGGGHTS thermo rows); touching particle-particle pairs per particle (LIGGGHTS
//     compute contact/atom / 2), mean over the same samples; mass flow off the spoon lip =
//     particles that left the domain during the timed phase x m / its duration; peak memory per
//     particle = VmHWM / mean particle count.
//
// Usage: bench_b2_chute [--threads T] [--fill-steps S] [--run-steps S]
//        bench_b2_chute --write-stl FILE   (writes the chute STL for LIGGGHTS and stops)
//   Prints a table row and one line starting with "csv," (header "csv,phase,...") for committing.
#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include "base/allocator.h"
#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "core/state.h"
#include "core/step.h"
#include "core/workspace.h"
#include "mesh_health.h"
#include "output/checkpoint.h"
#include "peak_memory.h"
#include "statistics/diagnostics.h"
#include "triangle_mesh.h"

namespace {

// Chute geometry [m, deg] and its triangulation.
constexpr double kStraightLength = 1.0;    // [m] straight part of the floor centre-line
constexpr double kSlopeDeg = 35.0;         // [deg] of the straight part
constexpr double kLipDeg = 10.0;           // [deg] slope at the spoon's end
constexpr double kSpoonRadius = 0.5;       // [m]
constexpr double kWidth = 0.30;            // [m] floor
constexpr double kWallHeight = 0.15;       // [m] side walls and back plate
constexpr int kStraightSegments = 40, kSpoonSegments = 10, kFloorStrips = 12, kWallStrips = 6;

// Particles, feed and run.
constexpr double kDiameter = 0.008;        // [m]
constexpr double kDensity = 2500.0;        // [kg/m^3]
constexpr double kDt = 3.0e-5;             // [s]
constexpr double kFeedRate = 30000.0;      // [particles/s]
constexpr int kInsertEvery = 500;          // steps between insertions (450 particles each)
constexpr int kSampleEvery = 500;          // steps between samples of the timed phase
constexpr std::uint64_t kSeed = 15485863;

double particle_mass() { return kDensity * std::numbers::pi / 6.0 * kDiameter * kDiameter * kDiameter; }  // [kg]

using Point = std::array<double, 3>;

/// Floor centre-line (x, z, slope angle [rad]) at the section nodes: the straight part from the
/// origin, then the spoon arc about its centre of curvature (upward normal of the floor is
/// (sin t, cos t) in the x-z plane).
std::vector<Point> centre_line() {
  std::vector<Point> out;
  const double t1 = kSlopeDeg * std::numbers::pi / 180.0, t2 = kLipDeg * std::numbers::pi / 180.0;
  for (int i = 0; i <= kStraightSegments; ++i) {
    const double s = kStraightLength * i / kStraightSegments;
    out.push_back({s * std::cos(t1), -s * std::sin(t1), t1});
  }
  const double cx = out.back()[0] + kSpoonRadius * std::sin(t1), cz = out.back()[1] + kSpoonRadius * std::cos(t1);
  for (int i = 1; i <= kSpoonSegments; ++i) {
    const double t = t1 + (t2 - t1) * i / kSpoonSegments;
    out.push_back({cx - kSpoonRadius * std::sin(t), cz - kSpoonRadius * std::cos(t), t});
  }
  return out;
}

/// Cross-section polyline at one centre-line node: left wall top down to the floor, across the
/// floor, right wall up to its top (walls along the local upward normal of the floor).
std::vector<Point> section(const Point& c) {
  const double x = c[0], z = c[1], nx = std::sin(c[2]), nz = std::cos(c[2]);
  std::vector<Point> p;
  for (int k = kWallStrips; k > 0; --k) {
    const double h = kWallHeight * k / kWallStrips;
    p.push_back({x + h * nx, -kWidth / 2, z + h * nz});
  }
  for (int k = 0; k <= kFloorStrips; ++k) p.push_back({x, -kWidth / 2 + kWidth * k / kFloorStrips, z});
  for (int k = 1; k <= kWallStrips; ++k) {
    const double h = kWallHeight * k / kWallStrips;
    p.push_back({x + h * nx, kWidth / 2, z + h * nz});
  }
  return p;
}

void facet(std::string& out, const Point& a, const Point& b, const Point& c) {
  const Point u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  Point n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (double& e : n) e /= length;
  out += fmt::format("  facet normal {:.7e} {:.7e} {:.7e}\n    outer loop\n", n[0], n[1], n[2]);
  for (const Point* q : {&a, &b, &c}) out += fmt::format("      vertex {:.9e} {:.9e} {:.9e}\n", (*q)[0], (*q)[1], (*q)[2]);
  out += "    endloop\n  endfacet\n";
}

/// Writes the chute as an ASCII STL in metres (both codes read this file); returns the number
/// of triangles. Chute quads between consecutive sections are split so that normals point into
/// the trough; the back plate shares its nodes with the first section.
int write_chute_stl(const std::string& path) {
  const std::vector<Point> line = centre_line();
  std::vector<std::vector<Point>> sections;
  for (const Point& c : line) sections.push_back(section(c));
  std::string out = "solid b2_chute\n";
  int triangles = 0;
  for (size_t i = 0; i + 1 < sections.size(); ++i) {
    const auto &s0 = sections[i], &s1 = sections[i + 1];
    for (size_t k = 0; k + 1 < s0.size(); ++k) {
      facet(out, s0[k], s1[k + 1], s0[k + 1]);
      facet(out, s0[k], s1[k], s1[k + 1]);
      triangles += 2;
    }
  }
  const double nx = std::sin(line[0][2]), nz = std::cos(line[0][2]);
  auto node = [&](int j, int k) {
    const double h = kWallHeight * j / kWallStrips;
    return Point{line[0][0] + h * nx, -kWidth / 2 + kWidth * k / kFloorStrips, line[0][1] + h * nz};
  };
  for (int j = 0; j < kWallStrips; ++j)
    for (int k = 0; k < kFloorStrips; ++k) {
      facet(out, node(j, k), node(j, k + 1), node(j + 1, k + 1));
      facet(out, node(j, k), node(j + 1, k + 1), node(j + 1, k));
      triangles += 2;
    }
  out += "endsolid b2_chute\n";
  std::ofstream file(path);
  if (!file || !(file << out)) throw std::runtime_error(fmt::format("cannot write {}", path));
  return triangles;
}

/// The case as YAML; the mesh file is set afterwards (the STL is written to a temporary file).
std::string case_yaml() {
  return fmt::format(R"(title: B2 mesh chute
simulation:
  duration: 100.0
  time_step: {dt}
  unsafe_time_step: warn
  gravity: [0, 0, -9.81]
  skin: 0.002
  seed: {seed}
  domain: {{min: [-0.02, -0.16, -0.70], max: [1.06, 0.16, 0.20]}}
materials:
  grain: {{density: {rho}, youngs_modulus: 5.0e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5, rolling_friction: 0.05}}
  chute: {{density: 7800, youngs_modulus: 5.0e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.4, rolling_friction: 0.05}}
interactions:
  - {{materials: [grain, chute], restitution: 0.5, friction: 0.4, rolling_friction: 0.05}}
contact:
  normal: hertz
  damping: {{model: restitution, end_of_contact: tension}}
  tangential: mindlin
  rolling: cdt
meshes:
  - {{name: chute, file: chute.stl, material: chute}}
inlets:
  - name: feed
    material: grain
    diameter: {d}
    mass_rate_kgs: {rate:.17g}
    interval: {interval:.17g}
    region: {{min: [0.10, -0.12, 0.02], max: [0.30, 0.12, 0.12]}}
    velocity: [1.0, 0, -0.5]
)",
                     fmt::arg("dt", kDt), fmt::arg("seed", kSeed), fmt::arg("rho", kDensity), fmt::arg("d", kDiameter),
                     fmt::arg("rate", kFeedRate * particle_mass()),
                     // Half a step short of 500 steps: the inlet fires on the first step whose time has
                     // reached the next insertion time, and the sum of 500 steps of dt may fall a rounding
                     // error short of 500 dt. Each batch still delivers what the rate owes (450).
                     fmt::arg("interval", (kInsertEvery - 0.5) * kDt));
}

/// Mesh files go through the geometry library as in a run (import, health check, safe repair).
dem::TriangleSoup load_mesh(const dem::MeshWallSpec& spec) {
  dem::geometry::TriangleMesh mesh = dem::geometry::import_mesh(spec.file);
  const dem::geometry::MeshReport report = dem::geometry::check_and_repair(mesh, kDiameter);
  if (!report.simulable()) throw std::runtime_error(fmt::format("the chute mesh cannot be simulated:\n{}", report.text()));
  fmt::print("  chute mesh: {} triangles, {} vertices, edges {:.4f}-{:.4f} m\n", report.triangles_out, report.vertices_out,
             report.edge_min, report.edge_max);
  for (const auto& issue : report.issues)
    if (issue.severity != dem::geometry::MeshIssue::Severity::info) fmt::print("  chute mesh: {} ({})\n", issue.what, issue.count);
  return {std::move(mesh.vertices), std::move(mesh.triangles)};
}

using bench::peak_rss_bytes;

/// Touching particle-particle pairs (overlap > 0).
std::size_t touching_pairs(const dem::State& s) {
  std::size_t n = 0;
  for (std::size_t k = 0; k < s.pairs.size(); ++k) {
    const auto i = s.pairs.i[k], j = s.pairs.j[k];
    const double dx = s.x[i] - s.x[j], dy = s.y[i] - s.y[j], dz = s.z[i] - s.z[j];
    const double reach = s.radius[i] + s.radius[j];
    if (dx * dx + dy * dy + dz * dz < reach * reach) ++n;
  }
  return n;
}

struct Result {
  std::int64_t fill_steps = 0, run_steps = 0;
  int threads = 0;
  double fill_seconds = 0, seconds = 0, rate = 0;
  double mean_particles = 0, pairs_per_particle = 0, mass_flow = 0, feed_flow = 0;
  std::int64_t left = 0, inserted = 0, rebuilds = 0;
  double peak_mib = 0, peak_bytes_per_particle = 0, max_overlap = 0;
};

std::string csv_header() {
  return "csv,phase,fill_steps,steps,threads,seconds,particle_steps_per_s,mean_particles,pp_contacts_per_particle,"
         "mass_flow_kg_s,feed_kg_s,left_domain,rebuilds,max_overlap_ratio,peak_MiB,peak_bytes_per_particle";
}

std::string csv_line(const Result& r) {
  return fmt::format("csv,run,{},{},{},{:.4f},{:.6g},{:.1f},{:.4f},{:.4f},{:.4f},{},{},{:.5g},{:.1f},{:.0f}", r.fill_steps,
                     r.run_steps, r.threads, r.seconds, r.rate, r.mean_particles, r.pairs_per_particle, r.mass_flow, r.feed_flow, r.left, r.rebuilds, r.max_overlap, r.peak_mib, r.peak_bytes_per_particle);
}

Result run(std::int64_t fill_steps, std::int64_t run_steps, const std::string& fill_state) {
  // The STL both codes read, in a private temporary directory.
  char dir_template[] = "/tmp/bench_b2_XXXXXX";
  if (!mkdtemp(dir_template)) throw std::runtime_error("cannot create a temporary directory");
  const std::filesystem::path dir(dir_template), stl = dir / "chute.stl";
  write_chute_stl(stl.string());
  dem::CaseSpec spec = dem::parse_case_text(case_yaml(), "b2_chute");
  spec.meshes.at(0).file = stl.string();
  fmt::print("B2 mesh chute, {} threads\n", omp_get_max_threads());
  const dem::Model model = dem::compile(spec, load_mesh);
  std::filesystem::remove_all(dir);
  fmt::print("{}\n  neighbour skin {:.3g} m, interaction range {:.3g} m, insertion every {:.6g} s\n", model.advice.report,
             model.skin, model.interaction_range, model.inlets.at(0).interval);
  for (const std::string& note : model.notes) fmt::print("  note: {}\n", note);

  dem::State state = dem::initial_state(model);
  dem::Workspace work;
  dem::prepare(model, state, work);
  using Clock = std::chrono::steady_clock;

  Result r;
  r.fill_steps = fill_steps;
  r.run_steps = run_steps;
  r.threads = omp_get_max_threads();
  const double mass = particle_mass();

  // Fill: from the empty chute to steady flow (timed only for information), or the state at
  // its end read from --fill-state (written there by the first run that fills).
  auto start = Clock::now();
  const bool resumed = !fill_state.empty() && std::filesystem::exists(fill_state);
  if (resumed) {
    state = dem::load_checkpoint(fill_state, model);
    work = dem::Workspace{};
    dem::prepare(model, state, work);
    fmt::print("  fill: the state after the fill read from {} (t = {:.3f} s, {} particles)\n", fill_state, state.time, state.size());
  }
  for (std::int64_t k = 0; k < (resumed ? 0 : fill_steps); ++k) {
    dem::step(model, state, work);
    if ((k + 1) % 5000 == 0) {
      fmt::print("  fill: step {:>6}, t = {:.3f} s, {} particles, {} left the domain\n", state.step, state.time, state.size(),
                 state.lost);
      std::fflush(stdout);
    }
  }
  r.fill_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (!fill_state.empty() && !resumed) dem::save_checkpoint(fill_state, model, state);
  dem::check_numerics(model, state, work);

  // Timed phase: the clock runs around dem::step only; samples every kSampleEvery steps.
  const std::int64_t lost_before = state.lost, inserted_before = state.inlets.at(0).inserted, rebuilds_before = work.rebuilds;
  const std::int64_t ahead_before = work.drifts_ahead, scans_before = work.near_refreshes;
  double sum_particles = 0, sum_pairs = 0;
  int samples = 0;
  auto sample = [&] {
    const double n = static_cast<double>(state.size());
    sum_particles += n;
    sum_pairs += n > 0 ? static_cast<double>(touching_pairs(state)) / n : 0.0;
    ++samples;
  };
  sample();
  for (std::int64_t done = 0; done < run_steps;) {
    const std::int64_t chunk = std::min<std::int64_t>(kSampleEvery, run_steps - done);
    start = Clock::now();
    dem::advance(model, state, work, chunk);
    r.seconds += std::chrono::duration<double>(Clock::now() - start).count();
    done += chunk;
    sample();
  }
  dem::check_numerics(model, state, work);
  const dem::Scalars sc = dem::measure(model, state, work);
  r.mean_particles = sum_particles / samples;
  r.rate = r.seconds > 0 ? r.mean_particles * static_cast<double>(run_steps) / r.seconds : 0.0;
  r.pairs_per_particle = sum_pairs / samples;
  r.left = state.lost - lost_before;
  r.inserted = state.inlets.at(0).inserted - inserted_before;
  const double duration = static_cast<double>(run_steps) * model.dt;
  r.mass_flow = duration > 0 ? static_cast<double>(r.left) * mass / duration : 0.0;
  r.feed_flow = duration > 0 ? static_cast<double>(r.inserted) * mass / duration : 0.0;
  r.rebuilds = work.rebuilds - rebuilds_before;
  r.max_overlap = sc.max_overlap_ratio;
  const std::size_t peak = peak_rss_bytes();
  r.peak_mib = static_cast<double>(peak) / (1024.0 * 1024.0);
  r.peak_bytes_per_particle = r.mean_particles > 0 ? static_cast<double>(peak) / r.mean_particles : 0.0;
  fmt::print("  fill: {} steps to t = {:.4g} s in {:.2f} s; timed: {} steps in {:.2f} s, {} inserted, {} left the domain, "
             "{} contacts at the end (walls included), {} list rebuilds, {} full scans of the pair list, {} steps drifted ahead "
             "by the step before\n",
             fill_steps, fill_steps * model.dt, r.fill_seconds, run_steps, r.seconds, r.inserted, r.left, sc.contacts,
             r.rebuilds, work.near_refreshes - scans_before, work.drifts_ahead - ahead_before);
  return r;
}

[[noreturn]] void usage(const char* argv0, const std::string& problem) {
  std::fprintf(stderr,
               "%s\nusage: %s [--threads T] [--fill-steps S] [--run-steps S] [--write-stl FILE] [--fill-state FILE]\n"
               "  default: all threads, fill 30000 steps, timed run 3000 steps\n"
               "  --fill-state FILE: the state after the fill is written to FILE, or read from it when it exists\n"
               "    (for A/B comparisons of builds: the timed phase starts from the same state)\n",
               problem.c_str(), argv0);
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  dem::tune_allocator();
  std::int64_t fill_steps = 30000, run_steps = 3000;
  int threads = 0;
  std::string fill_state;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "-h" || arg == "--help") usage(argv[0], "B2 mesh chute benchmark");
    if (a + 1 >= argc) usage(argv[0], "missing value after " + arg);
    const std::string value = argv[++a];
    if (arg == "--write-stl") {  // the chute for LIGGGHTS; stop
      try {
        const int n = write_chute_stl(value);
        const Point lip = centre_line().back();
        fmt::print("wrote {} triangles to {}; spoon exit floor point x={:.5f} z={:.5f}\n", n, value, lip[0], lip[1]);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_b2_chute: %s\n", e.what());
        return 1;
      }
      return 0;
    }
    if (arg == "--fill-state") {
      fill_state = value;
      continue;
    }
    char* end = nullptr;
    const long long v = std::strtoll(value.c_str(), &end, 10);
    if (end == value.c_str() || *end != '\0' || v < 0) usage(argv[0], arg + ": not a non-negative integer: " + value);
    if (arg == "--threads") threads = static_cast<int>(v);
    else if (arg == "--fill-steps") fill_steps = v;
    else if (arg == "--run-steps") run_steps = v;
    else usage(argv[0], "unknown option " + arg);
  }
  if (threads > 0) omp_set_num_threads(threads);
  try {
    const Result r = run(fill_steps, run_steps, fill_state);
    fmt::print("\nB2 mesh chute: particle-steps/s of the timed loop; N = mean particle count (samples every {} steps);\n"
               "pp/p = touching particle-particle pairs / N (mean over the samples);\n"
               "flow = particles that left the domain x m / timed duration (feed {:.4g} kg/s); peak = VmHWM / N\n",
               kSampleEvery, kFeedRate * particle_mass());
    fmt::print("{:>6} {:>6} {:>8} {:>11} {:>8} {:>7} {:>9} {:>8} {:>8} {:>8}\n", "fill", "steps", "seconds", "p-steps/s", "N",
               "pp/p", "flow kg/s", "maxovl%", "peakMiB", "peakB/p");
    fmt::print("{:>6} {:>6} {:>8.2f} {:>11.4g} {:>8.0f} {:>7.3f} {:>9.3f} {:>8.3f} {:>8.1f} {:>8.0f}\n", r.fill_steps,
               r.run_steps, r.seconds, r.rate, r.mean_particles, r.pairs_per_particle, r.mass_flow,
               100 * r.max_overlap, r.peak_mib, r.peak_bytes_per_particle);
    fmt::print("{}\n{}\n", csv_header(), csv_line(r));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_b2_chute: %s\n", e.what());
    return 1;
  }
  return 0;
}
