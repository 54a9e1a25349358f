// Reading a case's walls into the CaseSpec: the equipment section a generator expands into
// meshes, mesh walls (a file or inline triangles, their motion and surface velocity) and
// analytic walls (planes and cylinders, servo walls).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <numbers>

#include "case/spec.h"
#include "case/spec_reading.h"
#include "case/yaml_check.h"

namespace dem::spec_reading {

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
  m.active_from = map.number("active_from", 0.0, 0.0, 1e9, "s");
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

PlaneWallSpec read_wall(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("walls[{}]", index));
  PlaneWallSpec w;
  w.location = map.location();
  w.name = map.string("name", fmt::format("wall{}", index));
  w.material = map.required_string("material", "name one of the case's materials");
  const YAML::Node plane = map.node("plane"), cylinder = map.node("cylinder"), disc = map.node("disc"), tube = map.node("tube");
  if (int(bool(plane)) + int(bool(cylinder)) + int(bool(disc)) + int(bool(tube)) != 1)
    map.fail("plane", "give one of plane: {point, normal}, cylinder: {point, axis, radius} (particles inside), "
                      "disc: {point, normal, radius, hole_radius} or tube: {point, axis, radius, length} (both sides); "
                      "CAD walls go under `meshes:`");
  if (plane) {
    MapReader p(plane, file, map.key_path("plane"));
    w.point = p.vec3("point", w.point);
    w.normal = p.vec3("normal", w.normal);
    if (w.normal.norm() < 1e-12) p.fail("normal", "must not be zero");
    w.normal.normalize();
    p.finish();
  } else if (disc) {
    MapReader c(disc, file, map.key_path("disc"));
    w.shape = PlaneWallSpec::Shape::disc;
    w.point = c.vec3("point", w.point);
    w.normal = c.vec3("normal", w.normal);
    if (w.normal.norm() < 1e-12) c.fail("normal", "must not be zero");
    w.normal.normalize();
    w.radius = c.required_number("radius", 1e-6, 1e4, "m");
    w.hole_radius = c.number("hole_radius", 0.0, 0.0, 1e4, "m");
    if (w.hole_radius >= w.radius) c.fail("hole_radius", fmt::format("{:g} m is not inside the radius {:g} m", w.hole_radius, w.radius));
    c.finish();
  } else {
    MapReader c(cylinder ? cylinder : tube, file, map.key_path(cylinder ? "cylinder" : "tube"));
    w.shape = cylinder ? PlaneWallSpec::Shape::cylinder : PlaneWallSpec::Shape::tube;
    w.point = c.vec3("point", w.point);
    w.normal = c.vec3("axis", w.normal);
    if (w.normal.norm() < 1e-12) c.fail("axis", "must not be zero");
    w.normal.normalize();
    w.radius = c.required_number("radius", 1e-6, 1e4, "m");
    if (tube) w.length = c.required_number("length", 1e-6, 1e4, "m");
    c.finish();
  }
  w.velocity = map.vec3("velocity", w.velocity);
  w.spin = map.number("spin", 0.0, -1e4, 1e4, "rad/s");
  if (const YAML::Node servo = map.node("servo")) {
    if (w.shape != PlaneWallSpec::Shape::plane) map.fail("servo", "only plane walls can be servo-controlled");
    MapReader sv(servo, file, map.key_path("servo"));
    w.has_servo = true;
    w.servo.target_stress = sv.required_number("target_stress", 1e-6, 1e12, "Pa");
    w.servo.area = sv.number("area", 0.0, 0.0, 1e6, "m^2");
    w.servo.max_speed = sv.number("max_speed", 0.0, 0.0, 1e3, "m/s");
    sv.finish();
    if (std::abs(w.velocity.dot(w.normal)) > 0) map.fail("velocity", "a servo wall sets its own normal speed; give only a tangential velocity");
    if (w.spin != 0) map.fail("spin", "a servo wall cannot also turn; give one of them");
  }
  map.finish();
  return w;
}

}  // namespace dem::spec_reading
