// Calibration batches over MPI ranks (app/campaign/mpi_campaign.h), run as `mpirun -np 2 campaign_mpi_tests`
// (see tests/CMakeLists.txt). Each rank calibrates the same material against the same analytic
// stand-in twice: alone (every simulation in this process) and with its simulations shared among
// the ranks. The two must agree bitwise, each rank must have run only its share, a design point
// whose simulation fails must be skipped alike, and bad input must stop every rank with the
// serial run's error.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>

#include "calibration/calibration.h"
#include "case/spec.h"
#include "model/material_model.h"
#include "campaign/mpi_campaign.h"

namespace {

using namespace dem::materials;
namespace mpi = dem::app::mpi;

const std::string kMaterials = DEMDESIGN_SOURCE_DIR "/materials";

void add(MeasurementSet& set, const std::string& id, const std::string& test, std::map<std::string, double> numbers,
         const std::string& observable, double value, double sigma) {
  Experiment e;
  e.id = id;
  e.setup.test = test;
  e.setup.numbers = std::move(numbers);
  e.observed[observable] = Observation{value, sigma, {}};
  set.experiments.push_back(e);
}

/// Known responses in friction mu and restitution e with packing noise from the seed; counts the
/// simulations this process runs. A friction above `fail_above` fails the hopper (a design point
/// to skip); `bad_input` makes the drum refuse its set-up (CaseError).
struct Analytic {
  int* calls;
  double fail_above = 10;
  bool bad_input = false;
  SimulatedOutcome operator()(const MaterialModel& m, const TestSetup& s, const TestOptions& o) const {
    ++*calls;
    const double mu = get_parameter(m, "friction"), e = get_parameter(m, "restitution");
    std::mt19937_64 random(o.seed * 7919 + std::hash<std::string>{}(s.test));
    std::normal_distribution<double> n(0.0, 1.0);
    SimulatedOutcome out;
    out.particles = 100 + static_cast<int>(o.seed);
    if (s.test == "drop_rebound") out.observables["restitution"] = e + 0.002 * n(random);
    if (s.test == "angle_of_repose_cylinder") out.observables["angle_deg"] = 18 + 12 * mu + 5 * e * mu + 0.3 * n(random);
    if (s.test == "rotating_drum") {
      if (bad_input) throw dem::CaseError("m.yaml:7:5: experiments[2].setup.rpm: 900 rpm is out of range; valid: (0, 60] rpm");
      out.observables["dynamic_angle_deg"] = 22 + 8 * mu + 0.15 * s.numbers.at("rpm") + 0.3 * n(random);
    }
    if (s.test == "hopper_discharge") {
      if (mu > fail_above) throw std::runtime_error("the orifice blocked at once (no flow to measure)");
      out.observables["mass_flow_rate"] = 2.0 - 0.6 * mu + 0.1 * e + 0.005 * n(random);
      if (mu > 0.9) out.flags.push_back("blocked");
    }
    return out;
  }
};

MeasurementSet measurements() {
  MeasurementSet set;
  add(set, "drop", "drop_rebound", {{"drop_height", 0.3}}, "restitution", 0.42, 0.02);
  add(set, "aor", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 26.0, 1.0);
  add(set, "drum_10", "rotating_drum", {{"rpm", 10}}, "dynamic_angle_deg", 28.5, 1.0);
  add(set, "drum_20", "rotating_drum", {{"rpm", 20}}, "dynamic_angle_deg", 30.0, 1.0);
  add(set, "hopper", "hopper_discharge", {{"orifice_diameter", 0.05}}, "mass_flow_rate", 1.7, 0.02);
  return set;
}

CalibrationOptions options(const Simulator& sim, bool shared) {
  CalibrationOptions o;
  o.simulator = sim;
  o.replicas = 3;
  if (shared) o.batch = mpi::calibration_batch_runner();
  return o;
}

void expect_same(const CalibrationResult& a, const CalibrationResult& b) {
  ASSERT_EQ(a.value.size(), b.value.size());
  for (size_t i = 0; i < a.value.size(); ++i) {
    EXPECT_EQ(a.value[i], b.value[i]) << a.parameters[i].key;  // bitwise: the same doubles
    EXPECT_EQ(a.sigma[i], b.sigma[i]) << a.parameters[i].key;
  }
  EXPECT_EQ(a.surrogate_chi2, b.surrogate_chi2);
  EXPECT_EQ(a.before.chi2, b.before.chi2);
  EXPECT_EQ(a.after.chi2, b.after.chi2);
  EXPECT_EQ(a.simulations, b.simulations);
  EXPECT_EQ(a.surrogate.points, b.surrogate.points);
  EXPECT_EQ(a.surrogate.values, b.surrogate.values);
  ASSERT_EQ(a.after.runs.size(), b.after.runs.size());
  for (size_t k = 0; k < a.after.runs.size(); ++k) {
    EXPECT_EQ(a.after.runs[k].values, b.after.runs[k].values) << a.after.runs[k].id;
    EXPECT_EQ(a.after.runs[k].flag_fraction, b.after.runs[k].flag_fraction) << a.after.runs[k].id;
    EXPECT_EQ(a.after.runs[k].particles, b.after.runs[k].particles) << a.after.runs[k].id;
  }
}

/// The simulations every rank ran, summed over the ranks.
int total_over_ranks(int mine) {
  int total = 0;
  for (const std::string& bytes : mpi::all_gather(std::to_string(mine))) total += std::stoi(bytes);
  return total;
}

TEST(CampaignMpi, RunsUnderMpirunWithTwoRanks) {
  ASSERT_EQ(mpi::world().size, 2) << "run this program as `mpirun -np 2 campaign_mpi_tests` (tests/CMakeLists.txt does)";
}

TEST(CampaignMpi, CalibrationSharedAmongRanksEqualsSerial) {
  const MaterialModel model = read_material_model(kMaterials + "/gravel.yaml");
  const std::vector<FitParameter> params = fit_parameters(model, {"friction", "restitution"});
  int serial_calls = 0, shared_calls = 0;
  const CalibrationResult alone = calibrate(model, measurements(), params, options(Analytic{&serial_calls}, false));
  const CalibrationResult shared = calibrate(model, measurements(), params, options(Analytic{&shared_calls}, true));
  expect_same(alone, shared);
  // Each rank ran about half, together exactly the serial run's simulations.
  EXPECT_EQ(total_over_ranks(shared_calls), serial_calls);
  EXPECT_LT(shared_calls, serial_calls * 2 / 3) << "this rank ran more than its share";
  EXPECT_GT(shared_calls, 0);
}

TEST(CampaignMpi, DiagnosisSharedAmongRanksEqualsSerial) {
  // Rolling resistance switched off, so the diagnosis has effects to try (their signature runs
  // and confirmations are batches too).
  MaterialModel model = read_material_model(kMaterials + "/gravel.yaml");
  model.contact.rolling.model = "none";
  model.particle.params.erase("rolling_friction");
  model.tunable.erase("rolling_friction");
  const std::vector<FitParameter> params = fit_parameters(model, {"friction", "restitution"});
  int serial_calls = 0, shared_calls = 0;
  CalibrationOptions a = options(Analytic{&serial_calls}, false), b = options(Analytic{&shared_calls}, true);
  a.rounds = b.rounds = 1;
  // Every candidate screened and the leaders confirmed, however well the model fits already.
  a.effects = b.effects = candidate_names();
  a.fits_within_noise = b.fits_within_noise = 0;
  const Diagnosis alone = diagnose(model, measurements(), params, a);
  const Diagnosis shared = diagnose(model, measurements(), params, b);
  expect_same(alone.base, shared.base);
  ASSERT_FALSE(alone.candidates.empty());
  ASSERT_EQ(alone.candidates.size(), shared.candidates.size());
  for (size_t k = 0; k < alone.candidates.size(); ++k) {
    EXPECT_EQ(alone.candidates[k].name, shared.candidates[k].name);
    EXPECT_EQ(alone.candidates[k].signature, shared.candidates[k].signature) << alone.candidates[k].name;
    EXPECT_EQ(alone.candidates[k].explained, shared.candidates[k].explained) << alone.candidates[k].name;
    EXPECT_EQ(alone.candidates[k].confirmed, shared.candidates[k].confirmed) << alone.candidates[k].name;
    EXPECT_EQ(alone.candidates[k].bic, shared.candidates[k].bic) << alone.candidates[k].name;
  }
  EXPECT_TRUE(std::any_of(alone.candidates.begin(), alone.candidates.end(), [](const CandidateResult& c) { return c.confirmed; }));
  EXPECT_EQ(alone.recommended, shared.recommended);
  EXPECT_EQ(total_over_ranks(shared_calls), serial_calls);
}

TEST(CampaignMpi, FailedDesignPointsAreSkippedAlike) {
  const MaterialModel model = read_material_model(kMaterials + "/gravel.yaml");
  const std::vector<FitParameter> params = fit_parameters(model, {"friction", "restitution"});
  // Design points with friction above the middle of its range fail their hopper simulation.
  const double fail_above = 0.5 * (params[0].min + params[0].max) + 0.1 * (params[0].max - params[0].min);
  int serial_calls = 0, shared_calls = 0;
  CalibrationOptions a = options(Analytic{&serial_calls, fail_above}, false), b = options(Analytic{&shared_calls, fail_above}, true);
  std::vector<std::string> skipped_alone, skipped_shared;
  a.progress = [&](const std::string& line) {
    if (line.find("skipped") != std::string::npos) skipped_alone.push_back(line);
  };
  b.progress = [&](const std::string& line) {
    if (line.find("skipped") != std::string::npos) skipped_shared.push_back(line);
  };
  a.rounds = b.rounds = 1;
  const CalibrationResult alone = calibrate(model, measurements(), params, a);
  const CalibrationResult shared = calibrate(model, measurements(), params, b);
  expect_same(alone, shared);
  EXPECT_FALSE(skipped_alone.empty()) << "no design point failed: the test tests nothing";
  std::sort(skipped_alone.begin(), skipped_alone.end()), std::sort(skipped_shared.begin(), skipped_shared.end());
  EXPECT_EQ(skipped_alone, skipped_shared);
  EXPECT_EQ(total_over_ranks(shared_calls), serial_calls);
}

TEST(CampaignMpi, BadInputStopsEveryRankWithTheSerialError) {
  const MaterialModel model = read_material_model(kMaterials + "/gravel.yaml");
  std::string alone, shared;
  int calls = 0;
  try {
    compare(model, measurements(), options(Analytic{&calls, 10, true}, false));
  } catch (const dem::CaseError& e) {
    alone = e.what();
  }
  try {
    compare(model, measurements(), options(Analytic{&calls, 10, true}, true));
  } catch (const dem::CaseError& e) {
    shared = e.what();
  }
  EXPECT_NE(alone.find("experiments[2].setup.rpm"), std::string::npos) << alone;
  EXPECT_EQ(alone, shared);
}

}  // namespace
