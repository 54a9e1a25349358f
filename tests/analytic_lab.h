// Analytic stand-ins for the virtual tests (known responses, no DEM) and the measurement sets the
// calibration and diagnosis tests make from them.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>

#include "calibration/calibration.h"
#include "model/material_model.h"
#include "lab/measurements.h"

namespace dem::materials::analytic {

inline const std::string kMaterials = DEMDESIGN_SOURCE_DIR "/materials";

/// Known responses: friction mu, rolling friction mr (0 without rolling; the constant torque cdt
/// steepens the drum bed less than epsd's spring-dashpot, by 20 instead of 35 deg per unit and
/// without the rpm term), liquid content lc,
/// surface energy g (JKR), cohesion energy density k (sjkr, in MJ/m^3: a strength that grows
/// with the load), clump aspect a, restitution e. Noise from the seed (packing).
struct Analytic {
  double noise = 1.0;  ///< scales the packing noise
  bool product = false;  ///< angle depends on friction x restitution only
  SimulatedOutcome operator()(const MaterialModel& m, const TestSetup& s, const TestOptions& o) const {
    const double mu = get_parameter(m, "friction"), e = get_parameter(m, "restitution");
    const double mr = m.contact.rolling.model == "none" ? 0.0 : get_parameter(m, "rolling_friction");
    const bool cdt = m.contact.rolling.model == "cdt";
    bool wet = false;
    for (const auto& c : m.contact.extra) wet = wet || c.model == "liquid_bridge";
    const double lc = wet ? get_parameter(m, "liquid_content") : 0.0;
    const auto adhesion = [&](const char* name) {
      return std::any_of(m.contact.adhesion.begin(), m.contact.adhesion.end(), [&](const ContactSpec::Choice& c) { return c.model == name; });
    };
    const double g = adhesion("jkr") ? get_parameter(m, "surface_energy") / 10.0 : 0.0;
    const double k = adhesion("sjkr") ? get_parameter(m, "cohesion_energy_density") / 1e6 : 0.0;
    const double a = get_parameter(m, "clump_aspect_ratio") - 1.0;
    std::mt19937_64 random(o.seed * 7919 + std::hash<std::string>{}(s.test));
    std::normal_distribution<double> n(0.0, noise);
    SimulatedOutcome out;
    if (s.test == "drop_rebound") out.observables["restitution"] = e + 0.002 * n(random);
    else if (s.test == "angle_of_repose_cylinder")
      out.observables["angle_deg"] = product ? 20 + 40 * mu * e + 0.3 * n(random)
                                             : 18 + 12 * mu + 40 * mr + 400 * lc + 300 * g + 200 * k + 10 * a + 0.3 * n(random);
    else if (s.test == "bulk_density")
      out.observables["bulk_density"] = 1600 - 250 * mu - 100 * mr - 2000 * lc - 1000 * g - 300 * k - 100 * a + 3 * n(random);
    else if (s.test == "rotating_drum")
      out.observables["dynamic_angle_deg"] =
          22 + 8 * mu + (cdt ? 20 : 35) * mr + 100 * lc + 80 * g + 60 * k + 5 * a + (0.15 + (cdt ? 0.0 : 0.5) * mr) * s.numbers.at("rpm") +
          0.3 * n(random);
    else if (s.test == "hopper_discharge") out.observables["mass_flow_rate"] = 2.0 - 0.6 * mu - 0.2 * mr - 30 * lc - 5 * g - 4 * k - 0.1 * a + 0.005 * n(random);
    else if (s.test == "direct_shear") {
      const double sn = s.numbers.at("normal_stress");
      out.observables["peak_shear_stress"] =
          (0.3 + 0.5 * mu + 0.3 * mr + 0.2 * a + 0.5 * k) * sn + 2e5 * lc + 3e4 * g * (1 + sn / 4000) + 10 * n(random);
    }
    return out;
  }
};

inline void add(MeasurementSet& set, const std::string& id, const std::string& test, std::map<std::string, double> numbers, const std::string& observable,
         double sigma) {
  Experiment e;
  e.id = id;
  e.setup.test = test;
  e.setup.id = id;
  e.setup.numbers = std::move(numbers);
  e.observed[observable] = Observation{0.0, sigma, {}};
  set.experiments.push_back(e);
}

/// Synthetic measurements: the truth simulated (its own packing) plus measurement noise.
inline MeasurementSet synthesise(MeasurementSet set, const MaterialModel& truth, const Simulator& sim, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  for (Experiment& e : set.experiments) {
    TestOptions o;
    o.seed = 1000 + seed;
    const SimulatedOutcome out = sim(truth, e.setup, o);
    for (auto& [key, obs] : e.observed) obs.value = out.observables.at(key) + obs.sigma * n(random);
  }
  return set;
}

inline MaterialModel dry_spheres() {
  MaterialModel m = read_material_model(kMaterials + "/gravel.yaml");
  m.contact.rolling.model = "none";
  m.particle.params.erase("rolling_friction");
  m.tunable.erase("rolling_friction");
  return m;
}

inline MeasurementSet flow_tests() {
  MeasurementSet set;
  add(set, "drop", "drop_rebound", {{"drop_height", 0.3}}, "restitution", 0.02);
  add(set, "aor_1", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 1.0);
  add(set, "aor_2", "angle_of_repose_cylinder", {{"fill_height", 0.15}}, "angle_deg", 1.0);
  add(set, "density", "bulk_density", {{"cup_diameter", 0.1}}, "bulk_density", 10);
  add(set, "drum_10", "rotating_drum", {{"rpm", 10}}, "dynamic_angle_deg", 1.0);
  add(set, "drum_20", "rotating_drum", {{"rpm", 20}}, "dynamic_angle_deg", 1.0);
  add(set, "drum_30", "rotating_drum", {{"rpm", 30}}, "dynamic_angle_deg", 1.0);
  add(set, "hopper", "hopper_discharge", {{"orifice_diameter", 0.05}}, "mass_flow_rate", 0.02);
  return set;
}

inline CalibrationOptions analytic_options(const Simulator& sim) {
  CalibrationOptions o;
  o.simulator = sim;
  o.replicas = 3;
  return o;
}

/// Dry spheres with friction 0.3 and a guessed steel restitution of 0.5, and what `sim` measures
/// of friction 0.5 and a steel restitution of 0.8: two drops on steel, a heap and a density.
inline std::pair<MaterialModel, MeasurementSet> guessed_wall(const Simulator& sim) {
  MaterialModel start = dry_spheres();
  set_parameter(start, "friction", 0.3), set_parameter(start, "steel.restitution", 0.5);
  MaterialModel truth = start;
  set_parameter(truth, "friction", 0.5), set_parameter(truth, "steel.restitution", 0.8);
  MeasurementSet set;
  add(set, "drop_low", "drop_rebound", {{"drop_height", 0.1}}, "restitution", 0.02);
  add(set, "drop_high", "drop_rebound", {{"drop_height", 0.5}}, "restitution", 0.02);
  for (Experiment& e : set.experiments) e.setup.words["plate"] = "steel";
  add(set, "aor", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 1.0);
  add(set, "density", "bulk_density", {{"cup_diameter", 0.1}}, "bulk_density", 10);
  return {start, synthesise(set, truth, sim, 3)};
}

}  // namespace dem::materials::analytic
