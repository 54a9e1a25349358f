// Dispatch to the generators, expansion of a case's `equipment:` section, STL output, and the
// helpers the generators share (cylinders, belt profiles, domains).
#include "equipment.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdint>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include "generators.h"

namespace dem::equipment {

namespace detail {

void cylinder(MeshBuilder& mesh, const Vec3& a, const Vec3& b, double radius, int around, bool caps) {
  const Vec3 axis = (b - a).normalized();
  const auto frame = perpendicular_pair(axis);  // not a structured binding: lambdas capture it (clang 14)
  const Vec3 u = frame.first, v = frame.second;
  const int along = segments((b - a).norm(), kCell);
  // u runs along the axis, w around it: normals point outward.
  mesh.grid([&](double s, double w) {
    const double angle = 2 * kPi * w;
    return Vec3(a + s * (b - a) + radius * (std::cos(angle) * u + std::sin(angle) * v));
  }, along, around);
  if (!caps) return;
  for (const Vec3& end : {a, b}) {
    std::vector<Vec3> ring;
    for (int k = 0; k < around; ++k) {
      const double angle = 2 * kPi * k / around * (end == a ? -1 : 1);
      ring.push_back(end + radius * (std::cos(angle) * u + std::sin(angle) * v));
    }
    mesh.fan(ring);
  }
}

std::pair<Vec3, Vec3> perpendicular_pair(const Vec3& axis) {
  const Vec3 n = axis.normalized();
  const Vec3 helper = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 u = (helper - helper.dot(n) * n).normalized();
  return {u, n.cross(u)};
}

std::pair<Vec3, Vec3> rotated_box(const Eigen::Matrix3d& rotation, const Vec3& lo, const Vec3& hi) {
  Vec3 a = Vec3::Constant(1e300), b = Vec3::Constant(-1e300);
  for (int k = 0; k < 8; ++k) {
    const Vec3 corner((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
    include(a, b, rotation * corner);
  }
  return {a, b};
}

MapReader sub_map(MapReader& parent, const std::string& key) {
  if (!parent.has(key)) {
    parent.node(key);  // marks it read
    return MapReader(YAML::Node(YAML::NodeType::Map), parent.file(), parent.key_path(key));
  }
  const YAML::Node node = parent.node(key);
  if (node.IsNull()) return MapReader(YAML::Node(YAML::NodeType::Map), parent.file(), parent.key_path(key));
  if (!node.IsMap()) parent.fail(key, "must be a map of parameters, e.g. {radius: 0.8}");
  return MapReader(node, parent.file(), parent.key_path(key));
}

void set_domain(Generated& out, double margin, double floor) {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const MeshWallSpec& mesh : out.meshes)
    for (const auto& v : mesh.vertices) include(lo, hi, Vec3(v[0], v[1], v[2]));
  for (const Port& port : out.ports) include(lo, hi, port.region_min), include(lo, hi, port.region_max);
  for (const OutletSpec& o : out.outlets) include(lo, hi, o.region_min), include(lo, hi, o.region_max);
  for (const SensorSpec& s : out.sensors) include(lo, hi, s.region_min), include(lo, hi, s.region_max);
  out.domain_min = lo - Vec3::Constant(margin);
  out.domain_max = hi + Vec3::Constant(margin);
  out.domain_min.z() = std::min(out.domain_min.z(), floor);
}

Materials read_materials(MapReader& reader) {
  Materials m;
  m.liner = reader.string("liner_material", m.liner);
  m.belt = reader.string("belt_material", m.belt);
  if (m.liner.empty()) reader.fail("liner_material", "must name a case material");
  if (m.belt.empty()) reader.fail("belt_material", "must name a case material");
  return m;
}

std::vector<std::pair<double, double>> trough_profile(double width, double trough, double cell) {
  const double centre = kCentreRollFraction * width;  // [m] centre roll length
  const double wing = 0.5 * (width - centre);        // [m] wing length
  std::vector<std::pair<double, double>> points;
  const int wing_pieces = segments(wing, cell), centre_pieces = segments(centre, cell);
  // From the -y edge down the wing, across the centre roll, up the +y wing.
  for (int k = 0; k < wing_pieces; ++k) {
    const double along = wing * (1.0 - double(k) / wing_pieces);
    points.push_back({-0.5 * centre - along * std::cos(trough), along * std::sin(trough)});
  }
  for (int k = 0; k <= centre_pieces; ++k) points.push_back({-0.5 * centre + centre * k / centre_pieces, 0.0});
  for (int k = 1; k <= wing_pieces; ++k) {
    const double along = wing * double(k) / wing_pieces;
    points.push_back({0.5 * centre + along * std::cos(trough), along * std::sin(trough)});
  }
  return points;
}

double trough_height(double width, double trough, double y) {
  const double centre = kCentreRollFraction * width;
  return std::max(0.0, std::abs(y) - 0.5 * centre) * std::tan(trough);
}

}  // namespace detail

namespace {

using Generator = Generated (*)(MapReader&, const EquipmentSpec&);
const std::vector<std::pair<std::string, Generator>>& generators() {
  static const std::vector<std::pair<std::string, Generator>> table = {
      {"transfer_chute", detail::transfer_chute},
      {"screw_conveyor", detail::screw_conveyor},
      {"bucket_elevator", detail::bucket_elevator},
      {"belt_conveyor", detail::belt_conveyor},
      {"silo", detail::silo},
  };
  return table;
}

/// [m] The largest diameter the case's inlets and particle sets draw; 0 when it has none.
double largest_particle(const CaseSpec& spec) {
  double largest = 0;
  for (const InletSpec& inlet : spec.inlets) largest = std::max(largest, inlet.diameter.largest());
  for (const ParticleSetSpec& set : spec.particles) largest = std::max(largest, set.diameter.largest());
  return largest;
}

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

}  // namespace

std::vector<std::string> generator_names() {
  std::vector<std::string> names;
  for (const auto& [name, run] : generators()) names.push_back(name);
  return names;
}

Generated generate(const EquipmentSpec& spec) {
  for (const auto& [name, run] : generators()) {
    if (name != spec.type) continue;
    YAML::Node params = spec.params && *spec.params && !spec.params->IsNull() ? YAML::Node(*spec.params)
                                                                              : YAML::Node(YAML::NodeType::Map);
    MapReader reader(params, spec.file, "equipment." + spec.type);
    Generated out = run(reader, spec);
    reader.finish();
    return out;
  }
  const std::string hint = nearest_word(spec.type, generator_names());
  throw CaseError(fmt::format("{}: equipment: '{}' is not an equipment generator{}; valid: {}", spec.location.str(),
                              spec.type, hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint),
                              join(generator_names())));
}

void expand_equipment(CaseSpec& spec) {
  if (!spec.equipment) {
    for (const InletSpec& inlet : spec.inlets)
      if (!inlet.port.empty()) {
        throw CaseError(fmt::format("{}: inlets.{}.port: '{}' names an equipment port, but the case has no "
                                    "`equipment:` section; give the inlet a `region` instead",
                                    inlet.location.str(), inlet.name, inlet.port));
      }
    return;
  }
  // The generators check openings and beds against the largest particle the case feeds.
  spec.equipment->largest_particle = largest_particle(spec);
  const EquipmentSpec& equipment = *spec.equipment;
  Generated made = generate(equipment);
  const auto clash = [&](const std::string& what, const std::string& name) {
    throw CaseError(fmt::format("{}: equipment.{}: generates the {} '{}', but the case already has one of that "
                                "name; rename the case's {}", equipment.location.str(), equipment.type, what, name, what));
  };
  std::set<std::string> names;
  for (const MeshWallSpec& m : spec.meshes) names.insert(m.name);
  for (const PlaneWallSpec& p : spec.planes) names.insert(p.name);
  for (MeshWallSpec& m : made.meshes) {
    if (!names.insert(m.name).second) clash("mesh", m.name);
    m.location = equipment.location;
    spec.meshes.push_back(std::move(m));
  }
  for (PlaneWallSpec& p : made.planes) {
    if (!names.insert(p.name).second) clash("wall", p.name);
    p.location = equipment.location;
    spec.planes.push_back(std::move(p));
  }
  names.clear();
  for (const OutletSpec& o : spec.outlets) names.insert(o.name);
  for (OutletSpec& o : made.outlets) {
    if (!names.insert(o.name).second) clash("outlet", o.name);
    o.location = equipment.location;
    spec.outlets.push_back(std::move(o));
  }
  names.clear();
  for (const SensorSpec& s : spec.sensors) names.insert(s.name);
  for (SensorSpec& s : made.sensors) {
    if (!names.insert(s.name).second) clash("sensor", s.name);
    s.location = equipment.location;
    spec.sensors.push_back(std::move(s));
  }
  for (InletSpec& inlet : spec.inlets) {
    if (inlet.port.empty()) continue;
    const auto port = std::find_if(made.ports.begin(), made.ports.end(), [&](const Port& p) { return p.name == inlet.port; });
    if (port == made.ports.end()) {
      std::vector<std::string> valid;
      for (const Port& p : made.ports) valid.push_back(p.name);
      const std::string hint = nearest_word(inlet.port, valid);
      throw CaseError(fmt::format("{}: inlets.{}.port: '{}' is not a port of the {}{}; valid: {}", inlet.location.str(),
                                  inlet.name, inlet.port, equipment.type,
                                  hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint),
                                  valid.empty() ? "(none)" : join(valid)));
    }
    inlet.region_min = port->region_min, inlet.region_max = port->region_max;
    if (inlet.velocity.isZero(0.0)) inlet.velocity = port->velocity;
  }
  if (!spec.simulation.has_domain) {
    spec.simulation.has_domain = true;
    spec.simulation.domain_min = made.domain_min, spec.simulation.domain_max = made.domain_max;
  }
  spec.design = made.design;
  spec.equipment_camera = made.camera;
}

std::vector<std::string> write_equipment_meshes(const CaseSpec& spec, const std::string& directory) {
  namespace fs = std::filesystem;
  fs::create_directories(directory);
  std::vector<std::string> paths;
  for (const MeshWallSpec& mesh : spec.meshes) {
    if (mesh.triangles.empty()) continue;
    // File names keep letters, digits, '-' and '_' of the mesh name.
    std::string stem = mesh.name;
    for (char& c : stem)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_')) c = '_';
    const fs::path path = fs::path(directory) / (stem + ".stl");
    std::ofstream out(path, std::ios::binary);
    if (!out) throw std::runtime_error(fmt::format("cannot write {}", path.string()));
    // Binary STL: 80-byte header, triangle count, then per triangle normal, 3 vertices (float32)
    // and a 2-byte attribute: 84 + 50 n bytes.
    char header[80] = {};
    const std::string title = fmt::format("demdesign equipment mesh {}", mesh.name);
    std::memcpy(header, title.data(), std::min<size_t>(title.size(), sizeof header));
    out.write(header, sizeof header);
    const std::uint32_t count = static_cast<std::uint32_t>(mesh.triangles.size());
    out.write(reinterpret_cast<const char*>(&count), 4);
    for (const auto& t : mesh.triangles) {
      const auto corner = [&](int k) {
        const auto& v = mesh.vertices.at(static_cast<size_t>(t[k]));
        return Vec3(v[0], v[1], v[2]);
      };
      const Vec3 a = corner(0), b = corner(1), c = corner(2);
      Vec3 normal = (b - a).cross(c - a);
      if (normal.norm() > 0) normal.normalize();
      float values[12];
      for (int k = 0; k < 3; ++k) {
        values[k] = float(normal[k]), values[3 + k] = float(a[k]), values[6 + k] = float(b[k]), values[9 + k] = float(c[k]);
      }
      out.write(reinterpret_cast<const char*>(values), sizeof values);
      const std::uint16_t attribute = 0;
      out.write(reinterpret_cast<const char*>(&attribute), 2);
    }
    if (!out) throw std::runtime_error(fmt::format("cannot write {}", path.string()));
    paths.push_back(path.string());
  }
  return paths;
}

}  // namespace dem::equipment
