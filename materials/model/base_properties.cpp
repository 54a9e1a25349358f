// The table of a material model's base properties (model/base_properties.h), and the two-sphere
// clump its shape row builds. The ranges are the ones the file readers check (density and Poisson's
// ratio as src/case/spec_materials.cpp's kMaterialProperties, Young's modulus as lab/measurements.cpp
// reads a measured one), and clump_aspect_ratio's the span of the two-sphere clumps set_parameter accepts.
#include "model/base_properties.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <stdexcept>

namespace dem::materials {

namespace {

template <double MaterialSpec::*Field>
double particle_field(const MaterialModel& model) {
  return model.particle.*Field;
}

template <double MaterialSpec::*Field>
void set_particle_field(MaterialModel& model, double value) {
  model.particle.*Field = value;
}

/// The row of a field of the particle material: read and written in `model.particle`.
template <double MaterialSpec::*Field>
BaseProperty material_field(const ParamSpec& spec) {
  return {spec, Field, &particle_field<Field>, &set_particle_field<Field>, false};
}

/// [-] Length / width of the model's two-sphere clumps; 1 for spheres, NaN for another shape.
double clump_aspect_ratio(const MaterialModel& model) {
  if (model.shape.empty()) return 1.0;
  const ClumpTemplateSpec& c = model.shape.front();
  if (c.centres.size() != 2) return std::nan("");
  return 1.0 + 0.5 * (c.centres[1] - c.centres[0]).norm() / c.radii[0];
}

void set_clump_aspect_ratio(MaterialModel& model, double aspect) { model.shape = {two_sphere_clump(aspect)}; }

}  // namespace

ClumpTemplateSpec two_sphere_clump(double aspect) {
  ClumpTemplateSpec c;
  c.name = "two_sphere";
  const double r = 0.5, offset = (aspect - 1.0) * r;  // centres at +-offset along x
  c.centres = {Vec3{-offset, 0, 0}, Vec3{offset, 0, 0}};
  c.radii = {r, r};
  return c;
}

std::span<const BaseProperty> base_properties() {
  // Columns as an effect's parameters: key, unit, default, min, max, mixing, tunable, doc,
  // coarse-graining exponent. The defaults are MaterialSpec's (src/case/spec.h; a file must state
  // density and youngs_modulus) and the sphere's aspect ratio, 1.
  // mixing: not used, arithmetic as a neutral value. A pair's moduli combine as its effective E*
  // and G* (core/compile.cpp); density and shape stay each body's own.
  // tunable: none. A calibration fits a base property only in a range the material file declares
  // under `tunable:`, or clump_aspect_ratio in the one the diagnosis' shape candidate gives.
  // Coarse graining (core/coarse_grain.h): all 0, stress similarity keeps the density and the
  // moduli, and an aspect ratio is a ratio of lengths.
  static const std::array<BaseProperty, 4> table = [] {
    const MaterialSpec defaults{};
    return std::array<BaseProperty, 4>{{
        material_field<&MaterialSpec::density>(
            {"density", "kg/m^3", defaults.density, 1.0, 1e5, Mixing::arithmetic, false, "density of the solid particles", 0}),
        material_field<&MaterialSpec::youngs_modulus>(
            {"youngs_modulus", "Pa", defaults.youngs_modulus, 1e3, 1e15, Mixing::arithmetic, false,
             "Young's modulus (a case's material may also be rigid, +inf)", 0}),
        material_field<&MaterialSpec::poisson_ratio>(
            {"poisson_ratio", "-", defaults.poisson_ratio, -0.99, 0.499, Mixing::arithmetic, false, "Poisson's ratio", 0}),
        {{"clump_aspect_ratio", "-", 1.0, 1.0, 3.0, Mixing::arithmetic, false,
          "particle shape: two-sphere clumps of this length / width (1: spheres)", 0},
         nullptr, &clump_aspect_ratio, &set_clump_aspect_ratio, true},
    }};
  }();
  return table;
}

const BaseProperty* find_base_property(std::string_view key) {
  for (const BaseProperty& b : base_properties())
    if (b.spec.key == key) return &b;
  return nullptr;
}

const BaseProperty& base_property(std::string_view key) {
  if (const BaseProperty* b = find_base_property(key)) return *b;
  throw std::logic_error(fmt::format("'{}' is not a base property (model/base_properties.cpp)", key));
}

std::vector<std::string> material_property_keys() {
  std::vector<std::string> keys;
  for (const BaseProperty& b : base_properties())
    if (b.field) keys.emplace_back(b.spec.key);
  return keys;
}

}  // namespace dem::materials
