// The base properties of a material model: the parameters that belong to no contact effect
// (density, Young's modulus, Poisson's ratio, and the particles' shape as a clump aspect ratio).
// One row each, described as an effect's parameters are (ParamSpec: key, unit, default, range,
// tunable, ...), with how the row reads and writes it in a model. Every reader of these keys loops
// over the table: get_parameter and set_parameter, the valid keys an error lists, the measurement
// reader, the calibrated material file and the simulation store's keys. Rejected alternative: a
// row type of its own; ParamSpec's fields fit apart from `mixing` (see the table), and rows of the
// same type can be shown by the code that shows the effects' parameters.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "contact/effect.h"
#include "model/material.h"

namespace dem::materials {

/// One base property: its description, and how a model holds it.
struct BaseProperty {
  /// Key, SI unit, default, valid range [min_value, max_value], tunable, doc, coarse-graining
  /// exponent. `mixing` is not used: see the table (base_properties.cpp).
  ParamSpec spec;
  /// Its field in a MaterialSpec, the particle material's and a wall material's alike; nullptr
  /// for a property of the particles' shape, which a material's `properties:` does not state.
  double MaterialSpec::*field;
  /// Its value in `model` (in spec.unit).
  double (*get)(const MaterialModel& model);
  /// Writes `value` (in spec.unit, finite) into `model`; no range check.
  void (*set)(MaterialModel& model, double value);
  /// set_parameter refuses a value outside the range. The MaterialSpec fields' ranges are checked
  /// where a file states them (the case reader, the measurement reader); a calibration sets them
  /// within the `tunable:` range the material file declares.
  bool checked_when_set;
};

/// Every base property, in the order the keys are listed: density, youngs_modulus, poisson_ratio,
/// clump_aspect_ratio.
std::span<const BaseProperty> base_properties();
/// nullptr when `key` is not a base property.
const BaseProperty* find_base_property(std::string_view key);
/// The row of `key`; throws std::logic_error when there is none (a key the code itself names).
const BaseProperty& base_property(std::string_view key);
/// The keys of the rows with a MaterialSpec field, in table order: what a material's
/// `properties:` states besides its contact parameters.
std::vector<std::string> material_property_keys();

/// Two equal spheres, overlapping; aspect = length / width [-]. The engine scales a template to
/// the volume-equivalent diameter, so only the shape matters here.
ClumpTemplateSpec two_sphere_clump(double aspect);

}  // namespace dem::materials
