// Reading a case file into a CaseSpec. The YAML layout is documented in cases/hello_sphere.yaml
// and README.md; every key read here is checked for type and range. This file reads the top
// level, the simulation and output sections and calls the readers of the other sections
// (spec_reading.h): materials and the contact model (spec_materials.cpp), equipment, meshes and
// walls (spec_walls.cpp), particles, inlets, outlets and sensors (spec_particles.cpp), and
// motions (spec_motion.cpp).
#include "case/spec.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "case/liner_materials.h"
#include "case/spec_reading.h"
#include "case/yaml_check.h"

namespace dem {

using namespace spec_reading;

namespace {

SimulationSpec read_simulation(const YAML::Node& node, const std::string& file) {
  SimulationSpec s;
  if (!node) return s;
  MapReader map(node, file, "simulation");
  s.duration = map.required_number("duration", 0.0, 1e6, "s");
  const YAML::Node step = map.node("time_step");
  if (step && !(step.IsScalar() && step.Scalar() == "auto")) s.time_step = map.number("time_step", 0.0, 1e-12, 1.0, "s");
  s.rayleigh_fraction = map.number("rayleigh_fraction", s.rayleigh_fraction, 0.01, 1.0);
  s.steps_per_contact = map.number("steps_per_contact", s.steps_per_contact, kMinStepsPerContact, 1000.0);
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
  o.checkpoint_seconds = map.number("checkpoint_seconds", o.checkpoint_seconds, 0.0, 1e9, "s");
  o.rows_seconds = map.number("rows_seconds", o.rows_seconds, 0.0, 1e9, "s");
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

/// Names label a run's columns and files (walls.h5, scalars.csv): two parts of one kind under one
/// name would give two columns of one name. Plane walls and meshes are one kind, the walls.
void refuse_duplicate_names(const std::vector<std::pair<std::string, SourceLocation>>& named, const std::string& kind) {
  for (size_t i = 0; i < named.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (named[i].first == named[j].first)
        throw CaseError(fmt::format("{}: {} name '{}' given twice (first at {}); each {} needs a name of its own: its results are reported under it",
                                    named[i].second.str(), kind, named[i].first, named[j].second.line > 0 ? fmt::format("line {}", named[j].second.line) : named[j].second.str(), kind));
}

template <class Items>
void add_names(std::vector<std::pair<std::string, SourceLocation>>& named, const Items& items) {
  for (const auto& item : items) named.emplace_back(item.name, item.location);
}

/// What library materials bring beyond their own entries: the contact model the first of them was
/// calibrated with, and their pair parameters against wall materials.
struct LibraryContacts {
  YAML::Node contact;  // valid only when file is set
  std::string file;
  std::vector<std::pair<std::string, std::pair<std::string, YAML::Node>>> walls;  // material, (wall, params)
};

/// `materials`: each entry read in place or from the material library.
void read_materials(MapReader& top, const std::string& file, const LibraryLookup& lookup, CaseSpec& spec, LibraryContacts& library) {
  const YAML::Node materials = top.node("materials");
  if (!materials || !materials.IsMap() || materials.size() == 0)
    top.fail("materials", "missing: a map of material names to {density, youngs_modulus, ...}");
  for (const auto& kv : materials) {
    const std::string name = kv.first.as<std::string>();
    if (kv.second.IsMap() && kv.second["library"]) {
      MapReader entry(kv.second, file, "materials." + name);
      LibraryMaterial lib = read_library_material(name, entry, file, lookup);
      if (lib.contact && library.file.empty()) library.contact = lib.contact, library.file = lib.file;
      for (auto& wall : lib.walls) library.walls.push_back({name, {wall.first, wall.second}});
      spec.materials.push_back(std::move(lib.material));
    } else {
      spec.materials.push_back(read_material(name, kv.second, file, "materials." + name));
    }
  }
}

/// `interactions`: the pair parameters the case gives.
void read_interactions(MapReader& top, const std::string& file, CaseSpec& spec) {
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
}

/// Pair parameters a library material gives against wall materials the case has, unless the
/// case gives that pair itself.
void add_library_wall_pairs(const LibraryContacts& library, CaseSpec& spec) {
  for (const auto& material_wall : library.walls) {
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
}

/// The parts of the scene, in this order: plane walls, mesh walls, clump templates, inlets,
/// outlets, particle sets and sensors.
void read_parts(MapReader& top, const std::string& file, CaseSpec& spec) {
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
    for (const auto& kv : clumps) {
      const std::string name = kv.first.as<std::string>();
      spec.clumps.push_back(read_clump(name, kv.second, file, "clumps." + name));
    }
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
}

/// Walls (planes and meshes), inlets, outlets and sensors each need names of their own.
void refuse_duplicate_part_names(const CaseSpec& spec) {
  std::vector<std::pair<std::string, SourceLocation>> walls, inlets, outlets, sensors;
  add_names(walls, spec.planes), add_names(walls, spec.meshes), add_names(inlets, spec.inlets), add_names(outlets, spec.outlets),
      add_names(sensors, spec.sensors);
  refuse_duplicate_names(walls, "wall");
  refuse_duplicate_names(inlets, "inlet");
  refuse_duplicate_names(outlets, "outlet");
  refuse_duplicate_names(sensors, "sensor");
}

/// `wear_coefficients`: per mesh name, or `default`.
void read_wear_coefficients(MapReader& top, const std::string& file, CaseSpec& spec) {
  if (const YAML::Node wear = top.node("wear_coefficients")) {
    MapReader w(wear, file, "wear_coefficients");
    w.keys_are_names("MESH");  // a mesh name, or `default`
    for (const std::string& key : w.keys()) spec.wear_coefficients[key] = w.number(key, 0.0, 0.0, 1e-6, "m^3/J");
  }
}

/// One entry of `wear.liners`: its material from the liner-material table, its thickness, and
/// the material's coefficients unless the entry gives its own.
LinerSpec read_liner(MapReader& liners, const std::string& name, const std::string& file) {
  const std::vector<std::string> materials = liner_material_keys();
  std::string words;
  for (const std::string& m : materials) words += (words.empty() ? "" : ", ") + m;
  const YAML::Node node = liners.node(name);
  if (!node.IsMap()) liners.fail(name, "must be a map, e.g. {material: ar400, thickness_mm: 20}");
  MapReader entry(node, file, liners.key_path(name));
  LinerSpec liner;
  liner.location = entry.location();
  liner.material = entry.required_string("material", "give the liner's material, one of: " + words, materials);
  const LinerMaterial& material = *find_liner_material(liner.material);
  liner.thickness = 1e-3 * entry.required_number("thickness_mm", 0.1, 1000.0, "mm");
  liner.sliding_coefficient = entry.number("sliding_coefficient", material.sliding_coefficient, 0.0, 1e-6, "m^3/J");
  liner.impact_coefficient = entry.number("impact_coefficient", material.impact_coefficient, 0.0, 1e-6, "m^3/J");
  entry.finish();
  return liner;
}

/// `wear`: the hours of operation a year and the liner of each mesh (or `default`).
void read_wear(MapReader& top, const std::string& file, CaseSpec& spec) {
  const YAML::Node node = top.node("wear");
  if (!node) return;
  MapReader wear(node, file, "wear");
  spec.wear.hours_given = wear.has("operating_hours_per_year");
  spec.wear.operating_hours_per_year =
      wear.number("operating_hours_per_year", kDefaultOperatingHoursPerYear, 1.0, kHoursInALeapYear, "h");
  if (const YAML::Node liners = wear.node("liners")) {
    MapReader map(liners, file, "wear.liners");
    map.keys_are_names("MESH");  // a mesh name, or `default`
    for (const std::string& name : map.keys()) spec.wear.liners[name] = read_liner(map, name, file);
  }
  wear.finish();
}

/// A mesh's sliding coefficient is given once: in `wear_coefficients` (the older form) or with
/// its liner in `wear.liners`.
void refuse_two_wear_rates(const MapReader& top, const CaseSpec& spec) {
  for (const auto& [name, liner] : spec.wear.liners)
    if (spec.wear_coefficients.count(name))
      throw CaseError(fmt::format("{}: wear_coefficients.{}: '{}' also has a liner in wear.liners (line {}); give one of them: "
                                  "the liner's own `sliding_coefficient` replaces this value",
                                  top.where("wear_coefficients").str(), name, name, liner.location.line));
}

CaseSpec read_case(const YAML::Node& root, const std::string& file, const LibraryLookup& lookup) {
  MapReader top(root, file, "");
  CaseSpec spec;
  spec.path = file;
  spec.title = top.string("title", "");
  spec.simulation = read_simulation(top.node("simulation"), file);
  if (!top.has("simulation")) top.fail("simulation", "missing: give at least {duration: SECONDS}");
  LibraryContacts library;
  read_materials(top, file, lookup, spec, library);
  read_interactions(top, file, spec);
  // The contact model: the case's, else the one the first library material was calibrated with.
  if (top.has("contact") || library.file.empty()) spec.contact = read_contact(top.node("contact"), file);
  else spec.contact = read_contact(library.contact, library.file);
  add_library_wall_pairs(library, spec);
  read_parts(top, file, spec);
  refuse_duplicate_part_names(spec);
  if (const YAML::Node equipment = top.node("equipment")) spec.equipment = read_equipment(equipment, file);
  read_wear_coefficients(top, file, spec);
  read_wear(top, file, spec);
  refuse_two_wear_rates(top, spec);
  top.node("sweep");  // read by the sweep runner (app/campaign/sweep.cpp) before the variants are parsed
  top.node("uncertainty");  // likewise (app/campaign/uncertainty.h)
  top.node("bias_check");   // likewise (app/campaign/bias_check.h)
  top.node("coarse_grain_check");  // likewise (app/campaign/bias_check.h)
  spec.output = read_output(top.node("output"), file, file);
  top.finish();
  return spec;
}

}  // namespace

CaseSpec parse_case_node(const YAML::Node& root, const std::string& file, const LibraryLookup& library) {
  try {
    return read_case(root, file, library);
  } catch (const YAML::Exception& e) {
    throw CaseError(fmt::format("{}:{}:{}: {}", file, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
}

CaseSpec parse_case_text(const std::string& text, const std::string& name, const LibraryLookup& library) {
  try {
    return read_case(parse_yaml(text, name), name, library);
  } catch (const YAML::Exception& e) {
    throw CaseError(fmt::format("{}:{}:{}: {}", name, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
}

CaseSpec parse_case_file(const std::string& path, const LibraryLookup& library) {
  std::ifstream in(path);
  if (!in) throw CaseError(fmt::format("{}: cannot open the case file", path));
  std::stringstream text;
  text << in.rdbuf();
  return parse_case_text(text.str(), path, library);
}

}  // namespace dem
