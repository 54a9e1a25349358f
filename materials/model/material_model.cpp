// Library material files become calibratable models. The file is read by the case reader itself
// (a one-particle case text that names the file as a library material, with the wall materials
// its `walls:` pairs need), so a library file means the same here as in a case, with the same
// errors. Rejected alternative: a second reader of library files that could drift from the case
// reader's (src/case/spec_materials.cpp).
#include "model/material_model.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <type_traits>

#include "case/yaml_check.h"
#include "contact/effect.h"
#include "model/base_properties.h"
#include "model/library.h"

namespace dem::materials {

namespace {

namespace fs = std::filesystem;

/// Every key get_parameter knows besides the particle-wall pairs': the base properties, then the
/// effects' parameters.
std::vector<std::string> parameter_keys() {
  std::vector<std::string> keys;
  for (const BaseProperty& b : base_properties()) keys.emplace_back(b.spec.key);
  for (const EffectSpec* e : effect_table())
    for (const ParamSpec& p : e->params) keys.emplace_back(p.key);
  return keys;
}

/// The library file of a wall material, when one is shipped (steel.yaml, rubber.yaml).
std::string wall_library_file(const fs::path& dir, const std::string& name) {
  std::vector<fs::path> folders = {dir};
  for (const std::string& f : library_folders()) folders.emplace_back(f);
  for (const fs::path& d : folders)
    if (fs::is_regular_file(d / (name + ".yaml"))) return (d / (name + ".yaml")).string();
  return "";
}

double param_value(const std::map<std::string, double>& params, const std::string& key) {
  const auto it = params.find(key);
  if (it != params.end()) return it->second;
  const ParamSpec* p = find_param(key);
  return p ? p->default_value : std::nan("");
}

[[noreturn]] void unknown_key(const std::string& key) {
  const std::string hint = nearest_word(key, parameter_keys());
  std::string properties;  // "density, youngs_modulus, ...": the base properties' keys
  for (const BaseProperty& b : base_properties()) properties += fmt::format("{}, ", b.spec.key);
  throw std::invalid_argument(fmt::format("'{}' is not a material parameter{}; valid: {}an effect parameter (see `demdesign effects`), "
                                          "or wall.KEY / WALL.KEY for particle-wall pairs",
                                          key, hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint), properties));
}

/// Typical (median by number) diameter [m].
double typical_diameter(const SizeDistributionSpec& d) {
  switch (d.kind) {
    case SizeDistributionSpec::Kind::fixed: return d.value;
    case SizeDistributionSpec::Kind::normal: return d.mean;
    case SizeDistributionSpec::Kind::uniform: return 0.5 * (d.min + d.max);
    case SizeDistributionSpec::Kind::discrete: {
      double s = 0;
      for (size_t k = 0; k < d.values.size(); ++k) s += d.values[k] * d.mass_fractions[k];
      return s;
    }
  }
  return d.value;
}

}  // namespace

MaterialModel read_material_model(const std::string& path) {
  if (!fs::is_regular_file(path)) throw CaseError(fmt::format("{}: cannot open the material file", path));
  const fs::path file = fs::absolute(path).lexically_normal();
  const std::string stem = file.stem().string();
  const YAML::Node root = read_yaml_file(path, "the material file");
  // Wall materials named in `walls:`: the shipped library file, else a steel-like placeholder
  // (the measurement file replaces it with what was measured).
  std::string case_text = fmt::format("simulation: {{duration: 0.001}}\nmaterials:\n  \"{}\": {{library: \"{}\"}}\n", stem, stem);
  std::vector<std::string> wall_names;
  if (root["walls"] && root["walls"].IsMap())
    for (const auto& kv : root["walls"]) wall_names.push_back(kv.first.as<std::string>());
  for (const std::string& w : wall_names) {
    if (w == stem) continue;
    const std::string lib = wall_library_file(file.parent_path(), w);
    if (!lib.empty()) case_text += fmt::format("  \"{}\": {{library: \"{}\"}}\n", w, fs::path(lib).stem().string());
    else case_text += fmt::format("  \"{}\": {{density: 7800, youngs_modulus: 2.0e11, poisson_ratio: 0.3}}\n", w);
  }
  case_text += fmt::format("particles:\n  - {{material: \"{}\", diameter: 0.01, positions: [[0, 0, 0]]}}\n", stem);
  // Named as a file beside the material, so `library:` finds this very file first.
  const CaseSpec spec = parse_case_text(case_text, (file.parent_path() / "__material_model__.yaml").string(), library_lookup());

  MaterialModel model;
  model.name = stem;
  for (const MaterialSpec& m : spec.materials) {
    if (m.name == stem) model.particle = m;
    else model.walls.push_back(m);
  }
  // The wall library files stand for the wall material's elasticity only; their own
  // friction/restitution are placeholders for the pairs.
  for (MaterialSpec& w : model.walls) w.tunable.clear();
  // The shape (`shape:` of the file) is the model's, not the particle material's: the virtual
  // tests give it to their particle sets themselves.
  if (model.particle.shape) model.shape = {*model.particle.shape}, model.particle.shape.reset();
  model.contact = spec.contact;
  model.wall_pairs = spec.interactions;
  model.tunable = model.particle.tunable;
  if (root["name"]) model.name = root["name"].as<std::string>();
  model.particle.name = model.name;
  for (InteractionSpec& in : model.wall_pairs) {
    if (in.material_a == stem) in.material_a = model.name;
    if (in.material_b == stem) in.material_b = model.name;
  }
  // The typical size: `size:` read like a particle set's `diameter:`.
  if (root["size"]) {
    MapReader reader(root, file.string(), "");
    model.diameter = read_size_distribution(reader, file.string(), "size");
  }
  // Tunable keys must be parameters the model knows.
  for (const auto& [key, range] : model.tunable) {
    try {
      (void)get_parameter(model, key);
    } catch (const std::invalid_argument& e) {
      throw CaseError(fmt::format("{}: tunable.{}: {}", file.string(), key, e.what()));
    }
  }
  return model;
}

double get_parameter(const MaterialModel& model, const std::string& key) {
  if (const BaseProperty* b = find_base_property(key)) return b->get(model);
  const auto dot = key.find('.');
  if (dot != std::string::npos) {
    const std::string wall = key.substr(0, dot), param = key.substr(dot + 1);
    if (!find_param(param)) unknown_key(key);
    for (const InteractionSpec& in : model.wall_pairs)
      if (wall == "wall" || in.material_a == wall || in.material_b == wall) return param_value(in.params, param);
    throw std::invalid_argument(fmt::format("'{}': the model has no particle-wall pair{}", key, wall == "wall" ? "" : " with " + wall));
  }
  if (!find_param(key)) unknown_key(key);
  return param_value(model.particle.params, key);
}

void set_parameter(MaterialModel& model, const std::string& key, double value) {
  if (!std::isfinite(value)) throw std::invalid_argument(fmt::format("'{}': value {} is not finite", key, value));
  if (const BaseProperty* b = find_base_property(key)) {
    const ParamSpec& p = b->spec;
    if (b->checked_when_set && (value < p.min_value || value > p.max_value))
      throw std::invalid_argument(fmt::format("{} {:g} out of range; valid: [{:g}, {:g}]", key, value, p.min_value, p.max_value));
    b->set(model, value);
  } else if (const auto dot = key.find('.'); dot != std::string::npos) {
    const std::string wall = key.substr(0, dot), param = key.substr(dot + 1);
    const ParamSpec* p = find_param(param);
    if (!p) unknown_key(key);
    bool any = false;
    for (InteractionSpec& in : model.wall_pairs)
      if (wall == "wall" || in.material_a == wall || in.material_b == wall) in.params[param] = std::clamp(value, p->min_value, p->max_value), any = true;
    if (!any) throw std::invalid_argument(fmt::format("'{}': the model has no particle-wall pair{}", key, wall == "wall" ? "" : " with " + wall));
  } else {
    const ParamSpec* p = find_param(key);
    if (!p) unknown_key(key);
    if (value < p->min_value || value > p->max_value)
      throw std::invalid_argument(fmt::format("{} = {:g} out of range; valid: [{:g}, {:g}] {}", key, value, p->min_value, p->max_value, p->unit));
    model.particle.params[key] = value;
  }
  model.particle.sources[key] = "calibrated";
}

namespace {

/// Whether `effect` could be added to the contact model: its stage is free and its normal
/// model is there.
bool stage_free(const ContactSpec& contact, const EffectSpec& effect) {
  if (!effect.requires_normal.empty() && contact.normal.model != effect.requires_normal) return false;
  if (const auto* choices = contact.additive(effect.stage))
    return std::none_of(choices->begin(), choices->end(), [&](const ContactSpec::Choice& c) {
      const EffectSpec* other = find_effect(effect.stage, c.model);
      return c.model == effect.name || (other && other->candidate);
    });
  const ContactSpec::Choice* choice = contact.single(effect.stage);
  return choice && choice->model == "none";
}

EffectCandidate contact_candidate(const EffectSpec& effect, const ParticleScale& scale) {
  const CandidateSpec& spec = *effect.candidate;
  const std::string stage(stage_name(effect.stage));
  EffectCandidate c;
  c.name = std::string(effect.name);
  c.title = std::string(spec.title);
  c.why = std::string(spec.signature);
  c.switch_on = fmt::format("contact: {{{}: {}}}", stage, effect.name);
  c.description = fmt::format("{}: {} ({}; {})", c.title, effect.summary, c.switch_on, effect.citation);
  for (const std::string_view m : spec.moves) c.moves.emplace_back(m);
  const double factor = spec.scale ? spec.scale(scale) : 1.0;
  for (const FittedParam& f : spec.fitted) {
    const ParamSpec* p = find_param(f.key);
    const double lo = std::max(f.min * factor, p ? p->min_value : -HUGE_VAL);
    const double hi = std::min(f.max * factor, p ? p->max_value : HUGE_VAL);
    c.parameters[std::string(f.key)] = {lo, hi};
    c.start[std::string(f.key)] = std::clamp(f.start * factor, lo, hi);
    c.stronger[std::string(f.key)] = std::clamp(lo + 2.0 * (c.start[std::string(f.key)] - lo), lo, hi);
    if (f.min == 0.0) c.unchanged[std::string(f.key)] = 0.0;  // FittedParam: a strength of 0 adds nothing
  }
  for (const StartValue& v : spec.also_set) c.start[std::string(v.key)] = v.value;
  const Stage s = effect.stage;
  const std::string name(effect.name);
  c.add = [s, name](MaterialModel& m) {
    if (auto* choices = m.contact.additive(s)) choices->push_back(ContactSpec::Choice{name, {}, {}});
    else *m.contact.single(s) = ContactSpec::Choice{name, {}, {}};
  };
  return c;
}

/// Particle shape: not a contact effect, so not in the effect table.
EffectCandidate clump_candidate() {
  EffectCandidate c;
  c.name = "clump_shape";
  c.kind = "shape";
  c.title = "particle shape (two-sphere clumps)";
  c.why = "interlocking of non-spherical particles (steeper heaps, higher shear strength, looser packing)";
  c.switch_on = "shape: two-sphere clumps of the fitted aspect ratio (clump_aspect_ratio)";
  c.description = "particle shape as two-sphere clumps (aspect ratio length/width): interlocking that resists rolling and raises dilatancy";
  c.moves = {"angle_of_repose_cylinder/angle_deg", "rotating_drum/dynamic_angle_deg", "bulk_density/bulk_density", "direct_shear/peak_shear_stress"};
  c.parameters = {{"clump_aspect_ratio", {1.0, 2.0}}};
  c.start = {{"clump_aspect_ratio", 1.5}};
  c.stronger = {{"clump_aspect_ratio", 2.0}};
  c.add = [](MaterialModel& m) { m.shape = {two_sphere_clump(1.5)}; };
  return c;
}

}  // namespace

std::vector<EffectCandidate> missing_effects(const MaterialModel& model) {
  std::vector<EffectCandidate> out;
  const ParticleScale scale{model.particle.density, typical_diameter(model.diameter), model.particle.youngs_modulus, model.particle.poisson_ratio};
  for (const EffectSpec* e : effect_table())
    if (e->candidate && stage_free(model.contact, *e)) out.push_back(contact_candidate(*e, scale));
  if (model.shape.empty()) out.push_back(clump_candidate());
  return out;
}

std::vector<std::string> candidate_names() {
  std::vector<std::string> out;
  for (const EffectSpec* e : effect_table())
    if (e->candidate) out.emplace_back(e->name);
  out.emplace_back("clump_shape");
  return out;
}

}  // namespace dem::materials
