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

Generated belt_conveyor(MapReader& reader, const EquipmentSpec& spec) {
  const Materials materials = read_materials(reader);
  const double length = reader.number("length", 8.0, 1.0, 500.0, "m");
  const double width = reader.number("width", 0.8, 0.3, 3.0, "m");
  const double speed = reader.number("speed", 2.0, 0.05, 10.0, "m/s");
  const double trough = radians(reader.number("troughing_angle_deg", 30.0, 0.0, 45.0, "deg"));
  const double inclination = reader.number("inclination_deg", 0.0, -20.0, 20.0, "deg");
  const double pulley_radius = 0.5 * reader.number("pulley_diameter", 0.5, 0.1, 2.0, "m");
  const double belt_thickness = reader.number("belt_thickness", 0.015, 0.0, 0.1, "m");
  const double load_height = reader.number("load_height", 0.1, 0.01, 1.0, "m");
  const double transition = reader.number("transition_length", std::min(0.8, 0.3 * length), 0.0, 0.5 * length, "m");
  MapReader idler = sub_map(reader, "idler");
  const double spacing = idler.number("spacing", 1.2, 0.3, 5.0, "m");
  const double roll_radius = 0.5 * idler.number("roll_diameter", 0.127, 0.05, 0.3, "m");
  idler.finish();
  MapReader skirt = sub_map(reader, "skirt");
  const double skirt_width = skirt.number("width", 2.0 / 3.0 * width, 0.1, width, "m");
  const double skirt_start = skirt.number("start", 0.2, 0.0, 0.5 * length, "m");
  const double skirt_length = skirt.number("length", std::min(2.0, 0.4 * length), 0.1, length - skirt_start, "m");
  const double skirt_height = skirt.number("height", 0.3, 0.05, 2.0, "m");
  skirt.finish();
  const double margin = reader.number("margin", 0.5, 0.0, 10.0, "m");
  const SourceLocation& where = spec.location;
  const double tilt_angle = radians(inclination);
  Eigen::Matrix3d tilt;  // raises the head end: x -> (cos, 0, sin)
  tilt << std::cos(tilt_angle), 0, -std::sin(tilt_angle), 0, 1, 0, std::sin(tilt_angle), 0, std::cos(tilt_angle);
  const Vec3 along = tilt * Vec3::UnitX();
  const double centre = kCentreRollFraction * width, wing = 0.5 * (width - centre);

  Generated out;
  out.camera = "side";
  // Belt: profile across, x along; wings flatten over the transition.
  {
    MeshBuilder belt;
    const auto profile = trough_profile(width, trough, kCell);
    const int across = static_cast<int>(profile.size()) - 1, pieces = segments(length, kCell);
    belt.grid([&](double w, double u) {
      const double x = w * length;
      const auto [y, h] = profile[static_cast<size_t>(std::lround(u * across))];
      const double angle = transition > 0 ? trough * std::clamp((length - x) / transition, 0.0, 1.0) : trough;
      if (std::abs(y) <= 0.5 * centre + 1e-12) return Vec3(x, y, 0);
      const double distance = (std::abs(y) - 0.5 * centre) / std::max(std::cos(trough), 1e-12);
      return Vec3(x, std::copysign(0.5 * centre + distance * std::cos(angle), y), distance * std::sin(angle));
    }, pieces, across);
    belt.transform(tilt, Vec3::Zero());
    MeshWallSpec wall = belt.wall("belt", materials.belt, where);
    wall.surface.kind = SurfaceVelocitySpec::Kind::linear;
    wall.surface.velocity = speed * along;
    out.meshes.push_back(std::move(wall));
  }
  // Head and tail pulleys: omega = V / R_p about +y moves the top +x (omega y x R z = omega R x).
  for (const double x : {0.0, length}) {
    MeshBuilder pulley;
    cylinder(pulley, Vec3(x, -0.5 * width, -pulley_radius), Vec3(x, 0.5 * width, -pulley_radius), pulley_radius,
             segments(2 * kPi * pulley_radius, 0.08, 24), true);
    pulley.transform(tilt, Vec3::Zero());
    MeshWallSpec wall = pulley.wall(x > 0 ? "head_pulley" : "tail_pulley", materials.belt, where);
    wall.surface.kind = SurfaceVelocitySpec::Kind::rotation;
    wall.surface.axis = Vec3::UnitY();
    wall.surface.point = tilt * Vec3(x, 0, -pulley_radius);
    wall.surface.angular_speed = speed / pulley_radius;
    out.meshes.push_back(std::move(wall));
  }
  // Idler rolls under the troughed part: centre roll and two wing rolls per station.
  {
    MeshBuilder rolls;
    const double below = belt_thickness + roll_radius;  // [m] roll axis below the belt surface
    for (double x = spacing; x < length - transition - 0.5 * spacing + 1e-9; x += spacing) {
      const Vec3 down(0, 0, -below);
      cylinder(rolls, Vec3(x, -0.5 * centre, 0) + down, Vec3(x, 0.5 * centre, 0) + down, roll_radius, 12, true);
      for (const int side : {-1, 1}) {
        const Vec3 inner(x, side * 0.5 * centre, 0);
        const Vec3 outward(0, side * std::cos(trough), std::sin(trough));
        const Vec3 normal(0, -side * std::sin(trough), std::cos(trough));  // belt surface normal on the wing
        cylinder(rolls, inner - below * normal, inner + wing * outward - below * normal, roll_radius, 12, true);
      }
    }
    rolls.transform(tilt, Vec3::Zero());
    if (!rolls.triangles.empty()) out.meshes.push_back(rolls.wall("idlers", materials.liner, where));
  }
  // Skirts with a back plate at their start.
  {
    MeshBuilder skirts;
    const double y = 0.5 * skirt_width;
    const double bottom = trough_height(width, trough, y) + 0.01;
    const double x0 = skirt_start, x1 = skirt_start + skirt_length, top = bottom + skirt_height;
    skirts.quad(Vec3(x0, -y, bottom), Vec3(x1, -y, bottom), Vec3(x1, -y, top), Vec3(x0, -y, top));
    skirts.quad(Vec3(x0, y, bottom), Vec3(x0, y, top), Vec3(x1, y, top), Vec3(x1, y, bottom));
    skirts.quad(Vec3(x0, -y, 0.01), Vec3(x0, -y, top), Vec3(x0, y, top), Vec3(x0, y, 0.01));
    skirts.transform(tilt, Vec3::Zero());
    out.meshes.push_back(skirts.wall("skirts", materials.liner, where));
  }
  // Loading port between the skirts near the tail: 70 % of the belt width (inside the skirts),
  // above the wing tops so that no particle is inserted into the belt, long enough to take a
  // batch at the design rate; material arrives at belt speed, as from a loading chute.
  const double port_x = skirt_start + 0.1;
  {
    const double half = std::min(0.35 * width, 0.5 * skirt_width - 0.02);
    const double bottom = trough_height(width, trough, half) + 0.01;
    const auto [lo, hi] = rotated_box(tilt, Vec3(port_x, -half, bottom),
                                      Vec3(port_x + std::min(1.0, skirt_length - 0.2), half, bottom + 0.25));
    out.ports.push_back({"loading", lo, hi, speed * along});
  }
  // Outlet: below and beyond the head pulley where the stream lands.
  const Vec3 head = tilt * Vec3(length, 0, -pulley_radius);
  OutletSpec discharge;
  discharge.name = "discharge";
  discharge.region_min = Vec3(head.x() - pulley_radius, -0.5 * width - 0.5, head.z() - 1.5);
  discharge.region_max = Vec3(head.x() + 0.6 * speed + 1.0, 0.5 * width + 0.5, head.z() - pulley_radius - 0.1);
  out.outlets.push_back(discharge);
  SensorSpec on_belt;
  on_belt.kind = SensorSpec::Kind::plane, on_belt.name = "on_belt";
  on_belt.point = tilt * Vec3(0.5 * length, 0, 0), on_belt.normal = along;
  std::tie(on_belt.region_min, on_belt.region_max) =
      rotated_box(tilt, Vec3(0.5 * length - 0.1, -0.5 * width, -0.05), Vec3(0.5 * length + 0.1, 0.5 * width, 0.6));
  out.sensors.push_back(on_belt);
  SensorSpec loading;
  loading.kind = SensorSpec::Kind::box, loading.name = "loading_zone", loading.across = Vec3::UnitY();
  std::tie(loading.region_min, loading.region_max) =
      rotated_box(tilt, Vec3(skirt_start, -0.5 * width, -0.05), Vec3(skirt_start + skirt_length, 0.5 * width, 0.5));
  out.sensors.push_back(loading);
  set_domain(out, margin, head.z() - 2.0);

  // CEMA discharge at the head pulley.
  const double radius = pulley_radius + belt_thickness + 0.5 * load_height;  // [m]
  const double ratio = speed * speed / (kGravity * radius);
  const bool at_tangent = ratio >= std::cos(tilt_angle);
  const double release = at_tangent ? tilt_angle : std::acos(std::min(ratio, 1.0));  // [rad] from vertical
  out.design = {
      {"belt_speed_m_s", speed},
      {"belt_width_m", width},
      {"length_m", length},
      {"troughing_angle_deg", trough * 180 / kPi},
      {"inclination_deg", inclination},
      {"pulley_diameter_m", 2 * pulley_radius},
      {"discharge_radius_m", radius},
      {"discharge_ratio_v2_gr", ratio},
      {"discharge_at_tangent", at_tangent ? 1.0 : 0.0},
      {"discharge_angle_from_vertical_deg", (at_tangent ? 0.0 - tilt_angle : release) * 180 / kPi},  // negative: before top dead centre
      {"idler_spacing_m", spacing},
      {"skirt_width_m", skirt_width},
  };
  return out;
}

}  // namespace dem::equipment::detail
