// Diagnosis with real simulations: hidden-effect data sets made by the engine (ctest label
// `long`, minutes each; tests/CMakeLists.txt).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>

#include "calibration/calibration.h"
#include "model/material_model.h"
#include "lab/measurements.h"

namespace dem::materials {
namespace {

// Hidden-effect data sets made by the engine: a TRUTH material with an effect the starting
// model lacks is simulated (its own packing seed) and a lab's repeatability is added as Gaussian
// noise with a fixed seed (1 deg on angles, 2 % on densities, 3 % on stresses, 0.02 on a
// restitution). Sized for the suite (about a minute each on one core): spheres 2.5-3.5 mm, soft
// (E = 0.5 MPa: overlaps below 1 % of d at these stresses, time step 5e-5 s), apparatus shrunk
// to a few hundred particles (size_factor 0.5: a 2.5 cm cylinder filled 1.5 cm, a 2 cm cup, a
// 1.5 cm periodic shear cell), two replicas when comparing (simulation noise), one surrogate
// round with a small design (design_factor 0.5: 4 points for one parameter, 7 for two).

/// Coarse soft spheres; friction is the parameter the starting model calibrates.
MaterialModel coarse_beads(double rolling) {
  MaterialModel m;
  m.name = m.particle.name = "coarse_beads";
  m.particle.density = 2500, m.particle.youngs_modulus = 5e5, m.particle.poisson_ratio = 0.25;
  m.particle.params = {{"restitution", 0.5}, {"friction", 0.4}};
  if (rolling > 0) m.contact.rolling.model = "epsd", m.particle.params["rolling_friction"] = rolling;
  m.diameter.kind = SizeDistributionSpec::Kind::uniform;
  m.diameter.min = 0.0025, m.diameter.max = 0.0035;
  MaterialSpec steel;
  steel.name = "steel", steel.density = 7800, steel.youngs_modulus = 2e11, steel.poisson_ratio = 0.3;
  m.walls.push_back(steel);
  InteractionSpec pair;
  pair.material_a = m.name, pair.material_b = "steel";
  pair.params = {{"restitution", 0.5}, {"friction", 0.5}};
  m.wall_pairs.push_back(pair);
  m.tunable["friction"] = {0.2, 0.9};
  return m;
}

/// An experiment whose value synthesise_real fills in; sigma < 0: relative (-0.02 = 2 %).
void add_real(MeasurementSet& set, const std::string& id, const std::string& test, std::map<std::string, double> numbers,
              std::map<std::string, std::string> words, const std::string& observable, double sigma) {
  Experiment e;
  e.id = id;
  e.setup.test = test;
  e.setup.numbers = std::move(numbers);
  e.setup.words = std::move(words);
  e.observed[observable] = Observation{0.0, sigma, {}};
  set.experiments.push_back(e);
}

/// Flow tests on the small apparatus: drop on steel, lifted cylinder, poured cup.
MeasurementSet small_flow_tests() {
  MeasurementSet set;
  add_real(set, "drop", "drop_rebound", {{"drop_height", 0.1}}, {{"plate", "steel"}}, "restitution", 0.02);
  add_real(set, "aor", "angle_of_repose_cylinder", {{"cylinder_diameter", 0.05}, {"cylinder_height", 0.05}, {"fill_height", 0.03}, {"lift_speed", 0.05}},
           {{"base", "steel"}}, "angle_deg", 1.0);
  add_real(set, "density", "bulk_density", {{"cup_diameter", 0.04}, {"cup_height", 0.03}}, {{"base", "steel"}}, "bulk_density", -0.02);
  return set;
}

/// sigma < 0 in `set`: relative to the value (-0.02 = 2 %). The truth is simulated with seed
/// 1000 + seed (not a packing the calibration uses), then noise of sigma is added.
MeasurementSet synthesise_real(MeasurementSet set, const MaterialModel& truth, std::uint64_t seed, double size_factor) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  for (Experiment& e : set.experiments) {
    TestOptions o;
    o.seed = 1000 + seed, o.threads = 1, o.size_factor = size_factor;
    const SimulatedOutcome out = run_virtual_test(truth, e.setup, o);
    for (auto& [key, obs] : e.observed) {
      const double v = out.observables.at(key);
      if (obs.sigma < 0) obs.sigma = -obs.sigma * v;
      obs.value = v + obs.sigma * n(random);
    }
  }
  return set;
}

CalibrationOptions real_options() {
  CalibrationOptions o;
  o.replicas = 2;
  o.size_factor = 0.5;
  o.correct_size = false;  // the measurements are synthesised at this size
  o.threads = 1;
  o.parallel = 2;  // two simulations at once (the outcomes do not depend on it)
  o.rounds = 1;
  o.design_factor = 0.5;
  return o;
}

void print(const char* what, const Diagnosis& d, double seconds) {
  std::printf("%s: %.0f s\n  base: %s\n  base: %s\n", what, seconds, d.base.words[0].c_str(), d.base.words[1].c_str());
  for (const Term& t : d.base.after.terms)
    std::printf("    %-24s measured %10.4g +- %-8.3g simulated %10.4g +- %-8.3g residual %+.2f\n", t.name().c_str(), t.measured, t.sigma_measured,
                t.simulated, t.sigma_simulated, t.residual);
  for (const std::string& w : d.words) std::printf("  %s\n", w.c_str());
  for (const CandidateResult& c : d.candidates) {
    std::printf("  %s (delta BIC %+.1f)\n", c.words.c_str(), c.delta_bic);
    if (c.confirmed)
      for (const Term& t : c.fit.after.terms) std::printf("    %-24s residual %+.2f\n", t.name().c_str(), t.residual);
  }
}

/// The hidden effect `name` is recommended, or it is a rival the data cannot rule out and the
/// diagnosis names an experiment that separates the two: their predictions lie at least 3 sigma
/// apart, and simulated with the truth (another packing) its outcome lies at least 1 sigma nearer
/// the hidden effect's prediction (a measurement there picks the hidden effect). Runs
/// (2026-12-03): rolling resistance behind JKR, a direct shear test proposed, the truth 0.7 sigma
/// from epsd and 4.1 from JKR; liquid bridges behind clump shape, a shear test at a quarter of the
/// lower stress proposed, the truth 0.7 sigma from the bridges and 2.6 from the clumps.
void expect_named_or_separated(const Diagnosis& d, const std::string& name, const MaterialModel& truth, double size_factor) {
  if (d.recommended == name) return;
  ASSERT_NE(std::find(d.rivals.begin(), d.rivals.end(), name), d.rivals.end()) << name << " is neither recommended nor a rival";
  ASSERT_TRUE(d.separators.count(name) && !d.separators.at(name).empty()) << "no experiment proposed to tell " << name << " from " << d.recommended;
  const Separator& best = d.separators.at(name).front();
  EXPECT_GE(best.separation, 3.0) << best.words;
  TestOptions o;
  o.seed = 4242, o.threads = 1, o.size_factor = size_factor;
  const double value = run_virtual_test(truth, best.setup, o).observables.at(best.observable);
  const double off_hidden = std::abs(value - best.predicted_b) / best.sigma, off_recommended = std::abs(value - best.predicted_a) / best.sigma;
  std::printf("  proposed: %s\n  the truth there: %.4g (%.1f sigma from %s, %.1f from %s)\n", best.words.c_str(), value, off_hidden, name.c_str(),
              off_recommended, d.recommended.c_str());
  EXPECT_LE(off_hidden + 1.0, off_recommended) << "the proposed experiment must pick the hidden effect";
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Truth: rolling resistance mu_r = 0.2 (friction 0.5); start: the same spheres without it,
// calibrating friction. Spheres without rolling resistance spread into a sheet on the plate
// (no heap: angle 0 against a measured heap), which no friction can mend.
TEST(DiagnoseReal, HiddenRollingResistanceWithVirtualTests) {
  const auto t0 = std::chrono::steady_clock::now();
  const MaterialModel start = coarse_beads(0.0);
  MaterialModel truth = coarse_beads(0.2);
  set_parameter(truth, "friction", 0.5);
  const MeasurementSet set = synthesise_real(small_flow_tests(), truth, 21, 0.5);
  const Diagnosis d = diagnose(start, set, {}, real_options());
  print("hidden rolling resistance", d, seconds_since(t0));
  EXPECT_GT(d.base.after.chi2_per_n(), 5.0);  // the starting model fails visibly
  ASSERT_FALSE(d.candidates.empty());
  // Three observations (a drop, a heap, a cup) move alike under rolling resistance and under
  // cohesion: epsd is recommended, or named as a rival with an experiment that tells them apart.
  expect_named_or_separated(d, "epsd", truth, 0.5);
  const auto rolling = std::find_if(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& c) { return c.name == "epsd"; });
  ASSERT_NE(rolling, d.candidates.end());
  ASSERT_TRUE(rolling->confirmed);
  EXPECT_LT(rolling->fit.after.chi2_per_n(), 2.0);
}

// Truth: liquid bridges (liquid content 1 % of the solid volume, water) on spheres with rolling
// resistance 0.1; start: the same spheres dry, calibrating friction. Observations: the yield
// locus at two normal stresses after pre-shear at 600 Pa, and the poured bulk density.
TEST(DiagnoseReal, HiddenLiquidBridgesWithVirtualTests) {
  const auto t0 = std::chrono::steady_clock::now();
  const MaterialModel start = coarse_beads(0.1);
  MaterialModel truth = start;
  for (const EffectCandidate& c : missing_effects(truth))
    if (c.name == "liquid_bridge") c.add(truth);
  set_parameter(truth, "liquid_content", 0.01), set_parameter(truth, "friction", 0.5);
  MeasurementSet set;
  for (double sn : {150.0, 600.0})
    add_real(set, fmt::format("shear_{:.0f}", sn), "direct_shear",
             {{"cell_length", 0.03}, {"cell_width", 0.03}, {"preshear_stress", 600}, {"normal_stress", sn}, {"shear_velocity", 0.05}}, {},
             "peak_shear_stress", -0.03);
  add_real(set, "density", "bulk_density", {{"cup_diameter", 0.04}, {"cup_height", 0.03}}, {{"base", "steel"}}, "bulk_density", -0.02);
  set = synthesise_real(set, truth, 22, 0.5);
  CalibrationOptions options = real_options();
  options.rounds = 2;  // the second round zooms on the optimum: liquid content acts strongly below 1 %
  const Diagnosis d = diagnose(start, set, {}, options);
  print("hidden liquid bridges", d, seconds_since(t0));
  EXPECT_GT(d.base.after.chi2_per_n(), 5.0);
  ASSERT_FALSE(d.candidates.empty());
  // Liquid bridges come first, or second as a rival these data cannot rule out: JKR cohesion is
  // cohesion too, and two points of a yield locus with a bulk density do not always tell the two
  // apart (the diagnosis then says so and names what to measure). Runs on 2026-12-01:
  // bridges first by 0.9 in BIC over clump shape; with the neighbour lists following the drift (which
  // changed the bulk-density pours' last bits), JKR first by 2.5 over the bridges, under the
  // rival margin. Earlier builds: bridges first, JKR second by more than 5. 2026-12-06 (signatures screened
  // whole when the calibrated residual lies along friction's direction): clump shape first by 0.1 over
  // the bridges, both named, a drum at 20 rpm proposed that puts them 9.3 sigma apart. 2026-12-07
  // (wall-parameter candidates screened from the parameter rows): three wall parameters with
  // unstable signatures took the confirmations and clump shape was named missing alone; with
  // stable signatures confirmed first within a band, clump shape and the bridges tie again (0.1).
  const auto bridges = std::find_if(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& c) { return c.name == "liquid_bridge"; });
  ASSERT_NE(bridges, d.candidates.end());
  const bool first = bridges == d.candidates.begin();
  const bool named_rival = std::find(d.rivals.begin(), d.rivals.end(), "liquid_bridge") != d.rivals.end();
  EXPECT_TRUE(first || named_rival) << d.words.front();
  if (first) {
    EXPECT_EQ(d.recommended, "liquid_bridge") << d.words.front();
  }
  expect_named_or_separated(d, "liquid_bridge", truth, 0.5);
  // Two surrogate rounds (one round left chi^2/n at 6.6). Measured: chi^2/n 17.7 -> 1.8 (251 s on
  // one core; an earlier engine build 31.1 -> 3.8). With two replicas of a ~500-particle shear cell
  // the simulation noise itself is poorly known (a peak scatters by up to 18 %), so the assertion
  // leaves room: the bridges take the error down fivefold and below 5.
  ASSERT_TRUE(bridges->confirmed);
  EXPECT_LT(bridges->fit.after.chi2_per_n(), 5.0);
  EXPECT_LT(bridges->fit.after.chi2_per_n(), d.base.after.chi2_per_n() / 5.0);
  // The runner-up either loses clearly or is named as a rival these data cannot rule out.
  ASSERT_GE(d.candidates.size(), 2u);
  const CandidateResult& second = d.candidates[1];
  const bool rival = std::find(d.rivals.begin(), d.rivals.end(), second.name) != d.rivals.end();
  if (second.confirmed && d.candidates.front().bic - second.bic > -options.rival_margin && second.delta_bic > options.bic_margin)
    EXPECT_TRUE(rival) << second.name << " is within the rival margin and must be named";
  else
    EXPECT_FALSE(rival);
}

// Control: the truth is the starting model (spheres with rolling resistance 0.2) at another
// friction; calibrating friction fits within the noise and nothing is recommended.
TEST(DiagnoseReal, ControlWithVirtualTestsGetsNoRecommendation) {
  const auto t0 = std::chrono::steady_clock::now();
  const MaterialModel start = coarse_beads(0.2);
  MaterialModel truth = start;
  set_parameter(truth, "friction", 0.55);
  const MeasurementSet set = synthesise_real(small_flow_tests(), truth, 23, 0.5);
  const Diagnosis d = diagnose(start, set, {}, real_options());
  print("control", d, seconds_since(t0));
  EXPECT_LT(d.base.after.chi2_per_n(), 2.0);
  EXPECT_EQ(d.recommended, "");
}

}  // namespace
}  // namespace dem::materials
