// Benchmark B1 "box settle": particles on a jittered lattice fall into an open-top box and
// settle into a bed (phase 1), then the dense bed is stepped on (phase 2). The figure of merit
// is particle time steps per second of the timed stepping loop (no output inside it).
//
// Specification (copied from the team's benchmark spec; the program reads no files):
//   Common: SI units, gravity 9.81 m/s^2 along -z, spheres only, velocity Verlet, no global
//     damping, no cohesion. Contact law: Hertz normal + Mindlin tangential with history +
//     restitution damping, tension allowed, i.e.
//     contact: {normal: hertz, damping: {model: restitution, end_of_contact: tension},
//               tangential: mindlin}.
//   Particles: monodisperse d = 4 mm (R = 2 mm), density 2500 kg/m^3. Material of particles
//     and walls: E = 5.0e7 Pa, nu = 0.25, restitution e = 0.5, friction mu = 0.5, no rolling
//     friction.
//   Time step: dt = 1.5e-5 s (given explicitly).
//   Box: open-top, planar walls x = 0, x = Lx, y = 0, y = Ly (normals inwards), floor z = 0,
//     same material as the particles.
//   Initial state: simple-cubic lattice NX x NY x NZ, spacing S = 5 mm; site (i, j, k) has
//     id = 1 + i + NX (j + NY k) and centre
//       x = (i + 0.5) S + jx,  y = (j + 0.5) S + jy,  z = (k + 0.5) S,
//     jx, jy = 0.4 mm (2u - 1), u = (splitmix64 >> 11) 2^-53, seed 20240601, two draws per
//     particle in id order (jx then jy); zero velocity. splitmix64:
//       state += 0x9e3779b97f4a7c15; z = state; z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9;
//       z = (z ^ (z >> 27)) * 0x94d049bb133111eb; return z ^ (z >> 31)
//     (dem::Random in src/core/particles.h is exactly this).
//   Sizes: N = 20,000: 25 x 25 x 32, Lx = Ly = 0.125 m.
//          N = 100,000: 50 x 50 x 40, Lx = Ly = 0.25 m.
//   Neighbour skin: 1 mm.
//   Phase 1 "settle": 20,000 steps from t = 0. Phase 2 "dense bed": 4,000 steps (20k) or
//     1,000 steps (100k), continuing from the end of phase 1.
//   Figure of merit: particle-steps/s = particles x steps / loop seconds, per phase.
//   Also reported: peak memory per particle (VmHWM of /proc/self/status / N), bytes per
//     particle of the engine's state, contacts per particle at the end of each phase
//     (dem::measure(...).contacts / N, which counts particle-wall contacts too; the
//     particle-particle count alone is printed beside it), and the bed height (max z + r) at
//     the end of phase 2. Physics check: about 2.28 particle-particle contacts per particle in
//     the dense bed, bed about 0.078 m high for 20k.
//
// Usage: bench_b1_settle [--n 20000|100000] [--threads T] [--phase1-steps S1] [--phase2-steps S2]
//        bench_b1_settle --n N --liggghts-data FILE   (writes the same lattice for LIGGGHTS; --n first)
//   Without --n it runs 20,000 and then 100,000. Each run prints a table row per phase and one
//   line per phase starting with "csv," (header line "csv,N,...") for committing results.
//   The peak memory is reset before each size (/proc/self/clear_refs); where that is not
//   possible the value is the process peak so far (marked with '*').
#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "b1_spec.h"
#include "base/allocator.h"
#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "core/state.h"
#include "core/step.h"
#include "core/workspace.h"
#include "peak_memory.h"
#include "statistics/diagnostics.h"

namespace {

using bench::b1::kSpacing;
using bench::b1::Size;
using bench::b1::case_yaml;
using bench::b1::lattice;
using bench::b1::size_for;

/// Writes the lattice of size `b` as a LIGGGHTS data file (atom_style granular: id type diameter
/// density x y z), so that the LIGGGHTS run of bench/b1_side_by_side.sh starts from exactly the
/// same positions as this program.
void write_liggghts_data(const Size& b, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(fmt::format("cannot write {}", path));
  const std::vector<dem::Vec3> centres = lattice(b);
  out << fmt::format("LIGGGHTS data file: B1 box settle lattice {} x {} x {} (bench_b1_settle)\n\n{} atoms\n1 atom types\n\n", b.nx,
                     b.ny, b.nz, centres.size());
  out << fmt::format("0 {:.17g} xlo xhi\n0 {:.17g} ylo yhi\n0 {:.17g} zlo zhi\n\nAtoms\n\n", b.lx, b.ly, (b.nz + 1) * kSpacing + 0.01);
  for (size_t p = 0; p < centres.size(); ++p)
    out << fmt::format("{} 1 0.004 2500 {:.17g} {:.17g} {:.17g}\n", p + 1, centres[p].x(), centres[p].y(), centres[p].z());
}

using bench::peak_rss_bytes;
using bench::reset_peak_rss;

/// Bytes a vector holds (capacity, i.e. what it really occupies).
template <typename T>
std::size_t bytes(const std::vector<T>& v) { return v.capacity() * sizeof(T); }

/// Bytes of the particle columns of State in use (size, not capacity): the engine's
/// per-particle hot state (148 B for 17 doubles + int32 material + int64 id).
std::size_t particle_bytes_used(const dem::State& s) {
  std::size_t b = 0;
  for (const auto* c : {&s.x, &s.y, &s.z, &s.vx, &s.vy, &s.vz, &s.wx, &s.wy, &s.wz, &s.fx, &s.fy, &s.fz, &s.tx, &s.ty,
                        &s.tz, &s.radius, &s.inv_mass, &s.inv_inertia})
    b += c->size() * sizeof(double);
  return b + s.material.size() * sizeof(std::int32_t) + s.id.size() * sizeof(std::int64_t);
}

/// Bytes held by the particle columns of State (capacity: growth slack and permute scratch).
std::size_t particle_bytes_held(const dem::State& s) {
  std::size_t b = 0;
  for (const auto* c : {&s.x, &s.y, &s.z, &s.vx, &s.vy, &s.vz, &s.wx, &s.wy, &s.wz, &s.fx, &s.fy, &s.fz, &s.tx, &s.ty,
                        &s.tz, &s.radius, &s.inv_mass, &s.inv_inertia})
    b += bytes(*c);
  for (const auto* c : {&s.offset_x, &s.offset_y, &s.offset_z, &s.x_built, &s.y_built, &s.z_built}) b += bytes(*c);
  return b + bytes(s.material) + bytes(s.id) + bytes(s.body);
}

std::size_t contact_list_bytes(const dem::ContactList& c) { return bytes(c.i) + bytes(c.j) + bytes(c.history); }

std::size_t contact_forces_bytes(const dem::ContactForces& f) { return bytes(f.fx) + bytes(f.fy) + bytes(f.fz) + bytes(f.active); }

std::size_t pair_forces_bytes(const dem::PairForces& f) {
  return bytes(f.fx) + bytes(f.fy) + bytes(f.fz) + bytes(f.active);
}

/// The buffers a rebuild keeps between calls: partners and mesh candidates per thread, the sort's gathers,
/// the histories by id.
std::size_t scratch_bytes(const dem::Workspace& w) {
  std::size_t b = 0;
  for (const auto& v : w.partner_scratch) b += bytes(v);
  for (const auto& v : w.candidate_scratch) b += bytes(v);
  const dem::PermuteScratch& p = w.permute_scratch;
  for (const dem::HistoryRows* h : {&w.old_pairs, &w.old_walls}) b += bytes(h->a) + bytes(h->b) + bytes(h->rows);
  return b + bytes(p.f64) + bytes(p.slots_f64) + bytes(p.history) + bytes(p.i32) + bytes(p.slots_i32) + bytes(p.i64) +
         bytes(p.u8);
}

std::size_t workspace_bytes(const dem::Workspace& w) {
  return bytes(w.pair_begin) + bytes(w.wall_begin) + bytes(w.mesh_rows) + pair_forces_bytes(w.pair_forces) +
         contact_forces_bytes(w.wall_forces) + bytes(w.cell_of) + bytes(w.cell_start) + bytes(w.order) +
         bytes(w.members) + bytes(w.ghost_owners) + scratch_bytes(w) + bytes(w.near.k) + bytes(w.near.i) + bytes(w.near.j) + bytes(w.near.end) +
         bytes(w.near.x) + bytes(w.near.y) + bytes(w.near.z) + bytes(w.block_work) + bytes(w.block_time) +
         bytes(w.block_prefix) + bytes(w.block_done);
}

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

double bed_height(const dem::State& s) {
  double h = -1e300;
  for (std::size_t p = 0; p < s.size(); ++p) h = std::max(h, s.z[p] + s.radius[p]);
  return h;
}

struct Row {
  long n;
  std::string phase;
  std::int64_t steps;
  double seconds, rate, contacts_per_particle, pp_contacts_per_particle, bed, max_overlap, kinetic;
  std::int64_t rebuilds;
  double peak_mib, peak_bytes_per_particle, hot_bytes_per_particle, engine_bytes_per_particle;
  bool peak_reset;
  int threads;
};

void print_header() {
  fmt::print("{:>7} {:>6} {:>6} {:>8} {:>11} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}\n", "N", "phase", "steps",
             "seconds", "p-steps/s", "cont/p", "pp/p", "bed[m]", "maxovl%", "rebuilds", "peakMiB", "peakB/p",
             "hotB/p");
}

void print_row(const Row& r) {
  fmt::print("{:>7} {:>6} {:>6} {:>8.2f} {:>11.4g} {:>8.3f} {:>8.3f} {:>8.4f} {:>8.3f} {:>8} {:>7.1f}{} {:>8.0f} {:>8.0f}\n",
             r.n, r.phase, r.steps, r.seconds, r.rate, r.contacts_per_particle, r.pp_contacts_per_particle, r.bed,
             100 * r.max_overlap, r.rebuilds, r.peak_mib, r.peak_reset ? " " : "*", r.peak_bytes_per_particle,
             r.hot_bytes_per_particle);
}

std::string csv_header() {
  return "csv,N,phase,steps,threads,seconds,particle_steps_per_s,contacts_per_particle,pp_contacts_per_particle,"
         "bed_height_m,max_overlap_ratio,kinetic_J,rebuilds,peak_MiB,peak_bytes_per_particle,hot_bytes_per_particle,"
         "engine_bytes_per_particle";
}

std::string csv_line(const Row& r) {
  return fmt::format("csv,{},{},{},{},{:.4f},{:.6g},{:.4f},{:.4f},{:.5f},{:.5g},{:.6g},{},{:.1f},{:.0f},{:.0f},{:.0f}", r.n,
                     r.phase, r.steps, r.threads, r.seconds, r.rate, r.contacts_per_particle, r.pp_contacts_per_particle,
                     r.bed, r.max_overlap, r.kinetic, r.rebuilds, r.peak_mib, r.peak_bytes_per_particle,
                     r.hot_bytes_per_particle, r.engine_bytes_per_particle);
}

std::vector<Row> run_size(long n, std::optional<std::int64_t> phase1, std::optional<std::int64_t> phase2) {
  Size b = size_for(n);
  if (phase1) b.phase1 = *phase1;
  if (phase2) b.phase2 = *phase2;
  const bool peak_reset = reset_peak_rss();

  dem::CaseSpec spec = dem::parse_case_text(case_yaml(b), "b1_settle");
  spec.particles[0].positions = lattice(b);
  spec.particles[0].count = static_cast<std::int64_t>(spec.particles[0].positions.size());
  const dem::Model model = dem::compile(spec);
  fmt::print("\nB1 box settle, N = {} ({} x {} x {}), box {} x {} m, {} threads\n", n, b.nx, b.ny, b.nz, b.lx, b.ly,
             omp_get_max_threads());
  fmt::print("{}\n  neighbour skin {:.3g} m, interaction range {:.3g} m\n", model.advice.report, model.skin,
             model.interaction_range);
  for (const std::string& note : model.notes) fmt::print("  note: {}\n", note);

  dem::State state = dem::initial_state(model);
  if (static_cast<long>(state.size()) != b.n()) throw std::runtime_error(fmt::format("created {} particles, not {}", state.size(), b.n()));
  dem::Workspace work;
  dem::prepare(model, state, work);

  std::vector<Row> rows;
  using Clock = std::chrono::steady_clock;
  auto run_phase = [&](const std::string& name, std::int64_t steps) {
    const std::int64_t rebuilds_before = work.rebuilds, ahead_before = work.drifts_ahead, scans_before = work.near_refreshes;
    const auto start = Clock::now();
    dem::advance(model, state, work, steps);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    // Outside the timed loop: checks and figures.
    dem::check_numerics(model, state, work);
    const dem::Scalars sc = dem::measure(model, state, work);
    const double np = static_cast<double>(state.size());
    Row r;
    r.n = static_cast<long>(b.n());
    r.phase = name;
    r.steps = steps;
    r.threads = omp_get_max_threads();
    r.seconds = seconds;
    r.rate = seconds > 0 ? np * static_cast<double>(steps) / seconds : 0.0;
    r.contacts_per_particle = static_cast<double>(sc.contacts) / np;
    r.pp_contacts_per_particle = static_cast<double>(touching_pairs(state)) / np;
    r.bed = bed_height(state);
    r.max_overlap = sc.max_overlap_ratio;
    r.kinetic = sc.kinetic_translation + sc.kinetic_rotation;
    r.rebuilds = work.rebuilds - rebuilds_before;
    const std::size_t peak = peak_rss_bytes();
    r.peak_mib = static_cast<double>(peak) / (1024.0 * 1024.0);
    r.peak_bytes_per_particle = static_cast<double>(peak) / np;
    const std::size_t hot = particle_bytes_used(state), held = particle_bytes_held(state);
    const std::size_t engine = held + contact_list_bytes(state.pairs) + contact_list_bytes(state.wall_pairs) + workspace_bytes(work);
    r.hot_bytes_per_particle = static_cast<double>(hot) / np;
    r.engine_bytes_per_particle = static_cast<double>(engine) / np;
    r.peak_reset = peak_reset;
    rows.push_back(r);
    fmt::print("  {}: {} steps ({} drifted ahead by the step before, {} full scans of the pair list) to t = {:.4g} s in {:.2f} s; {} "
               "contacts ({} particle-particle listed pairs, {} wall pairs), kinetic energy {:.4g} J; engine memory {:.0f} B/particle "
               "(particles {:.0f}, contact lists {:.0f}, workspace {:.0f})\n",
               name, steps, work.drifts_ahead - ahead_before, work.near_refreshes - scans_before, state.time, seconds, sc.contacts, state.pairs.size(), state.wall_pairs.size(), r.kinetic,
               r.engine_bytes_per_particle, static_cast<double>(held) / np,
               static_cast<double>(contact_list_bytes(state.pairs) + contact_list_bytes(state.wall_pairs)) / np,
               static_cast<double>(workspace_bytes(work)) / np);
    std::fflush(stdout);
  };
  run_phase("settle", b.phase1);
  run_phase("dense", b.phase2);
  return rows;
}

[[noreturn]] void usage(const char* argv0, const std::string& problem) {
  std::fprintf(stderr,
               "%s\nusage: %s [--n 20000|100000] [--threads T] [--phase1-steps S1] [--phase2-steps S2] [--liggghts-data FILE]\n"
               "  default: N = 20000 then 100000, all threads, the spec's step counts\n",
               problem.c_str(), argv0);
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  dem::tune_allocator();
  std::vector<long> sizes{20000, 100000};
  std::optional<std::int64_t> phase1, phase2;
  int threads = 0;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "-h" || arg == "--help") usage(argv[0], "B1 box settle benchmark");
    if (a + 1 >= argc) usage(argv[0], "missing value after " + arg);
    const std::string value = argv[++a];
    if (arg == "--liggghts-data") {  // write the lattice for LIGGGHTS and stop
      try {
        write_liggghts_data(size_for(sizes.size() == 1 ? sizes[0] : 20000), value);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_b1_settle: %s\n", e.what());
        return 1;
      }
      return 0;
    }
    char* end = nullptr;
    const long long v = std::strtoll(value.c_str(), &end, 10);
    if (end == value.c_str() || *end != '\0' || v < 0) usage(argv[0], arg + ": not a non-negative integer: " + value);
    if (arg == "--n") sizes = {static_cast<long>(v)};
    else if (arg == "--threads") threads = static_cast<int>(v);
    else if (arg == "--phase1-steps") phase1 = v;
    else if (arg == "--phase2-steps") phase2 = v;
    else usage(argv[0], "unknown option " + arg);
  }
  if (threads > 0) omp_set_num_threads(threads);

  try {
    std::vector<Row> rows;
    for (long n : sizes) {
      const auto r = run_size(n, phase1, phase2);
      rows.insert(rows.end(), r.begin(), r.end());
    }
    fmt::print("\nB1 box settle: particle-steps/s of the timed loop; cont/p = dem::measure contacts (incl. walls) / N,\n"
               "pp/p = touching particle-particle pairs / N (expect ~2.28 in the dense bed), bed = max(z + r)\n"
               "(expect ~0.078 m for 20k after the full phases); hotB/p = particle columns of State in use;\n"
               "engine B/p (csv) = all State and Workspace vectors by capacity;\n"
               "peak = VmHWM{}\n",
               std::all_of(rows.begin(), rows.end(), [](const Row& r) { return r.peak_reset; })
                   ? " (reset before each size)"
                   : " (* = process peak so far, could not reset)");
    print_header();
    for (const Row& r : rows) print_row(r);
    fmt::print("{}\n", csv_header());
    for (const Row& r : rows) fmt::print("{}\n", csv_line(r));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_b1_settle: %s\n", e.what());
    return 1;
  }
  return 0;
}
