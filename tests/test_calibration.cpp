// Measurement files, material models, compare and calibrate, on analytic stand-ins for the virtual
// tests (analytic_lab.h: known answers, no DEM). Diagnosis, budget and ledger: test_diagnose.cpp;
// the hidden-effect tests with real simulations: test_diagnose_real.cpp.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <mutex>
#include <numbers>
#include <random>
#include <set>
#include <tuple>

#include "analytic_lab.h"
#include "calibration/calibration.h"
#include "calibration/calibration_support.h"
#include "model/material_model.h"
#include "lab/measurements.h"
#include "lab/yield_locus.h"

namespace dem::materials {
namespace {

using namespace analytic;

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
  EXPECT_NE(with_zero.warnings[0].find("compared as `outcome: no_heap`"), std::string::npos) << with_zero.warnings[0];
  EXPECT_NE(with_zero.warnings[0].find("beside `observed:`"), std::string::npos) << with_zero.warnings[0];
  EXPECT_EQ(with_zero.warnings[0].rfind("m.yaml:20:", 0), 0u) << with_zero.warnings[0];
  // ... and compared as that outcome, the value left out.
  EXPECT_EQ(with_zero.experiments.back().outcome, "no_heap");
  EXPECT_TRUE(with_zero.experiments.back().observed.empty());
  // `outcome: none` keeps the number as a number, without a warning.
  std::string as_number = zero;
  as_number.replace(as_number.find("    observed:\n      angle_deg: {value: 0"), 4, "    outcome: none\n    ");
  const MeasurementSet kept = parse_measurements(as_number, "m.yaml");
  EXPECT_TRUE(kept.warnings.empty());
  EXPECT_EQ(kept.experiments.back().outcome, "");
  EXPECT_DOUBLE_EQ(kept.experiments.back().observed.at("angle_deg").value, 0.0);
  // A mass flow of 0 reads as an arch, a drum angle of 0 as a bed that slid.
  for (const auto& [test, setup, key, outcome] : {std::tuple{"hopper_discharge", "{silo_diameter: 0.1, orifice_diameter: 0.012, fill_height: 0.1, wall: steel}", "mass_flow_rate", "blocked"},
                                                  std::tuple{"rotating_drum", "{drum_diameter: 0.2, drum_depth: 0.05, fill_fraction: 0.35, rpm: 20, wall: steel}", "dynamic_angle_deg", "slipping"}}) {
    const MeasurementSet read = parse_measurements(text + fmt::format("  - id: x\n    test: {}\n    setup: {}\n    observed:\n      {}: {{value: 0, sigma: 0.01}}\n",
                                                                       test, setup, key), "m.yaml");
    EXPECT_EQ(read.experiments.back().outcome, outcome) << test;
    EXPECT_EQ(read.warnings.size(), 1u) << test;
  }
  EXPECT_TRUE(m.warnings.empty());
  // An outcome read from a number is read from the simulated numbers by the same rule: a drum
  // whose level bed rides on the shell (no `slipping` flag, angles 0.3 and 0.6 deg) matches the
  // lab's angle of 0.2; beds at 19 and 21 deg do not, nor does half of them.
  {
    const MeasurementSet read = parse_measurements(
        text + "  - id: drum\n    test: rotating_drum\n    setup: {drum_diameter: 0.2, drum_depth: 0.05, fill_fraction: 0.35, rpm: 20, wall: steel}\n"
               "    observed:\n      dynamic_angle_deg: {value: 0.2, sigma: 1}\n",
        "m.yaml");
    ASSERT_EQ(read.experiments.back().outcome_read_from, "dynamic_angle_deg");
    MeasurementSet drum = read;
    drum.experiments = {read.experiments.back()};
    const auto outcome_term = [&](std::vector<double> angles) {
      ExperimentRun run;
      run.id = "drum", run.test = "rotating_drum", run.replicas = static_cast<int>(angles.size());
      run.values["dynamic_angle_deg"] = angles;
      run.mean["dynamic_angle_deg"] = angles.front(), run.sigma["dynamic_angle_deg"] = 0.1;
      const Comparison c = compare_runs(drum, {run}, CalibrationOptions{});
      const auto t = std::find_if(c.terms.begin(), c.terms.end(), [](const Term& x) { return x.is_outcome(); });
      EXPECT_NE(t, c.terms.end());
      return t == c.terms.end() ? -1.0 : t->simulated;
    };
    EXPECT_DOUBLE_EQ(outcome_term({0.3, 0.6}), 1.0);
    EXPECT_DOUBLE_EQ(outcome_term({19.0, 21.0}), 0.0);
    EXPECT_DOUBLE_EQ(outcome_term({0.3, 21.0}), 0.5);
  }
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
    EXPECT_NO_THROW(check_experiments(model, m, {})) << path;  // every set-up key known, every value in range
  }
  // The worked example's file, against the dry beads it starts from.
  MaterialModel dry = read_material_model(kMaterials + "/glass_beads.yaml");
  const MeasurementSet wet = read_measurements(std::string(DEMDESIGN_SOURCE_DIR) + "/cases/calibration/wet_glass_beads_measurements.yaml");
  apply_measured(dry, wet);
  EXPECT_NO_THROW(check_experiments(dry, wet, {}));
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

TEST(Calibration, AFitOutOfThePlausibleOrAtItsRangesEdgeIsNamed) {
  // The plausible spans come from the parameter rows (ParamSpec::plausible; Coetzee 2017) for a
  // particle key and a wall pair's alike; a material file's `plausible:` would replace them.
  MaterialModel m = read_material_model(kMaterials + "/gravel.yaml");
  EXPECT_EQ(plausible_range(m, "friction"), (std::pair{0.1, 0.7}));
  EXPECT_EQ(plausible_range(m, "wall.friction"), (std::pair{0.1, 0.7}));
  EXPECT_EQ(plausible_range(m, "restitution"), (std::pair{0.1, 0.95}));
  EXPECT_EQ(plausible_range(m, "rolling_friction"), (std::pair{0.0, 0.4}));
  EXPECT_FALSE(plausible_range(m, "youngs_modulus").has_value());
  const std::vector<FitParameter> fitted = {{"friction", 0.1, 0.9}, {"rolling_friction", 0.0, 0.5}, {"restitution", 0.2, 0.9}};
  std::vector<std::string> words;
  // friction 0.79 +- 0.02: out by more than twice its error; rolling 0.45 +- 0.1: within two
  // errors of 0.4, not named; restitution at 0.899, the edge of its tunable range [0.2, 0.9].
  const std::vector<std::string> keys = implausible_fits(m, fitted, {0.79, 0.45, 0.899}, {0.02, 0.1, 0.01}, words);
  EXPECT_EQ(keys, (std::vector<std::string>{"friction", "restitution"}));
  ASSERT_EQ(words.size(), 1u);
  EXPECT_NE(words[0].find("friction = 0.79, outside 0.1 to 0.7 (what dry bulk solids usually show)"), std::string::npos) << words[0];
  EXPECT_NE(words[0].find("restitution = 0.899, at the edge of its range [0.2, 0.9]"), std::string::npos) << words[0];
  // At the edge but undetermined (an error of half the range): said apart, not as implausible.
  words.clear();
  const std::vector<std::string> loose = implausible_fits(m, fitted, {0.4, 0.2, 0.201}, {0.02, 0.05, 0.3}, words);
  EXPECT_TRUE(loose.empty());
  ASSERT_EQ(words.size(), 1u);
  EXPECT_EQ(words[0].find("Implausible"), std::string::npos) << words[0];
  EXPECT_NE(words[0].find("Not determined by these experiments: restitution = 0.201 +- 0.3 in [0.2, 0.9]"), std::string::npos) << words[0];
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
  ASSERT_EQ(candidates.size(), 6u);  // epsd, cdt, liquid_bridge, jkr, sjkr, clump_shape
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

// Two workers start a batch's longest simulations first (by what each set-up cost when it last
// ran), and return every outcome in batch order; after a fatal outcome, only the jobs before it in
// batch order still run.
TEST(Calibration, ABatchStartsItsLongestSimulationsFirst) {
  const MaterialModel model = dry_spheres();
  std::vector<TestSetup> setups(4);
  const std::vector<double> seconds = {1, 5, 2, 9};  // what each set-up "costs"
  for (size_t k = 0; k < setups.size(); ++k) setups[k].test = "batch_order", setups[k].numbers["which"] = static_cast<double>(k);
  std::mutex m;
  std::vector<int> started;
  CalibrationOptions options;
  options.parallel = 2;
  options.context = std::make_shared<detail::CommandContext>();  // one command: its later batches know what the first cost
  options.simulator = [&](const MaterialModel&, const TestSetup& setup, const TestOptions&) {
    const int which = static_cast<int>(setup.numbers.at("which"));
    {
      const std::lock_guard<std::mutex> lock(m);
      started.push_back(which);
    }
    if (setup.numbers.count("fatal")) throw CaseError("bad input");
    SimulatedOutcome out;
    out.observables["x"] = which;
    out.wall_seconds = seconds[which];
    return out;
  };
  std::vector<detail::Job> jobs;
  for (const TestSetup& s : setups) jobs.push_back({&model, &s, 1});
  const auto none = [](size_t, const BatchOutcome&) {};
  const auto fatal = [](const BatchOutcome& b) { return b.error == BatchOutcome::Error::input; };
  // The first batch knows no costs: batch order.
  std::vector<BatchOutcome> out = detail::run_batch(jobs, options, none, fatal);
  for (size_t k = 0; k < jobs.size(); ++k) EXPECT_EQ(out[k].outcome.observables.at("x"), static_cast<double>(k));
  // The second starts the 9 s and 5 s set-ups, then 2 s, then 1 s; outcomes stay in batch order.
  started.clear();
  out = detail::run_batch(jobs, options, none, fatal);
  ASSERT_EQ(started.size(), 4u);
  EXPECT_EQ(std::set<int>(started.begin(), started.begin() + 2), (std::set<int>{3, 1}));
  EXPECT_EQ(std::set<int>(started.begin() + 2, started.end()), (std::set<int>{2, 0}));
  for (size_t k = 0; k < jobs.size(); ++k) EXPECT_EQ(out[k].outcome.observables.at("x"), static_cast<double>(k));
  // Job 1 fails with bad input. It is started second, after the 9 s job; job 0, which comes before
  // it in batch order, still runs although it is started last.
  setups[1].numbers["fatal"] = 1;
  out = detail::run_batch(jobs, options, none, fatal);
  EXPECT_EQ(out[0].error, BatchOutcome::Error::none);
  EXPECT_EQ(out[1].error, BatchOutcome::Error::input);
}

// A command's count and the costs it measured (CommandContext) are its own: two comparisons in
// one process each count their simulations and estimate the time left from their own costs, and
// the comparisons a calibration calls count into the calibration's one count.
TEST(Calibration, ACommandSharesItsCountAndCostsOnlyWithTheCommandsItCalls) {
  const Analytic sim;
  MaterialModel truth = dry_spheres();
  set_parameter(truth, "friction", 0.5);
  MeasurementSet set;
  add(set, "aor", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 1.0);
  add(set, "density", "bulk_density", {{"cup_diameter", 0.1}}, "bulk_density", 10);
  const MeasurementSet measured = synthesise(set, truth, sim, 5);
  // Options whose simulations each say they took `seconds`, with progress lines of their own.
  const auto options_with = [&](double seconds, std::vector<std::string>& lines) {
    CalibrationOptions o = analytic_options([&sim, seconds](const MaterialModel& m, const TestSetup& s, const TestOptions& t) {
      SimulatedOutcome out = sim(m, s, t);
      out.wall_seconds = seconds;
      return out;
    });
    o.most_replicas = o.replicas;  // no packings added: 2 experiments x 3 replicas
    o.progress = [&lines](const std::string& line) { lines.push_back(line); };
    return o;
  };

  // Two comparisons with the options as a library user leaves them (no context): after its first
  // simulation each expects its 5 others at its own cost, 10 s and 25 s (with the first
  // comparison's costs in the second's estimate it would say 12 s), and counts 1 to 6 of 6.
  std::vector<std::string> first_lines, second_lines;
  compare(dry_spheres(), measured, options_with(2.0, first_lines));
  compare(dry_spheres(), measured, options_with(5.0, second_lines));
  ASSERT_EQ(first_lines.size(), 6u);
  ASSERT_EQ(second_lines.size(), 6u);
  EXPECT_TRUE(first_lines.front().ends_with(" elapsed, about 10 s left")) << first_lines.front();
  EXPECT_TRUE(second_lines.front().ends_with(" elapsed, about 25 s left")) << second_lines.front();
  for (const std::vector<std::string>* lines : {&first_lines, &second_lines})
    for (size_t k = 0; k < lines->size(); ++k)
      EXPECT_NE((*lines)[k].find(fmt::format("; compare: simulation {} of about 6, ", k + 1)), std::string::npos) << (*lines)[k];

  // Given contexts hold each command's own count and costs.
  std::vector<std::string> quiet;
  CalibrationOptions first = options_with(2.0, quiet), second = options_with(5.0, quiet);
  first.context = std::make_shared<detail::CommandContext>();
  second.context = std::make_shared<detail::CommandContext>();
  compare(dry_spheres(), measured, first);
  compare(dry_spheres(), measured, second);
  for (const CalibrationOptions* o : {&first, &second}) {
    EXPECT_FALSE(o->context->count.active());
    EXPECT_EQ(o->context->count.done(), 6);
    EXPECT_EQ(o->context->count.left(), 0);
  }
  EXPECT_DOUBLE_EQ(first.context->costs.estimate("bulk_density/density"), 2.0);
  EXPECT_DOUBLE_EQ(second.context->costs.estimate("bulk_density/density"), 5.0);

  // A calibration's comparisons count into the calibration: one count over all its simulations,
  // its first comparison's included.
  std::vector<std::string> nested_lines;
  CalibrationOptions nested = options_with(5.0, nested_lines);
  nested.context = std::make_shared<detail::CommandContext>();
  calibrate(dry_spheres(), measured, fit_parameters(dry_spheres(), {"friction"}), nested);
  ASSERT_FALSE(nested_lines.empty());
  EXPECT_TRUE(nested_lines.front().starts_with("compare: simulation 1 of 6 done")) << nested_lines.front();
  EXPECT_NE(nested_lines.front().find("; calibrate: simulation 1 of about "), std::string::npos) << nested_lines.front();
  int counted = 0;
  for (const std::string& line : nested_lines) {
    const size_t at = line.find("; calibrate: simulation ");
    if (at == std::string::npos) continue;
    int done = 0, planned = 0;
    ASSERT_EQ(std::sscanf(line.c_str() + at, "; calibrate: simulation %d of about %d", &done, &planned), 2) << line;
    EXPECT_EQ(done, ++counted) << line;
  }
  EXPECT_GT(counted, 6);
  EXPECT_EQ(nested.context->count.done(), counted);
  EXPECT_EQ(first.context->count.done(), 6) << "the calibration left the first comparison's count alone";
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

TEST(Calibration, PackingsAreAddedWhereTheVerdictDependsOnThem) {
  // A hopper whose flow rate scatters by 25 % from packing to packing (an orifice near its arching
  // limit): its first two packings happen to agree 0.3 above the model's own mean. With two
  // packings the comparison says chi^2/n > 1.5 and blames the hopper at 6 sigma; a third packing
  // shows the scatter and the verdict turns. The deterministic drop is never repeated, and a
  // comparison far from the line (a 20 sigma heap) gets no packings.
  const Analytic quiet{0.0};
  const std::vector<double> hopper_offset = {0.30, 0.31, -0.30, -0.20, -0.35, -0.05};  // by packing (seed 1, 2, ...)
  const Simulator sim = [&](const MaterialModel& m, const TestSetup& s, const TestOptions& o) {
    SimulatedOutcome out = quiet(m, s, o);
    if (s.test == "hopper_discharge") out.observables["mass_flow_rate"] = 1.0 + hopper_offset.at(o.seed - 1);
    if (s.test != "drop_rebound")  // small packing noise elsewhere
      for (auto& [key, v] : out.observables) v *= 1.0 + 1e-4 * static_cast<double>(o.seed);
    return out;
  };
  const MaterialModel model = dry_spheres();
  MeasurementSet set = flow_tests();
  for (Experiment& e : set.experiments)
    for (auto& [key, obs] : e.observed) obs.value = quiet(model, e.setup, TestOptions{}).observables.at(key);
  set.experiments[7].observed["mass_flow_rate"] = {1.0, 0.05};
  set.experiments[0].observed["restitution"].value += 0.05;  // the drop misfits by 2.5 sigma: deterministic
  CalibrationOptions o = analytic_options(sim);
  o.replicas = 2;

  CalibrationOptions fixed = o;
  fixed.most_replicas = 2;
  const Comparison two = compare(model, set, fixed);
  EXPECT_GT(two.residual("hopper", "mass_flow_rate"), 5.0);
  EXPECT_GT(two.chi2_per_n(), 1.5);

  const Comparison adaptive = compare(model, set, o);
  EXPECT_LT(adaptive.chi2_per_n(), 1.5);
  EXPECT_LT(std::abs(adaptive.residual("hopper", "mass_flow_rate")), 2.0);
  for (const ExperimentRun& run : adaptive.runs) EXPECT_EQ(run.replicas, run.id == "hopper" ? 3 : 2) << run.id;
  EXPECT_EQ(adaptive.simulations(), 8 * 2 + 1);
  // A diagnosis's runner-up whose chi^2 lies beyond the bar of a rival gets no packings; just
  // below the bar, it gets them as before.
  CalibrationOptions behind = o;
  behind.no_rival_above_chi2 = 0.9 * two.chi2;
  EXPECT_EQ(compare(model, set, behind).simulations(), 8 * 2);
  behind.no_rival_above_chi2 = 1.1 * two.chi2;
  EXPECT_EQ(compare(model, set, behind).simulations(), 8 * 2 + 1);

  set.experiments[1].observed["angle_deg"].value += 20;  // far from fitting: no decision turns on the noise
  const Comparison far = compare(model, set, o);
  EXPECT_GT(far.chi2_per_n(), 6.0);
  EXPECT_EQ(far.simulations(), 8 * 2);
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

/// An angle that saturates within a narrow band of friction (a heap that stops forming below
/// 0.4), and a heap and a drum measured of friction 0.5: four design points cannot draw it as a
/// quadratic, so the surrogate's optimum, simulated, misses.
std::pair<Simulator, MeasurementSet> saturating_angles() {
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
  return {sim, set};
}

TEST(Calibration, AConfirmationThatMissesTheSurrogateRefinesAroundTheBestPoint) {
  // One more round in half the box around the best point simulated so far finds the optimum the
  // saturating angles hide from the first round.
  const auto [sim, set] = saturating_angles();
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
  // A runner-up of a diagnosis whose simulations and surrogate both lie beyond the bar (a leader's
  // BIC plus twice the rival margin) is not refined; just above both, it is.
  o.no_rival_above_chi2 = 0.9 * std::min(once.after.chi2, once.surrogate_chi2);
  const CalibrationResult behind = calibrate(dry_spheres(), set, fit_parameters(dry_spheres(), {"friction"}), o);
  EXPECT_EQ(behind.after.chi2, once.after.chi2);
  EXPECT_TRUE(std::any_of(behind.words.begin(), behind.words.end(), [](const std::string& w) { return w.starts_with("Not refined"); }));
  o.no_rival_above_chi2 = 1.1 * std::min(once.after.chi2, once.surrogate_chi2);
  const CalibrationResult within = calibrate(dry_spheres(), set, fit_parameters(dry_spheres(), {"friction"}), o);
  EXPECT_EQ(within.after.chi2, refined.after.chi2);
}

// A refinement round that would end past its deadline (a diagnosis's budget, for a runner-up) is
// not run: the first round's optimum stands, the result says so and is marked unrefined, and the
// surrogate's prediction stays beside the simulations for the verdict (write_verdict).
TEST(Calibration, ARefinementRoundPastItsDeadlineIsNotRun) {
  const auto [sim, set] = saturating_angles();
  CalibrationOptions o = analytic_options(sim);
  o.replicas = 2, o.rounds = 1, o.design_factor = 0.5;
  o.refine_deadline = 3600;  // an hour away: refined
  const CalibrationResult refined = calibrate(dry_spheres(), set, fit_parameters(dry_spheres(), {"friction"}), o);
  ASSERT_TRUE(std::any_of(refined.words.begin(), refined.words.end(), [](const std::string& w) { return w.starts_with("One more surrogate round"); }));
  EXPECT_FALSE(refined.unrefined);
  o.refine_deadline = 0;  // already past
  const CalibrationResult cut = calibrate(dry_spheres(), set, fit_parameters(dry_spheres(), {"friction"}), o);
  EXPECT_TRUE(cut.unrefined);
  EXPECT_TRUE(std::none_of(cut.words.begin(), cut.words.end(), [](const std::string& w) { return w.starts_with("One more surrogate round"); }));
  EXPECT_TRUE(std::any_of(cut.words.begin(), cut.words.end(), [](const std::string& w) { return w.find("would end past the budget") != std::string::npos; }));
  EXPECT_GT(cut.after.chi2, 2 * refined.after.chi2) << "the round not run is the one that found the optimum";
  // Simulations that say they took 10 s each (2 experiments, one at a time): a refinement round of
  // 4 points and its 2-packing comparison is counted at 2 min. A deadline 1 min away cuts it, one
  // an hour away does not.
  const Simulator timed = [&](const MaterialModel& m, const TestSetup& s, const TestOptions& t) {
    SimulatedOutcome out = sim(m, s, t);
    out.wall_seconds = 10;
    return out;
  };
  CalibrationOptions slow = analytic_options(timed);
  slow.replicas = 2, slow.rounds = 1, slow.design_factor = 0.5;
  slow.refine_deadline = 60;
  EXPECT_TRUE(calibrate(dry_spheres(), set, fit_parameters(dry_spheres(), {"friction"}), slow).unrefined) << "2 min of refinement before a deadline 1 min away";
  slow.refine_deadline = 3600;
  EXPECT_FALSE(calibrate(dry_spheres(), set, fit_parameters(dry_spheres(), {"friction"}), slow).unrefined);
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
  // The diagnosis does not offer the settled wall parameter again, even when asked to screen it.
  CalibrationOptions screen_all = analytic_options(sim);
  screen_all.effects = candidate_names();
  screen_all.effects.insert(screen_all.effects.end(), {"steel.restitution", "steel.friction"});
  const Diagnosis d = diagnose(start, set, {{"friction", 0.1, 0.9}}, screen_all);
  EXPECT_TRUE(d.recommended.empty()) << d.recommended;
  ASSERT_FALSE(d.candidates.empty());
  EXPECT_TRUE(std::any_of(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& c) { return c.name == "steel.friction"; }));
  for (const CandidateResult& c : d.candidates) EXPECT_NE(c.name, "steel.restitution");
  // Measured, it is an input: kept as given.
  MaterialModel measured = start;
  measured.known.push_back("steel.restitution");
  const CalibrationResult kept = calibrate(measured, set, {{"friction", 0.1, 0.9}}, analytic_options(sim));
  EXPECT_DOUBLE_EQ(get_parameter(kept.fitted, "steel.restitution"), 0.5);
  EXPECT_TRUE(kept.fitted.fitted_first.empty());
  // Points simulated before with the guessed wall are not points of a calibration whose drops
  // give the wall another value: left out, and said; with the wall kept, they are data.
  EarlierPoints earlier;
  earlier.known.push_back(fit.points.front());
  earlier.known.front().x = {0.123456};  // a point no design of these calibrations makes
  const auto holds = [](const CalibrationResult& r, const SimulatedPoint& q) {
    return std::any_of(r.points.begin(), r.points.end(), [&](const SimulatedPoint& x) { return x.x == q.x && x.values == q.values; });
  };
  const CalibrationResult moved = calibrate(start, set, {{"friction", 0.1, 0.9}}, analytic_options(sim), nullptr, earlier);
  EXPECT_FALSE(holds(moved, earlier.known.front()));
  EXPECT_TRUE(std::any_of(moved.words.begin(), moved.words.end(),
                          [](const std::string& w) { return w.find("The 1 point simulated before was left out") != std::string::npos; }));
  const CalibrationResult same = calibrate(measured, set, {{"friction", 0.1, 0.9}}, analytic_options(sim), nullptr, earlier);
  EXPECT_TRUE(holds(same, earlier.known.front()));
  // A design reduced to stand beside the known points takes the full rule again without them
  // (two points could not fit a quadratic in one parameter).
  CalibrationOptions beside = analytic_options(sim);
  beside.design_points = 2;
  EXPECT_NO_THROW(calibrate(start, set, {{"friction", 0.1, 0.9}}, beside, nullptr, earlier));
}

// ---- yield loci ---------------------------------------------------------------------------

/// Points exactly on tau = c + sigma tan(phi) at 5, 10 and 20 kPa, each with standard error `error` [Pa].
std::vector<LocusPoint> exact_locus(double phi_deg, double cohesion, double error) {
  std::vector<LocusPoint> points;
  for (double sigma : {5000.0, 10000.0, 20000.0})
    points.push_back({sigma, cohesion + sigma * std::tan(phi_deg * std::numbers::pi / 180), error, ""});
  return points;
}

TEST(YieldLocus, AnExactLocusGivesItsAngleAndCohesionWithTheClosedFormErrors) {
  const std::vector<LocusPoint> points = exact_locus(30, 2000, 100);
  const YieldLocusFit fit = fit_yield_locus(points);
  ASSERT_TRUE(fit.fitted) << fit.reason;
  EXPECT_NEAR(fit.friction_angle, 30, 30 * 1e-9);
  EXPECT_NEAR(fit.cohesion, 2000, 2000 * 1e-9);
  // Weighted linear regression in closed form: var(slope) = S/D, var(intercept) = Sxx/D,
  // cov = -Sx/D, D = S Sxx - Sx^2, with S = sum w, Sx = sum w x, Sxx = sum w x^2, w = 1/err^2.
  double S = 0, Sx = 0, Sxx = 0;
  for (const LocusPoint& p : points) {
    const double w = 1 / (p.error * p.error);
    S += w, Sx += w * p.normal_stress, Sxx += w * p.normal_stress * p.normal_stress;
  }
  const double D = S * Sxx - Sx * Sx, tan_phi = std::tan(std::numbers::pi / 6);
  const double phi_sigma = std::sqrt(S / D) / (1 + tan_phi * tan_phi) * 180 / std::numbers::pi;
  EXPECT_NEAR(fit.friction_angle_sigma, phi_sigma, phi_sigma * 1e-9);
  EXPECT_NEAR(fit.cohesion_sigma, std::sqrt(Sxx / D), std::sqrt(Sxx / D) * 1e-9);
  EXPECT_NEAR(fit.correlation, -Sx / std::sqrt(S * Sxx), 1e-9);
  EXPECT_EQ(fit.points, 3);
  EXPECT_EQ(fit.dof, 1);
  EXPECT_NEAR(fit.chi2_per_dof, 0, 1e-12);
  EXPECT_FALSE(fit.cohesion_zero);  // 2000 Pa against a standard error of 122 Pa
}

TEST(YieldLocus, OneNormalStressGivesNoFitAndSaysWhy) {
  const YieldLocusFit one = fit_yield_locus({{10000, 7000, 100, "a"}, {10000, 7100, 100, "b"}});
  EXPECT_FALSE(one.fitted);
  EXPECT_NE(one.reason.find("one normal stress"), std::string::npos) << one.reason;
  const YieldLocusFit none = fit_yield_locus({});
  EXPECT_FALSE(none.fitted);
  EXPECT_FALSE(none.reason.empty());
  // A point without a standard error cannot be weighted.
  const YieldLocusFit unweighted = fit_yield_locus({{5000, 4000, 100, ""}, {10000, 7000, 0, "b"}});
  EXPECT_FALSE(unweighted.fitted);
  EXPECT_NE(unweighted.reason.find("standard error"), std::string::npos) << unweighted.reason;
  // Two distinct normal stresses fit, with no degrees of freedom left.
  const YieldLocusFit two = fit_yield_locus({{5000, 4000, 100, ""}, {10000, 7000, 100, ""}});
  ASSERT_TRUE(two.fitted) << two.reason;
  EXPECT_EQ(two.dof, 0);
  EXPECT_TRUE(std::isnan(two.chi2_per_dof));
}

TEST(YieldLocus, WordsNameAFlatterOrLowerLocusOrTheNoise) {
  const auto contains = [](const std::string& text, const std::string& word) { return text.find(word) != std::string::npos; };
  // 5 deg flatter, far beyond the errors (about 0.4 deg each), the same intercept.
  const std::string flatter = compare_yield_loci(fit_yield_locus(exact_locus(30, 2000, 100)), fit_yield_locus(exact_locus(25, 2000, 100)));
  EXPECT_TRUE(contains(flatter, "flatter")) << flatter;
  EXPECT_TRUE(contains(flatter, "friction")) << flatter;
  EXPECT_FALSE(contains(flatter, "lower")) << flatter;
  EXPECT_FALSE(contains(flatter, "within the noise")) << flatter;
  // The same slope, 3 kPa less intercept (standard errors of c about 0.6 kPa each).
  const std::string lower = compare_yield_loci(fit_yield_locus(exact_locus(30, 3000, 500)), fit_yield_locus(exact_locus(30, 0, 500)));
  EXPECT_TRUE(contains(lower, "lower")) << lower;
  EXPECT_TRUE(contains(lower, "lacks the intercept")) << lower;
  EXPECT_TRUE(contains(lower, "cohesion")) << lower;
  EXPECT_FALSE(contains(lower, "flatter")) << lower;
  EXPECT_FALSE(contains(lower, "steeper")) << lower;
  // Identical loci.
  const YieldLocusFit same = fit_yield_locus(exact_locus(30, 2000, 100));
  const std::string noise = compare_yield_loci(same, same);
  EXPECT_TRUE(contains(noise, "within the noise")) << noise;
  // No measured fit: no comparison, and why.
  const std::string none = compare_yield_loci(fit_yield_locus({}), same);
  EXPECT_TRUE(contains(none, "No comparison")) << none;
}

TEST(YieldLocus, AComparisonsShearTermsFormMeasuredAndSimulatedLoci) {
  // Three direct shear experiments after pre-shear at 20 kPa, and a bulk density that is no locus.
  MeasurementSet set;
  Comparison comparison;
  const double tan30 = std::tan(std::numbers::pi / 6), tan25 = std::tan(25 * std::numbers::pi / 180);
  for (double sigma : {10000.0, 5000.0, 20000.0}) {
    Experiment e;
    e.id = e.setup.id = fmt::format("shear_{:g}", sigma / 1000);
    e.setup.test = "direct_shear";
    e.setup.numbers = {{"preshear_stress", 20000}, {"normal_stress", sigma}};
    Term peak;
    peak.experiment = e.id, peak.test = "direct_shear", peak.observable = "peak_shear_stress";
    peak.measured = 2000 + sigma * tan30, peak.sigma_measured = 100;
    peak.simulated = 500 + sigma * tan25, peak.sigma_simulated = 100;
    Term steady = peak;
    steady.observable = "steady_shear_stress";
    steady.measured = 2000 + 20000 * tan30, steady.simulated = 500 + 20000 * tan25;
    comparison.terms.push_back(peak);
    comparison.terms.push_back(steady);
    e.observed["peak_shear_stress"].value = peak.measured, e.observed["peak_shear_stress"].sigma = 100;
    e.observed["steady_shear_stress"].value = steady.measured, e.observed["steady_shear_stress"].sigma = 100;
    set.experiments.push_back(e);
  }
  Experiment density;
  density.id = density.setup.id = "density";
  density.setup.test = "bulk_density";
  set.experiments.push_back(density);
  Term bulk;
  bulk.experiment = "density", bulk.test = "bulk_density", bulk.observable = "bulk_density";
  bulk.measured = 1500, bulk.sigma_measured = 20, bulk.simulated = 1480, bulk.sigma_simulated = 10;
  comparison.terms.push_back(bulk);

  const std::vector<LocusComparison> loci = yield_loci(set, comparison);
  ASSERT_EQ(loci.size(), 2u);
  // The peaks: one locus over the normal stresses, in ascending order.
  const LocusComparison& peak = loci[0];
  EXPECT_EQ(peak.measured.observable, "peak_shear_stress");
  EXPECT_DOUBLE_EQ(peak.measured.preshear_stress, 20000);
  ASSERT_EQ(peak.measured.points.size(), 3u);
  EXPECT_DOUBLE_EQ(peak.measured.points.front().normal_stress, 5000);
  EXPECT_EQ(peak.measured.points.front().experiment, "shear_5");
  ASSERT_TRUE(peak.measured.fit.fitted && peak.simulated.fit.fitted);
  EXPECT_NEAR(peak.measured.fit.friction_angle, 30, 1e-9);
  EXPECT_NEAR(peak.measured.fit.cohesion, 2000, 1e-6);
  EXPECT_NEAR(peak.simulated.fit.friction_angle, 25, 1e-9);
  EXPECT_NEAR(peak.simulated.fit.cohesion, 500, 1e-6);
  EXPECT_NE(peak.words.find("flatter"), std::string::npos) << peak.words;
  // The steady states all lie at the pre-shear stress: one normal stress, no locus.
  const LocusComparison& steady = loci[1];
  EXPECT_EQ(steady.measured.observable, "steady_shear_stress");
  EXPECT_FALSE(steady.measured.fit.fitted);
  EXPECT_NE(steady.measured.fit.reason.find("one normal stress"), std::string::npos) << steady.measured.fit.reason;
  EXPECT_NE(steady.words.find("No comparison"), std::string::npos) << steady.words;
  // The measured set alone gives the same measured loci.
  const std::vector<YieldLocus> measured = measured_yield_loci(set);
  ASSERT_EQ(measured.size(), 2u);
  EXPECT_EQ(measured[0].points.size(), 3u);
  EXPECT_NEAR(measured[0].fit.friction_angle, peak.measured.fit.friction_angle, 1e-12);
  EXPECT_NEAR(measured[0].fit.cohesion, peak.measured.fit.cohesion, 1e-9);
  EXPECT_FALSE(measured[1].fit.fitted);
}

}  // namespace
}  // namespace dem::materials
