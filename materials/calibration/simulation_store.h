// The store of finished simulations of a calibration command (OUT/simulations/): each virtual
// test run is kept, as it finishes, in a file of its own (written atomically) holding its inputs
// (set-up, material, seed, size factor, scaling, coarse grain, engine version) and its outcome. A simulation
// whose inputs match a stored one is not run again: across a rerun after an interruption, and
// across commands that share the folder (the compare before a calibrate, the plain model's pass
// of a diagnose). Outcomes are stored with 17 significant digits, so a stored outcome is the
// outcome the run would give, to the bit.
#pragma once

#include <optional>
#include <string>

#include "lab/virtual_tests.h"

namespace dem::materials {

/// Everything that determines the outcome of one virtual test run, as text: the key of the store.
std::string simulation_inputs(const MaterialModel& model, const TestSetup& setup, const TestOptions& options);

/// The outcome stored in `folder` for these inputs; nullopt when there is none, or when the file
/// cannot be read (a file cut short is treated as absent: the simulation runs again).
std::optional<SimulatedOutcome> load_simulation(const std::string& folder, const std::string& test, const std::string& inputs);

/// Stores an outcome under its inputs (temporary file and rename: never a partial file).
void store_simulation(const std::string& folder, const std::string& test, const std::string& inputs, const SimulatedOutcome& outcome);

}  // namespace dem::materials
