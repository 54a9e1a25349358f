// A calibratable material: read from a library file (materials/NAME.yaml: properties, contact,
// walls, tunable ranges, typical size), combined with what a measurement file measured directly,
// its parameters read and set by key, and the effects it could gain (the diagnosis candidates).
#pragma once

#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "measurements.h"
#include "virtual_tests.h"

namespace dem::materials {

/// Reads a library material file into a model (walls from its `walls:` pairs; wall materials
/// themselves come from the measurement file or the library's steel/rubber files).
MaterialModel read_material_model(const std::string& path);

/// Takes size, density and wall materials from the measurements (measured, not calibrated).
void apply_measured(MaterialModel& model, const MeasurementSet& measured);

/// A parameter by key: "friction", "rolling_friction", "restitution", "liquid_content",
/// "surface_energy", "youngs_modulus", ... Particle-wall pair keys are "wall.friction" etc.
double get_parameter(const MaterialModel& model, const std::string& key);
void set_parameter(MaterialModel& model, const std::string& key, double value);

/// A physical effect the model does not use, and how to add it.
struct EffectCandidate {
  std::string name;         ///< "rolling_resistance", "liquid_bridges", "jkr_cohesion", "clump_shape", ...
  std::string description;  ///< one line for the report: what physics it adds
  /// Switches the effect on in `model` with its parameters at their starting values.
  std::function<void(MaterialModel&)> add;
  std::map<std::string, std::pair<double, double>> parameters;  ///< key -> [min, max] it adds to the fit
  std::map<std::string, double> start;                          ///< key -> starting value
};

/// The candidates the model does not yet use, from the effect table.
std::vector<EffectCandidate> missing_effects(const MaterialModel& model);

}  // namespace dem::materials
