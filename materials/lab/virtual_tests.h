// Virtual laboratory tests: the calibration experiments of the measurement file format, each
// simulated with exactly its set-up and observed with exactly its extraction rule (see
// docs in README, section "Calibration"). A test takes the material model being calibrated and
// the set-up of one experiment, builds a case (CaseSpec) in code, runs it with the engine and
// returns the observables.
//
//   dem::materials::MaterialModel model = dem::materials::read_material_model("materials/gravel.yaml");
//   dem::materials::TestSetup setup{"rotating_drum", {{"drum_diameter", 0.2}, {"rpm", 20}, ...}, {...}};
//   dem::materials::SimulatedOutcome out = dem::materials::run_virtual_test(model, setup, {});
//   out.observables["dynamic_angle_deg"]
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/state.h"
#include "model/material.h"

namespace dem::materials {

/// What a virtual test observed.
struct SimulatedOutcome {
  std::map<std::string, double> observables;  ///< by the measurement file's observable names
  /// Observable -> standard error of its extraction in this one run, where the test can tell it
  /// (angle_deg: the heap line's fitted slope). A small apparatus gives a few bins to fit, and
  /// the calibration must not trust that angle more than the fit does (calibration/calibration.h).
  std::map<std::string, double> uncertainty;
  std::vector<std::string> flags;             ///< outcomes: no_heap, blocked, slipping
  std::int64_t particles = 0;
  double simulated_seconds = 0, wall_seconds = 0;
  std::vector<std::string> notes;  ///< e.g. "stress tensor agrees with the plate stress to 1.3 %"
};

/// The virtual tests' time step as a fraction of the Rayleigh time of the smallest particle
/// (the drop test takes a tenth of it). The evidence for the value: docs/materials-and-calibration.md,
/// "The lab tests' time step" (bench/lab_time_step.sh).
inline constexpr double kLabRayleighFraction = 0.2;
/// ... and at least the engine's safe minimum of steps in the shortest contact at the test's
/// characteristic speed (the engine's own auto step keeps 20).
inline constexpr double kLabStepsPerContact = kMinStepsPerContact;

struct TestOptions {
  std::uint64_t seed = 1;     ///< packing replica: a different seed gives a different packing
  /// Time step as a fraction of the Rayleigh time; 0: kLabRayleighFraction. Kept at least
  /// kLabStepsPerContact steps per contact at the characteristic velocity.
  double rayleigh_fraction = 0;
  int threads = 0;            ///< 0: OpenMP default
  double size_factor = 1.0;   ///< < 1 shrinks the apparatus (fewer particles) for fast screening; 1 = as measured
  bool progress = false;      ///< progress lines to stdout
  /// Read and check the set-up (keys, ranges, what the apparatus can hold) and return before
  /// simulating anything: a measurement file is checked whole before its first simulation.
  bool validate_only = false;
  /// Called with the final state of the test (the app renders it); may be empty.
  std::function<void(const Model&, const State&)> on_final;
};

/// Names of the tests and of each test's observables.
std::vector<std::string> test_names();
std::vector<std::string> observable_names(const std::string& test);

/// Runs one virtual test. Throws CaseError naming the experiment's location for a set-up that
/// is missing a key or has a value out of range (what is valid is said).
SimulatedOutcome run_virtual_test(const MaterialModel& model, const TestSetup& setup, const TestOptions& options);

}  // namespace dem::materials
