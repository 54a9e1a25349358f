// Troughed belt conveyor: belt on 3-roll idlers from the tail (x = 0) to the head pulley (top at
// x = length), optionally inclined (head raised by inclination_deg about y through the origin).
//
// Layout (local, before inclination): belt centre surface z = 0, troughed at troughing_angle_deg
// and flattening linearly over the transition_length before the head pulley (axis along y through
// (length, 0, -R_p)). Idler stations every idler.spacing from the tail up to the transition:
// a centre roll and two wing rolls of idler.roll_diameter under the belt (static meshes for the
// renders; particles do not reach them). Skirts at y = +-skirt.width/2 from skirt.start for
// skirt.length with a back plate across at the start; the loading port is between them, above
// the wing tops (no particle is inserted into the belt), and feeds at belt speed.
// CEMA discharge: r = R_p + belt_thickness + a1 with a1 = load_height / 2; with V^2 / (g r) >=
// cos(inclination) the material leaves at the tangent point, otherwise at the angle from vertical
// where cos(angle) = V^2 / (g r) (CEMA, Belt Conveyors for Bulk Materials, 7th ed., ch. 12).
#include <fmt/format.h>

#include "generators.h"

namespace dem::equipment::detail {

namespace {

/// A belt conveyor's parameters as read (defaults filled in), and the tilt and roll widths that
/// follow from them.
struct ConveyorLayout {
  Materials materials;
  double length = 0, width = 0;                                                    // [m]
  double speed = 0;                                                                // [m/s]
  double trough = 0;                                                               // [rad] wing angle
  double inclination = 0;                                                          // [deg]
  double pulley_radius = 0, belt_thickness = 0, load_height = 0, transition = 0;  // [m]
  double spacing = 0, roll_radius = 0;                                             // [m] idlers
  double skirt_width = 0, skirt_start = 0, skirt_length = 0, skirt_height = 0;    // [m]
  double margin = 0;                                                               // [m]
  double tilt_angle = 0;                                                           // [rad]
  Eigen::Matrix3d tilt = Eigen::Matrix3d::Identity();  // raises the head end: x -> (cos, 0, sin)
  Vec3 along = Vec3::UnitX();                          // belt direction, tilted
  double centre = 0, wing = 0;                         // [m] centre roll and wing widths across
};

/// Reads every parameter (the reader records the keys, in this order, for the case-key reference),
/// then derives the tilt and the roll widths.
ConveyorLayout read_layout(MapReader& reader) {
  ConveyorLayout c;
  c.materials = read_materials(reader);
  c.length = reader.number("length", 8.0, 1.0, 500.0, "m");
  c.width = reader.number("width", 0.8, 0.3, 3.0, "m");
  c.speed = reader.number("speed", 2.0, 0.05, 10.0, "m/s");
  c.trough = radians(reader.number("troughing_angle_deg", 30.0, 0.0, 45.0, "deg"));
  c.inclination = reader.number("inclination_deg", 0.0, -20.0, 20.0, "deg");
  c.pulley_radius = 0.5 * reader.number("pulley_diameter", 0.5, 0.1, 2.0, "m");
  c.belt_thickness = reader.number("belt_thickness", 0.015, 0.0, 0.1, "m");
  c.load_height = reader.number("load_height", 0.1, 0.01, 1.0, "m");
  c.transition = reader.number("transition_length", std::min(0.8, 0.3 * c.length), 0.0, 0.5 * c.length, "m");
  MapReader idler = sub_map(reader, "idler");
  c.spacing = idler.number("spacing", 1.2, 0.3, 5.0, "m");
  c.roll_radius = 0.5 * idler.number("roll_diameter", 0.127, 0.05, 0.3, "m");
  idler.finish();
  MapReader skirt = sub_map(reader, "skirt");
  c.skirt_width = skirt.number("width", 2.0 / 3.0 * c.width, 0.1, c.width, "m");
  c.skirt_start = skirt.number("start", 0.2, 0.0, 0.5 * c.length, "m");
  c.skirt_length = skirt.number("length", std::min(2.0, 0.4 * c.length), 0.1, c.length - c.skirt_start, "m");
  c.skirt_height = skirt.number("height", 0.3, 0.05, 2.0, "m");
  skirt.finish();
  c.margin = reader.number("margin", 0.5, 0.0, 10.0, "m");

  c.tilt_angle = radians(c.inclination);
  c.tilt << std::cos(c.tilt_angle), 0, -std::sin(c.tilt_angle), 0, 1, 0, std::sin(c.tilt_angle), 0,
      std::cos(c.tilt_angle);
  c.along = c.tilt * Vec3::UnitX();
  c.centre = kCentreRollFraction * c.width, c.wing = 0.5 * (c.width - c.centre);
  return c;
}

/// Belt: profile across, x along; wings flatten over the transition.
void add_belt(const ConveyorLayout& c, const SourceLocation& where, Generated& out) {
  MeshBuilder belt;
  const auto profile = trough_profile(c.width, c.trough, kCell);
  const int across = static_cast<int>(profile.size()) - 1, pieces = segments(c.length, kCell);
  belt.grid([&](double w, double u) {
    const double x = w * c.length;
    const auto [y, h] = profile[static_cast<size_t>(std::lround(u * across))];
    const double angle = c.transition > 0 ? c.trough * std::clamp((c.length - x) / c.transition, 0.0, 1.0) : c.trough;
    if (std::abs(y) <= 0.5 * c.centre + 1e-12) return Vec3(x, y, 0);
    const double distance = (std::abs(y) - 0.5 * c.centre) / std::max(std::cos(c.trough), 1e-12);
    return Vec3(x, std::copysign(0.5 * c.centre + distance * std::cos(angle), y), distance * std::sin(angle));
  }, pieces, across);
  belt.transform(c.tilt, Vec3::Zero());
  MeshWallSpec wall = belt.wall("belt", c.materials.belt, where);
  wall.surface.kind = SurfaceVelocitySpec::Kind::linear;
  wall.surface.velocity = c.speed * c.along;
  out.meshes.push_back(std::move(wall));
}

/// Head and tail pulleys: omega = V / R_p about +y moves the top +x (omega y x R z = omega R x).
void add_pulleys(const ConveyorLayout& c, const SourceLocation& where, Generated& out) {
  for (const double x : {0.0, c.length}) {
    MeshBuilder pulley;
    cylinder(pulley, Vec3(x, -0.5 * c.width, -c.pulley_radius), Vec3(x, 0.5 * c.width, -c.pulley_radius),
             c.pulley_radius, segments(2 * kPi * c.pulley_radius, 0.08, 24), true);
    pulley.transform(c.tilt, Vec3::Zero());
    MeshWallSpec wall = pulley.wall(x > 0 ? "head_pulley" : "tail_pulley", c.materials.belt, where);
    wall.surface.kind = SurfaceVelocitySpec::Kind::rotation;
    wall.surface.axis = Vec3::UnitY();
    wall.surface.point = c.tilt * Vec3(x, 0, -c.pulley_radius);
    wall.surface.angular_speed = c.speed / c.pulley_radius;
    out.meshes.push_back(std::move(wall));
  }
}

/// Idler rolls under the troughed part: centre roll and two wing rolls per station.
void add_idlers(const ConveyorLayout& c, const SourceLocation& where, Generated& out) {
  MeshBuilder rolls;
  const double below = c.belt_thickness + c.roll_radius;  // [m] roll axis below the belt surface
  for (double x = c.spacing; x < c.length - c.transition - 0.5 * c.spacing + 1e-9; x += c.spacing) {
    const Vec3 down(0, 0, -below);
    cylinder(rolls, Vec3(x, -0.5 * c.centre, 0) + down, Vec3(x, 0.5 * c.centre, 0) + down, c.roll_radius, 12, true);
    for (const int side : {-1, 1}) {
      const Vec3 inner(x, side * 0.5 * c.centre, 0);
      const Vec3 outward(0, side * std::cos(c.trough), std::sin(c.trough));
      const Vec3 normal(0, -side * std::sin(c.trough), std::cos(c.trough));  // belt surface normal on the wing
      cylinder(rolls, inner - below * normal, inner + c.wing * outward - below * normal, c.roll_radius, 12, true);
    }
  }
  rolls.transform(c.tilt, Vec3::Zero());
  if (!rolls.triangles.empty()) out.meshes.push_back(rolls.wall("idlers", c.materials.liner, where));
}

/// Skirts with a back plate at their start.
void add_skirts(const ConveyorLayout& c, const SourceLocation& where, Generated& out) {
  MeshBuilder skirts;
  const double y = 0.5 * c.skirt_width;
  const double bottom = trough_height(c.width, c.trough, y) + 0.01;
  const double x0 = c.skirt_start, x1 = c.skirt_start + c.skirt_length, top = bottom + c.skirt_height;
  skirts.quad(Vec3(x0, -y, bottom), Vec3(x1, -y, bottom), Vec3(x1, -y, top), Vec3(x0, -y, top));
  skirts.quad(Vec3(x0, y, bottom), Vec3(x0, y, top), Vec3(x1, y, top), Vec3(x1, y, bottom));
  skirts.quad(Vec3(x0, -y, 0.01), Vec3(x0, -y, top), Vec3(x0, y, top), Vec3(x0, y, 0.01));
  skirts.transform(c.tilt, Vec3::Zero());
  out.meshes.push_back(skirts.wall("skirts", c.materials.liner, where));
}

/// Loading port between the skirts near the tail: 70 % of the belt width (inside the skirts),
/// above the wing tops so that no particle is inserted into the belt, long enough to take a
/// batch at the design rate; material arrives at belt speed, as from a loading chute.
void add_loading_port(const ConveyorLayout& c, Generated& out) {
  const double port_x = c.skirt_start + 0.1;
  const double half = std::min(0.35 * c.width, 0.5 * c.skirt_width - 0.02);
  const double bottom = trough_height(c.width, c.trough, half) + 0.01;
  const auto [lo, hi] = rotated_box(c.tilt, Vec3(port_x, -half, bottom),
                                    Vec3(port_x + std::min(1.0, c.skirt_length - 0.2), half, bottom + 0.25));
  out.ports.push_back({"loading", lo, hi, c.speed * c.along});
}

/// Outlet: below and beyond the head pulley (axis at `head`) where the stream lands.
void add_discharge_outlet(const ConveyorLayout& c, const Vec3& head, Generated& out) {
  OutletSpec discharge;
  discharge.name = "discharge";
  discharge.region_min = Vec3(head.x() - c.pulley_radius, -0.5 * c.width - 0.5, head.z() - 1.5);
  discharge.region_max = Vec3(head.x() + 0.6 * c.speed + 1.0, 0.5 * c.width + 0.5, head.z() - c.pulley_radius - 0.1);
  out.outlets.push_back(discharge);
}

/// Sensors: flow across the belt halfway along it; load in the loading zone between the skirts.
void add_sensors(const ConveyorLayout& c, Generated& out) {
  SensorSpec on_belt;
  on_belt.kind = SensorSpec::Kind::plane, on_belt.name = "on_belt";
  on_belt.point = c.tilt * Vec3(0.5 * c.length, 0, 0), on_belt.normal = c.along;
  std::tie(on_belt.region_min, on_belt.region_max) = rotated_box(
      c.tilt, Vec3(0.5 * c.length - 0.1, -0.5 * c.width, -0.05), Vec3(0.5 * c.length + 0.1, 0.5 * c.width, 0.6));
  out.sensors.push_back(on_belt);
  SensorSpec loading;
  loading.kind = SensorSpec::Kind::box, loading.name = "loading_zone", loading.across = Vec3::UnitY();
  std::tie(loading.region_min, loading.region_max) =
      rotated_box(c.tilt, Vec3(c.skirt_start, -0.5 * c.width, -0.05),
                  Vec3(c.skirt_start + c.skirt_length, 0.5 * c.width, 0.5));
  out.sensors.push_back(loading);
}

/// CEMA discharge at the head pulley, with the design values the report shows.
void set_design(const ConveyorLayout& c, Generated& out) {
  const double radius = c.pulley_radius + c.belt_thickness + 0.5 * c.load_height;  // [m]
  const double ratio = c.speed * c.speed / (kGravity * radius);
  const bool at_tangent = ratio >= std::cos(c.tilt_angle);
  const double release = at_tangent ? c.tilt_angle : std::acos(std::min(ratio, 1.0));  // [rad] from vertical
  out.design = {
      {"belt_speed_m_s", c.speed},
      {"belt_width_m", c.width},
      {"length_m", c.length},
      {"troughing_angle_deg", c.trough * 180 / kPi},
      {"inclination_deg", c.inclination},
      {"pulley_diameter_m", 2 * c.pulley_radius},
      {"discharge_radius_m", radius},
      {"discharge_ratio_v2_gr", ratio},
      {"discharge_at_tangent", at_tangent ? 1.0 : 0.0},
      {"discharge_angle_from_vertical_deg", (at_tangent ? 0.0 - c.tilt_angle : release) * 180 / kPi},  // negative: before top dead centre
      {"idler_spacing_m", c.spacing},
      {"skirt_width_m", c.skirt_width},
  };
}

}  // namespace

Generated belt_conveyor(MapReader& reader, const EquipmentSpec& spec) {
  const ConveyorLayout c = read_layout(reader);
  const SourceLocation& where = spec.location;
  Generated out;
  out.camera = "side";

  add_belt(c, where, out);
  add_pulleys(c, where, out);
  add_idlers(c, where, out);
  add_skirts(c, where, out);

  add_loading_port(c, out);
  const Vec3 head = c.tilt * Vec3(c.length, 0, -c.pulley_radius);  // head pulley axis
  add_discharge_outlet(c, head, out);
  add_sensors(c, out);
  set_domain(out, c.margin, head.z() - 2.0);

  set_design(c, out);
  return out;
}

}  // namespace dem::equipment::detail
