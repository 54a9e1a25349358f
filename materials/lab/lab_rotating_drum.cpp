// rotating_drum: a drum (`drum_diameter`, `drum_depth` along its horizontal axis y, wall material
// `wall`) filled to `fill_fraction` of its volume (bulk volume at the poured solid fraction,
// optional `poured_solid_fraction`, default 0.6) rotates at `rpm`. `ends: walls` (default) closes
// it with flat ends of the drum's material; `ends: periodic` makes the axis periodic. After one
// revolution of spin-up the surface is sampled 24 times over the next revolution: particles in
// the middle half of the depth (all when periodic) projected on the cross-section; the extent of
// their centres split into bins of width d50, surface = largest height + radius in a bin, a line
// fitted to the bins in the middle 60 % of the extent; dynamic_angle_deg = mean |atan(slope)|.
// Flag `slipping` when the particles within one diameter of the drum wall move along it at less
// than half the wall speed on average (the bed slides as a block instead of being carried up).
//
// Set-up decisions: the drum is an exact cylinder wall about the axis whose surface turns at
// the drum's speed (PlaneWallSpec::spin), closed by two turning end plates for `walls`. A
// cylinder turning about its own axis occupies the same space at every instant, so only the
// contact velocity changes. Rejected: a rotating Motion of a mesh (the contact lists rebuild as
// the facets move, for the same physics); a static tube mesh with a rotating surface velocity
// (the protocol's first form, and LIGGGHTS' in calibration/liggghts/, whose primitive cylinder
// gives no wall velocity): facets d50/2 long put 6 to 8 triangles near each sphere of the wall
// layer, a sixth of the test's time, where the exact wall is one contact; and its wall velocity
// leaves the facet plane by up to 1.5 %.
// The fill is a jittered cubic lattice (spacing 1.05 largest bounding diameters) in the lowest
// part of the drum; it collapses during the spin-up revolution. Clumps too long for the lattice
// to hold the fill are poured by a packing inlet in the drum's inscribed square instead, and the
// spin-up starts when they are in and have fallen.
// Rejected: a shorter spin-up (a quarter revolution, then dense samples over half a revolution).
// The bed does not reach a steady angle within the first revolutions: on the benchmark beads
// (bench/lab/beads_plain.yaml, 160 mm drum at 10 rpm, six packings, 2026-12-06) the mean angle
// per quarter revolution fell from 24.4 deg (0.25-0.5) to 23.0 deg (1.75-2), so the same runs
// read 0.70 +- 0.18 deg steeper over 0.25-0.75 than over the second revolution. The window of
// the protocol is part of what the observable means (LIGGGHTS' deck samples the same one).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/particles.h"
#include "lab/virtual_test_support.h"

namespace dem::materials::detail {

namespace {

/// The protocol's surface-line extraction on one sample; returns |angle| [deg], or -1 when the
/// bed has fewer than two bins to fit.
double surface_angle(const State& s, double d50, double half_depth, bool periodic) {
  double lo = 1e300, hi = -1e300;
  auto use = [&](size_t p) { return periodic || std::abs(s.y[p]) <= 0.5 * half_depth; };
  for (size_t p = 0; p < s.size(); ++p)
    if (use(p)) lo = std::min(lo, s.x[p]), hi = std::max(hi, s.x[p]);
  if (!(hi > lo)) return -1;
  const int bins = std::max(1, static_cast<int>(std::ceil((hi - lo) / d50)));
  std::vector<double> surface(bins, -1e300);
  for (size_t p = 0; p < s.size(); ++p) {
    if (!use(p)) continue;
    const int b = std::min(bins - 1, static_cast<int>((s.x[p] - lo) / d50));
    surface[b] = std::max(surface[b], s.z[p] + s.radius[p]);
  }
  std::vector<double> x, z;
  const double extent = hi - lo;
  for (int b = 0; b < bins; ++b) {
    const double centre = lo + (b + 0.5) * d50;
    if (surface[b] > -1e300 && centre >= lo + 0.2 * extent && centre <= hi - 0.2 * extent) x.push_back(centre), z.push_back(surface[b]);
  }
  if (x.size() < 2) return -1;
  return std::abs(std::atan(fit_line(x, z).second)) * 180 / std::numbers::pi;
}

/// The drum the set-up asks for, scaled by size_factor, and the figures every phase reads.
struct Drum {
  double diameter = 0, depth_asked = 0;  // [m] as asked, times size_factor
  double fill = 0;                       // [-] fill_fraction
  double rpm = 0;                        // [rev/min]
  double poured = 0;                     // [-] poured solid fraction
  bool periodic = false;                 // `ends: periodic`
  std::string wall_material;
  SizeFigures size;
  double radius = 0, d50 = 0;            // [m]
  double spacing = 0;                    // [m] lattice pitch: 1.05 largest bounding diameters
  double omega = 0, revolution = 0;      // [rad/s], [s]
  double depth = 0;                      // [m] depth_asked, raised for a periodic slice
};

/// How the drum is filled: the particle count, and whether a packing inlet pours them.
struct Fill {
  std::int64_t count = 0;
  bool poured = false;
};

/// What the samples over the revolution add up.
struct DrumSamples {
  double angle_sum = 0;    // [deg] of the fitted samples
  double carried_sum = 0;  // [-] wall layer speed over wall speed, of all samples
  int used = 0;            // samples whose surface could be fitted
};

constexpr int kSamples = 24;  // over the revolution after spin-up

/// Reads and checks the set-up.
Drum read_drum(const SetupReader& read, const MaterialModel& model, const TestOptions& options) {
  Drum drum;
  const double scale = options.size_factor;
  drum.diameter = scale * read.number("drum_diameter", 1e-3, 20.0, "m");
  drum.depth_asked = scale * read.number("drum_depth", 1e-3, 20.0, "m");
  drum.fill = read.number("fill_fraction", 0.05, 0.7, "-");
  drum.rpm = read.number("rpm", 0.01, 1000.0, "rev/min");
  drum.poured = read.number("poured_solid_fraction", 0.6, 0.2, 0.74, "-");
  drum.periodic = read.word("ends", "walls", {"walls", "periodic"}) == "periodic";
  drum.wall_material = read.wall("wall");
  drum.size = size_figures(model);
  const SizeFigures& size = drum.size;
  drum.radius = 0.5 * drum.diameter, drum.d50 = size.d50, drum.spacing = 1.05 * size.largest * size.bounding_factor;
  drum.omega = drum.rpm * 2 * std::numbers::pi / 60, drum.revolution = 60 / drum.rpm;
  // A periodic slice must span three neighbour cells of the engine (2 x largest radius + skin
  // of half the smallest radius + interaction range, model.cpp's check), with 10 % to spare;
  // a contact law reaching further deepens it again (deepen_for_reach). The angle is per unit
  // depth, so a thicker slice changes only the count: a size factor never makes the drum invalid.
  const double min_periodic_depth = 3.0 * 1.1 * (size.largest * size.bounding_factor + 0.25 * size.largest);
  drum.depth = drum.periodic ? std::max(drum.depth_asked, min_periodic_depth) : drum.depth_asked;
  if (drum.radius < 3 * drum.spacing)
    read.fail("drum_diameter", fmt::format("{:g} m (x size_factor {:g}) holds fewer than six particles across; make it at least {:g} m",
                                           drum.diameter / scale, scale, 6 * drum.spacing / scale));
  read.finish();
  return drum;
}

/// The case without its particles: the turning drum and its domain.
CaseSpec drum_case(const MaterialModel& model, const TestOptions& options, const Drum& drum) {
  const double radius = drum.radius, depth = drum.depth, omega = drum.omega;
  const bool periodic = drum.periodic;
  const std::string& wall_material = drum.wall_material;
  CaseSpec spec = base_case(model, options, {wall_material}, "rotating_drum");
  // The drum about the y axis, its surface turning at omega about +y (v = omega y x r); an end
  // plate turns about its own normal, so the back one (normal -y) at -omega.
  PlaneWallSpec shell;
  shell.name = "drum", shell.material = wall_material;
  shell.shape = PlaneWallSpec::Shape::cylinder, shell.radius = radius, shell.point = Vec3::Zero(), shell.normal = Vec3(0, 1, 0), shell.spin = omega;
  spec.planes.push_back(shell);
  if (!periodic)
    for (const double side : {-1.0, 1.0}) {
      PlaneWallSpec end;
      end.name = side < 0 ? "front" : "back", end.material = wall_material;
      end.point = Vec3(0, 0.5 * side * depth, 0), end.normal = Vec3(0, -side, 0), end.spin = -side * omega;
      spec.planes.push_back(end);
    }
  spec.simulation.has_domain = true;
  spec.simulation.domain_min = Vec3(-radius - 0.01, -0.5 * depth - (periodic ? 0.0 : 0.01), -radius - 0.01);
  spec.simulation.domain_max = Vec3(radius + 0.01, 0.5 * depth + (periodic ? 0.0 : 0.01), radius + 0.01);
  spec.simulation.periodic[1] = periodic;
  return spec;
}

/// A periodic slice deep enough for the contact law's own reach: three neighbour cells of a trial
/// compile (2 x largest radius + interaction range + skin, with 1.7 % to spare), as the shear cell
/// sizes its period. read_drum's figure covers the spheres' contact; a liquid bridge's rupture
/// distance or a JKR neck reaches further, and without this the drum refused such a candidate.
void deepen_for_reach(const MaterialModel& model, const TestOptions& options, Drum& drum) {
  Drum trial = drum;
  trial.depth = 100 * drum.spacing;
  CaseSpec spec = drum_case(model, options, trial);
  const Vec3 corner(drum.spacing, drum.spacing, drum.spacing);
  spec.particles.push_back(particle_box(model, 1, -corner, corner));
  const Model probe = compile(spec);
  drum.depth = std::max(drum.depth, 3.05 * (2 * probe.radius_max + probe.interaction_range + probe.skin));
}

/// The fill: the lowest sites of a jittered cubic lattice inside the drum, or a packing inlet
/// when the lattice has too few.
Fill add_fill(const MaterialModel& model, const TestOptions& options, const Drum& drum, CaseSpec& spec) {
  const double radius = drum.radius, depth = drum.depth, spacing = drum.spacing;
  const bool periodic = drum.periodic;
  const auto count =
      static_cast<std::int64_t>(std::ceil(drum.fill * std::numbers::pi * radius * radius * depth * drum.poured / drum.size.mean_volume));
  const int layers = std::max(1, static_cast<int>(std::floor((periodic ? depth : depth - spacing) / spacing + (periodic ? 0 : 1))));
  const double sy = periodic ? depth / layers : spacing;
  ParticleSetSpec set = particle_box(model, 0, Vec3::Zero(), Vec3::Zero());
  Random jitter(options.seed * 7919 + 13);
  const double inner = radius - 0.5 * spacing;
  for (double z = -inner; z <= inner && static_cast<std::int64_t>(set.positions.size()) < count; z += spacing) {
    const double half_chord = std::sqrt(std::max(0.0, inner * inner - z * z));
    for (double x = -half_chord; x <= half_chord && static_cast<std::int64_t>(set.positions.size()) < count; x += spacing)
      for (int k = 0; k < layers && static_cast<std::int64_t>(set.positions.size()) < count; ++k) {
        const double y = -0.5 * depth + (periodic ? 0.5 * sy : 0.5 * spacing) + k * sy;
        set.positions.push_back(Vec3(x + 0.02 * spacing * (jitter.uniform() - 0.5), y + 0.02 * spacing * (jitter.uniform() - 0.5), z));
      }
  }
  // Clumps whose bounding spheres leave the lattice too few sites (a two-sphere clump's lattice
  // cell is several times its volume) are poured instead: a packing inlet over the square the
  // drum's cross-section inscribes inserts as many as it takes, again as they fall, until the
  // count is in (LIGGGHTS insert/pack).
  const bool poured_fill = static_cast<std::int64_t>(set.positions.size()) < count;
  if (poured_fill) {
    const double half = inner / std::sqrt(2.0), half_y = 0.5 * depth - (periodic ? 0.0 : 0.5 * spacing);
    InletSpec inlet;
    inlet.name = "fill", inlet.material = set.material, inlet.diameter = set.diameter, inlet.clump = set.clump;
    // Stated as particle_box states a set: real particles and the factor, `count` parcels inserted.
    inlet.coarse_grain = set.coarse_grain;
    inlet.count = real_count(count, set.coarse_grain);
    inlet.region_min = Vec3(-half, -half_y, -half), inlet.region_max = Vec3(half, half_y, half);
    spec.inlets.push_back(inlet);
  } else {
    spec.particles.push_back(set);
  }
  Fill made;
  made.count = count, made.poured = poured_fill;
  return made;
}

/// A poured fill: until the count is in, then the time to fall across the drum. Returns the
/// time [s] the fill took.
double pour(Runner& run, const SetupReader& read, const Drum& drum, const Fill& fill, SimulatedOutcome& out) {
  const std::int64_t count = fill.count;
  const double fall = std::sqrt(2 * drum.diameter / 9.81), cap = 40 * fall;
  if (!run.advance_until([&] { return run.state.inlets[0].inserted >= count; }, cap, 0.25 * fall))
    read.fail("fill_fraction", fmt::format("{:g}: {} of {} particles poured into the drum in {:.2g} s; use a smaller fill", drum.fill,
                                           run.state.inlets[0].inserted, count, cap));
  run.advance_until([] { return false; }, run.state.time + fall, fall);
  const double filled = run.state.time;
  out.notes.push_back(fmt::format("poured in {:.2g} s (clumps leave a lattice too few sites)", filled));
  return filled;
}

/// How fast the wall layer moves along the wall, as a share of the wall speed.
double wall_layer_share(const State& state, const Drum& drum) {
  const double radius = drum.radius, spacing = drum.spacing, omega = drum.omega;
  double along = 0;
  int n = 0;
  for (size_t p = 0; p < state.size(); ++p) {
    const double x = state.x[p], z = state.z[p], rho = std::hypot(x, z);
    if (rho < radius - spacing || rho == 0) continue;
    along += (state.vx[p] * z - state.vz[p] * x) / rho, ++n;  // omega along +y: v = w y x r
  }
  return n ? along / n / (omega * radius) : 0.0;
}

/// Spin-up, then 24 samples over one revolution.
DrumSamples sample_revolution(Runner& run, const Drum& drum, double filled) {
  const double revolution = drum.revolution;
  run.advance_until([] { return false; }, filled + revolution, revolution);
  DrumSamples sum;
  for (int k = 1; k <= kSamples; ++k) {
    run.advance_until([] { return false; }, filled + revolution * (1 + double(k) / kSamples), revolution);
    const double angle = surface_angle(run.state, drum.d50, 0.5 * drum.depth, drum.periodic);
    if (angle >= 0) sum.angle_sum += angle, ++sum.used;
    sum.carried_sum += wall_layer_share(run.state, drum);
  }
  return sum;
}

/// The dynamic angle, the slipping flag and the notes.
void report_angle(const Drum& drum, const DrumSamples& sum, SimulatedOutcome& out) {
  const double carried = sum.carried_sum / kSamples;
  out.observables["dynamic_angle_deg"] = sum.used ? sum.angle_sum / sum.used : 0.0;
  if (carried < 0.5) out.flags.push_back("slipping");
  if (drum.depth > drum.depth_asked)
    out.notes.push_back(fmt::format("periodic depth {:.4g} m raised to {:.4g} m, three neighbour cells", drum.depth_asked, drum.depth));
  out.notes.push_back(
      fmt::format("wall layer moves at {:.0f} % of the wall speed; {} of {} samples fitted", 100 * carried, sum.used, kSamples));
}

}  // namespace

SimulatedOutcome run_rotating_drum(const MaterialModel& model, const TestSetup& setup, const TestOptions& options) {
  const Clock clock;
  const SetupReader read(model, setup);
  Drum drum = read_drum(read, model, options);
  if (options.validate_only) return {};
  if (drum.periodic) deepen_for_reach(model, options, drum);

  CaseSpec spec = drum_case(model, options, drum);
  const Fill fill = add_fill(model, options, drum, spec);

  SimulatedOutcome out;
  Runner run(spec);
  const std::int64_t particles =
      fill.poured ? fill.count : static_cast<std::int64_t>(run.state.bodies.size() ? run.state.bodies.size() : run.state.size());
  progress(options, fmt::format("rotating_drum: {} particles, {:.3g} m drum at {:g} rpm", particles, drum.diameter, drum.rpm));
  const double filled = fill.poured ? pour(run, read, drum, fill, out) : 0.0;
  const DrumSamples samples = sample_revolution(run, drum, filled);
  report_angle(drum, samples, out);
  finish(out, run, clock, particles, options);
  return out;
}

}  // namespace dem::materials::detail
