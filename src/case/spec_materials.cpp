// Reading a case's materials into the CaseSpec: each material's properties and effect
// parameters, library materials (materials/NAME.yaml, found beside the case or through the
// material library's lookup) with their overrides, wall pair parameters and calibration, and the
// contact model (`contact:`, one effect per stage or a list for the additive stages).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "case/calibration_record.h"
#include "case/spec.h"
#include "case/spec_reading.h"
#include "case/yaml_check.h"
#include "contact/effect.h"

namespace dem {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// A material's properties besides its effect parameters (MaterialSpec's fields): key, field,
/// valid range (inclusive), SI unit, and whether a material must state it (otherwise it keeps
/// MaterialSpec's default). Read in this order, which the key reference lists and which decides
/// which of two mistakes is reported first. Every reader of them below loops over these rows.
/// Rejected: the rows of materials/model/base_properties.cpp, which describe the same keys: the
/// engine does not include materials/ (materials/ builds on the engine), and a case's material
/// may be rigid (youngs_modulus +inf) where a measured one stops at 1e15 Pa.
struct MaterialProperty {
  std::string_view key;
  double MaterialSpec::*field;
  double min_value, max_value;
  std::string_view unit;
  bool required;
};
constexpr MaterialProperty kMaterialProperties[] = {
    {"density", &MaterialSpec::density, 1.0, 1e5, "kg/m^3", true},
    {"youngs_modulus", &MaterialSpec::youngs_modulus, 1e3, kInf, "Pa", true},
    {"poisson_ratio", &MaterialSpec::poisson_ratio, -0.99, 0.499, "-", false},
};

/// `keys` followed by the material properties' keys: the keys of a material's map that are not
/// effect parameters.
std::vector<std::string> with_property_keys(std::vector<std::string> keys) {
  for (const MaterialProperty& p : kMaterialProperties) keys.emplace_back(p.key);
  return keys;
}

std::vector<std::string> all_param_keys() {
  std::vector<std::string> keys;
  for (const EffectSpec* effect : effect_table())
    for (const ParamSpec& p : effect->params) keys.emplace_back(p.key);
  return keys;
}

/// Where `materials: {NAME: {library: gravel}}` finds gravel.yaml, first match wins: the case's
/// folder, its `materials/` and `../materials/` folders, then `lookup` (a material library's).
std::filesystem::path find_library_file(const std::string& wanted, const std::string& case_file, const LibraryLookup& lookup, std::string& searched) {
  const std::filesystem::path dir = std::filesystem::path(case_file).parent_path();
  for (const std::filesystem::path& folder : {dir, dir / "materials", dir / ".." / "materials"}) {
    const std::filesystem::path candidate = folder / (wanted + ".yaml");
    searched += "\n  " + candidate.lexically_normal().string();
    if (std::filesystem::is_regular_file(candidate)) return candidate;
  }
  return lookup ? lookup(wanted, case_file, searched) : std::filesystem::path();
}

ContactSpec::Choice read_choice(const YAML::Node& node, const std::string& file, const std::string& path,
                                MapReader& parent, const std::string& key) {
  ContactSpec::Choice choice;
  choice.location = parent.at(node);
  if (node.IsScalar()) {
    choice.model = node.Scalar();
    return choice;
  }
  if (!node.IsMap()) parent.fail(key, "must be a model name or a map {model: NAME, OPTION: VALUE}");
  MapReader map(node, file, path);
  choice.model = map.string("model", "");
  if (choice.model.empty()) map.fail("model", "missing: name the model");
  for (const std::string& k : map.keys())
    if (k != "model") choice.options[k] = map.string(k, "");
  return choice;
}

std::vector<std::string> effect_names(Stage stage, bool with_none) {
  std::vector<std::string> names;
  if (with_none) names.emplace_back("none");
  for (const EffectSpec* e : effect_table())
    if (e->stage == stage) names.emplace_back(e->name);
  return names;
}

void check_choice(const ContactSpec::Choice& c, Stage stage, const std::string& path) {
  const auto valid = effect_names(stage, !stage_is_additive(stage));
  if (std::find(valid.begin(), valid.end(), c.model) != valid.end()) return;
  const std::string hint = nearest_word(c.model, valid);
  std::string list;
  for (const auto& v : valid) list += (list.empty() ? "" : ", ") + v;
  throw CaseError(fmt::format("{}: {}: '{}' is not a {} model{}; valid: {}", c.location.str(), path, c.model,
                              stage_name(stage),
                              hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint), list));
}

/// `contact.STAGE: MODEL` of a single stage; an absent key keeps the default choice.
void read_single_stage(MapReader& map, const std::string& file, Stage stage, ContactSpec::Choice& choice) {
  const std::string key(stage_name(stage));
  if (!map.has(key)) {
    map.node(key);
    return;
  }
  choice = read_choice(map.node(key), file, "contact." + key, map, key);
  check_choice(choice, stage, "contact." + key);
}

/// `contact.STAGE: [MODEL, ...]` of an additive stage.
void read_additive_stage(MapReader& map, const std::string& file, Stage stage, std::vector<ContactSpec::Choice>& out) {
  const std::string key(stage_name(stage));
  const YAML::Node list = map.node(key);
  if (!list) return;
  if (!list.IsSequence()) map.fail(key, "must be a list of models, e.g. [liquid_bridge]");
  for (size_t k = 0; k < list.size(); ++k) {
    const std::string path = fmt::format("contact.{}[{}]", key, k);
    out.push_back(read_choice(list[k], file, path, map, key));
    check_choice(out.back(), stage, path);
  }
}

}  // namespace

const ContactSpec::Choice* ContactSpec::single(Stage stage) const {
  switch (stage) {
    case Stage::normal: return &normal;
    case Stage::damping: return &damping;
    case Stage::tangential: return &tangential;
    case Stage::rolling: return &rolling;
    case Stage::twisting: return &twisting;
    case Stage::adhesion:
    case Stage::extra: return nullptr;
  }
  return nullptr;
}

const std::vector<ContactSpec::Choice>* ContactSpec::additive(Stage stage) const {
  switch (stage) {
    case Stage::adhesion: return &adhesion;
    case Stage::extra: return &extra;
    case Stage::normal:
    case Stage::damping:
    case Stage::tangential:
    case Stage::rolling:
    case Stage::twisting: return nullptr;
  }
  return nullptr;
}

std::vector<const ContactSpec::Choice*> ContactSpec::choices(Stage stage) const {
  std::vector<const Choice*> out;
  if (const Choice* one = single(stage)) out.push_back(one);
  if (const std::vector<Choice>* list = additive(stage))
    for (const Choice& c : *list) out.push_back(&c);
  return out;
}

namespace spec_reading {

/// Reads the effect parameters of a material or interaction map (all keys not in `fixed`).
void read_effect_params(MapReader& map, const std::vector<std::string>& fixed, std::map<std::string, double>& params,
                        std::map<std::string, SourceLocation>& where) {
  std::vector<std::string> valid = fixed;
  const auto keys = all_param_keys();
  valid.insert(valid.end(), keys.begin(), keys.end());
  for (const std::string& key : map.keys()) {
    if (std::find(fixed.begin(), fixed.end(), key) != fixed.end()) continue;
    const ParamSpec* p = find_param(key);
    if (!p) continue;  // reported by finish() with a suggestion
    params[key] = map.number(key, p->default_value, p->min_value, p->max_value, p->unit);
    where[key] = map.where(key);
  }
  map.finish(valid);
}

/// A material's properties: the map under `materials.NAME` of a case, or `properties` of a
/// material file (`path` names it in errors).
MaterialSpec read_material(const std::string& name, const YAML::Node& node, const std::string& file, const std::string& path) {
  MapReader map(node, file, path);
  MaterialSpec m;
  m.name = name;
  m.location = map.location();
  for (const MaterialProperty& p : kMaterialProperties) {
    const std::string key(p.key);
    m.*p.field = p.required ? map.required_number(key, p.min_value, p.max_value, p.unit)
                            : map.number(key, m.*p.field, p.min_value, p.max_value, p.unit);
  }
  read_effect_params(map, with_property_keys({}), m.params, m.where);
  return m;
}

LibraryMaterial read_library_material(const std::string& name, MapReader& entry, const std::string& case_file, const LibraryLookup& lookup) {
  const std::string wanted = entry.string("library", "");
  std::string searched;
  const std::filesystem::path found = find_library_file(wanted, case_file, lookup, searched);
  if (found.empty()) entry.fail("library", fmt::format("no material file '{}.yaml' found; looked in:{}", wanted, searched));
  LibraryMaterial lib;
  lib.file = found.lexically_normal().string();
  const YAML::Node root = read_yaml_file(lib.file, "the material file");
  MapReader file_map(root, lib.file, "");
  if (!file_map.has("properties")) file_map.fail("properties", "missing: the material's {density, youngs_modulus, ...}");
  lib.material = read_material(name, file_map.node("properties"), lib.file, "properties");
  lib.material.library_file = lib.file;
  lib.material.description = file_map.string("name", wanted);
  lib.material.description = file_map.string("description", lib.material.description);
  if (const YAML::Node sources = file_map.node("sources")) {
    MapReader s(sources, lib.file, "sources");
    s.keys_are_names("PARAMETER");
    for (const std::string& key : s.keys()) lib.material.sources[key] = s.string(key, "");
  }
  for (const char* section : {"tunable", "plausible"}) {
    const YAML::Node ranges = file_map.node(section);
    if (!ranges) continue;
    MapReader t(ranges, lib.file, section);
    t.keys_are_names("PARAMETER");
    for (const std::string& key : t.keys()) {
      const YAML::Node range = t.node(key);
      if (!range.IsSequence() || range.size() != 2) t.fail(key, "must be a range [min, max]");
      const double lo = MapReader::finite_number(range[0], t, key), hi = MapReader::finite_number(range[1], t, key);
      if (!(lo < hi)) t.fail(key, "needs min < max");
      (std::string(section) == "tunable" ? lib.material.tunable : lib.material.plausible)[key] = {lo, hi};
    }
  }
  if (const YAML::Node walls = file_map.node("walls")) {
    if (!walls.IsMap()) file_map.fail("walls", "must map wall material names to pair parameters {friction: ..., ...}");
    for (const auto& kv : walls) lib.walls.emplace_back(kv.first.as<std::string>(), kv.second);
  }
  if (const YAML::Node shape = file_map.node("shape")) lib.material.shape = read_clump(name, shape, lib.file, "shape");
  lib.contact = file_map.node("contact");
  file_map.node("size");  // a typical size, for the calibration tests
  if (const YAML::Node fit = file_map.node("calibration")) {
    lib.material.calibration = read_calibration_record(fit, lib.file);
    // The values the file states are the fit's: a file edited after its calibration is refused.
    const CalibrationRecord& r = *lib.material.calibration;
    for (size_t k = 0; k < r.parameters.size(); ++k) {
      const auto given = lib.material.params.find(r.parameters[k]);
      if (given != lib.material.params.end() && std::abs(given->second - r.value[k]) > 1e-6 * std::max(1.0, std::abs(r.value[k])))
        throw CaseError(fmt::format("{}: properties.{} is {:g} but calibration.value gives {:g}: the file was edited after its calibration; "
                                    "calibrate again, or remove the calibration block",
                                    r.location.str(), r.parameters[k], given->second, r.value[k]));
    }
  }
  file_map.finish();
  // Overrides in the case entry, beside `library:`.
  MaterialSpec& m = lib.material;
  m.location = entry.location();
  for (const MaterialProperty& p : kMaterialProperties) {
    const std::string key(p.key);
    m.*p.field = entry.number(key, m.*p.field, p.min_value, p.max_value, p.unit);
    if (entry.has(key)) m.where[key] = entry.where(key), m.sources[key] = "set in the case";
  }
  std::map<std::string, double> overrides;
  std::map<std::string, SourceLocation> where;
  read_effect_params(entry, with_property_keys({"library"}), overrides, where);
  for (const auto& [key, value] : overrides) m.params[key] = value, m.where[key] = where[key], m.sources[key] = "set in the case";
  return lib;
}

ContactSpec read_contact(const YAML::Node& node, const std::string& file) {
  ContactSpec contact;
  if (!node) return contact;
  MapReader map(node, file, "contact");
  // Single stages, then the lists: of two mistakes, the one reported first stays the same.
  for (const Stage stage : kStagesSingleFirst) {
    if (stage_is_additive(stage)) read_additive_stage(map, file, stage, *contact.additive(stage));
    else read_single_stage(map, file, stage, *contact.single(stage));
  }
  map.finish();
  return contact;
}

}  // namespace spec_reading

}  // namespace dem
