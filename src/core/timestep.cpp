#include "core/timestep.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace dem {

namespace {
constexpr double kPi = std::numbers::pi;
constexpr double kMaxRayleighFraction = 0.4;
}  // namespace

double rayleigh_time(double radius, double density, double youngs, double poisson) {
  const double shear = youngs / (2.0 * (1.0 + poisson));
  return kPi * radius * std::sqrt(density / shear) / (0.1631 * poisson + 0.8766);
}

TimeStepAdvice advise_time_step(const Model& model, const SimulationSpec& sim) {
  TimeStepAdvice advice;
  // Characteristic impact speed: given, or the largest of initial speeds and a free fall over
  // the height the particles start above the lowest point of the scene.
  double speed = sim.characteristic_velocity;
  if (speed <= 0) {
    const double g = std::sqrt(model.gravity[0] * model.gravity[0] + model.gravity[1] * model.gravity[1] +
                               model.gravity[2] * model.gravity[2]);
    double low = std::numeric_limits<double>::infinity(), high = -low;
    const Vec3 down = g > 0 ? Vec3(model.gravity[0], model.gravity[1], model.gravity[2]) / g : Vec3(0, 0, -1);
    for (const ParticleSource& s : model.sources) {
      speed = std::max(speed, s.spec.velocity.norm() + s.spec.angular_velocity.norm() * 0.5 * s.spec.diameter.largest());
      auto extend = [&](const Vec3& p) { low = std::min(low, -down.dot(p)), high = std::max(high, -down.dot(p)); };
      for (const Vec3& p : s.spec.positions) extend(p);
      if (s.spec.positions.empty()) extend(s.spec.region_min), extend(s.spec.region_max);
    }
    for (const PlaneWall& w : model.planes) low = std::min(low, -down.dot(Vec3(w.point[0], w.point[1], w.point[2])));
    if (std::isfinite(high) && high > low) speed = std::max(speed, std::sqrt(2.0 * g * (high - low)));
    speed = std::max(speed, 0.1);
  }
  advice.characteristic_velocity = speed;

  // Shortest Rayleigh time and contact time over the particle materials and their partners.
  advice.rayleigh_time = std::numeric_limits<double>::infinity();
  advice.contact_time = std::numeric_limits<double>::infinity();
  // The normal law (the first effect) says how long a contact lasts and whether the Rayleigh
  // time binds the step (contact/effect.h).
  const ActiveEffect& normal = model.effects.front();
  const bool rayleigh_binds = normal.spec->rayleigh_binds;
  struct Kind { int material; double diameter; };
  std::vector<Kind> kinds;
  for (const ParticleSource& s : model.sources) kinds.push_back({s.material, s.spec.diameter.smallest()});
  for (const Inlet& in : model.inlets) {
    kinds.push_back({in.material, in.spec.diameter.smallest()});
    speed = std::max(speed, in.spec.velocity.norm());
  }
  for (const Kind& s : kinds) {
    const Material& m = model.materials[s.material];
    const double radius = 0.5 * s.diameter;
    const double mass = m.density * 4.0 / 3.0 * kPi * radius * radius * radius;
    advice.rayleigh_time = std::min(advice.rayleigh_time, rayleigh_time(radius, m.density, m.youngs_modulus, m.poisson_ratio));
    std::vector<std::pair<int, bool>> partners{{s.material, false}};
    for (const PlaneWall& w : model.planes) partners.push_back({w.material, true});
    for (const MeshWall& w : model.meshes) partners.push_back({w.material, true});
    for (const Kind& o : kinds) partners.push_back({o.material, false});
    for (auto [other, wall] : partners) {
      const double m_eff = wall ? mass : 0.5 * mass, r_eff = wall ? radius : 0.5 * radius;
      const double* row = model.pair_row(model.pair_type(s.material, other));
      advice.contact_time = std::min(advice.contact_time, normal.spec->contact_time(row, row + normal.param_offset, m_eff, r_eff, speed));
    }
  }

  advice.user_given = sim.time_step > 0;
  advice.dt = advice.user_given ? sim.time_step
                                : std::min(sim.rayleigh_fraction * advice.rayleigh_time, advice.contact_time / sim.steps_per_contact);
  const double fraction = advice.dt / advice.rayleigh_time;
  const double steps_per_contact = advice.contact_time / advice.dt;
  advice.safe = (!rayleigh_binds || fraction <= kMaxRayleighFraction) && steps_per_contact >= kMinStepsPerContact;
  advice.report = fmt::format(
      "  time step {:.4g} s ({}): {:.1f} % of the Rayleigh time {:.4g} s{}, {:.1f} steps per contact of {:.4g} s at "
      "{:.3g} m/s (limits: {:.0f} %, {:.0f} steps)",
      advice.dt, advice.user_given ? "given" : "auto", 100 * fraction, advice.rayleigh_time,
      rayleigh_binds ? "" : fmt::format(" (not binding for the {} law)", normal.spec->name),
      steps_per_contact, advice.contact_time, speed, 100 * kMaxRayleighFraction, kMinStepsPerContact);
  return advice;
}

}  // namespace dem
