// Measurement files, material models, compare / calibrate / diagnose. The calibration machinery
// is tested on analytic stand-ins for the virtual tests (known answers, no DEM); the hidden-effect
// tests with real simulations are in test_diagnose_real.cpp.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "calibration.h"
#include "calibration_report.h"
#include "material_model.h"
#include "measurements.h"

namespace dem::materials {
namespace {

const std::string kMaterials = DEMDESIGN_SOURCE_DIR "/materials";

std::string error_of(const std::string& text) {
  try {
    parse_measurements(text, "m.yaml");
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

const char* kGood = R"(material: gravel_5mm
particles:
  diameter: {distribution: normal, mean: 0.005, std: 0.0003}
  density: 2600
walls:
  steel: {youngs_modulus: 2.0e11, poisson_ratio: 0.3, density: 7800}
experiments:
  - id: aor_1
    test: angle_of_repose_cylinder
    setup: {cylinder_diameter: 0.10, cylinder_height: 0.15, fill_height: 0.10,
            lift_speed: 0.05, base: steel}
    observed:
      angle_deg: {value: 31.5, sigma: 1.0}
  - id: drum_20rpm
    test: rotating_drum
    setup: {drum_diameter: 0.20, drum_depth: 0.05, fill_fraction: 0.35, rpm: 20,
            ends: periodic, wall: steel}
    observed:
      dynamic_angle_deg: {value: 34.0, sigma: 1.0}
  - id: hopper_small
    test: hopper_discharge
    setup: {silo_diameter: 0.1, orifice_diameter: 0.012, fill_height: 0.1, wall: steel}
    outcome: blocked
)";

TEST(Measurements, ReadsTheProtocolExample) {
  const MeasurementSet m = parse_measurements(kGood, "m.yaml");
  EXPECT_EQ(m.material, "gravel_5mm");
  EXPECT_TRUE(m.has_diameter);
  EXPECT_DOUBLE_EQ(m.diameter.mean, 0.005);
  EXPECT_DOUBLE_EQ(m.density, 2600);
  ASSERT_EQ(m.walls.size(), 1u);
  EXPECT_DOUBLE_EQ(m.walls[0].youngs_modulus, 2e11);
  ASSERT_EQ(m.experiments.size(), 3u);
  EXPECT_EQ(m.experiments[0].setup.test, "angle_of_repose_cylinder");
  EXPECT_DOUBLE_EQ(m.experiments[0].setup.numbers.at("lift_speed"), 0.05);
  EXPECT_EQ(m.experiments[0].setup.words.at("base"), "steel");
  EXPECT_DOUBLE_EQ(m.experiments[0].observed.at("angle_deg").value, 31.5);
  EXPECT_EQ(m.experiments[1].setup.words.at("ends"), "periodic");
  EXPECT_EQ(m.experiments[2].outcome, "blocked");
  EXPECT_TRUE(m.experiments[2].observed.empty());
  EXPECT_EQ(m.experiments[0].location.line, 8);
}

TEST(Measurements, WhatAUserMeasuredIsAnInputNotAnError) {
  // Particle stiffness, Poisson's ratio, a restitution, the wall's friction against the
  // particles, and sieve classes by number: all read, used and never fitted.
  const std::string text = R"(material: beads
particles:
  diameter: {distribution: discrete, values: [0.004, 0.006], number_fractions: [0.5, 0.5]}
  density: 2500
  youngs_modulus: 5.0e7
  poisson_ratio: 0.25
  restitution: 0.6
walls:
  steel: {youngs_modulus: 2.0e11, poisson_ratio: 0.3, density: 7800, friction: 0.35}
experiments:
  - id: drop
    test: drop_rebound
    setup: {drop_height: 0.1, plate: steel}
    observed:
      restitution: {value: 0.6, sigma: 0.02}
)";
  const MeasurementSet m = parse_measurements(text, "m.yaml");
  ASSERT_EQ(m.known.size(), 4u);
  EXPECT_EQ(m.known[0].key, "youngs_modulus");
  EXPECT_EQ(m.known[3].key, "steel.friction");
  EXPECT_EQ(m.known[3].location.line, 9);
  // Number fractions 1:1 of 4 and 6 mm are mass fractions 64:216.
  EXPECT_NEAR(m.diameter.mass_fractions[0], 64.0 / 280.0, 1e-12);
  MaterialModel model = read_material_model(kMaterials + "/gravel.yaml");
  apply_measured(model, m);
  EXPECT_DOUBLE_EQ(get_parameter(model, "youngs_modulus"), 5e7);
  EXPECT_DOUBLE_EQ(get_parameter(model, "poisson_ratio"), 0.25);
  EXPECT_DOUBLE_EQ(get_parameter(model, "restitution"), 0.6);
  EXPECT_DOUBLE_EQ(get_parameter(model, "steel.friction"), 0.35);
  EXPECT_EQ(model.particle.sources.at("steel.friction").rfind("measured (m.yaml:9:", 0), 0u) << model.particle.sources.at("steel.friction");
  EXPECT_EQ(model.tunable.count("restitution"), 0u) << "a measured value is not fitted";
  EXPECT_THROW((void)fit_parameters(model, {"restitution"}), std::invalid_argument);
  // An angle of repose of 0 with a small sigma is most likely a heap that did not form.
  std::string zero = text;
  zero += R"(  - id: heap
    test: angle_of_repose_cylinder
    setup: {cylinder_diameter: 0.05, cylinder_height: 0.05, fill_height: 0.03, lift_speed: 0.05, base: steel}
    observed:
      angle_deg: {value: 0, sigma: 0.5}
)";
  const MeasurementSet with_zero = parse_measurements(zero, "m.yaml");
  ASSERT_EQ(with_zero.warnings.size(), 1u);
  EXPECT_NE(with_zero.warnings[0].find("outcome: no_heap"), std::string::npos) << with_zero.warnings[0];
  EXPECT_EQ(with_zero.warnings[0].rfind("m.yaml:20:", 0), 0u) << with_zero.warnings[0];
  EXPECT_TRUE(m.warnings.empty());
  // A misspelt measured key still names the nearest valid one.
  const std::string bad = std::string(text).replace(text.find("poisson_ratio: 0.25"), 19, "poison_ratio: 0.25");
  try {
    (void)parse_measurements(bad, "m.yaml");
    FAIL() << "accepted a misspelt key";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("poisson_ratio"), std::string::npos) << e.what();
  }
}

// The cross-engine sets (measured by LIGGGHTS, calibration/liggghts/) read as measurement files,
// say in their first line how they were made, and give the particles' stiffness as known.
TEST(Measurements, TheCrossEngineSetsReadAndSayHowTheyWereMade) {
  const std::string dir = std::string(DEMDESIGN_SOURCE_DIR) + "/tests/data/cross_engine/";
  MaterialModel start = read_material_model(dir + "glass_beads_6mm.yaml");
  for (const char* set : {"control", "rolling_epsd2", "cohesion_sjkr", "rolling_cdt"}) {
    const std::string path = dir + set + ".yaml";
    std::ifstream in(path);
    std::string first;
    std::getline(in, first);
    EXPECT_EQ(first.rfind("# Simulated with LIGGGHTS", 0), 0u) << path;
    const MeasurementSet m = read_measurements(path);
    EXPECT_EQ(m.experiments.size(), 7u) << path;
    MaterialModel model = start;
    apply_measured(model, m);
    EXPECT_DOUBLE_EQ(get_parameter(model, "youngs_modulus"), 5e6) << path;
  }
}

TEST(Measurements, ErrorsNameFileLineKeyAndWhatIsValid) {
  std::string text = kGood;
  // A misspelt top-level key.
  std::string e = error_of(std::string(kGood).replace(0, 8, "materal"));
  EXPECT_NE(e.find("m.yaml:1"), std::string::npos) << e;
  EXPECT_NE(e.find("material"), std::string::npos) << e;
  // Unknown test: the valid ones are listed, with the nearest.
  e = error_of(std::string(kGood).replace(text.find("rotating_drum"), 13, "rotating_drums"));
  EXPECT_NE(e.find("m.yaml:15"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'rotating_drum'"), std::string::npos) << e;
  EXPECT_NE(e.find("hopper_discharge"), std::string::npos) << e;
  // An observable the test does not have.
  e = error_of(std::string(kGood).replace(text.find("dynamic_angle_deg"), 17, "angle_deg"));
  EXPECT_NE(e.find("m.yaml:19"), std::string::npos) << e;
  EXPECT_NE(e.find("not an observable of rotating_drum"), std::string::npos) << e;
  EXPECT_NE(e.find("dynamic_angle_deg"), std::string::npos) << e;
  // sigma must be > 0, and must be given.
  e = error_of(std::string(kGood).replace(text.find("sigma: 1.0}"), 11, "sigma: 0}"));
  EXPECT_NE(e.find("sigma"), std::string::npos) << e;
  EXPECT_NE(e.find("> 0"), std::string::npos) << e;
  e = error_of(std::string(kGood).replace(text.find(", sigma: 1.0}"), 13, "}"));
  EXPECT_NE(e.find("sigma"), std::string::npos) << e;
  // A misspelt key in an observation: the nearest valid key.
  e = error_of(std::string(kGood).replace(text.find("value: 31.5"), 5, "valeu"));
  EXPECT_NE(e.find("value"), std::string::npos) << e;
  EXPECT_NE(e.find("experiments[0].observed.angle_deg"), std::string::npos) << e;
  // An outcome the test cannot have.
  e = error_of(std::string(kGood).replace(text.find("outcome: blocked"), 16, "outcome: no_heap"));
  EXPECT_NE(e.find("blocked"), std::string::npos) << e;
  EXPECT_NE(e.find("m.yaml:23"), std::string::npos) << e;
  // A wall material the file does not declare.
  e = error_of(std::string(kGood).replace(text.find("base: steel"), 11, "base: steal"));
  EXPECT_NE(e.find("did you mean 'steel'"), std::string::npos) << e;
  // Duplicate ids.
  e = error_of(std::string(kGood).replace(text.find("id: drum_20rpm"), 14, "id: aor_1"));
  EXPECT_NE(e.find("used twice"), std::string::npos) << e;
  // Bad YAML.
  e = error_of("experiments: [");
  EXPECT_NE(e.find("not valid YAML"), std::string::npos) << e;
}

TEST(MaterialModel, ReadsALibraryFile) {
  MaterialModel m = read_material_model(kMaterials + "/gravel.yaml");
  EXPECT_EQ(m.name, "gravel");
  EXPECT_DOUBLE_EQ(m.particle.density, 2650);
  EXPECT_EQ(m.contact.rolling.model, "epsd");
  EXPECT_DOUBLE_EQ(get_parameter(m, "friction"), 0.65);
  EXPECT_DOUBLE_EQ(get_parameter(m, "rolling_friction"), 0.20);
  EXPECT_DOUBLE_EQ(get_parameter(m, "wall.friction"), 0.45);
  EXPECT_DOUBLE_EQ(get_parameter(m, "rubber.friction"), 0.7);
  ASSERT_EQ(m.tunable.size(), 3u);
  EXPECT_DOUBLE_EQ(m.tunable.at("friction").second, 1.0);
  EXPECT_EQ(m.diameter.kind, SizeDistributionSpec::Kind::uniform);
  EXPECT_DOUBLE_EQ(m.diameter.max, 0.032);
  EXPECT_EQ(m.walls.size(), 2u);
  set_parameter(m, "friction", 0.3);
  EXPECT_DOUBLE_EQ(get_parameter(m, "friction"), 0.3);
  set_parameter(m, "steel.friction", 0.2);
  EXPECT_DOUBLE_EQ(get_parameter(m, "steel.friction"), 0.2);
  EXPECT_THROW(set_parameter(m, "frictoin", 0.3), std::invalid_argument);
  EXPECT_THROW(set_parameter(m, "friction", -1), std::invalid_argument);
  // Gravel already rolls: its candidates are cohesion and shape.
  std::vector<std::string> names;
  for (const auto& c : missing_effects(m)) names.push_back(c.name);
  EXPECT_EQ(names, (std::vector<std::string>{"jkr", "sjkr", "liquid_bridge", "clump_shape"}));  // in the effect table's order
  // Measured size, density and walls replace the library's.
  const MeasurementSet measured = parse_measurements(kGood, "m.yaml");
  apply_measured(m, measured);
  EXPECT_DOUBLE_EQ(m.particle.density, 2600);
  EXPECT_DOUBLE_EQ(m.diameter.mean, 0.005);
}

TEST(MaterialModel, CandidatesAddTheirEffects) {
  MaterialModel m = read_material_model(kMaterials + "/glass_beads.yaml");
  EXPECT_EQ(m.contact.rolling.model, "none");
  const auto candidates = missing_effects(m);
  ASSERT_EQ(candidates.size(), 5u);
  for (const auto& c : candidates) {
    MaterialModel with = m;
    c.add(with);
    for (const auto& [key, v] : c.start) set_parameter(with, key, v);
    for (const auto& [key, range] : c.parameters) EXPECT_NO_THROW((void)get_parameter(with, key)) << key;
    EXPECT_LT(missing_effects(with).size(), candidates.size()) << c.name;
  }
  MaterialModel wet = read_material_model(kMaterials + "/glass_beads_wet.yaml");
  EXPECT_DOUBLE_EQ(get_parameter(wet, "liquid_content"), 0.005);
  set_parameter(wet, "clump_aspect_ratio", 1.6);
  EXPECT_NEAR(get_parameter(wet, "clump_aspect_ratio"), 1.6, 1e-12);
}

// ---- analytic stand-ins -------------------------------------------------------------------

/// Known responses: friction mu, rolling friction mr (0 without rolling), liquid content lc,
/// surface energy g (JKR), cohesion energy density k (sjkr, in MJ/m^3: a strength that grows
/// with the load), clump aspect a, restitution e. Noise from the seed (packing).
struct Analytic {
  double noise = 1.0;  ///< scales the packing noise
  bool product = false;  ///< angle depends on friction x restitution only
  SimulatedOutcome operator()(const MaterialModel& m, const TestSetup& s, const TestOptions& o) const {
    const double mu = get_parameter(m, "friction"), e = get_parameter(m, "restitution");
    const double mr = m.contact.rolling.model == "none" ? 0.0 : get_parameter(m, "rolling_friction");
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
          22 + 8 * mu + 35 * mr + 100 * lc + 80 * g + 60 * k + 5 * a + (0.15 + 0.5 * mr) * s.numbers.at("rpm") + 0.3 * n(random);
    else if (s.test == "hopper_discharge") out.observables["mass_flow_rate"] = 2.0 - 0.6 * mu - 0.2 * mr - 30 * lc - 5 * g - 4 * k - 0.1 * a + 0.005 * n(random);
    else if (s.test == "direct_shear") {
      const double sn = s.numbers.at("normal_stress");
      out.observables["peak_shear_stress"] =
          (0.3 + 0.5 * mu + 0.3 * mr + 0.2 * a + 0.5 * k) * sn + 2e5 * lc + 3e4 * g * (1 + sn / 4000) + 10 * n(random);
    }
    return out;
  }
};

void add(MeasurementSet& set, const std::string& id, const std::string& test, std::map<std::string, double> numbers, const std::string& observable,
         double sigma) {
  Experiment e;
  e.id = id;
  e.setup.test = test;
  e.setup.numbers = std::move(numbers);
  e.observed[observable] = Observation{0.0, sigma, {}};
  set.experiments.push_back(e);
}

/// Synthetic measurements: the truth simulated (its own packing) plus measurement noise.
MeasurementSet synthesise(MeasurementSet set, const MaterialModel& truth, const Simulator& sim, std::uint64_t seed) {
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

MaterialModel dry_spheres() {
  MaterialModel m = read_material_model(kMaterials + "/gravel.yaml");
  m.contact.rolling.model = "none";
  m.particle.params.erase("rolling_friction");
  m.tunable.erase("rolling_friction");
  return m;
}

MeasurementSet flow_tests() {
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

CalibrationOptions analytic_options(const Simulator& sim) {
  CalibrationOptions o;
  o.simulator = sim;
  o.replicas = 3;
  return o;
}

TEST(Calibration, CompareFormsNormalisedResidualsWithSimulationNoise) {
  const Analytic sim;
  MaterialModel model = dry_spheres();
  MeasurementSet set = flow_tests();
  for (Experiment& e : set.experiments) {
    const SimulatedOutcome out = sim(model, e.setup, TestOptions{});
    for (auto& [key, obs] : e.observed) obs.value = out.observables.at(key);
  }
  set.experiments[1].observed["angle_deg"].value += 5;  // 5 sigma too high a measured angle
  Experiment blocked;
  blocked.id = "hopper_small";
  blocked.setup.test = "hopper_discharge";
  blocked.outcome = "blocked";
  set.experiments.push_back(blocked);
  const Comparison c = compare(model, set, analytic_options(sim));
  EXPECT_EQ(c.n, 9);
  EXPECT_LT(c.residual("aor_1", "angle_deg"), -4.0);
  EXPECT_NEAR(c.residual("hopper_small", "outcome"), -3.0, 1e-12);  // observed an arch, simulated flow
  for (const Term& t : c.terms)
    if (!t.is_outcome()) {
      EXPECT_GT(t.sigma_simulated, 0) << t.name();
    }
  // Drum residuals all fit: pattern "fits"; the drum group varies rpm.
  bool drum = false;
  for (const Pattern& p : c.patterns)
    if (p.test == "rotating_drum") {
      drum = true;
      EXPECT_EQ(p.kind, "fits") << p.words;
      EXPECT_EQ(p.varied, "rpm");
    }
  EXPECT_TRUE(drum);
}

TEST(Calibration, AnObservablesOwnExtractionErrorBoundsItsSimulationNoise) {
  // Replicas that agree closely (noise 0.01 of the stand-in's) but report an extraction error of
  // 3 deg each on the angle (a heap line fitted on a few bins): with 3 replicas the angle's
  // sigma_simulated is 3 / sqrt(3), not the replicas' tiny spread. Other observables keep theirs.
  const Analytic quiet{0.01};
  const Simulator sim = [&](const MaterialModel& m, const TestSetup& s, const TestOptions& o) {
    SimulatedOutcome out = quiet(m, s, o);
    if (s.test == "angle_of_repose_cylinder") out.uncertainty["angle_deg"] = 3.0;
    return out;
  };
  const MaterialModel model = dry_spheres();
  MeasurementSet set = flow_tests();
  for (Experiment& e : set.experiments)
    for (auto& [key, obs] : e.observed) obs.value = sim(model, e.setup, TestOptions{}).observables.at(key);
  const Comparison c = compare(model, set, analytic_options(sim));
  int angles = 0;
  for (const Term& t : c.terms) {
    if (t.observable == "angle_deg") {
      ++angles;
      EXPECT_NEAR(t.sigma_simulated, 3.0 / std::sqrt(3.0), 1e-12) << t.name();
    } else {
      EXPECT_LT(t.sigma_simulated, 0.05) << t.name();
    }
  }
  EXPECT_EQ(angles, 2);
}

TEST(Calibration, PatternsNameOffsetAndTrend) {
  std::vector<Term> terms;
  for (int k = 0; k < 4; ++k) {
    Term t;
    t.experiment = "s" + std::to_string(k), t.test = "direct_shear", t.observable = "peak_shear_stress";
    t.varied = "normal_stress", t.varied_value = 1000.0 * (k + 1);
    t.residual = -4.0 + 0.1 * (k % 2);
    terms.push_back(t);
    Term d = t;
    d.test = "rotating_drum", d.observable = "dynamic_angle_deg", d.varied = "rpm", d.varied_value = 10.0 * (k + 1);
    d.residual = -3.0 + 2.0 * k;
    terms.push_back(d);
  }
  const auto patterns = analyse_patterns(terms);
  ASSERT_EQ(patterns.size(), 2u);
  EXPECT_EQ(patterns[0].kind, "offset") << patterns[0].words;
  EXPECT_NE(patterns[0].words.find("yield locus is offset by a constant while its slope fits: cohesion"), std::string::npos) << patterns[0].words;
  EXPECT_EQ(patterns[1].kind, "trend") << patterns[1].words;
  EXPECT_NEAR(patterns[1].slope, 6.0, 1e-9);
}

TEST(Calibration, RecoversKnownParametersThroughTheSurrogate) {
  const Analytic sim{0.0};  // no packing noise: the parameters are exact
  MaterialModel truth = read_material_model(kMaterials + "/gravel.yaml");
  set_parameter(truth, "friction", 0.55);
  set_parameter(truth, "rolling_friction", 0.22);
  set_parameter(truth, "restitution", 0.4);
  MeasurementSet set = flow_tests();
  for (Experiment& e : set.experiments)
    for (auto& [key, obs] : e.observed) obs.value = sim(truth, e.setup, TestOptions{}).observables.at(key);
  const MaterialModel start = read_material_model(kMaterials + "/gravel.yaml");
  CalibrationOptions o = analytic_options(sim);
  const CalibrationResult r = calibrate(start, set, {}, o);
  ASSERT_EQ(r.parameters.size(), 3u);
  std::map<std::string, double> fitted;
  for (size_t i = 0; i < r.parameters.size(); ++i) fitted[r.parameters[i].key] = r.value[i];
  EXPECT_NEAR(fitted["friction"], 0.55, 0.01);
  EXPECT_NEAR(fitted["rolling_friction"], 0.22, 0.005);
  EXPECT_NEAR(fitted["restitution"], 0.4, 0.01);
  EXPECT_LT(r.after.chi2_per_n(), 0.01);
  EXPECT_GT(r.before.chi2_per_n(), 2);
  EXPECT_TRUE(r.unidentified.empty()) << r.words.back();
  for (double s : r.sigma) EXPECT_TRUE(std::isfinite(s) && s > 0);
  ASSERT_EQ(r.contours.size(), 1u);
  EXPECT_EQ(r.contours[0].fields.size(), 2u);
}

TEST(Calibration, FlagsParametersThatOnlyEnterAsAProduct) {
  const Analytic sim{1.0, true};
  MaterialModel model = dry_spheres();
  MeasurementSet set;
  add(set, "aor_1", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 1.0);
  add(set, "aor_2", "angle_of_repose_cylinder", {{"fill_height", 0.15}}, "angle_deg", 1.0);
  MaterialModel truth = model;
  set_parameter(truth, "friction", 0.6), set_parameter(truth, "restitution", 0.5);
  set = synthesise(set, truth, sim, 3);
  const CalibrationResult r = calibrate(model, set, fit_parameters(model, {"friction", "restitution"}), analytic_options(sim));
  EXPECT_EQ(r.unidentified.size(), 2u);
  EXPECT_GT(r.condition, 1e3);
  // A drop test pins the restitution down: both are then identified.
  add(set, "drop", "drop_rebound", {{"drop_height", 0.3}}, "restitution", 0.02);
  set = synthesise(set, truth, sim, 3);
  const CalibrationResult both = calibrate(model, set, fit_parameters(model, {"friction", "restitution"}), analytic_options(sim));
  EXPECT_TRUE(both.unidentified.empty()) << both.words.back();
  EXPECT_NEAR(both.value[0], 0.6, 0.05);
}

TEST(Calibration, SurrogateFormsAreChosenByLeaveOneOutError) {
  // Twelve points in two parameters: a plane with noise takes the linear form (a full quadratic
  // would fit the noise), a saddle the quadratic one (no other form reproduces u1 u2).
  const std::vector<FitParameter> box = {{"a", 0.0, 1.0}, {"b", -1.0, 1.0}};
  const Eigen::MatrixXd points = latin_hypercube(box, 12, 5);
  std::mt19937_64 random(11);
  std::normal_distribution<double> noise(0.0, 0.05);
  Eigen::MatrixXd values(12, 2);
  for (int k = 0; k < 12; ++k) {
    const double u1 = 2 * points(k, 0) - 1, u2 = points(k, 1);
    values(k, 0) = 1 + 2 * u1 - u2 + noise(random);
    values(k, 1) = u1 * u2;
  }
  const Surrogate s = fit_surrogate(box, {"plane", "saddle"}, points, values, Eigen::Vector2d(0.05, 0.05));
  ASSERT_EQ(s.form.size(), 2u);
  EXPECT_EQ(s.form[0], "linear");
  EXPECT_EQ(s.form[1], "quadratic");
  EXPECT_LT(s.fit_rms[0], 1.5);  // the noise, in its sigma
  EXPECT_LT(s.fit_rms[1], 1e-9);
  EXPECT_NEAR(s.predict(Eigen::Vector2d(1.0, 1.0))[1], 1.0, 1e-9);
}

TEST(Calibration, AConfirmationThatMissesTheSurrogateRefinesAroundTheBestPoint) {
  // An angle that saturates within a narrow band of friction (a heap that stops forming below
  // 0.4): four design points cannot draw it as a quadratic, and the surrogate's optimum, simulated,
  // misses. One more round in half the box around the best point simulated so far finds it.
  const Simulator sim = [](const MaterialModel& m, const TestSetup& s, const TestOptions&) {
    const double mu = get_parameter(m, "friction");
    SimulatedOutcome out;
    if (s.test == "angle_of_repose_cylinder") out.observables["angle_deg"] = 20 + 12 * std::tanh((mu - 0.45) / 0.05);
    else out.observables["dynamic_angle_deg"] = 25 + 4 * std::tanh((mu - 0.45) / 0.05);
    return out;
  };
  MeasurementSet set;
  add(set, "aor", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 0.5);
  add(set, "drum", "rotating_drum", {{"rpm", 20}}, "dynamic_angle_deg", 0.5);
  MaterialModel truth = dry_spheres();
  set_parameter(truth, "friction", 0.5);
  for (Experiment& e : set.experiments)
    for (auto& [key, obs] : e.observed) obs.value = sim(truth, e.setup, TestOptions{}).observables.at(key);
  CalibrationOptions o = analytic_options(sim);
  o.replicas = 2, o.rounds = 1, o.design_factor = 0.5;
  o.refine_rounds = 0;
  const CalibrationResult once = calibrate(dry_spheres(), set, fit_parameters(dry_spheres(), {"friction"}), o);
  o.refine_rounds = 1;
  const CalibrationResult refined = calibrate(dry_spheres(), set, fit_parameters(dry_spheres(), {"friction"}), o);
  EXPECT_GT(once.after.chi2_per_n(), 2 * once.surrogate_chi2 / 2 + 1) << "the stand-in no longer defeats one round";
  EXPECT_LT(refined.after.chi2_per_n(), once.after.chi2_per_n() / 2);
  EXPECT_LT(std::abs(refined.value[0] - 0.5), std::abs(once.value[0] - 0.5));
  EXPECT_TRUE(std::any_of(refined.words.begin(), refined.words.end(), [](const std::string& w) { return w.starts_with("One more surrogate round"); }));
  fmt::print("one round: friction {:.4f}, chi^2/n {:.2f}; refined: friction {:.4f}, chi^2/n {:.2f}\n", once.value[0], once.after.chi2_per_n(),
             refined.value[0], refined.after.chi2_per_n());
}

struct HiddenCase {
  const char* effect;
  MeasurementSet set;
  MaterialModel truth;
};

TEST(Diagnose, AnalyticHiddenRollingResistanceIsNamedFirst) {
  const Analytic sim;
  const MaterialModel start = dry_spheres();
  MaterialModel truth = read_material_model(kMaterials + "/gravel.yaml");  // rolls: mu_r = 0.2
  set_parameter(truth, "friction", 0.5), set_parameter(truth, "restitution", 0.5);
  const MeasurementSet set = synthesise(flow_tests(), truth, sim, 11);
  const Diagnosis d = diagnose(start, set, {}, analytic_options(sim));
  EXPECT_GT(d.base.after.chi2_per_n(), 5.0);  // the starting model fails visibly
  ASSERT_FALSE(d.candidates.empty());
  EXPECT_EQ(d.candidates.front().name, "epsd") << d.words.front();
  EXPECT_EQ(d.recommended, "epsd") << d.words.front();
  EXPECT_LT(d.candidates.front().fit.after.chi2_per_n(), 2.0);
  EXPECT_GT(d.candidates.front().explained, 0.5);
  // The report: self-contained HTML with the diagnosis, contour maps and the ledger.
  const std::string dir = (std::filesystem::temp_directory_path() / "demdesign_calibration_report").string();
  std::filesystem::remove_all(dir);
  report::CalibrationReportInput in;
  in.title = "diagnose gravel";
  in.diagnosis = &d;
  in.ledger = append_ledger(dir + "/ledger.yaml", "gravel", {ledger_entry(start, d.base.before, "start", {"friction"}),
                                                             ledger_entry(d.candidates.front().fit.fitted, d.candidates.front().fit.after, "+ rolling", {"friction"})});
  const std::string html = report::write_calibration_report(in, dir);
  std::ifstream file(html);
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("Most likely missing: epsd"), std::string::npos);
  EXPECT_NE(text.find("Error ledger"), std::string::npos);
  EXPECT_EQ(text.find("http"), std::string::npos);
  // Per experiment, the observable that drives its misfit.
  EXPECT_NE(text.find("what drives its misfit"), std::string::npos);
  const materials::Term* worst = nullptr;
  for (const materials::Term& t : d.base.before.terms)
    if (t.experiment == d.base.before.runs.front().id && (!worst || std::abs(t.residual) > std::abs(worst->residual))) worst = &t;
  ASSERT_NE(worst, nullptr);
  EXPECT_NE(text.find(fmt::format("<td>{}</td><td>{} {:+.2f} &sigma;</td>", worst->experiment, worst->observable, worst->residual)), std::string::npos);
  if (std::filesystem::exists(dir + "/plots/base_contour0.png")) {
    EXPECT_NE(text.find("data:image/png;base64"), std::string::npos);
  }
}

/// The dry spheres with liquid bridges of this liquid content, at friction 0.5.
MaterialModel wet_spheres(double liquid_content) {
  MaterialModel m = dry_spheres();
  for (const EffectCandidate& c : missing_effects(m))
    if (c.name == "liquid_bridge") c.add(m);
  set_parameter(m, "liquid_content", liquid_content), set_parameter(m, "friction", 0.5);
  return m;
}

TEST(Diagnose, AnalyticHiddenLiquidBridgesAreNamedFirst) {
  const Analytic sim;
  const MaterialModel start = dry_spheres(), truth = wet_spheres(0.01);
  MeasurementSet set;
  add(set, "drop", "drop_rebound", {{"drop_height", 0.3}}, "restitution", 0.02);
  add(set, "aor", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 1.0);
  add(set, "density", "bulk_density", {{"cup_diameter", 0.1}}, "bulk_density", 10);
  add(set, "hopper", "hopper_discharge", {{"orifice_diameter", 0.05}}, "mass_flow_rate", 0.02);
  for (double sn : {2000.0, 4000.0, 6000.0}) add(set, fmt::format("shear_{:.0f}", sn), "direct_shear", {{"normal_stress", sn}}, "peak_shear_stress", 50);
  set = synthesise(set, truth, sim, 5);
  const Diagnosis d = diagnose(start, set, {}, analytic_options(sim));
  EXPECT_GT(d.base.after.chi2_per_n(), 5.0);
  EXPECT_EQ(d.recommended, "liquid_bridge") << d.words.front();
  EXPECT_LT(d.candidates.front().fit.after.chi2_per_n(), 2.0);
  bool offset_words = false;
  for (const Pattern& p : d.base.before.patterns) offset_words = offset_words || p.words.find("yield locus") != std::string::npos;
  EXPECT_TRUE(offset_words);
  EXPECT_TRUE(d.rivals.empty()) << "a yield locus at three stresses tells an offset (bridges) from a steeper slope";
}

TEST(Diagnose, AnalyticRivalsTheDataCannotTellApartAreNamed) {
  // Truth: liquid bridges. Measured: a heap angle and a bulk density only. Friction cannot move
  // both as the bridges did, but any effect that moves them in another direction, with friction,
  // fits two numbers exactly: the runner-up is as good, and the diagnosis must say so.
  const Analytic sim;
  const MaterialModel start = dry_spheres(), truth = wet_spheres(0.03);
  MeasurementSet set;
  add(set, "aor", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 1.0);
  add(set, "density", "bulk_density", {{"cup_diameter", 0.1}}, "bulk_density", 10);
  set = synthesise(set, truth, sim, 5);
  const Diagnosis d = diagnose(start, set, {}, analytic_options(sim));
  for (const std::string& w : d.words) std::printf("%s\n", w.c_str());
  for (const CandidateResult& c : d.candidates) std::printf("  %s\n", c.words.c_str());
  ASSERT_FALSE(d.recommended.empty()) << d.words.front();
  ASSERT_GE(d.candidates.size(), 2u);
  ASSERT_TRUE(d.candidates[1].confirmed);
  EXPECT_LT(d.candidates[1].bic - d.candidates[0].bic, CalibrationOptions{}.rival_margin);
  ASSERT_EQ(d.rivals.size(), 1u);
  EXPECT_EQ(d.rivals.front(), d.candidates[1].name);
  bool words = false;
  for (const std::string& w : d.words) words = words || w.find("These data do not tell " + d.recommended + " from " + d.rivals.front()) == 0;
  EXPECT_TRUE(words);
  // The experiment it names separates them: simulated with the truth (bridges, which neither
  // candidate is), its outcome lies at least 2 sigma nearer one prediction than the other, so the
  // measurement decides between the two (here it also rejects both: the diagnosis is run again
  // with it).
  ASSERT_FALSE(d.separators.at(d.rivals.front()).empty());
  const Separator& best = d.separators.at(d.rivals.front()).front();
  EXPECT_GE(best.separation, 3.0) << best.words;
  bool named = false;
  for (const std::string& w : d.words) named = named || w.find("To tell " + d.recommended + " from " + d.rivals.front() + ", measure " + best.id) == 0;
  EXPECT_TRUE(named);
  TestOptions o;
  o.seed = 4242;
  const double truth_value = sim(truth, best.setup, o).observables.at(best.observable);
  const double off_a = std::abs(truth_value - best.predicted_a) / best.sigma, off_b = std::abs(truth_value - best.predicted_b) / best.sigma;
  std::printf("named: %s; truth %.4g (%.1f and %.1f sigma from the two)\n", best.words.c_str(), truth_value, off_a, off_b);
  EXPECT_GE(std::max(off_a, off_b) - std::min(off_a, off_b), 2.0) << "the measurement decides between the two";
}

TEST(Diagnose, AnalyticControlGetsNoRecommendation) {
  const Analytic sim;
  const MaterialModel start = dry_spheres();
  MaterialModel truth = start;
  set_parameter(truth, "friction", 0.7), set_parameter(truth, "restitution", 0.35);
  const MeasurementSet set = synthesise(flow_tests(), truth, sim, 17);
  const Diagnosis d = diagnose(start, set, {}, analytic_options(sim));
  EXPECT_LT(d.base.after.chi2_per_n(), 1.5);
  EXPECT_EQ(d.recommended, "");
  EXPECT_NE(d.words.front().find("No effect recommended"), std::string::npos);
}

/// Dry spheres with friction 0.3 and a guessed steel restitution of 0.5, and what `sim` measures
/// of friction 0.5 and a steel restitution of 0.8: two drops on steel, a heap and a density.
std::pair<MaterialModel, MeasurementSet> guessed_wall(const Simulator& sim) {
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

// A drop test misses because the particles' restitution on the steel plate is off, while the
// flow tests fit: the diagnosis points at the wall parameter, not at missing physics.
TEST(Diagnose, AWallParameterTheFitLeftOutIsNamedAsAParameter) {
  const Simulator sim = [](const MaterialModel& m, const TestSetup& s, const TestOptions& o) {
    std::mt19937_64 random(o.seed * 7919 + std::hash<std::string>{}(s.test));
    std::normal_distribution<double> n(0.0, 1.0);
    const double mu = get_parameter(m, "friction");
    const double mr = m.contact.rolling.model == "none" ? 0.0 : get_parameter(m, "rolling_friction");
    SimulatedOutcome out;
    if (s.test == "drop_rebound") out.observables["restitution"] = get_parameter(m, s.words.at("plate") + ".restitution") + 0.002 * n(random);
    if (s.test == "angle_of_repose_cylinder") out.observables["angle_deg"] = 18 + 20 * mu + 40 * mr + 0.3 * n(random);
    if (s.test == "bulk_density") out.observables["bulk_density"] = 1650 - 150 * mu - 300 * mr + 3 * n(random);
    return out;
  };
  const auto [start, set] = guessed_wall(sim);
  CalibrationOptions options = analytic_options(sim);
  options.walls_first = false;  // (on, the drops settle the restitution first: the next test)
  const Diagnosis d = diagnose(start, set, {{"friction", 0.1, 0.9}}, options);
  for (const std::string& w : d.words) std::cout << w << "\n";
  for (const CandidateResult& c : d.candidates) std::cout << "  " << c.words << "\n";
  EXPECT_GT(d.base.after.chi2_per_n(), 5.0);
  EXPECT_EQ(d.recommended, "steel.restitution") << fmt::format("{}", fmt::join(d.words, "\n"));
  ASSERT_FALSE(d.words.empty());
  EXPECT_EQ(d.words.front().rfind("Not missing physics: steel.restitution", 0), 0u) << d.words.front();
  const auto it = std::find_if(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& c) { return c.name == "steel.restitution"; });
  ASSERT_NE(it, d.candidates.end());
  EXPECT_NEAR(get_parameter(it->fit.fitted, "steel.restitution"), 0.8, 0.03);
  // An effect is not recommended to absorb it: no effect candidate beats the parameter.
  EXPECT_EQ(d.candidates.front().kind, "parameter");
}

// The first stage of a calibration: the drops on the steel plate settle the particle-steel
// restitution before the bulk fit, so the guessed wall value neither misfits the drops nor is
// left to the diagnosis; a measured wall restitution is an input and is not fitted.
TEST(Calibration, TheDropsSettleTheWallRestitutionFirst) {
  const Simulator sim = [](const MaterialModel& m, const TestSetup& s, const TestOptions& o) {
    std::mt19937_64 random(o.seed * 7919 + std::hash<std::string>{}(s.test));
    std::normal_distribution<double> n(0.0, 1.0);
    const double mu = get_parameter(m, "friction");
    SimulatedOutcome out;
    if (s.test == "drop_rebound") out.observables["restitution"] = get_parameter(m, s.words.at("plate") + ".restitution") + 0.002 * n(random);
    if (s.test == "angle_of_repose_cylinder") out.observables["angle_deg"] = 18 + 20 * mu + 0.3 * n(random);
    if (s.test == "bulk_density") out.observables["bulk_density"] = 1650 - 150 * mu + 3 * n(random);
    return out;
  };
  const auto [start, set] = guessed_wall(sim);
  const CalibrationResult fit = calibrate(start, set, {{"friction", 0.1, 0.9}}, analytic_options(sim));
  for (const std::string& w : fit.words) std::cout << w << "\n";
  // Two drops of sigma 0.02: the mean restitution to within 3 x 0.02 / sqrt(2).
  EXPECT_NEAR(get_parameter(fit.fitted, "steel.restitution"), 0.8, 0.045);
  EXPECT_EQ(fit.fitted.fitted_first, std::vector<std::string>{"steel.restitution"});
  ASSERT_FALSE(fit.words.empty());
  EXPECT_EQ(fit.words.front().rfind("steel.restitution fitted first", 0), 0u) << fit.words.front();
  EXPECT_NEAR(fit.value[0], 0.5, 3 * fit.sigma[0]);
  EXPECT_GT(fit.before.chi2_per_n(), 20.0);  // the guessed wall, before
  EXPECT_LE(fit.after.chi2_per_n(), 1.5);
  // The diagnosis does not offer the settled wall parameter again.
  const Diagnosis d = diagnose(start, set, {{"friction", 0.1, 0.9}}, analytic_options(sim));
  EXPECT_TRUE(d.recommended.empty()) << d.recommended;
  for (const CandidateResult& c : d.candidates) EXPECT_NE(c.name, "steel.restitution");
  // Measured, it is an input: kept as given.
  MaterialModel measured = start;
  measured.known.push_back("steel.restitution");
  const CalibrationResult kept = calibrate(measured, set, {{"friction", 0.1, 0.9}}, analytic_options(sim));
  EXPECT_DOUBLE_EQ(get_parameter(kept.fitted, "steel.restitution"), 0.5);
  EXPECT_TRUE(kept.fitted.fitted_first.empty());
}

// --budget: from what a pass over the experiments costs, the plan gives up rounds, design
// points, packings and candidates in that order until it fits, and says so.
TEST(Budget, PlansTheDiagnosisToFitAndSaysWhatItGaveUp) {
  Comparison first;
  for (int e = 0; e < 7; ++e) {
    ExperimentRun run;
    run.replicas = 3, run.wall_seconds = 3 * 10.0;  // 10 s a simulation: 70 s a pass
    first.runs.push_back(run);
  }
  CalibrationOptions options;
  options.parallel = 2;  // 35 s a pass
  options.budget_seconds = 1e6;
  const BudgetPlan roomy = plan_within_budget(options, first, 2, 4, 4);
  EXPECT_TRUE(roomy.given_up.empty());
  // Defaults, 2 parameters: 2 x 14 + 3 passes; 8 candidates x 3; 2 confirmations x (2 x 22 + 3): 149 passes.
  EXPECT_NEAR(roomy.seconds, 149 * 35.0, 1e-9);
  options.budget_seconds = 1800;
  const BudgetPlan tight = plan_within_budget(options, first, 2, 4, 4);
  EXPECT_LE(tight.seconds, 1800);
  ASSERT_FALSE(tight.given_up.empty());
  EXPECT_EQ(tight.given_up.front().rfind("one surrogate round", 0), 0u);
  EXPECT_EQ(tight.options.rounds, 1);
  // The wall parameters' screen goes only after the design points and the packings (a guessed
  // wall pair misfits like missing physics): 51 passes fit 1800 s with the walls still screened.
  EXPECT_TRUE(tight.options.wall_candidates);
  EXPECT_EQ(tight.options.replicas, 2);
  EXPECT_EQ(tight.options.design_factor, 0.5);
  EXPECT_NEAR(tight.seconds, 51 * 35.0, 1e-9);
  options.budget_seconds = 60;
  const BudgetPlan impossible = plan_within_budget(options, first, 2, 4, 4);
  EXPECT_NE(impossible.given_up.back().find("cannot be met"), std::string::npos);
  EXPECT_EQ(impossible.options.confirm_candidates, 1);
  // A diagnosis with a budget plans after its first comparison and says so first.
  const Simulator costly = [](const MaterialModel& m, const TestSetup& s, const TestOptions& o) {
    SimulatedOutcome out = Analytic{}(m, s, o);
    out.wall_seconds = 10;
    return out;
  };
  CalibrationOptions budgeted = analytic_options(costly);
  budgeted.budget_seconds = 1200;
  const Diagnosis d = diagnose(dry_spheres(), synthesise(flow_tests(), read_material_model(kMaterials + "/gravel.yaml"), costly, 11), {}, budgeted);
  ASSERT_FALSE(d.words.empty());
  EXPECT_EQ(d.words.front().rfind("Planned for the budget of 20 min", 0), 0u) << d.words.front();
  EXPECT_NE(d.words.front().find("given up"), std::string::npos) << d.words.front();
}

// Progress over the whole command: every line counts one more of the diagnosis' simulations,
// the count planned in all is never below those done, and by the end the plan (made again as the
// diagnosis learns which candidates it confirms) equals what ran.
TEST(Budget, ProgressCountsTheWholeDiagnosis) {
  const Analytic sim;
  const MaterialModel start = dry_spheres();
  MaterialModel truth = read_material_model(kMaterials + "/gravel.yaml");
  set_parameter(truth, "friction", 0.5), set_parameter(truth, "restitution", 0.5);
  CalibrationOptions options = analytic_options(sim);
  std::vector<std::pair<int, int>> counts;  // (done, planned in all)
  options.progress = [&](const std::string& line) {
    const auto at = line.find("; diagnose: simulation ");
    if (at == std::string::npos) return;
    int done = 0, planned = 0;
    ASSERT_EQ(std::sscanf(line.c_str() + at, "; diagnose: simulation %d of about %d", &done, &planned), 2) << line;
    counts.emplace_back(done, planned);
  };
  diagnose(start, synthesise(flow_tests(), truth, sim, 11), {}, options);
  ASSERT_GT(counts.size(), 100u);
  for (size_t k = 0; k < counts.size(); ++k) {
    EXPECT_EQ(counts[k].first, static_cast<int>(k) + 1);
    EXPECT_GE(counts[k].second, counts[k].first);
  }
  EXPECT_EQ(counts.back().first, counts.back().second);
}

TEST(Ledger, AppendsVersions) {
  const std::string path = (std::filesystem::temp_directory_path() / "demdesign_ledger_test" / "ledger.yaml").string();
  std::filesystem::remove_all(std::filesystem::path(path).parent_path());
  const MaterialModel m = dry_spheres();
  Comparison c;
  Term t;
  t.experiment = "aor", t.observable = "angle_deg", t.residual = -3.5;
  c.terms.push_back(t), c.chi2 = 12.25, c.n = 1;
  append_ledger(path, "gravel", {ledger_entry(m, c, "start", {"friction"})});
  c.terms[0].residual = 0.5, c.chi2 = 0.25;
  const auto all = append_ledger(path, "gravel", {ledger_entry(m, c, "+ epsd", {"friction"})});
  ASSERT_EQ(all.size(), 2u);
  const auto read = read_ledger(path);
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[1].version, 2);
  EXPECT_EQ(read[1].label, "+ epsd");
  EXPECT_DOUBLE_EQ(read[0].residuals.at("aor/angle_deg"), -3.5);
  EXPECT_DOUBLE_EQ(read[1].chi2_per_n(), 0.25);
  EXPECT_DOUBLE_EQ(read[0].parameters.at("friction"), 0.65);
}

}  // namespace
}  // namespace dem::materials
