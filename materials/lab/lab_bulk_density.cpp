// bulk_density: particles poured from `pour_height` [m] above the rim (default half the cup
// height) into a cylindrical cup (`cup_diameter`, `cup_height`) of wall material `base` (its
// side `wall`, default `base`), until the heap stands above the rim. The bed comes to rest (mean
// particle speed below 1 mm/s); every particle whose centre lies above the rim is removed;
// bulk_density = mass left / cup volume.
//
// Set-up decisions: the cup is an exact disc (its floor) and tube (its side), walls touched from
// both sides with edges, so what overflows falls past the rim and leaves the domain 2 cm below
// the cup floor. Rejected: the cup as triangles (its first form, and LIGGGHTS' in
// calibration/liggghts/): a fifth of the test's time went to the facets near each sphere. The pour is a column of particles
// placed at random (12 % solid) in the square inscribed in the cup, from the pour height up,
// enough for 1.3 cups at a solid fraction of 0.64 (the column shape pours everything in about one
// free fall; an inlet at a mass rate was rejected as several times slower to simulate). Rest is
// checked every 5 ms of simulated time, capped at the fall time of the column plus 3 s.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lab/virtual_test_support.h"

namespace dem::materials::detail {

SimulatedOutcome run_bulk_density(const MaterialModel& model, const TestSetup& setup, const TestOptions& options) {
  const Clock clock;
  const SetupReader read(model, setup);
  const double scale = options.size_factor;
  const double diameter = scale * read.number("cup_diameter", 1e-3, 10.0, "m");
  const double height = scale * read.number("cup_height", 1e-3, 10.0, "m");
  const double pour = scale * read.number("pour_height", 0.5 * height / scale, 0.0, 10.0, "m");
  const std::string base = read.wall("base"), side = read.wall("wall", "base");
  const SizeFigures size = size_figures(model);
  const double radius = 0.5 * diameter, reach = 0.5 * size.largest * size.bounding_factor;
  if (radius < 2 * reach)
    read.fail("cup_diameter", fmt::format("{:g} m (x size_factor {:g}) holds fewer than two particles across; make it at least {:g} m",
                                          diameter / scale, scale, 4 * reach / scale));
  read.finish();
  if (options.validate_only) return {};

  CaseSpec spec = base_case(model, options, {base, side}, "bulk_density");
  // The cup: an exact disc and tube (what overflows falls past the floor's edge).
  PlaneWallSpec floor, wall;
  floor.name = "cup_floor", floor.material = base, floor.shape = PlaneWallSpec::Shape::disc, floor.radius = radius;
  wall.name = "cup_wall", wall.material = side, wall.shape = PlaneWallSpec::Shape::tube, wall.radius = radius, wall.length = height;
  spec.planes.push_back(floor);
  spec.planes.push_back(wall);
  // The pour: a column in the inscribed square above the rim.
  const double volume = std::numbers::pi * radius * radius * height;
  const auto count = static_cast<std::int64_t>(std::ceil(1.3 * volume * 0.64 / size.mean_volume));
  const double half = (radius - reach) / std::sqrt(2.0);
  // Random placement jams near 25 % solid in a wide box and earlier in a narrow one (a few
  // diameters across, where the wall-side shell is excluded): the column is placed at 12 %.
  const double column = count * size.mean_volume / (0.12 * 4 * half * half);
  const double z0 = height + pour + reach, z1 = z0 + column;
  spec.particles.push_back(particle_box(model, count, Vec3(-half, -half, z0), Vec3(half, half, z1)));
  spec.simulation.has_domain = true;
  spec.simulation.domain_min = Vec3(-radius - height - 0.02, -radius - height - 0.02, -0.02);
  spec.simulation.domain_max = Vec3(radius + height + 0.02, radius + height + 0.02, z1 + 0.02);

  Runner run(spec);
  const std::int64_t particles = static_cast<std::int64_t>(run.state.bodies.size() ? run.state.bodies.size() : run.state.size());
  progress(options, fmt::format("bulk_density: {} particles poured into a {:.3g} m x {:.3g} m cup", particles, diameter, height));
  const double fall = std::sqrt(2 * z1 / 9.81);
  const bool rest = run.advance_until([&] { return run.state.time > fall && run.mean_speed() < 1e-3; }, fall + 3.0);

  // Strike off: keep what has its centre of mass at or below the rim, inside the cup.
  double mass = 0;
  auto inside = [&](double x, double y, double z) { return z <= height && x * x + y * y <= radius * radius; };
  for (size_t p = 0; p < run.state.size(); ++p)
    if (run.state.body[p] < 0 && inside(run.state.x[p], run.state.y[p], run.state.z[p])) mass += 1.0 / run.state.inv_mass[p];
  for (size_t b = 0; b < run.state.bodies.size(); ++b)
    if (inside(run.state.bodies.x[b], run.state.bodies.y[b], run.state.bodies.z[b])) mass += run.state.bodies.mass[b];

  SimulatedOutcome out;
  const double bulk = mass / volume;
  out.observables["bulk_density"] = bulk / run.model.mass_scaling;
  const double solid = model.particle.density;
  out.notes.push_back(fmt::format("solid fraction {:.3f}; {} at {:.2f} s", bulk / (solid * run.model.mass_scaling),
                                  rest ? "settled" : "NOT settled (time cap)", run.state.time));
  double top = 0;
  for (size_t p = 0; p < run.state.size(); ++p) top = std::max(top, run.state.z[p] + run.state.radius[p]);
  if (top < height) out.notes.push_back(fmt::format("the bed ({:.3g} m) does not reach the rim ({:.3g} m)", top, height));
  finish(out, run, clock, particles, options);
  return out;
}

}  // namespace dem::materials::detail
