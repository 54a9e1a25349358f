// angle_of_repose_cylinder: an open cylinder (`cylinder_diameter`, `cylinder_height` default 1.5
// fill heights, wall material `wall`, default `base`) stands on a flat plate of wall material
// `base`, is filled by pouring to `fill_height` and the bed settles (mean speed below 1 mm/s).
// The cylinder is lifted at `lift_speed` [m/s] (default 0.05) until its lower rim is one d50
// above the bed's top; the heap comes to rest (particles with centres above one d50 slower than
// 1 mm/s on average). Extraction as the protocol says: radial bins of width d50, surface height
// = largest z + radius in a bin, R_heap = outer edge of the outermost bin higher than 2 d50, a
// line fitted to the bins with centres in [0.2, 0.8] R_heap, angle_deg = atan(-slope); no bin
// higher than 2 d50: angle 0 and the flag no_heap. The slope's standard error from the fit's
// residuals is returned as the angle's uncertainty: a heap a dozen d50 across is fitted on a
// handful of bins whose heights step by a sphere, and its angle scatters by several degrees
// from one packing to the next (7.5 +- 5.7 deg over 6 packings at mu_r 0.1, 720 spheres). A heap does not rise above the bed it came
// from: spheres with centres above the settled bed's top are held by the lifted cylinder (rolling
// resistance and friction wedge a few against the tube) and are left out, with a note. One such
// sphere in an outer bin once made a 720-sphere heap read -80 deg.
//
// Set-up decisions: the plate is an infinite plane and the domain ends two cylinder diameters
// from the axis (a plate four diameters across): what rolls beyond it is removed. The cylinder is
// an exact tube wall (touched from both sides, with rims), lifted by its wall velocity; as
// triangles (its first form, and LIGGGHTS' in calibration/liggghts/) it cost a twentieth of the
// test's time. The pour is a column of particles placed at random (12 % solid) in
// the square inscribed in the cylinder, as many as fill `fill_height` at a solid fraction of 0.6
// (the filled height reached is noted). One run in three phases: the settle runs with the
// cylinder at rest; at rest the case is recompiled with the cylinder's velocity the lift speed
// and the same state continues (the walls and particles are identical, so the state carries
// over), and again with the cylinder stopped when the lift ends. Caps:
// settle, fall time + 3 s; heap, 2 s after the lift ends. The lift takes its time step from its
// own speeds (Runner::phase_speed), the pour from its impacts.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lab/virtual_test_support.h"

namespace dem::materials::detail {

namespace {

struct Heap {
  double angle = 0;   ///< [deg] 0: no heap
  double error = 0;   ///< [deg] standard error of the fitted angle (0: unknown, two bins)
  double radius = 0;  ///< [m] R_heap
  int bins = 0;       ///< bins fitted
};

/// The protocol's heap extraction, with the standard error of the fitted line's angle.
/// `ceiling` [m]: the settled bed's top; spheres with centres above it are not part of the heap.
Heap heap_angle(const State& s, double d50, double plate_radius, double ceiling, std::string& note) {
  const int bins = std::max(1, static_cast<int>(std::ceil(plate_radius / d50)));
  std::vector<double> surface(bins, -1.0);
  int held = 0;
  for (size_t p = 0; p < s.size(); ++p) {
    if (s.z[p] > ceiling) {
      ++held;
      continue;
    }
    const double r = std::hypot(s.x[p], s.y[p]);
    const int b = static_cast<int>(r / d50);
    if (b >= 0 && b < bins) surface[b] = std::max(surface[b], s.z[p] + s.radius[p]);
  }
  if (held > 0) note = fmt::format("{} particles held above the bed's top by the lifted cylinder, left out of the heap; ", held);
  int outer = -1;
  for (int b = 0; b < bins; ++b)
    if (surface[b] > 2 * d50) outer = b;
  if (outer < 0) return {};
  const double r_heap = (outer + 1) * d50;
  std::vector<double> x, y;
  for (int b = 0; b <= outer; ++b) {
    const double centre = (b + 0.5) * d50;
    if (surface[b] >= 0 && centre >= 0.2 * r_heap && centre <= 0.8 * r_heap) x.push_back(centre), y.push_back(surface[b]);
  }
  if (x.size() < 2) {
    note += fmt::format("heap of radius {:.3g} m has fewer than two bins to fit", r_heap);
    return {0.0, 0.0, r_heap, static_cast<int>(x.size())};
  }
  const auto line = fit_line(x, y);
  const double slope = line.second, degrees = 180 / std::numbers::pi;
  // d(atan u)/du = 1 / (1 + u^2)
  const double error = slope_standard_error(x, y, line) / (1 + slope * slope) * degrees;
  return {std::atan(-slope) * degrees, error, r_heap, static_cast<int>(x.size())};
}

}  // namespace

SimulatedOutcome run_angle_of_repose_cylinder(const MaterialModel& model, const TestSetup& setup, const TestOptions& options) {
  const Clock clock;
  const SetupReader read(model, setup);
  const double scale = options.size_factor;
  const double diameter = scale * read.number("cylinder_diameter", 1e-3, 10.0, "m");
  const double fill = scale * read.number("fill_height", 1e-3, 10.0, "m");
  const double height = scale * read.number("cylinder_height", 1.5 * fill / scale, fill / scale, 20.0, "m");
  const double lift_speed = read.number("lift_speed", 0.05, 1e-4, 10.0, "m/s");
  const std::string base = read.wall("base"), side = read.wall("wall", "base");
  const SizeFigures size = size_figures(model);
  const double radius = 0.5 * diameter, reach = 0.5 * size.largest * size.bounding_factor, d50 = size.d50;
  if (radius < 2 * reach)
    read.fail("cylinder_diameter", fmt::format("{:g} m (x size_factor {:g}) holds fewer than two particles across; make it at least {:g} m",
                                               diameter / scale, scale, 4 * reach / scale));
  read.finish();
  if (options.validate_only) return {};

  CaseSpec spec = base_case(model, options, {base, side}, "angle_of_repose_cylinder");
  PlaneWallSpec plate;
  plate.name = "plate", plate.material = base;
  spec.planes.push_back(plate);
  // The cylinder: an exact tube, lifted by its wall velocity (set in the lift phase only).
  PlaneWallSpec cylinder;
  cylinder.name = "cylinder", cylinder.material = side, cylinder.shape = PlaneWallSpec::Shape::tube;
  cylinder.radius = radius, cylinder.length = height;
  spec.planes.push_back(cylinder);
  const double area = std::numbers::pi * radius * radius;
  const auto count = static_cast<std::int64_t>(std::ceil(area * fill * 0.6 / size.mean_volume));
  const double half = (radius - reach) / std::sqrt(2.0);
  // Random placement jams near 25 % solid in a wide box and earlier in a narrow one (a few
  // diameters across, where the wall-side shell is excluded): the column is placed at 12 %.
  const double column = count * size.mean_volume / (0.12 * 4 * half * half);
  const double z0 = reach, z1 = z0 + column;
  spec.particles.push_back(particle_box(model, count, Vec3(-half, -half, z0), Vec3(half, half, z1)));
  const double plate_radius = 2 * diameter;
  spec.simulation.has_domain = true;
  spec.simulation.domain_min = Vec3(-plate_radius, -plate_radius, -0.05);
  spec.simulation.domain_max = Vec3(plate_radius, plate_radius, std::max(z1, height) + 0.05 + height);

  SimulatedOutcome out;
  Runner run(spec);
  const std::int64_t particles = static_cast<std::int64_t>(run.state.bodies.size() ? run.state.bodies.size() : run.state.size());
  progress(options, fmt::format("angle_of_repose_cylinder: {} particles into a {:.3g} m cylinder", particles, diameter));
  const double fall = std::sqrt(2 * z1 / 9.81);
  const bool settled = run.advance_until([&] { return run.state.time > fall && run.mean_speed() < 1e-3; }, fall + 3.0);
  double top = 0;
  for (size_t p = 0; p < run.state.size(); ++p) top = std::max(top, run.state.z[p] + run.state.radius[p]);
  out.notes.push_back(fmt::format("{} at {:.2f} s, bed {:.3g} m high (fill_height {:.3g} m)", settled ? "settled" : "NOT settled (time cap)",
                                  run.state.time, top, fill));

  // Lift from now until the rim is one d50 above the bed, then let the heap come to rest.
  const double lift_start = run.state.time, lift_end = lift_start + (top + d50) / lift_speed;
  spec.planes[1].velocity = Vec3(0, 0, lift_speed);
  spec.simulation.characteristic_velocity = run.phase_speed(0.0);  // the lift's own speeds, not the pour's
  run.restart(spec);
  run.advance_until([] { return false; }, lift_end, lift_end);
  spec.planes[1].velocity = Vec3::Zero();
  run.restart(spec);
  const bool rest = run.advance_until(
      [&] { return run.state.time > lift_end && run.mean_speed([&](size_t p) { return run.state.z[p] > d50; }) < 1e-3; }, lift_end + 2.0);
  out.notes.push_back(fmt::format("heap {} at {:.2f} s ({} particles left the plate)", rest ? "at rest" : "NOT at rest (time cap)",
                                  run.state.time, run.state.lost));

  std::string note;
  const Heap heap = heap_angle(run.state, d50, plate_radius, top, note);
  if (!note.empty()) out.notes.push_back(note.ends_with("; ") ? note.substr(0, note.size() - 2) : note);
  out.observables["angle_deg"] = heap.angle;
  if (heap.angle == 0) {
    out.flags.push_back("no_heap");
  } else {
    out.uncertainty["angle_deg"] = heap.error;
    out.notes.push_back(fmt::format("R_heap {:.3g} m; line fitted to {} bins, angle +- {:.2g} deg (standard error of the fit)", heap.radius,
                                    heap.bins, heap.error));
  }
  finish(out, run, clock, particles, options);
  return out;
}

}  // namespace dem::materials::detail
