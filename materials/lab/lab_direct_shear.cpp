// The periodic direct shear test (docs/materials-and-calibration.md, `direct_shear`; the
// source paper's Fig. 9). A cell periodic in x (shear direction) and y between two rough plates:
// plane walls each carrying one glued layer of d50 spheres of the material (`attach_to`, a
// hexagonal layer 1.1 d50 apart). The bottom plate is fixed, the top plate is servo-controlled.
// No gravity: the sample is homogeneous and the plate stresses are the sample's stresses.
//
//   fill         spheres (or clumps) placed at random in a region ~2.7x the final height; the
//                servo plate closes on them at 4 x shear_velocity (stress error -100 %)
//   consolidate  at preshear_stress until both plates carry it within 8 % for 3 checks in a row;
//                bulk_density = free particle mass / (A x height between the glued layers' tops)
//   pre-shear    top plate moves at shear_velocity along x; every 0.1 H of displacement (H the
//                sample height) the mean shear stress of that window is compared with the one
//                before: steady when they differ by < 2 % (at least 0.3 H sheared, at most 2 H).
//                steady_shear_stress = mean of the last window.
//   unload       servo target normal_stress, plate at rest, until it holds it within 8 %
//   shear        at shear_velocity; shear stress smoothed over 0.02 H of displacement; the peak is
//                passed when the smoothed stress has fallen 3 % below its maximum and 0.05 H more
//                has been sheared (at most 0.6 H). peak_shear_stress = largest smoothed value.
//
// Stresses come from the plate forces over the cell area A: tau = (F_bottom,x - F_top,x) / 2A,
// sigma = mean of both plates' normal stress. Over the last pre-shear window the contact stress
// tensor (Eq. 5, src/statistics/stress.h) over the sample between the glued layers' centre
// planes is averaged and compared with them (notes). Mass scaling: raised so that the inertial
// number I = (v/H) d50 / sqrt(sigma_n / rho) is 8e-4 at the lower normal stress (quasi-static, GDR
// MiDi 2004: I < 1e-3), never lowered below the model's; I is reported.
#include "lab/lab_direct_shear.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "core/particles.h"
#include "core/step.h"
#include "core/workspace.h"
#include "statistics/stress.h"
#include "lab/virtual_test_support.h"

namespace dem::materials {

namespace {

constexpr double kTargetInertialNumber = 8e-4;

/// d50 by mass and the mean particle volume, from reproducible draws: of the particles the cell
/// simulates, parcels of model.coarse_grain (as detail::size_figures gives them to the other tests).
struct Sizes {
  double d50 = 0, mean_volume = 0, largest = 0;
};
Sizes sizes_of(const MaterialModel& model) {
  Random random(12345);
  std::vector<double> d(4000);
  for (double& v : d) v = draw_diameter(model.diameter, random);
  std::sort(d.begin(), d.end());
  double total = 0, volume = 0;
  for (double v : d) total += v * v * v;
  Sizes s;
  double cumulative = 0;
  for (double v : d) {
    cumulative += v * v * v;
    if (s.d50 == 0 && cumulative >= 0.5 * total) s.d50 = v;
    volume += std::numbers::pi / 6 * v * v * v;
  }
  s.mean_volume = volume / static_cast<double>(d.size());
  s.largest = d.back();
  const double f = model.coarse_grain;
  s.d50 *= f, s.largest *= f, s.mean_volume *= f * f * f;
  return s;
}

/// Geometry of the cell, fixed for all phases.
struct Cell {
  double length = 0, width = 0;   // [m] periods along x and y
  double d_glue = 0;              // [m] glued sphere diameter (d50)
  double top_start = 0;           // [m] top plane at t = 0
  std::int64_t count = 0;         // free particles
  double fill_low = 0, fill_high = 0;  // [m] placement region in z
};

/// A hexagonal layer of glued centres at height z, periodic in x and y.
std::vector<Vec3> glued_layer(const Cell& cell, double z) {
  const double a = 1.1 * cell.d_glue;
  const int nx = std::max(1, static_cast<int>(std::floor(cell.length / a)));
  int ny = static_cast<int>(std::floor(cell.width / (a * std::sqrt(3.0) / 2)));
  ny = std::max(2, ny - ny % 2);  // even: the stagger repeats across the period
  const double ax = cell.length / nx, ay = cell.width / ny;
  std::vector<Vec3> out;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) out.emplace_back((i + 0.25 + 0.5 * (j % 2)) * ax, (j + 0.5) * ay, z);
  return out;
}

/// The case of one phase: the servo target, its speed limit and the plate's tangential velocity.
CaseSpec shear_case(const MaterialModel& model, const TestOptions& options, const Cell& cell, double mass_scaling,
                    double target, double max_speed, double velocity) {
  CaseSpec spec;
  spec.path = "<direct_shear>";
  spec.title = "direct shear";
  spec.simulation.gravity = Vec3::Zero();
  spec.simulation.seed = options.seed;
  spec.simulation.threads = options.threads;
  spec.simulation.has_domain = true;
  spec.simulation.domain_min = Vec3(0, 0, -cell.top_start);
  spec.simulation.domain_max = Vec3(cell.length, cell.width, 2 * cell.top_start);
  spec.simulation.periodic[0] = spec.simulation.periodic[1] = true;
  spec.simulation.mass_scaling = mass_scaling;
  spec.simulation.stiffness_scaling = model.stiffness_scaling;
  MaterialSpec particle = model.particle;
  if (particle.name.empty()) particle.name = model.name.empty() ? "particle" : model.name;
  spec.materials.push_back(particle);
  spec.contact = model.contact;
  if (!model.shape.empty()) {
    spec.clumps = model.shape;
    spec.clumps[0].name = "shape";
  }
  // Plane walls of the particle material: the sample meets them only through gaps in the layer.
  PlaneWallSpec bottom;
  bottom.name = "bottom";
  bottom.material = particle.name;
  spec.planes.push_back(bottom);
  PlaneWallSpec top;
  top.name = "top";
  top.material = particle.name;
  top.point = Vec3(0, 0, cell.top_start);
  top.normal = Vec3(0, 0, -1);
  top.velocity = Vec3(velocity, 0, 0);
  top.has_servo = true;
  top.servo.target_stress = target;
  top.servo.max_speed = max_speed;
  spec.planes.push_back(top);
  for (const auto& [wall, z] : {std::pair<std::string, double>{"bottom", 0.5 * cell.d_glue},
                                {"top", cell.top_start - 0.5 * cell.d_glue}}) {
    // Every set stated as a case states it, real diameters with the factor (detail::particle_box).
    ParticleSetSpec glued;
    glued.material = particle.name;
    glued.diameter.value = cell.d_glue / model.coarse_grain;
    glued.coarse_grain = model.coarse_grain;
    glued.positions = glued_layer(cell, z);
    glued.count = static_cast<std::int64_t>(glued.positions.size());
    glued.attach_to = wall;
    spec.particles.push_back(glued);
  }
  ParticleSetSpec sample;
  sample.material = particle.name;
  sample.clump = model.shape.empty() ? "" : "shape";
  sample.diameter = model.diameter;
  sample.coarse_grain = model.coarse_grain;
  sample.count = detail::real_count(cell.count, model.coarse_grain);
  sample.region_min = Vec3(0, 0, cell.fill_low);
  sample.region_max = Vec3(cell.length, cell.width, cell.fill_high);
  spec.particles.push_back(sample);
  return spec;
}

/// What the plates carry now.
struct PlateStress {
  double normal = 0;  // [Pa] mean of both plates, compressive
  double shear = 0;   // [Pa] along x, positive resisting the top plate's motion
  double top = 0, bottom = 0;  // [Pa] normal stress of each plate
};
PlateStress plate_stress(const State& s, double area) {
  PlateStress p;
  p.bottom = -s.walls.fz[0] / area;
  p.top = s.walls.fz[1] / area;
  p.normal = 0.5 * (p.top + p.bottom);
  p.shear = 0.5 * (s.walls.fx[0] - s.walls.fx[1]) / area;
  return p;
}

/// A run through the phases: one state, a model per phase (same particles and walls), and what
/// the phases measure on the way.
struct Run {
  Model model;
  State state;
  Workspace work;
  double dt = 0;                // [s] the first phase's time step; every phase's step counts use it
  std::int64_t free_count = 0;  // particles not glued to a plate
  double free_mass = 0;         // [kg] of those, without mass scaling
  double sample_height = 0;     // [m] between the tops of the glued layers, once consolidated
  void start(const CaseSpec& spec) {
    model = compile(spec);
    state = initial_state(model);
    work.keep_pair_forces = true;  // the stress tensor is measured
    prepare(model, state, work);
  }
  void switch_to(const CaseSpec& spec) {
    model = compile(spec);
    work = Workspace();
    work.keep_pair_forces = true;
    prepare(model, state, work);
  }
};

/// The set-up's figures.
struct ShearSetup {
  double length = 0, width = 0;     // [m] cell periods asked for
  double preshear = 0, normal = 0;  // [Pa] pre-shear and normal stress
  double speed = 0;                 // [m/s] shear velocity
};

/// What every phase of a run reads: the cell, the stresses and speeds, the mass scaling.
struct ShearPlan {
  const MaterialModel& material;
  const TestOptions& options;
  const Cell& cell;
  double preshear, normal, speed;  // [Pa], [Pa], [m/s]
  double d50, height, area;        // [m] d50 and sample height aimed at, [m^2] cell area
  double density, rate;            // [kg/m^3] particle density, [1/s] shear rate
  double mass_scaling;             // [-]
  double servo_speed;              // [m/s] the servo's speed limit in consolidation and pre-shear
};

/// The peak of the shear phase.
struct Peak {
  double stress = 0;  // [Pa] largest smoothed shear stress
  double at = 0;      // [m] shear displacement there
  double normal = 0;  // [Pa] plate normal stress there
  bool passed = false;
};

/// Reads and checks the set-up.
ShearSetup read_setup(const MaterialModel& material, const TestSetup& setup) {
  const detail::SetupReader read(material, setup);
  ShearSetup asked;
  asked.length = read.number("cell_length", 1e-4, 10.0, "m");
  asked.width = read.number("cell_width", 1e-4, 10.0, "m");
  asked.preshear = read.number("preshear_stress", 1.0, 1e8, "Pa");
  asked.normal = read.number("normal_stress", 1.0, 1e8, "Pa");
  asked.speed = read.number("shear_velocity", 1e-9, 10.0, "m/s");
  if (asked.normal > asked.preshear)
    read.fail("normal_stress", fmt::format("{:g} Pa exceeds preshear_stress = {:g} Pa; a yield locus point is sheared at or below its "
                                           "pre-shear stress", asked.normal, asked.preshear));
  read.finish();
  return asked;
}

/// [-] A clump's bounding diameter over its equivalent diameter, roughly; 1 for spheres.
double bounding_factor(const MaterialModel& material) {
  double bounding = 1.0;
  if (!material.shape.empty()) {
    const auto& t = material.shape[0];
    double r_eq = 0, reach = 0;
    for (size_t k = 0; k < t.radii.size(); ++k) r_eq += t.radii[k] * t.radii[k] * t.radii[k];
    r_eq = std::cbrt(r_eq);  // rough: overlapping spheres make the true one smaller
    for (size_t k = 0; k < t.radii.size(); ++k) reach = std::max(reach, t.centres[k].norm() + t.radii[k]);
    bounding = std::max(1.0, reach / r_eq);
  }
  return bounding;
}

/// Cell: the set-up's area times size_factor, at least three neighbour cells per period (the
/// engine's rule; the reach of the contact law comes from a trial compile); the free particles
/// and the region they are placed in.
Cell size_cell(const MaterialModel& material, const TestOptions& options, const ShearSetup& asked, const Sizes& sizes,
               double height) {
  const double d50 = sizes.d50;
  Cell cell;
  cell.d_glue = d50;
  const double bounding = bounding_factor(material);
  cell.length = std::max(asked.length * options.size_factor, 1e-6);
  cell.width = std::max(asked.width * options.size_factor, 1e-6);
  {
    Cell trial = cell;
    trial.length = trial.width = 100 * sizes.largest * bounding;
    trial.top_start = 10 * height, trial.count = 1, trial.fill_low = d50 * 1.5, trial.fill_high = 9 * height;
    const Model probe = compile(shear_case(material, options, trial, 1.0, asked.preshear, 1.0, 0.0));
    const double minimum = 3.05 * (2 * probe.radius_max + probe.interaction_range + probe.skin);
    cell.length = std::max(cell.length, minimum);
    cell.width = std::max(cell.width, minimum);
  }
  const double area = cell.length * cell.width;
  const double packing = 0.6;  // [-] solid fraction expected after consolidation
  cell.count = std::max<std::int64_t>(20, std::llround(packing * area * height / sizes.mean_volume));
  // Placed at 22 % solid (random placement without overlap jams near 30 %); clumps, whose
  // bounding spheres jam earlier, at 22 % over the square of their bounding factor.
  const double fill_height = cell.count * sizes.mean_volume / (0.22 / (bounding * bounding) * area) + bounding * sizes.largest;
  cell.fill_low = 1.05 * d50;
  cell.fill_high = cell.fill_low + fill_height;
  cell.top_start = cell.fill_high + 1.05 * d50;
  return cell;
}

/// The loading of every phase, with the mass scaling for a quasi-static shear (I = 8e-4 at the
/// lower normal stress).
ShearPlan plan_loading(const MaterialModel& material, const TestOptions& options, const ShearSetup& asked, const Cell& cell,
                       double d50, double height) {
  const double area = cell.length * cell.width;
  const double density = material.particle.density;
  const double rate = asked.speed / height;  // [1/s]
  const double scaling_for_I =
      std::pow(kTargetInertialNumber * std::sqrt(asked.normal / density) / (rate * d50), 2);
  const double mass_scaling = std::max({material.mass_scaling, scaling_for_I, 1.0});
  const double servo_speed = 4 * asked.speed;
  return {material, options, cell, asked.preshear, asked.normal, asked.speed, d50, height, area, density, rate, mass_scaling,
          servo_speed};
}

/// The case of one phase of the run: the servo target, its speed limit and the plate's tangential velocity.
CaseSpec phase_case(const ShearPlan& plan, double target, double max_speed, double velocity) {
  return shear_case(plan.material, plan.options, plan.cell, plan.mass_scaling, target, max_speed, velocity);
}

/// [m] between the glued layers' centre planes.
double glued_gap(const ShearPlan& plan, const State& state) {
  return (state.walls.pz[1] - 0.5 * plan.cell.d_glue) - (state.walls.pz[0] + 0.5 * plan.cell.d_glue);
}

/// A progress line to stdout when options.progress.
void progress(const ShearPlan& plan, const std::string& line) {
  if (plan.options.progress) fmt::print("  direct_shear: {}\n", line);
}

/// Holding a stress: both plates' stresses, averaged over a check interval (the plate moving
/// 0.02 H at full servo speed), within 8 % of the target for 3 intervals in a row. (The servo
/// is a proportional controller; on a stiff packing it chatters about a mean a few % low.)
bool hold(const ShearPlan& plan, Run& run, double target, double max_time) {
  const double area = plan.area, dt = run.dt;
  const std::int64_t check = std::max<std::int64_t>(1, std::llround(0.02 * plan.height / plan.servo_speed / dt));
  int good = 0;
  const double until = run.state.time + max_time;
  while (good < 3 && run.state.time < until) {
    double top = 0, bottom = 0;
    for (std::int64_t k = 0; k < check; ++k) {
      step(run.model, run.state, run.work);
      const PlateStress p = plate_stress(run.state, area);
      top += p.top / check, bottom += p.bottom / check;
    }
    good = std::abs(top / target - 1) < 0.08 && std::abs(bottom / target - 1) < 0.08 ? good + 1 : 0;
  }
  return good >= 3;
}

/// The fill: the servo plate closing on it at the pre-shear stress; the free particles counted.
void start_run(const ShearPlan& plan, Run& run, SimulatedOutcome& out) {
  run.start(phase_case(plan, plan.preshear, plan.servo_speed, 0.0));
  std::int64_t free_count = 0;
  for (size_t p = 0; p < run.state.size(); ++p) free_count += run.state.attached[p] < 0 ? 1 : 0;
  run.free_count = free_count;
  run.free_mass = detail::mass_of_spheres(run.state, [&](std::size_t p) { return run.state.attached[p] < 0; }) / plan.mass_scaling;
  out.particles = static_cast<std::int64_t>(run.state.size());
  run.dt = run.model.dt;
}

/// Consolidation at the pre-shear stress; the bulk density between the glued layers' tops.
void consolidate(const ShearPlan& plan, Run& run, SimulatedOutcome& out) {
  const double height = plan.height, servo_speed = plan.servo_speed, preshear = plan.preshear;
  const bool consolidated = hold(plan, run, preshear, 3 * (plan.cell.top_start - height) / servo_speed + 20 * height / servo_speed);
  if (!consolidated) out.flags.push_back("not_consolidated");
  run.sample_height = glued_gap(plan, run.state) - plan.cell.d_glue;  // between the tops of the glued layers
  out.observables["bulk_density"] = run.free_mass / (plan.area * run.sample_height);
  progress(plan, fmt::format("consolidated at {:g} Pa{}: height {:.2f} d50, bulk density {:.0f} kg/m^3, t = {:.3g} s", preshear,
                             consolidated ? "" : " (not within 8 %)", run.sample_height / plan.d50, out.observables["bulk_density"],
                             run.state.time));
}

/// Pre-shear until the window means settle; sample every 1/50 window. The steady shear stress,
/// and the stress tensor over the last window against the plates.
void preshear_to_steady(const ShearPlan& plan, Run& run, SimulatedOutcome& out) {
  const double height = plan.height, speed = plan.speed, area = plan.area, dt = run.dt;
  run.switch_to(phase_case(plan, plan.preshear, plan.servo_speed, speed));
  const double window = 0.1 * height;  // [m] of shear displacement
  const std::int64_t sample_steps = std::max<std::int64_t>(1, std::llround(window / 50 / speed / dt));
  std::vector<double> means;
  double shear_sum = 0, normal_sum = 0, shifted = 0;
  int samples = 0;
  Eigen::Matrix3d tensor_sum = Eigen::Matrix3d::Zero();
  PlateStress plate_sum;
  int tensor_samples = 0;
  bool steady = false;
  while (!steady && shifted < 2.0 * height) {
    for (std::int64_t k = 0; k < sample_steps; ++k) step(run.model, run.state, run.work);
    shifted += sample_steps * dt * speed;
    const PlateStress p = plate_stress(run.state, area);
    shear_sum += p.shear, normal_sum += p.normal, ++samples;
    // The tensor over the sample between the glued centre planes, in the last window.
    const Eigen::Matrix3d sigma = contact_stress(run.model, run.state, run.work, area * glued_gap(plan, run.state));
    tensor_sum += sigma, plate_sum.shear += p.shear, plate_sum.normal += p.normal, ++tensor_samples;
    if (samples < 50) continue;
    means.push_back(shear_sum / samples);
    shear_sum = normal_sum = 0, samples = 0;
    const size_t m = means.size();
    steady = shifted >= 0.3 * height - 1e-12 && m >= 2 && std::abs(means[m - 1] / means[m - 2] - 1) < 0.02;
    if (!steady && shifted < 2.0 * height) tensor_sum.setZero(), plate_sum = PlateStress{}, tensor_samples = 0;
  }
  if (!steady) out.flags.push_back("not_steady");
  const double steady_shear = means.empty() ? 0.0 : means.back();
  out.observables["steady_shear_stress"] = steady_shear;
  const Eigen::Matrix3d tensor = tensor_sum / std::max(1, tensor_samples);
  const double plate_normal = plate_sum.normal / std::max(1, tensor_samples);
  const double plate_shear = plate_sum.shear / std::max(1, tensor_samples);
  out.observables["stress_tensor_normal"] = tensor(2, 2);
  out.observables["stress_tensor_shear"] = -tensor(0, 2);  // compression positive flips the shear sign
  out.observables["plate_normal_stress"] = plate_normal;
  out.observables["plate_shear_stress"] = plate_shear;
  out.notes.push_back(fmt::format(
      "pre-shear at {:g} Pa: steady after {:.2f} H of displacement; stress tensor (Eq. 5) agrees with the plates to "
      "{:.1f} % (normal: {:.0f} vs {:.0f} Pa) and {:.1f} % (shear: {:.0f} vs {:.0f} Pa), mean over the last window",
      plan.preshear, shifted / height, 100 * std::abs(tensor(2, 2) / plate_normal - 1), tensor(2, 2), plate_normal,
      100 * std::abs(-tensor(0, 2) / plate_shear - 1), -tensor(0, 2), plate_shear));
  progress(plan, out.notes.back());
}

/// Unload to the normal stress with the plate at rest. The servo's speed limit scales with its
/// target: the same gain per pascal as in pre-shear (a gain per relative error would chatter at
/// the lower stress and hold it too high). Returns that speed limit [m/s].
double unload(const ShearPlan& plan, Run& run, SimulatedOutcome& out) {
  const double normal = plan.normal;
  const double unload_speed = plan.servo_speed * normal / plan.preshear;
  run.switch_to(phase_case(plan, normal, unload_speed, 0.0));
  if (!hold(plan, run, normal, 20 * plan.height / unload_speed)) out.flags.push_back("not_unloaded");
  progress(plan, fmt::format("unloaded to {:g} Pa at t = {:.3g} s", normal, run.state.time));
  return unload_speed;
}

/// Shear at the normal stress past the peak of the smoothed shear stress.
Peak shear_past_peak(const ShearPlan& plan, Run& run, double unload_speed, SimulatedOutcome& out) {
  const double height = plan.height, speed = plan.speed, area = plan.area, dt = run.dt;
  run.switch_to(phase_case(plan, plan.normal, unload_speed, speed));
  const double smooth = 0.02 * height;  // [m]
  const std::int64_t smooth_steps = std::max<std::int64_t>(1, std::llround(smooth / 10 / speed / dt));
  double peak = -1e300, peak_at = 0, peak_normal = 0, window_normal = 0;
  double shifted = 0, shear_sum = 0;
  int samples = 0;
  bool passed = false;
  while (!passed && shifted < 0.6 * height) {
    for (std::int64_t k = 0; k < smooth_steps; ++k) step(run.model, run.state, run.work);
    shifted += smooth_steps * dt * speed;
    const PlateStress p = plate_stress(run.state, area);
    shear_sum += p.shear, window_normal += p.normal, ++samples;
    if (samples < 10) continue;
    const double smoothed = shear_sum / samples;
    if (smoothed > peak) peak = smoothed, peak_at = shifted, peak_normal = window_normal / samples;
    shear_sum = window_normal = 0, samples = 0;
    passed = smoothed < 0.97 * peak && shifted - peak_at >= 0.05 * height;
  }
  if (!passed) out.flags.push_back("no_peak");
  out.observables["peak_shear_stress"] = peak;
  Peak found;
  found.stress = peak, found.at = peak_at, found.normal = peak_normal, found.passed = passed;
  return found;
}

/// The shear phase's note, and the cell's with the inertial number reached.
void report_shear(const ShearPlan& plan, const Run& run, const Peak& peak, SimulatedOutcome& out) {
  const double d50 = plan.d50, normal = plan.normal, rate = plan.rate, mass_scaling = plan.mass_scaling;
  const double inertial = rate * d50 / std::sqrt(normal / (plan.density * mass_scaling));
  out.notes.push_back(fmt::format(
      "shear at {:g} Pa: peak {:.0f} Pa after {:.3f} H (plate normal stress there {:.0f} Pa){}", normal, peak.stress,
      peak.at / plan.height, peak.normal, peak.passed ? "" : "; no peak within 0.6 H (largest value reported)"));
  out.notes.push_back(fmt::format(
      "cell {:.4g} x {:.4g} m, sample {:.2f} d50 high, {} free + {} glued particles, d50 {:.4g} m; mass scaling {:g}, "
      "inertial number {:.2g} at {:g} Pa (shear rate {:.3g} 1/s)",
      plan.cell.length, plan.cell.width, run.sample_height / d50, run.free_count, out.particles - run.free_count, d50,
      mass_scaling, inertial, normal, rate));
  progress(plan, out.notes.back());
}

}  // namespace

SimulatedOutcome run_direct_shear(const MaterialModel& material, const TestSetup& setup, const TestOptions& options) {
  const auto clock = std::chrono::steady_clock::now();
  const ShearSetup asked = read_setup(material, setup);
  if (options.validate_only) return {};
  const Sizes sizes = sizes_of(material);
  const double height = 10 * sizes.d50;  // [m] sample height aimed at
  const Cell cell = size_cell(material, options, asked, sizes, height);
  const ShearPlan plan = plan_loading(material, options, asked, cell, sizes.d50, height);

  SimulatedOutcome out;
  Run run;
  start_run(plan, run, out);
  consolidate(plan, run, out);
  preshear_to_steady(plan, run, out);
  const double unload_speed = unload(plan, run, out);
  const Peak peak = shear_past_peak(plan, run, unload_speed, out);
  report_shear(plan, run, peak, out);
  if (material.coarse_grain != 1.0) out.notes.push_back(detail::coarse_grain_note(material.coarse_grain, out.particles));
  out.simulated_seconds = run.state.time;
  out.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
  if (options.on_final) options.on_final(run.model, run.state);
  return out;
}

}  // namespace dem::materials
