// Reading a case file into a CaseSpec. The YAML layout is documented in cases/hello_sphere.yaml
// and README.md; every key read here is checked for type and range.
#include "case/spec.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <limits>
#include <numbers>

#include "case/calibration_record.h"
#include "case/yaml_check.h"
#include "contact/effect.h"

namespace dem {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<std::string> all_param_keys() {
  std::vector<std::string> keys;
  for (const EffectSpec* effect : effect_table())
    for (const ParamSpec& p : effect->params) keys.emplace_back(p.key);
  return keys;
}

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
  m.density = map.required_number("density", 1.0, 1e5, "kg/m^3");
  m.youngs_modulus = map.required_number("youngs_modulus", 1e3, kInf, "Pa");
  m.poisson_ratio = map.number("poisson_ratio", 0.25, -0.99, 0.499, "-");
  read_effect_params(map, {"density", "youngs_modulus", "poisson_ratio"}, m.params, m.where);
  return m;
}

LibraryLookup& library_lookup() {
  static LibraryLookup lookup;
  return lookup;
}

/// Where `materials: {NAME: {library: gravel}}` finds gravel.yaml, first match wins: the case's
/// folder, its `materials/` and `../materials/` folders, then the lookup the material library set.
std::filesystem::path find_library_file(const std::string& wanted, const std::string& case_file, std::string& searched) {
  const std::filesystem::path dir = std::filesystem::path(case_file).parent_path();
  for (const std::filesystem::path& folder : {dir, dir / "materials", dir / ".." / "materials"}) {
    const std::filesystem::path candidate = folder / (wanted + ".yaml");
    searched += "\n  " + candidate.lexically_normal().string();
    if (std::filesystem::is_regular_file(candidate)) return candidate;
  }
  return library_lookup() ? library_lookup()(wanted, case_file, searched) : std::filesystem::path();
}

/// A library material: materials/NAME.yaml with `properties` (as a case material), `sources`
/// (provenance of each value), `description`, `walls` (pair parameters against wall materials),
/// `contact` (the contact model it was calibrated with), `tunable` ranges and a typical `size`.
struct LibraryMaterial {
  MaterialSpec material;
  YAML::Node contact;  ///< null when the file has none
  std::string file;
  std::vector<std::pair<std::string, YAML::Node>> walls;
};

LibraryMaterial read_library_material(const std::string& name, MapReader& entry, const std::string& case_file) {
  const std::string wanted = entry.string("library", "");
  std::string searched;
  const std::filesystem::path found = find_library_file(wanted, case_file, searched);
  if (found.empty()) entry.fail("library", fmt::format("no material file '{}.yaml' found; looked in:{}", wanted, searched));
  std::ifstream in(found);
  std::stringstream text;
  text << in.rdbuf();
  LibraryMaterial lib;
  lib.file = found.lexically_normal().string();
  YAML::Node root;
  try {
    root = YAML::Load(text.str());
  } catch (const YAML::ParserException& e) {
    throw CaseError(fmt::format("{}:{}:{}: not valid YAML: {}", lib.file, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
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
  if (const YAML::Node tunable = file_map.node("tunable")) {
    MapReader t(tunable, lib.file, "tunable");
    t.keys_are_names("PARAMETER");
    for (const std::string& key : t.keys()) {
      const YAML::Node range = t.node(key);
      if (!range.IsSequence() || range.size() != 2) t.fail(key, "must be a range [min, max]");
      const double lo = MapReader::finite_number(range[0], t, key), hi = MapReader::finite_number(range[1], t, key);
      if (!(lo < hi)) t.fail(key, "needs min < max");
      lib.material.tunable[key] = {lo, hi};
    }
  }
  if (const YAML::Node walls = file_map.node("walls")) {
    if (!walls.IsMap()) file_map.fail("walls", "must map wall material names to pair parameters {friction: ..., ...}");
    for (const auto& kv : walls) lib.walls.emplace_back(kv.first.as<std::string>(), kv.second);
  }
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
  m.density = entry.number("density", m.density, 1.0, 1e5, "kg/m^3");
  m.youngs_modulus = entry.number("youngs_modulus", m.youngs_modulus, 1e3, kInf, "Pa");
  m.poisson_ratio = entry.number("poisson_ratio", m.poisson_ratio, -0.99, 0.499, "-");
  for (const char* key : {"density", "youngs_modulus", "poisson_ratio"})
    if (entry.has(key)) m.where[key] = entry.where(key), m.sources[key] = "set in the case";
  std::map<std::string, double> overrides;
  std::map<std::string, SourceLocation> where;
  read_effect_params(entry, {"library", "density", "youngs_modulus", "poisson_ratio"}, overrides, where);
  for (const auto& [key, value] : overrides) m.params[key] = value, m.where[key] = where[key], m.sources[key] = "set in the case";
  return lib;
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
                              kStageKeys[static_cast<int>(stage)],
                              hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint), list));
}

ContactSpec read_contact(const YAML::Node& node, const std::string& file) {
  ContactSpec contact;
  if (!node) return contact;
  MapReader map(node, file, "contact");
  const std::pair<Stage, ContactSpec::Choice*> single[] = {{Stage::normal, &contact.normal},
                                                           {Stage::damping, &contact.damping},
                                                           {Stage::tangential, &contact.tangential},
                                                           {Stage::rolling, &contact.rolling},
                                                           {Stage::twisting, &contact.twisting}};
  for (auto [stage, choice] : single) {
    const std::string key(kStageKeys[static_cast<int>(stage)]);
    if (!map.has(key)) {
      map.node(key);
      continue;
    }
    *choice = read_choice(map.node(key), file, "contact." + key, map, key);
    check_choice(*choice, stage, "contact." + key);
  }
  for (Stage stage : {Stage::adhesion, Stage::extra}) {
    const std::string key(kStageKeys[static_cast<int>(stage)]);
    const YAML::Node list = map.node(key);
    if (!list) continue;
    if (!list.IsSequence()) map.fail(key, "must be a list of models, e.g. [liquid_bridge]");
    auto& out = stage == Stage::adhesion ? contact.adhesion : contact.extra;
    for (size_t k = 0; k < list.size(); ++k) {
      const std::string path = fmt::format("contact.{}[{}]", key, k);
      out.push_back(read_choice(list[k], file, path, map, key));
      check_choice(out.back(), stage, path);
    }
  }
  map.finish();
  return contact;
}

SizeDistributionSpec read_diameter(MapReader& parent, const std::string& file, const std::string& key = "diameter") {
  SizeDistributionSpec d;
  const YAML::Node node = parent.node(key);
  if (!node) parent.fail(key, "missing: give a diameter [m] or {distribution: normal|uniform|discrete, ...}");
  if (node.IsScalar()) {
    d.value = MapReader::scalar_number(node, parent, key);
    if (!(d.value > 0 && d.value < 10)) parent.fail(key, fmt::format("{:g} m is out of range; valid: (0, 10] m", d.value));
    return d;
  }
  MapReader map(node, file, parent.key_path(key));
  const std::string kind = map.string("distribution", "", {"normal", "uniform", "discrete"});
  if (kind.empty()) map.fail("distribution", "missing: normal, uniform or discrete");
  if (kind == "normal") {
    d.kind = SizeDistributionSpec::Kind::normal;
    d.mean = map.required_number("mean", 1e-7, 10, "m");
    d.std_dev = map.required_number("std", 0, 10, "m");
    d.min = map.number("min", std::max(d.mean - 3 * d.std_dev, 0.1 * d.mean), 1e-7, 10, "m");
    d.max = map.number("max", d.mean + 3 * d.std_dev, 1e-7, 10, "m");
    if (!(d.min <= d.mean && d.mean <= d.max)) map.fail("min", "needs min <= mean <= max");
  } else if (kind == "uniform") {
    d.kind = SizeDistributionSpec::Kind::uniform;
    d.min = map.required_number("min", 1e-7, 10, "m");
    d.max = map.required_number("max", d.min, 10, "m");
  } else {
    // Size classes with their mass fractions (a sieve analysis) or number fractions (a count,
    // an image analysis); number fractions become mass fractions n_k d_k^3 / sum n d^3.
    d.kind = SizeDistributionSpec::Kind::discrete;
    const bool by_number = map.has("number_fractions");
    if (by_number && map.has("mass_fractions")) map.fail("number_fractions", "give mass_fractions or number_fractions, not both");
    const std::string fractions_key = by_number ? "number_fractions" : "mass_fractions";
    const YAML::Node values = map.node("values"), fractions = map.node(fractions_key);
    if (!values || !values.IsSequence() || values.size() == 0) map.fail("values", "must be a list of diameters [m]");
    if (!fractions || !fractions.IsSequence() || fractions.size() != values.size())
      map.fail(fractions_key, "must be a list as long as 'values' (mass_fractions, or number_fractions)");
    double sum = 0, mass_sum = 0;
    for (size_t k = 0; k < values.size(); ++k) {
      d.values.push_back(MapReader::finite_number(values[k], map, "values"));
      d.mass_fractions.push_back(MapReader::finite_number(fractions[k], map, fractions_key));
      if (!(d.values.back() > 0 && d.values.back() <= 10)) map.fail("values", "diameters must be in (0, 10] m");
      if (!(d.mass_fractions.back() >= 0)) map.fail(fractions_key, "fractions must not be negative");
      sum += d.mass_fractions.back();
      if (by_number) d.mass_fractions.back() *= d.values.back() * d.values.back() * d.values.back();
      mass_sum += d.mass_fractions.back();
    }
    if (std::abs(sum - 1.0) > 1e-6) map.fail(fractions_key, fmt::format("sum to {:g}; they must sum to 1", sum));
    if (by_number)
      for (double& f : d.mass_fractions) f /= mass_sum;
  }
  map.finish();
  return d;
}

/// A box {min: [x,y,z], max: [x,y,z]} under `key` of `map`.
void read_box(MapReader& map, const std::string& key, const std::string& file, Vec3& lo, Vec3& hi) {
  const YAML::Node node = map.node(key);
  if (!node) map.fail(key, "missing: the box {min: [x,y,z], max: [x,y,z]}");
  MapReader box(node, file, map.key_path(key));
  lo = box.vec3("min", Vec3::Zero());
  hi = box.vec3("max", Vec3::Zero());
  if (!(hi.array() > lo.array()).all()) box.fail("max", "each component must exceed min");
  box.finish();
}

ClumpTemplateSpec read_clump(const std::string& name, const YAML::Node& node, const std::string& file) {
  MapReader map(node, file, "clumps." + name);
  ClumpTemplateSpec c;
  c.name = name;
  c.location = map.location();
  const YAML::Node spheres = map.node("spheres");
  if (!spheres || !spheres.IsSequence() || spheres.size() == 0)
    map.fail("spheres", "must be a list of {centre: [x,y,z], diameter: D} in the clump's own frame [m]");
  for (size_t k = 0; k < spheres.size(); ++k) {
    MapReader sphere(spheres[k], file, fmt::format("clumps.{}.spheres[{}]", name, k));
    c.centres.push_back(sphere.vec3("centre", Vec3::Zero()));
    c.radii.push_back(0.5 * sphere.required_number("diameter", 1e-7, 10, "m"));
    sphere.finish();
  }
  map.finish();
  return c;
}

InletSpec read_inlet(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("inlets[{}]", index));
  InletSpec in;
  in.location = map.location();
  in.name = map.string("name", fmt::format("inlet{}", index));
  in.material = map.required_string("material", "name one of the case's materials");
  in.clump = map.string("clump", "");
  in.diameter = read_diameter(map, file);
  in.port = map.string("port", "");
  const bool tph = map.has("mass_rate_tph"), kgs = map.has("mass_rate_kgs");
  if (tph == kgs) map.fail("mass_rate_tph", "give exactly one of mass_rate_tph [t/h] or mass_rate_kgs [kg/s]");
  in.mass_rate = tph ? map.number("mass_rate_tph", 0, 1e-9, 1e6, "t/h") / 3.6 : map.number("mass_rate_kgs", 0, 1e-12, 1e6, "kg/s");
  if (in.port.empty()) read_box(map, "region", file, in.region_min, in.region_max);
  else if (map.has("region")) map.fail("region", fmt::format("give either `port: {}` (the equipment's feed point) or `region`, not both", in.port));
  in.velocity = map.vec3("velocity", in.velocity);
  in.start = map.number("start", 0.0, 0.0, 1e9, "s");
  in.stop = map.number("stop", 1e300, in.start, 1e300, "s");
  in.interval = map.number("interval", 0.0, 0.0, 1e6, "s");
  map.finish();
  return in;
}

OutletSpec read_outlet(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("outlets[{}]", index));
  OutletSpec out;
  out.location = map.location();
  out.name = map.string("name", fmt::format("outlet{}", index));
  read_box(map, "region", file, out.region_min, out.region_max);
  out.spillage = map.boolean("spillage", false);
  map.finish();
  return out;
}

SensorSpec read_sensor(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("sensors[{}]", index));
  SensorSpec s;
  s.location = map.location();
  s.name = map.string("name", fmt::format("sensor{}", index));
  if (map.has("plane") == map.has("box"))
    map.fail("plane", "give exactly one of `plane: {point, normal, thickness}` (a flow plane) or `box: {min, max, across}`");
  if (const YAML::Node plane = map.node("plane")) {
    s.kind = SensorSpec::Kind::plane;
    MapReader p(plane, file, map.key_path("plane"));
    s.point = p.vec3("point", Vec3::Zero());
    s.normal = p.vec3("normal", Vec3(1, 0, 0));
    if (s.normal.norm() < 1e-12) p.fail("normal", "must not be zero");
    s.thickness = p.number("thickness", 0.0, 0.0, 100.0, "m");
    p.finish();
    read_box(map, "region", file, s.region_min, s.region_max);
  } else {
    s.kind = SensorSpec::Kind::box;
    MapReader b(map.node("box"), file, map.key_path("box"));
    s.region_min = b.vec3("min", Vec3::Zero());
    s.region_max = b.vec3("max", Vec3::Zero());
    if (!(s.region_max.array() > s.region_min.array()).all()) b.fail("max", "each component must exceed min");
    s.across = b.vec3("across", s.across);
    if (s.across.norm() < 1e-12) b.fail("across", "must not be zero");
    b.finish();
  }
  map.finish();
  return s;
}

EquipmentSpec read_equipment(const YAML::Node& node, const std::string& file) {
  MapReader map(node, file, "equipment");
  const std::vector<std::string> keys = map.keys();
  const std::vector<std::string> types = {"transfer_chute", "screw_conveyor", "bucket_elevator", "belt_conveyor", "silo"};
  if (keys.size() != 1)
    map.fail(keys.empty() ? "equipment" : keys[1], "must name exactly one generator: transfer_chute, screw_conveyor, bucket_elevator, belt_conveyor or silo");
  EquipmentSpec e;
  e.type = keys[0];
  if (std::find(types.begin(), types.end(), e.type) == types.end()) {
    const std::string near = nearest_word(e.type, types);
    map.fail(e.type, fmt::format("'{}' is not an equipment generator{}; valid: transfer_chute, screw_conveyor, bucket_elevator, belt_conveyor, silo",
                                 e.type, near.empty() ? "" : fmt::format(" (did you mean '{}'?)", near)));
  }
  e.location = map.where(e.type);
  YAML::Node params = map.node(e.type);
  if (!params || params.IsNull()) params = YAML::Node(YAML::NodeType::Map);
  e.params = std::make_shared<const YAML::Node>(params);
  e.file = file;
  map.finish();
  return e;
}

MeshWallSpec read_mesh(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("meshes[{}]", index));
  MeshWallSpec m;
  m.location = map.location();
  m.name = map.string("name", fmt::format("mesh{}", index));
  m.material = map.required_string("material", "name one of the case's materials");
  const std::string base_dir = std::filesystem::path(file).parent_path().string();
  m.file = map.string("file", "");
  if (!m.file.empty() && std::filesystem::path(m.file).is_relative() && !base_dir.empty())
    m.file = (std::filesystem::path(base_dir) / m.file).string();
  m.unit_scale = map.number("unit_scale", 1.0, 1e-9, 1e9);
  m.scale = map.vec3("scale", m.scale);
  m.rotate_deg = map.vec3("rotate_deg", m.rotate_deg);
  m.translate = map.vec3("translate", m.translate);
  const YAML::Node vertices = map.node("vertices"), triangles = map.node("triangles");
  if (vertices || triangles) {
    if (!m.file.empty()) map.fail("vertices", "give either `file` or inline `vertices` and `triangles`, not both");
    if (!vertices || !vertices.IsSequence() || !triangles || !triangles.IsSequence())
      map.fail("triangles", "inline meshes need `vertices: [[x,y,z], ...]` and `triangles: [[i,j,k], ...]`");
    for (const auto& v : vertices) {
      if (!v.IsSequence() || v.size() != 3) map.fail("vertices", "each vertex must be [x, y, z]");
      m.vertices.push_back({MapReader::finite_number(v[0], map, "vertices"), MapReader::finite_number(v[1], map, "vertices"),
                            MapReader::finite_number(v[2], map, "vertices")});
    }
    for (const auto& t : triangles) {
      if (!t.IsSequence() || t.size() != 3) map.fail("triangles", "each triangle must be three vertex indices [i, j, k]");
      std::array<std::int32_t, 3> tri;
      for (int k = 0; k < 3; ++k) {
        const double v = MapReader::finite_number(t[k], map, "triangles");
        if (v < 0 || v >= static_cast<double>(m.vertices.size()) || v != std::floor(v))
          map.fail("triangles", fmt::format("vertex index {:g} is not one of the {} vertices (0-based)", v, m.vertices.size()));
        tri[k] = static_cast<std::int32_t>(v);
      }
      m.triangles.push_back(tri);
    }
  } else if (m.file.empty()) {
    map.fail("file", "missing: a mesh file (STL, OBJ, PLY, glTF, 3MF, ...) or inline vertices and triangles");
  }
  if (const YAML::Node motion = map.node("motion")) m.motion = read_motion(motion, file, map.key_path("motion"), base_dir);
  if (const YAML::Node surface = map.node("surface_velocity")) {
    MapReader sv(surface, file, map.key_path("surface_velocity"));
    if (sv.has("linear")) {
      m.surface.kind = SurfaceVelocitySpec::Kind::linear;
      m.surface.velocity = sv.vec3("linear", Vec3::Zero());
    } else if (const YAML::Node rotation = sv.node("rotation")) {
      MapReader r(rotation, file, sv.key_path("rotation"));
      m.surface.kind = SurfaceVelocitySpec::Kind::rotation;
      m.surface.axis = r.vec3("axis", Vec3(0, 0, 1));
      if (m.surface.axis.norm() < 1e-12) r.fail("axis", "must not be zero");
      m.surface.axis.normalize();
      m.surface.point = r.vec3("point", Vec3::Zero());
      if (r.has("rpm") == r.has("rad_per_s")) r.fail("rpm", "give exactly one of rpm or rad_per_s");
      m.surface.angular_speed = r.has("rpm") ? r.number("rpm", 0, -1e5, 1e5) * 2 * std::numbers::pi / 60 : r.number("rad_per_s", 0, -1e5, 1e5);
      r.finish();
    } else {
      sv.fail("linear", "give {linear: [vx, vy, vz]} (a belt) or {rotation: {axis, point, rpm}} (a pulley or drum surface)");
    }
    sv.finish();
  }
  map.finish();
  return m;
}

ParticleSetSpec read_particles(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("particles[{}]", index));
  ParticleSetSpec p;
  p.location = map.location();
  p.material = map.required_string("material", "name one of the case's materials");
  p.clump = map.string("clump", "");
  p.diameter = read_diameter(map, file);
  p.velocity = map.vec3("velocity", p.velocity);
  p.angular_velocity = map.vec3("angular_velocity", p.angular_velocity);
  p.attach_to = map.string("attach_to", "");
  const YAML::Node positions = map.node("positions");
  if (positions) {
    if (!positions.IsSequence() || positions.size() == 0) map.fail("positions", "must be a list of [x, y, z] centres");
    for (const auto& item : positions) {
      if (!item.IsSequence() || item.size() != 3) map.fail("positions", "each entry must be [x, y, z]");
      p.positions.emplace_back(MapReader::finite_number(item[0], map, "positions"),
                               MapReader::finite_number(item[1], map, "positions"),
                               MapReader::finite_number(item[2], map, "positions"));
    }
    p.count = static_cast<int64_t>(p.positions.size());
  } else {
    p.count = map.integer("count", 0, 1, 100'000'000);
    if (p.count == 0) map.fail("count", "missing: give `count` with a `region`, or explicit `positions`");
    read_box(map, "region", file, p.region_min, p.region_max);
  }
  map.finish();
  return p;
}

PlaneWallSpec read_wall(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("walls[{}]", index));
  PlaneWallSpec w;
  w.location = map.location();
  w.name = map.string("name", fmt::format("wall{}", index));
  w.material = map.required_string("material", "name one of the case's materials");
  const YAML::Node plane = map.node("plane"), cylinder = map.node("cylinder");
  if (!plane == !cylinder)
    map.fail("plane", "give one of plane: {point, normal} or cylinder: {point, axis, radius} (particles inside); "
                      "CAD walls go under `meshes:`");
  if (plane) {
    MapReader p(plane, file, map.key_path("plane"));
    w.point = p.vec3("point", w.point);
    w.normal = p.vec3("normal", w.normal);
    if (w.normal.norm() < 1e-12) p.fail("normal", "must not be zero");
    w.normal.normalize();
    p.finish();
  } else {
    MapReader c(cylinder, file, map.key_path("cylinder"));
    w.cylinder = true;
    w.point = c.vec3("point", w.point);
    w.normal = c.vec3("axis", w.normal);
    if (w.normal.norm() < 1e-12) c.fail("axis", "must not be zero");
    w.normal.normalize();
    w.radius = c.required_number("radius", 1e-6, 1e4, "m");
    c.finish();
  }
  w.velocity = map.vec3("velocity", w.velocity);
  if (const YAML::Node servo = map.node("servo")) {
    if (w.cylinder) map.fail("servo", "only plane walls can be servo-controlled");
    MapReader sv(servo, file, map.key_path("servo"));
    w.has_servo = true;
    w.servo.target_stress = sv.required_number("target_stress", 1e-6, 1e12, "Pa");
    w.servo.area = sv.number("area", 0.0, 0.0, 1e6, "m^2");
    w.servo.max_speed = sv.number("max_speed", 0.0, 0.0, 1e3, "m/s");
    sv.finish();
    if (std::abs(w.velocity.dot(w.normal)) > 0) map.fail("velocity", "a servo wall sets its own normal speed; give only a tangential velocity");
  }
  map.finish();
  return w;
}

SimulationSpec read_simulation(const YAML::Node& node, const std::string& file) {
  SimulationSpec s;
  if (!node) return s;
  MapReader map(node, file, "simulation");
  s.duration = map.required_number("duration", 0.0, 1e6, "s");
  const YAML::Node step = map.node("time_step");
  if (step && !(step.IsScalar() && step.Scalar() == "auto")) s.time_step = map.number("time_step", 0.0, 1e-12, 1.0, "s");
  s.rayleigh_fraction = map.number("rayleigh_fraction", s.rayleigh_fraction, 0.01, 1.0);
  s.refuse_unsafe_step = map.string("unsafe_time_step", "refuse", {"refuse", "warn"}) == "refuse";
  s.characteristic_velocity = map.number("characteristic_velocity", 0.0, 0.0, 1e4, "m/s");
  s.gravity = map.vec3("gravity", s.gravity);
  s.seed = static_cast<uint64_t>(map.integer("seed", 1, 0, std::numeric_limits<int32_t>::max()));
  s.threads = static_cast<int>(map.integer("threads", 0, 0, 1024));
  s.skin = map.number("skin", 0.0, 0.0, 10.0, "m");
  if (const YAML::Node domain = map.node("domain")) {
    MapReader box(domain, file, "simulation.domain");
    s.has_domain = true;
    s.domain_min = box.vec3("min", Vec3::Zero());
    s.domain_max = box.vec3("max", Vec3::Zero());
    if (!(s.domain_max.array() > s.domain_min.array()).all()) box.fail("max", "each component must exceed min");
    box.finish();
  }
  if (const YAML::Node periodic = map.node("periodic")) {
    if (!periodic.IsSequence()) map.fail("periodic", "must be a list of axes, e.g. [x, y]");
    for (const auto& axis : periodic) {
      const std::string a = axis.IsScalar() ? axis.Scalar() : "";
      if (a != "x" && a != "y" && a != "z") map.fail("periodic", fmt::format("'{}' is not an axis; valid: x, y, z", a));
      s.periodic[a[0] - 'x'] = true;
    }
    if (!s.has_domain) map.fail("periodic", "needs a `domain` box: its size along each periodic axis is the period");
  }
  s.mass_scaling = map.number("mass_scaling", 1.0, 1e-6, 1e12);
  s.stiffness_scaling = map.number("stiffness_scaling", 1.0, 1e-9, 1e3);
  s.stop_on_trouble = map.string("numerical_trouble", "stop", {"stop", "warn"}) == "stop";
  s.max_overlap_ratio = map.number("max_overlap", s.max_overlap_ratio, 0.01, 1.0, "of the radius");
  s.energy_rise_limit = map.number("energy_rise_limit", s.energy_rise_limit, 1e-4, 100.0, "of the energy scale");
  map.finish();
  return s;
}

OutputSpec read_output(const YAML::Node& node, const std::string& file, const std::string& case_path) {
  OutputSpec o;
  o.directory = "out/" + std::filesystem::path(case_path).stem().string();
  if (!node) return o;
  MapReader map(node, file, "output");
  o.directory = map.string("directory", o.directory);
  // Results stay inside the working directory: a case file (perhaps from someone else) may not
  // write to an absolute path or climb out with `..`. `--out` on the command line may.
  {
    const std::filesystem::path dir(o.directory);
    const std::filesystem::path normal = dir.lexically_normal();
    if (o.directory.empty() || dir.is_absolute() || dir.has_root_name() || dir.has_root_directory() || normal.empty() ||
        normal == "." || *normal.begin() == "..")
      map.fail("directory", fmt::format("'{}' is not allowed: give a folder inside the working directory, e.g. "
                                        "out/my_case (no absolute path, no `..`); use `--out DIR` to write elsewhere",
                                        o.directory));
  }
  o.scalars_every = map.integer("scalars_every", 0, 0, std::numeric_limits<int32_t>::max());
  o.progress_seconds = map.number("progress_seconds", o.progress_seconds, 0.0, 1e6, "s");
  o.frames_every = map.number("frames_every", 0.0, 0.0, 1e9, "s");
  o.checkpoint_every = map.number("checkpoint_every", 0.0, 0.0, 1e9, "s");
  o.records_from = map.number("records_from", 0.0, 0.0, 1e9, "s");
  if (const YAML::Node render = map.node("render")) {
    MapReader r(render, file, "output.render");
    o.render_every = static_cast<int>(r.integer("every", 0, 0, 1000000));
    const YAML::Node camera = r.node("camera");
    if (camera && camera.IsMap()) {
      MapReader c(camera, file, "output.render.camera");
      o.has_camera_pose = true;
      o.camera_eye = c.vec3("eye", o.camera_eye);
      o.camera_target = c.vec3("target", o.camera_target);
      o.camera_up = c.vec3("up", o.camera_up);
      o.camera_fov_deg = c.number("fov_deg", o.camera_fov_deg, 1.0, 170.0, "deg");
      if ((o.camera_eye - o.camera_target).norm() < 1e-12) c.fail("eye", "must differ from target");
      if ((o.camera_eye - o.camera_target).cross(o.camera_up).norm() < 1e-12) c.fail("up", "must not be parallel to the view direction");
      c.finish();
    } else if (camera) {
      const std::vector<std::string> presets = {"side", "front", "top", "iso"};
      o.render_camera = camera.IsScalar() ? camera.Scalar() : "";
      if (std::find(presets.begin(), presets.end(), o.render_camera) == presets.end())
        r.fail("camera", fmt::format("'{}' is not a camera; valid: side, front, top, iso, or {{eye: [x,y,z], target: [x,y,z], up: [x,y,z], fov_deg: 35}}",
                                     o.render_camera));
    }
    o.render_colour = r.string("colour_by", o.render_colour, {"speed", "radius", "material"});
    o.render_width = static_cast<int>(r.integer("width", o.render_width, 16, 8192));
    o.render_height = static_cast<int>(r.integer("height", o.render_height, 16, 8192));
    r.finish();
  }
  map.finish();
  return o;
}

CaseSpec read_case(const YAML::Node& root, const std::string& file) {
  MapReader top(root, file, "");
  CaseSpec spec;
  spec.path = file;
  spec.title = top.string("title", "");
  spec.simulation = read_simulation(top.node("simulation"), file);
  if (!top.has("simulation")) top.fail("simulation", "missing: give at least {duration: SECONDS}");

  const YAML::Node materials = top.node("materials");
  if (!materials || !materials.IsMap() || materials.size() == 0)
    top.fail("materials", "missing: a map of material names to {density, youngs_modulus, ...}");
  YAML::Node library_contact;  // valid only when library_contact_file is set
  std::string library_contact_file;
  std::vector<std::pair<std::string, std::pair<std::string, YAML::Node>>> library_walls;  // material, (wall, params)
  for (const auto& kv : materials) {
    const std::string name = kv.first.as<std::string>();
    if (kv.second.IsMap() && kv.second["library"]) {
      MapReader entry(kv.second, file, "materials." + name);
      LibraryMaterial lib = read_library_material(name, entry, file);
      if (lib.contact && library_contact_file.empty()) library_contact = lib.contact, library_contact_file = lib.file;
      for (auto& wall : lib.walls) library_walls.push_back({name, {wall.first, wall.second}});
      spec.materials.push_back(std::move(lib.material));
    } else {
      spec.materials.push_back(read_material(name, kv.second, file, "materials." + name));
    }
  }

  if (const YAML::Node list = top.node("interactions")) {
    if (!list.IsSequence()) top.fail("interactions", "must be a list of {materials: [A, B], KEY: VALUE}");
    for (size_t k = 0; k < list.size(); ++k) {
      MapReader map(list[k], file, fmt::format("interactions[{}]", k));
      InteractionSpec in;
      in.location = map.location();
      const YAML::Node pair = map.node("materials");
      if (!pair || !pair.IsSequence() || pair.size() != 2) map.fail("materials", "must name two materials, [A, B]");
      in.material_a = pair[0].as<std::string>();
      in.material_b = pair[1].as<std::string>();
      read_effect_params(map, {"materials"}, in.params, in.where);
      spec.interactions.push_back(std::move(in));
    }
  }
  // The contact model: the case's, else the one the first library material was calibrated with.
  if (top.has("contact") || library_contact_file.empty()) spec.contact = read_contact(top.node("contact"), file);
  else spec.contact = read_contact(library_contact, library_contact_file);
  // Pair parameters a library material gives against wall materials the case has, unless the
  // case gives that pair itself.
  for (const auto& material_wall : library_walls) {
    // Named references, not structured bindings: clang 14 (the fuzz build) cannot capture those.
    const std::string& material = material_wall.first;
    const auto& wall = material_wall.second;
    const auto has = [&](const std::string& n) { return std::any_of(spec.materials.begin(), spec.materials.end(), [&](const MaterialSpec& m) { return m.name == n; }); };
    if (!has(wall.first)) continue;
    const bool given = std::any_of(spec.interactions.begin(), spec.interactions.end(), [&](const InteractionSpec& in) {
      return (in.material_a == material && in.material_b == wall.first) || (in.material_b == material && in.material_a == wall.first);
    });
    if (given) continue;
    const MaterialSpec& m = *std::find_if(spec.materials.begin(), spec.materials.end(), [&](const MaterialSpec& x) { return x.name == material; });
    MapReader map(wall.second, m.library_file, "walls." + wall.first);
    InteractionSpec in;
    in.location = map.location();
    in.material_a = material, in.material_b = wall.first;
    read_effect_params(map, {}, in.params, in.where);
    spec.interactions.push_back(std::move(in));
  }
  if (const YAML::Node walls = top.node("walls")) {
    if (!walls.IsSequence()) top.fail("walls", "must be a list of walls");
    for (size_t k = 0; k < walls.size(); ++k) spec.planes.push_back(read_wall(walls[k], file, k));
  }
  if (const YAML::Node meshes = top.node("meshes")) {
    if (!meshes.IsSequence()) top.fail("meshes", "must be a list of mesh walls");
    for (size_t k = 0; k < meshes.size(); ++k) spec.meshes.push_back(read_mesh(meshes[k], file, k));
  }
  if (const YAML::Node clumps = top.node("clumps")) {
    if (!clumps.IsMap()) top.fail("clumps", "must be a map of template names to {spheres: [...]}");
    for (const auto& kv : clumps) spec.clumps.push_back(read_clump(kv.first.as<std::string>(), kv.second, file));
  }
  if (const YAML::Node inlets = top.node("inlets")) {
    if (!inlets.IsSequence()) top.fail("inlets", "must be a list of inlets");
    for (size_t k = 0; k < inlets.size(); ++k) spec.inlets.push_back(read_inlet(inlets[k], file, k));
  }
  if (const YAML::Node outlets = top.node("outlets")) {
    if (!outlets.IsSequence()) top.fail("outlets", "must be a list of outlets");
    for (size_t k = 0; k < outlets.size(); ++k) spec.outlets.push_back(read_outlet(outlets[k], file, k));
  }
  const YAML::Node particles = top.node("particles");
  if (particles && !particles.IsSequence()) top.fail("particles", "must be a list of particle sets");
  if ((!particles || particles.size() == 0) && spec.inlets.empty())
    top.fail("particles", "missing: a list of particle sets {material, diameter, count + region | positions}, or inlets");
  if (particles)
    for (size_t k = 0; k < particles.size(); ++k) spec.particles.push_back(read_particles(particles[k], file, k));
  if (const YAML::Node sensors = top.node("sensors")) {
    if (!sensors.IsSequence()) top.fail("sensors", "must be a list of sensors ({name, plane: {...}, region} or {name, box: {...}})");
    for (size_t k = 0; k < sensors.size(); ++k) spec.sensors.push_back(read_sensor(sensors[k], file, k));
  }
  if (const YAML::Node equipment = top.node("equipment")) spec.equipment = read_equipment(equipment, file);
  if (const YAML::Node wear = top.node("wear_coefficients")) {
    MapReader w(wear, file, "wear_coefficients");
    w.keys_are_names("MESH");  // a mesh name, or `default`
    for (const std::string& key : w.keys()) spec.wear_coefficients[key] = w.number(key, 0.0, 0.0, 1e-6, "m^3/J");
  }
  top.node("sweep");  // read by the sweep runner (app/sweep.cpp) before the variants are parsed
  top.node("uncertainty");  // likewise (app/uncertainty.h)
  spec.output = read_output(top.node("output"), file, file);
  top.finish();
  return spec;
}

YAML::Node load_yaml(const std::string& text, const std::string& name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw CaseError(fmt::format("{}:{}:{}: not valid YAML: {}", name, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
}

}  // namespace

double SizeDistributionSpec::largest() const {
  switch (kind) {
    case Kind::fixed: return value;
    case Kind::normal:
    case Kind::uniform: return max;
    case Kind::discrete: return *std::max_element(values.begin(), values.end());
  }
  return value;
}

double SizeDistributionSpec::smallest() const {
  switch (kind) {
    case Kind::fixed: return value;
    case Kind::normal:
    case Kind::uniform: return min;
    case Kind::discrete: return *std::min_element(values.begin(), values.end());
  }
  return value;
}

SizeDistributionSpec read_size_distribution(MapReader& parent, const std::string& file, const std::string& key) {
  return read_diameter(parent, file, key);
}

CaseSpec parse_case_node(const YAML::Node& root, const std::string& file) {
  try {
    return read_case(root, file);
  } catch (const YAML::Exception& e) {
    throw CaseError(fmt::format("{}:{}:{}: {}", file, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
}

CaseSpec parse_case_text(const std::string& text, const std::string& name) {
  try {
    return read_case(load_yaml(text, name), name);
  } catch (const YAML::Exception& e) {
    throw CaseError(fmt::format("{}:{}:{}: {}", name, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
}

void set_library_lookup(LibraryLookup lookup) { library_lookup() = std::move(lookup); }

CaseSpec parse_case_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw CaseError(fmt::format("{}: cannot open the case file", path));
  std::stringstream text;
  text << in.rdbuf();
  return parse_case_text(text.str(), path);
}

}  // namespace dem
