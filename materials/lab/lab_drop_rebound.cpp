// drop_rebound: one particle falls from `drop_height` onto a flat plate of wall material `plate`
// (an infinite plane at z = 0). restitution = sqrt(rebound apex height / drop height), both
// measured by the centre of mass from where the particle touches the plate (centre one radius
// above it for a sphere; the lowest point of a clump), first bounce. With `impact_angle_deg`
// (0 = normal) the particle is released with the horizontal speed that makes it strike at that
// angle from the normal; tangential_restitution = horizontal speed after / before.
//
// A clump rebounds as its orientation at the strike makes it (a two-sphere clump's tangential
// restitution at 30 deg spans 0.25 to 1 over orientations, in LIGGGHTS as here), so it is
// dropped at kClumpDrops random orientations and the observables are their means, with their
// standard errors as the extraction's uncertainty; a lab drops an angular particle many times.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

#include "lab/virtual_test_support.h"
#include "statistics/steady_state.h"

namespace dem::materials::detail {
namespace {

/// Orientations a clump is dropped at (calibration/liggghts/make_measurements.py drops LIGGGHTS'
/// clumps as many times).
constexpr int kClumpDrops = 12;

struct Drop {
  double restitution = 0, tangential = 0;
  double vx_before = 0, vz_before = 0;
  bool capped = false;
};

/// One drop at the orientation `seed` draws. The fall through the air is ballistic (a constant
/// acceleration, which the integrator follows exactly), so the particle starts a tenth of a
/// diameter above the plate with the speed it would have reached there: the same strike as a
/// release from the full height, without the steps of the fall.
Drop drop_once(const MaterialModel& model, const TestOptions& options, const std::string& plate, double height, double angle_deg,
               std::uint64_t seed, std::unique_ptr<Runner>& run) {
  const SizeFigures size = size_figures(model);
  CaseSpec spec = base_case(model, options, {plate}, "drop_rebound");
  spec.simulation.seed = seed;
  PlaneWallSpec floor;
  floor.name = "plate", floor.material = plate;
  spec.planes.push_back(floor);
  const double g = 9.81, impact = std::sqrt(2 * g * height);
  const double tangential = impact * std::tan(angle_deg * std::numbers::pi / 180);
  const double reach = 0.5 * size.d50 * size.bounding_factor;  // centre of mass to the farthest surface point
  const double release = reach + height;                       // [m] centre height at release
  const double fallen_before = std::max(0.0, height - 0.1 * size.d50);
  // One particle of the median size: the first draw of a fixed distribution is that size.
  ParticleSetSpec one = particle_box(model, 0, Vec3::Zero(), Vec3::Zero());
  one.diameter = SizeDistributionSpec{};
  one.diameter.value = size.d50 / size.coarse_grain;  // stated real, as particle_box states a set: compile makes it the parcel
  one.positions.push_back(Vec3(0, 0, release - fallen_before));
  one.velocity = Vec3(tangential, 0, -std::sqrt(2 * g * fallen_before));
  spec.particles.push_back(one);
  spec.simulation.characteristic_velocity = std::hypot(impact, tangential);
  // One particle is cheap: a step of 2 % of the Rayleigh time (a few hundred steps per contact)
  // keeps the integration error of the damped rebound below 0.5 % (the bulk default of 20 %
  // loses 5 % of the rebound speed at e = 0.3).
  spec.simulation.rayleigh_fraction = 0.02;

  run = std::make_unique<Runner>(spec);
  auto body_z = [&] { return run->state.bodies.size() ? run->state.bodies.z[0] : run->state.z[0]; };
  auto body_vx = [&] { return run->state.bodies.size() ? run->state.bodies.vx[0] : run->state.vx[0]; };
  auto body_vz = [&] { return run->state.bodies.size() ? run->state.bodies.vz[0] : run->state.vz[0]; };
  auto lowest = [&] {
    double low = 1e300;
    for (size_t p = 0; p < run->state.size(); ++p) low = std::min(low, run->state.z[p] - run->state.radius[p]);
    return low;
  };
  // To the first touch: the centre height at touch is the reference for both heights.
  const double cap = 3 * std::sqrt(2 * height / g) + 0.5;
  Drop out;
  double touch_z = body_z();
  while (run->state.time < cap && lowest() > 0) {
    touch_z = body_z(), out.vx_before = body_vx(), out.vz_before = body_vz();
    run->advance();
  }
  // Leave the plate, then rise to the apex.
  while (run->state.time < cap && (lowest() <= 0 || body_vz() <= 0)) run->advance();
  const double vx_after = body_vx();
  double apex = body_z();
  while (run->state.time < cap && body_vz() > 0) run->advance(), apex = std::max(apex, body_z());
  const double fallen = std::max(1e-300, release - touch_z);  // centre drop to the touch
  out.restitution = std::sqrt(std::max(0.0, apex - touch_z) / fallen);
  out.tangential = out.vx_before != 0 ? vx_after / out.vx_before : 0.0;
  out.capped = run->state.time >= cap;
  return out;
}

}  // namespace

SimulatedOutcome run_drop_rebound(const MaterialModel& model, const TestSetup& setup, const TestOptions& options) {
  const Clock clock;
  const SetupReader read(model, setup);
  const double height = read.number("drop_height", 1e-4, 100.0, "m");
  const double angle_deg = read.number("impact_angle_deg", 0.0, 0.0, 85.0, "deg");
  const std::string plate = read.wall("plate");
  read.finish();
  if (options.validate_only) return {};

  const int drops = model.shape.empty() ? 1 : kClumpDrops;
  std::vector<Drop> list;
  std::unique_ptr<Runner> run;  // the last drop's, for its figures
  for (int k = 0; k < drops; ++k)  // per replica its own orientations
    list.push_back(drop_once(model, options, plate, height, angle_deg, options.seed * kClumpDrops + static_cast<std::uint64_t>(k), run));

  SimulatedOutcome out;
  // A clump's observables: the means of its drops, with their standard errors.
  const auto put = [&](const std::string& key, double Drop::*value) {
    std::vector<double> values;
    for (const Drop& d : list) values.push_back(d.*value);
    const auto [mean, error] = mean_and_standard_error(values);
    out.observables[key] = mean;
    if (drops > 1) out.uncertainty[key] = error;
  };
  put("restitution", &Drop::restitution);
  if (angle_deg > 0) put("tangential_restitution", &Drop::tangential);
  out.notes.push_back(fmt::format("impact {:.3f} m/s normal, {:.3f} m/s tangential", -list[0].vz_before, list[0].vx_before));
  if (drops > 1) out.notes.push_back(fmt::format("a clump: {} orientations, their mean", drops));
  if (std::any_of(list.begin(), list.end(), [](const Drop& d) { return d.capped; })) out.notes.push_back("time cap reached before the rebound apex");
  finish(out, *run, clock, 1, options);
  return out;
}

}  // namespace dem::materials::detail
