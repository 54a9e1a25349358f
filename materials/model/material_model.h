// A calibratable material: read from a library file (materials/NAME.yaml: properties, contact,
// walls, tunable ranges, typical size), combined with what a measurement file measured directly,
// its parameters read and set by key, and the effects it could gain (the diagnosis candidates).
#pragma once

#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "model/material.h"

namespace dem::materials {

/// Reads a library material file into a model (walls from its `walls:` pairs; wall materials
/// themselves come from the measurement file or the library's steel/rubber files).
MaterialModel read_material_model(const std::string& path);

/// A parameter by key: a base property (model/base_properties.h: "density", "youngs_modulus",
/// ...) or an effect parameter ("friction", "rolling_friction", "restitution", "liquid_content",
/// "surface_energy", ...). Particle-wall pair keys are "wall.friction" etc.
double get_parameter(const MaterialModel& model, const std::string& key);
void set_parameter(MaterialModel& model, const std::string& key, double value);

/// A physical effect the model does not use, and how to add it: a contact effect whose file
/// declares a CandidateSpec (src/contact/effect.h), or particle shape as clumps.
struct EffectCandidate {
  std::string name;         ///< the effect's name in the table ("epsd", "liquid_bridge", "jkr", ...) or "clump_shape"
  std::string title;        ///< in words: "rolling resistance"
  std::string description;  ///< one line for the report: what physics it adds
  std::string why;          ///< why its signature fits a misfit (the effect's own words)
  std::string switch_on;    ///< the YAML that switches it on: "contact: {rolling: epsd}"
  std::vector<std::string> moves;  ///< observables it is expected to move ("test/observable")
  /// "effect" (a contact effect), "shape" (clumps) or "parameter" (a wall parameter the fit
  /// leaves out: not missing physics, a value to calibrate or measure).
  std::string kind = "effect";
  /// Switches the effect on in `model` with its parameters at their starting values.
  std::function<void(MaterialModel&)> add;
  std::map<std::string, std::pair<double, double>> parameters;  ///< key -> [min, max] it adds to the fit
  std::map<std::string, double> start;                          ///< key -> starting value
  /// key -> the value of a second, stronger step for the signature (twice as far from where the
  /// candidate changes nothing as `start`).
  std::map<std::string, double> stronger;
  /// key -> the value at which the candidate changes nothing: the model with it there simulates
  /// as the model without it, so the model's own simulations are points of the candidate's
  /// calibration too. Empty when there is none (a clump of aspect ratio 1 is two coincident
  /// spheres, not the model's sphere).
  std::map<std::string, double> unchanged;
  /// `start` and `stronger` lie on either side of `unchanged`, the same step from it: a guessed
  /// value that may be off either way (a wall parameter), not an effect switched on from nothing.
  /// Its two signatures agree when they are opposite.
  bool two_sided = false;
};

/// The candidates the model does not yet use: every effect of the table that declares itself a
/// candidate and whose stage is free (a single stage at `none`; an additive stage without
/// another candidate of it), then clump shape for spheres. In table order.
std::vector<EffectCandidate> missing_effects(const MaterialModel& model);
/// Every candidate name there is (for checking `--effects`).
std::vector<std::string> candidate_names();

}  // namespace dem::materials
