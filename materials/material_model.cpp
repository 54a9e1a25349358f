// Library material files become calibratable models. The file is read by the case reader itself
// (a one-particle case text that names the file as a library material, with the wall materials
// its `walls:` pairs need), so a library file means the same here as in a case, with the same
// errors. Rejected alternative: a second reader of library files that could drift from spec.cpp.
#include "material_model.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "effect.h"
#include "library.h"
#include "yaml_check.h"

namespace dem::materials {

namespace {

namespace fs = std::filesystem;

const ParamSpec* find_param_spec(const std::string& key) {
  for (const EffectSpec* e : effect_table())
    for (const ParamSpec& p : e->params)
      if (p.key == key) return &p;
  return nullptr;
}

std::vector<std::string> parameter_keys() {
  std::vector<std::string> keys = {"density", "youngs_modulus", "poisson_ratio", "clump_aspect_ratio"};
  for (const EffectSpec* e : effect_table())
    for (const ParamSpec& p : e->params) keys.emplace_back(p.key);
  return keys;
}

/// The library file of a wall material, when one is shipped (steel.yaml, rubber.yaml).
std::string wall_library_file(const fs::path& dir, const std::string& name) {
  for (const fs::path& d : {dir, fs::path(library_folder())})
    if (fs::is_regular_file(d / (name + ".yaml"))) return (d / (name + ".yaml")).string();
  return "";
}

double param_value(const std::map<std::string, double>& params, const std::string& key) {
  const auto it = params.find(key);
  if (it != params.end()) return it->second;
  const ParamSpec* p = find_param_spec(key);
  return p ? p->default_value : std::nan("");
}

[[noreturn]] void unknown_key(const std::string& key) {
  const std::string hint = nearest_word(key, parameter_keys());
  throw std::invalid_argument(fmt::format("'{}' is not a material parameter{}; valid: density, youngs_modulus, poisson_ratio, "
                                          "clump_aspect_ratio, an effect parameter (see `demdesign effects`), or wall.KEY / WALL.KEY for particle-wall pairs",
                                          key, hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint)));
}

/// Two equal spheres, overlapping; aspect = length / width. The engine scales a template to
/// the volume-equivalent diameter, so only the shape matters here.
ClumpTemplateSpec two_sphere_clump(double aspect) {
  ClumpTemplateSpec c;
  c.name = "two_sphere";
  const double r = 0.5, offset = (aspect - 1.0) * r;  // centres at +-offset along x
  c.centres = {Vec3{-offset, 0, 0}, Vec3{offset, 0, 0}};
  c.radii = {r, r};
  return c;
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
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::ParserException& e) {
    throw CaseError(fmt::format("{}:{}:{}: not valid YAML: {}", path, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
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
  const CaseSpec spec = parse_case_text(case_text, (file.parent_path() / "__material_model__.yaml").string());

  MaterialModel model;
  model.name = stem;
  for (const MaterialSpec& m : spec.materials) {
    if (m.name == stem) model.particle = m;
    else model.walls.push_back(m);
  }
  // The wall library files stand for the wall material's elasticity only; their own
  // friction/restitution are placeholders for the pairs.
  for (MaterialSpec& w : model.walls) w.tunable.clear();
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
    YAML::Node holder(YAML::NodeType::Map);
    holder["diameter"] = root["size"];
    MapReader reader(holder, file.string(), "");
    model.diameter = read_size_distribution(reader, file.string());
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

void apply_measured(MaterialModel& model, const MeasurementSet& measured) {
  if (measured.has_diameter) model.diameter = measured.diameter;
  if (measured.density > 0) {
    model.particle.density = measured.density;
    model.particle.sources["density"] = "measured (" + measured.file + ")";
  }
  for (const MaterialSpec& w : measured.walls) {
    auto it = std::find_if(model.walls.begin(), model.walls.end(), [&](const MaterialSpec& m) { return m.name == w.name; });
    if (it != model.walls.end()) *it = w;
    else model.walls.push_back(w);
  }
}

double get_parameter(const MaterialModel& model, const std::string& key) {
  if (key == "density") return model.particle.density;
  if (key == "youngs_modulus") return model.particle.youngs_modulus;
  if (key == "poisson_ratio") return model.particle.poisson_ratio;
  if (key == "clump_aspect_ratio") {
    if (model.shape.empty()) return 1.0;
    const ClumpTemplateSpec& c = model.shape.front();
    if (c.centres.size() != 2) return std::nan("");
    return 1.0 + 0.5 * (c.centres[1] - c.centres[0]).norm() / c.radii[0];
  }
  const auto dot = key.find('.');
  if (dot != std::string::npos) {
    const std::string wall = key.substr(0, dot), param = key.substr(dot + 1);
    if (!find_param_spec(param)) unknown_key(key);
    for (const InteractionSpec& in : model.wall_pairs)
      if (wall == "wall" || in.material_a == wall || in.material_b == wall) return param_value(in.params, param);
    throw std::invalid_argument(fmt::format("'{}': the model has no particle-wall pair{}", key, wall == "wall" ? "" : " with " + wall));
  }
  if (!find_param_spec(key)) unknown_key(key);
  return param_value(model.particle.params, key);
}

void set_parameter(MaterialModel& model, const std::string& key, double value) {
  if (!std::isfinite(value)) throw std::invalid_argument(fmt::format("'{}': value {} is not finite", key, value));
  if (key == "density") model.particle.density = value;
  else if (key == "youngs_modulus") model.particle.youngs_modulus = value;
  else if (key == "poisson_ratio") model.particle.poisson_ratio = value;
  else if (key == "clump_aspect_ratio") {
    if (value < 1.0 || value > 3.0) throw std::invalid_argument(fmt::format("clump_aspect_ratio {:g} out of range; valid: [1, 3]", value));
    model.shape = {two_sphere_clump(value)};
  } else if (const auto dot = key.find('.'); dot != std::string::npos) {
    const std::string wall = key.substr(0, dot), param = key.substr(dot + 1);
    const ParamSpec* p = find_param_spec(param);
    if (!p) unknown_key(key);
    bool any = false;
    for (InteractionSpec& in : model.wall_pairs)
      if (wall == "wall" || in.material_a == wall || in.material_b == wall) in.params[param] = std::clamp(value, p->min_value, p->max_value), any = true;
    if (!any) throw std::invalid_argument(fmt::format("'{}': the model has no particle-wall pair{}", key, wall == "wall" ? "" : " with " + wall));
  } else {
    const ParamSpec* p = find_param_spec(key);
    if (!p) unknown_key(key);
    if (value < p->min_value || value > p->max_value)
      throw std::invalid_argument(fmt::format("{} = {:g} out of range; valid: [{:g}, {:g}] {}", key, value, p->min_value, p->max_value, p->unit));
    model.particle.params[key] = value;
  }
  model.particle.sources[key] = "calibrated";
}

std::vector<EffectCandidate> missing_effects(const MaterialModel& model) {
  std::vector<EffectCandidate> out;
  const double d = typical_diameter(model.diameter);
  const double weight_scale = model.particle.density * 9.81 * d * d;  // [N/m] rho g d^2: gravity per length
  if (model.contact.rolling.model == "none" && find_effect(Stage::rolling, "epsd")) {
    EffectCandidate c;
    c.name = "rolling_resistance";
    c.description = "rolling resistance (Ai et al. 2011 model C, epsd): a torque against rolling, standing in for non-spherical shape and surface roughness";
    c.parameters = {{"rolling_friction", {0.0, 0.5}}};
    c.start = {{"rolling_friction", 0.15}};
    c.add = [](MaterialModel& m) {
      m.contact.rolling = ContactSpec::Choice{"epsd", {}, {}};
      if (!m.particle.params.count("rolling_friction")) m.particle.params["rolling_friction"] = 0.15;
    };
    out.push_back(std::move(c));
  }
  const auto has_extra = [&](const std::string& name) {
    return std::any_of(model.contact.extra.begin(), model.contact.extra.end(), [&](const ContactSpec::Choice& c) { return c.model == name; });
  };
  const bool has_adhesion = !model.contact.adhesion.empty();
  if (!has_extra("liquid_bridge") && find_effect(Stage::extra, "liquid_bridge")) {
    EffectCandidate c;
    c.name = "liquid_bridges";
    c.description = "liquid bridges (Willett et al. 2000 capillary force): cohesion from moisture, independent of the normal load";
    c.parameters = {{"liquid_content", {0.0, 0.05}}};
    c.start = {{"liquid_content", 0.01}, {"contact_angle_deg", 20.0}};
    c.add = [](MaterialModel& m) {
      m.contact.extra.push_back(ContactSpec::Choice{"liquid_bridge", {}, {}});
      if (!m.particle.params.count("liquid_content")) m.particle.params["liquid_content"] = 0.01;
      if (!m.particle.params.count("contact_angle_deg")) m.particle.params["contact_angle_deg"] = 20.0;
    };
    out.push_back(std::move(c));
  }
  if (!has_adhesion && model.contact.normal.model == "hertz" && find_effect(Stage::adhesion, "jkr")) {
    // Surface energy that gives a pull-off force of `bond` particle weights: F = 3/2 pi W R*,
    // W = 2 gamma, R* = d/4, weight = rho pi d^3 g / 6  ->  gamma = bond rho g d^2 / 9.
    const double per_bond = weight_scale / 9.0;
    const double start = 3.0 * per_bond, top = std::min(10.0, 30.0 * per_bond);
    EffectCandidate c;
    c.name = "jkr_cohesion";
    c.description = "JKR adhesion (Johnson, Kendall & Roberts 1971): van der Waals cohesion of fine dry particles, growing with contact area";
    c.parameters = {{"surface_energy", {0.0, top}}};
    c.start = {{"surface_energy", start}};
    c.add = [start](MaterialModel& m) {
      m.contact.adhesion.push_back(ContactSpec::Choice{"jkr", {}, {}});
      if (!m.particle.params.count("surface_energy")) m.particle.params["surface_energy"] = start;
    };
    out.push_back(std::move(c));
  }
  if (model.shape.empty()) {
    EffectCandidate c;
    c.name = "clump_shape";
    c.description = "particle shape as two-sphere clumps (aspect ratio length/width): interlocking that resists rolling and raises dilatancy";
    c.parameters = {{"clump_aspect_ratio", {1.0, 2.0}}};
    c.start = {{"clump_aspect_ratio", 1.5}};
    c.add = [](MaterialModel& m) { m.shape = {two_sphere_clump(1.5)}; };
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace dem::materials
