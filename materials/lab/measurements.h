// Measurement files (the format of the calibration protocol): what was measured directly (size,
// density, wall materials) and the experiments with their set-ups and observations. Read with
// errors that name file, line and key and say what is valid.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "case/spec.h"
#include "lab/virtual_tests.h"

namespace dem::materials {

/// One observation with its one-sigma repeatability.
struct Observation {
  double value = 0;
  double sigma = 0;
  SourceLocation location;
};

struct Experiment {
  std::string id;
  TestSetup setup;                               ///< setup.test names the test
  std::map<std::string, Observation> observed;   ///< observable name -> value
  std::string outcome;                           ///< "" or an observed outcome: blocked, no_heap
  /// The observable whose value the outcome was read from (outcome_read_as_number), "" when the
  /// file wrote the outcome: the simulated values are then read by the same rule.
  std::string outcome_read_from;
  std::vector<std::string> warnings;             ///< see MeasurementSet::warnings
  SourceLocation location;
};

/// The outcome a value of `observable` in a `test` means, as a lab writes it, or "": no heap as
/// an angle of repose below 1 deg, an arch as no flow, a bed that moved without avalanching as a
/// drum angle below 1 deg. Measured values are read so (with a warning, unless the file says
/// `outcome: none`), and so are the simulated values they are compared with.
std::string outcome_read_as_number(const std::string& test, const std::string& observable, double value);

/// A value the user measured directly: an input of the model, never fitted.
struct KnownValue {
  std::string key;    ///< the model's parameter key: youngs_modulus, steel.friction, ...
  double value = 0;
  std::string unit;
  SourceLocation location;
};

struct MeasurementSet {
  std::string file;
  std::string material;           ///< free text
  SizeDistributionSpec diameter;  ///< measured particle size
  bool has_diameter = false;      ///< the file gives particles.diameter
  double density = 0;             // [kg/m^3] solid density
  /// Measured particle properties (particles.youngs_modulus, poisson_ratio, any contact
  /// parameter such as restitution) and particle-wall pair parameters (walls.steel.friction as
  /// steel.friction), in file order.
  std::vector<KnownValue> known;
  std::vector<MaterialSpec> walls;
  std::vector<Experiment> experiments;
  /// Things in the file that look like a mistake but are not errors (an outcome written as a
  /// number), with file and line; the commands print them and the report lists them.
  std::vector<std::string> warnings;
};

/// Takes size, density and wall materials from the measurements (measured, not calibrated), and
/// sets the values the file states as measured (inputs, never fitted).
void apply_measured(MaterialModel& model, const MeasurementSet& measured);

/// Checks every experiment's set-up against its test before anything is simulated: unknown keys
/// (with the nearest valid one), values out of range, an apparatus too small for the particles.
/// Throws CaseError naming the file, the line and the experiment's id.
void check_experiments(const MaterialModel& model, const MeasurementSet& set, const TestOptions& options);

/// Reads a measurement file; throws CaseError naming file, line and key.
MeasurementSet read_measurements(const std::string& path);
MeasurementSet parse_measurements(const std::string& text, const std::string& name);

}  // namespace dem::materials
