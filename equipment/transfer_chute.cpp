// Inline belt-to-belt transfer: troughed feed belt over a head pulley, a hood that catches the
// trajectory, a spoon that turns the stream onto the receiving belt, side and back plates,
// skirts. Everything lies in the x-z plane and is extruded along y about y = 0.
//
// Layout rules (defaults in brackets; all lengths in metres):
//  - Feed belt surface at z = drop_height [1.5] from x = -feed_belt.length [3] to the head pulley
//    top at x = 0; troughed [30 deg] and flattening linearly over the last transition_length [0.8].
//  - Head pulley: axis along y through (0, drop_height - R_p); surface turns at +speed / R_p about
//    +y (omega y x R z = omega R x: its top moves +x with the belt).
//  - Hood: arc of hood.radius [1.0] with its top (horizontal tangent) hood.top_height
//    [load_height + 0.15 = 0.25] above the feed belt, its vertical tangent hood.distance from the
//    pulley axis. The default distance puts the point 30 deg above the arc centre on the CEMA
//    high-speed trajectory z = drop_height - g x^2 / (2 V^2) (material leaving at top dead
//    centre), so the stream meets the hood at a glancing angle; when that point lies less than
//    0.05 m below the belt the impact point moves down to 0.05 m below it.
//  - The hood runs down past vertical to hood.exit_angle_deg [15] (heading down and back, -x),
//    cut shorter when its end would be lower than 0.15 spoon.radius + 0.05 above the spoon lip
//    (the spoon keeps at least a 32 deg arc); an error when that leaves less than 5 deg of hood
//    below the impact point.
//  - Spoon: arc of spoon.radius [0.8] from vertical (at its back, -x) to spoon.exit_angle_deg [15]
//    before horizontal at its lip, spoon.lip_height [0.15] above the receiving belt. Its top edge lies spoon.setback [0.15]
//    behind (-x of) the hood exit and at most 0.05 below it: when the full quarter would reach
//    higher, the arc starts lower (its vertical-tangent point is then virtual, above the top
//    edge). A vertical back plate rises from the spoon top edge to 0.1 above the hood exit.
//  - Side plates at y = +-chute_width/2 [0.7] from x = -R_p - 0.2 to 0.1 past the hood or the
//    spoon lip, from just above the receiving belt surface there to 0.05 above the hood top; a
//    roof closes the gap between the chute's back and the hood top.
//  - Receiving belt surface at z = 0 from the spoon lip - tail_length [to 0.5 behind the chute]
//    to the lip + length [3]; skirts at y = +-skirt_width/2 [min(chute_width, 0.9 width)] from
//    0.05 behind the lip for skirt_length [1.5], skirt_height [0.3] high.
#include <fmt/format.h>

#include "generators.h"

namespace dem::equipment {

namespace detail {

namespace {

/// [m] cell size of the chute's surfaces: finer than kCell so that the curved liners follow their
/// arcs and a chute has a few thousand triangles.
constexpr double kChuteCell = 0.12;

TransferChuteLayout read_layout(MapReader& reader) {
  TransferChuteLayout c;
  c.drop_height = reader.number("drop_height", 1.5, 0.3, 20.0, "m");
  c.chute_width = reader.number("chute_width", 0.7, 0.1, 5.0, "m");

  MapReader feed = sub_map(reader, "feed_belt");
  c.feed_width = feed.number("width", 0.8, 0.3, 3.0, "m");
  c.feed_speed = feed.number("speed", 2.5, 0.1, 10.0, "m/s");
  c.feed_length = feed.number("length", 3.0, 1.0, 50.0, "m");
  c.feed_trough = radians(feed.number("troughing_angle_deg", 30.0, 0.0, 45.0, "deg"));
  c.transition_length = feed.number("transition_length", 0.8, 0.0, c.feed_length - 0.5, "m");
  c.pulley_radius = 0.5 * feed.number("pulley_diameter", 0.5, 0.1, 2.0, "m");
  c.load_height = feed.number("load_height", 0.1, 0.01, 1.0, "m");
  c.feed_port_height = feed.number("port_height", 0.25, 0.01, 2.0, "m");
  feed.finish();

  MapReader hood = sub_map(reader, "hood");
  c.hood_radius = hood.number("radius", 1.0, 0.2, 5.0, "m");
  c.hood_top_height = hood.number("top_height", c.load_height + 0.15, 0.05, c.hood_radius, "m");
  c.hood_exit_angle = radians(hood.number("exit_angle_deg", 15.0, 0.0, 60.0, "deg"));
  // Default distance: the arc point 30 deg above the centre lies on the high-speed trajectory.
  const double rise = std::sin(radians(30.0));
  const double drop = std::max(c.hood_radius * (1 - rise) - c.hood_top_height, 0.05);  // [m] below the belt
  const double impact_sine = (c.hood_radius - c.hood_top_height - drop) / c.hood_radius;
  const double impact_x = c.feed_speed * std::sqrt(2 * drop / kGravity);
  const double fitted = impact_x - c.hood_radius * std::sqrt(1 - impact_sine * impact_sine) + c.hood_radius;
  c.hood_distance = hood.number("distance", std::max(fitted, 0.05), 0.05, 10.0, "m");
  // The hood must reach at least 5 deg below the impact point (45 deg above its centre when the
  // distance is given).
  const double lowest_end = hood.has("distance") ? radians(45.0) : std::asin(impact_sine) - radians(5.0);
  hood.finish();

  MapReader spoon = sub_map(reader, "spoon");
  c.spoon_radius = spoon.number("radius", 0.8, 0.2, 5.0, "m");
  c.spoon_lip_height = spoon.number("lip_height", 0.15, 0.02, 2.0, "m");
  c.spoon_setback = spoon.number("setback", 0.15, 0.0, 1.0, "m");
  // The arc ends this far before its lowest point, so the stream leaves the lip sloping down onto
  // the belt instead of having to be pushed out of a flat bottom (a dead bed forms there).
  c.spoon_exit_angle = radians(spoon.number("exit_angle_deg", 15.0, 0.0, 45.0, "deg"));
  spoon.finish();

  MapReader receiving = sub_map(reader, "receiving_belt");
  c.receiving_width = receiving.number("width", 0.8, 0.3, 3.0, "m");
  c.receiving_speed = receiving.number("speed", 3.0, 0.1, 10.0, "m/s");
  c.receiving_trough = radians(receiving.number("troughing_angle_deg", 30.0, 0.0, 45.0, "deg"));
  const double length = receiving.number("length", 3.0, 0.5, 50.0, "m");
  c.skirt_width = receiving.number("skirt_width", std::min(c.chute_width, 0.9 * c.receiving_width), 0.1,
                                   c.receiving_width, "m");
  c.skirt_length = receiving.number("skirt_length", 1.5, 0.0, length, "m");
  c.skirt_height = receiving.number("skirt_height", 0.3, 0.05, 2.0, "m");

  // Hood: centre below its top by the radius, vertical tangent at hood_distance.
  c.hood_centre_x = c.hood_distance - c.hood_radius;
  c.hood_centre_z = c.drop_height + c.hood_top_height - c.hood_radius;
  const double floor = c.spoon_lip_height + 0.15 * c.spoon_radius + 0.05;  // [m] lowest hood end
  c.hood_end_angle = -c.hood_exit_angle;
  if (c.hood_centre_z + c.hood_radius * std::sin(c.hood_end_angle) < floor) {
    c.hood_end_angle = std::asin(std::clamp((floor - c.hood_centre_z) / c.hood_radius, -1.0, 1.0));
  }
  if (c.hood_end_angle > lowest_end || floor > c.drop_height) {
    reader.fail("drop_height", fmt::format("{:g} m leaves no room for a hood of radius {:g} m above a spoon of radius "
                                           "{:g} m with its lip {:g} m above the receiving belt; valid: a larger drop "
                                           "height, or a smaller hood.radius or spoon.radius",
                                           c.drop_height, c.hood_radius, c.spoon_radius, c.spoon_lip_height));
  }
  c.hood_exit_x = c.hood_centre_x + c.hood_radius * std::cos(c.hood_end_angle);
  c.hood_exit_z = c.hood_centre_z + c.hood_radius * std::sin(c.hood_end_angle);

  // Spoon: top edge `setback` behind the hood exit and at least 0.05 below it.
  c.spoon_centre_z = c.spoon_lip_height + c.spoon_radius * std::cos(c.spoon_exit_angle);
  c.spoon_top_z = std::min(c.spoon_centre_z, c.hood_exit_z - 0.05);
  c.spoon_start_angle = std::acos(std::clamp((c.spoon_centre_z - c.spoon_top_z) / c.spoon_radius, -1.0, 1.0));
  if (c.spoon_start_angle < c.spoon_exit_angle + radians(20.0))
    spoon.fail("exit_angle_deg", fmt::format("leaves a spoon arc of {:.0f} deg under the hood; valid: a smaller exit angle, a "
                                             "smaller spoon radius or a larger drop height",
                                             (c.spoon_start_angle - c.spoon_exit_angle) * 180 / kPi));
  c.spoon_top_x = c.hood_exit_x - c.spoon_setback;
  c.spoon_centre_x = c.spoon_top_x + c.spoon_radius * std::sin(c.spoon_start_angle);
  c.spoon_lip_x = c.spoon_centre_x - c.spoon_radius * std::sin(c.spoon_exit_angle);
  c.back_plate_top = c.hood_exit_z + 0.1;

  // Side plates: from behind the pulley to past the hood and the lip, from the belt to the roof.
  const double hood_front = c.hood_end_angle < 0 ? c.hood_distance : c.hood_exit_x;
  c.side_x_min = -c.pulley_radius - 0.2;
  c.side_x_max = std::max(hood_front, c.spoon_lip_x) + 0.1;
  const double edge = std::min(0.5 * c.chute_width, 0.5 * c.receiving_width);
  c.side_z_min = trough_height(c.receiving_width, c.receiving_trough, edge) + 0.01;
  c.side_z_max = c.drop_height + c.hood_top_height + 0.05;

  const double tail = receiving.number("tail_length", c.spoon_lip_x - c.side_x_min + 0.5, 0.1, 50.0, "m");
  receiving.finish();
  c.receiving_x_min = c.spoon_lip_x - tail;
  c.receiving_x_max = c.spoon_lip_x + length;
  return c;
}

/// A troughed belt from x0 to x1 with surface at z (centre), wing angle trough(x) [rad].
void troughed_belt(MeshBuilder& mesh, double width, double x0, double x1, double z, double max_trough,
                   const std::function<double(double)>& trough) {
  const double centre = kCentreRollFraction * width, wing = 0.5 * (width - centre);
  // Profile stations as (side, distance along the wing); side 0: on the centre roll at y = along.
  std::vector<std::pair<int, double>> stations;
  const auto profile = trough_profile(width, max_trough, kChuteCell);
  for (const auto& [y, height] : profile) {
    if (std::abs(y) <= 0.5 * centre + 1e-12) stations.push_back({0, y});
    else stations.push_back({y > 0 ? 1 : -1, (std::abs(y) - 0.5 * centre) / std::max(std::cos(max_trough), 1e-12)});
  }
  (void)wing;
  const int along = segments(x1 - x0, kChuteCell), across = static_cast<int>(stations.size()) - 1;
  // u across (-y to +y), w along +x: normal (du x dw) = y x x = -z; swap to get +z up.
  mesh.grid([&](double w, double u) {
    const double x = x0 + w * (x1 - x0);
    const auto [side, distance] = stations[static_cast<size_t>(std::lround(u * across))];
    if (side == 0) return Vec3(x, distance, z);
    const double angle = trough(x);
    return Vec3(x, side * (0.5 * centre + distance * std::cos(angle)), z + distance * std::sin(angle));
  }, along, across);
}

/// What every part of the chute is built from: its layout, the materials of its walls, where the
/// case declares it, and the half widths its walls and sensors are placed at.
struct ChuteBuild {
  const TransferChuteLayout& layout;
  const Materials& materials;
  const SourceLocation& where;
  double half;            // [m] half the chute width: the side plates' y
  double receiving_half;  // [m] half the receiving belt's width
};

/// Feed belt, troughed, flattening linearly over the transition before the pulley.
void add_feed_belt(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder belt;
  troughed_belt(belt, c.feed_width, -c.feed_length, 0.0, c.drop_height, c.feed_trough, [&](double x) {
    return c.transition_length > 0 ? c.feed_trough * std::clamp(-x / c.transition_length, 0.0, 1.0) : c.feed_trough;
  });
  MeshWallSpec wall = belt.wall("feed_belt", chute.materials.belt, chute.where);
  wall.surface.kind = SurfaceVelocitySpec::Kind::linear;
  wall.surface.velocity = Vec3(c.feed_speed, 0, 0);
  out.meshes.push_back(std::move(wall));
}

/// Head pulley: omega = +V / R_p about +y moves its top (0, 0, R_p) at omega y x R z = +V x.
void add_head_pulley(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder pulley;
  const double axis_z = c.drop_height - c.pulley_radius;
  cylinder(pulley, Vec3(0, -0.5 * c.feed_width, axis_z), Vec3(0, 0.5 * c.feed_width, axis_z), c.pulley_radius,
           segments(2 * kPi * c.pulley_radius, 0.08, 24), true);
  MeshWallSpec wall = pulley.wall("head_pulley", chute.materials.belt, chute.where);
  wall.surface.kind = SurfaceVelocitySpec::Kind::rotation;
  wall.surface.axis = Vec3::UnitY();
  wall.surface.point = Vec3(0, 0, axis_z);
  wall.surface.angular_speed = c.feed_speed / c.pulley_radius;
  out.meshes.push_back(std::move(wall));
}

/// Hood arc from its top (90 deg) down to its end angle; roof from the chute back to the hood top.
void add_hood(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double half = chute.half;
  MeshBuilder hood;
  const double sweep = kPi / 2 - c.hood_end_angle;
  hood.grid([&](double u, double w) {
    const double angle = kPi / 2 - u * sweep;
    return Vec3(c.hood_centre_x + c.hood_radius * std::cos(angle), -half + w * c.chute_width,
                c.hood_centre_z + c.hood_radius * std::sin(angle));
  }, segments(sweep * c.hood_radius, kChuteCell, 8), segments(c.chute_width, kChuteCell));
  const double roof = c.drop_height + c.hood_top_height;
  if (c.hood_centre_x > c.side_x_min + 0.01) {
    hood.quad(Vec3(c.side_x_min, -half, roof), Vec3(c.hood_centre_x, -half, roof), Vec3(c.hood_centre_x, half, roof),
              Vec3(c.side_x_min, half, roof), kChuteCell);
  }
  out.meshes.push_back(hood.wall("hood", chute.materials.liner, chute.where));
}

/// Spoon arc from its top edge (start angle) to the lip, and the back plate above its top edge.
void add_spoon(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double half = chute.half;
  MeshBuilder spoon;
  spoon.grid([&](double u, double w) {
    const double angle = c.spoon_start_angle * (1 - u) + c.spoon_exit_angle * u;  // back to lip
    return Vec3(c.spoon_centre_x - c.spoon_radius * std::sin(angle), half - w * c.chute_width,
                c.spoon_centre_z - c.spoon_radius * std::cos(angle));
  }, segments(c.spoon_start_angle * c.spoon_radius, kChuteCell, 6), segments(c.chute_width, kChuteCell));
  spoon.quad(Vec3(c.spoon_top_x, -half, c.spoon_top_z), Vec3(c.spoon_top_x, half, c.spoon_top_z),
             Vec3(c.spoon_top_x, half, c.back_plate_top), Vec3(c.spoon_top_x, -half, c.back_plate_top), kChuteCell);
  out.meshes.push_back(spoon.wall("spoon", chute.materials.liner, chute.where));
}

/// Side plates.
void add_side_plates(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double half = chute.half;
  MeshBuilder sides;
  for (const double y : {-half, half}) {
    const Vec3 a(c.side_x_min, y, c.side_z_min), b(c.side_x_max, y, c.side_z_min);
    const Vec3 d(c.side_x_min, y, c.side_z_max), e(c.side_x_max, y, c.side_z_max);
    if (y < 0) sides.quad(a, b, e, d, kChuteCell);  // normals point into the chute
    else sides.quad(a, d, e, b, kChuteCell);
  }
  out.meshes.push_back(sides.wall("side_plates", chute.materials.liner, chute.where));
}

/// Receiving belt.
void add_receiving_belt(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder belt;
  troughed_belt(belt, c.receiving_width, c.receiving_x_min, c.receiving_x_max, 0.0, c.receiving_trough,
                [&](double) { return c.receiving_trough; });
  MeshWallSpec wall = belt.wall("receiving_belt", chute.materials.belt, chute.where);
  wall.surface.kind = SurfaceVelocitySpec::Kind::linear;
  wall.surface.velocity = Vec3(c.receiving_speed, 0, 0);
  out.meshes.push_back(std::move(wall));
}

/// Skirts on the receiving belt from just behind the spoon lip.
void add_skirts(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder skirts;
  const double y = 0.5 * c.skirt_width;
  const double bottom = trough_height(c.receiving_width, c.receiving_trough, y) + 0.01;
  const double x0 = c.spoon_lip_x - 0.05, x1 = c.spoon_lip_x + c.skirt_length;
  skirts.quad(Vec3(x0, -y, bottom), Vec3(x1, -y, bottom), Vec3(x1, -y, bottom + c.skirt_height), Vec3(x0, -y, bottom + c.skirt_height), kChuteCell);
  skirts.quad(Vec3(x0, y, bottom), Vec3(x0, y, bottom + c.skirt_height), Vec3(x1, y, bottom + c.skirt_height), Vec3(x1, y, bottom), kChuteCell);
  out.meshes.push_back(skirts.wall("skirts", chute.materials.liner, chute.where));
}

/// Feed port over the tail of the feed belt: 70 % of the belt width, above the wing tops (the
/// particles drop into the trough), long enough to take a batch at the design rate (a box the
/// belt empties every length / speed seconds holds about 30 % solid).
void add_feed_port(const TransferChuteLayout& c, Generated& out) {
  const double port_half_width = 0.35 * c.feed_width;
  const double port_bottom = c.drop_height + trough_height(c.feed_width, c.feed_trough, port_half_width) + 0.01;
  const double port_length = std::min(1.0, 0.4 * c.feed_length);
  out.ports.push_back({"feed_belt", Vec3(-c.feed_length + 0.1, -port_half_width, port_bottom),
                       Vec3(-c.feed_length + 0.1 + port_length, port_half_width, port_bottom + c.feed_port_height),
                       Vec3(c.feed_speed, 0, 0)});
}

/// Outlet beyond the end of the receiving belt.
void add_discharge_outlet(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double belt_half = chute.receiving_half;
  OutletSpec discharge;
  discharge.name = "discharge";
  discharge.region_min = Vec3(c.receiving_x_max + 0.02, -belt_half - 0.5, -1.0);
  discharge.region_max = Vec3(c.receiving_x_max + 1.0, belt_half + 0.5, 0.6);
  out.outlets.push_back(discharge);
}

/// Sensors: flow through the spoon lip and near the belt end; load on the belt after the lip.
void add_sensors(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double half = chute.half, belt_half = chute.receiving_half;
  SensorSpec spoon_exit;
  spoon_exit.kind = SensorSpec::Kind::plane, spoon_exit.name = "spoon_exit";
  spoon_exit.point = Vec3(c.spoon_lip_x, 0, c.spoon_lip_height), spoon_exit.normal = Vec3::UnitX();
  spoon_exit.region_min = Vec3(c.spoon_lip_x - 0.1, -half, -0.05);
  spoon_exit.region_max = Vec3(c.spoon_lip_x + 0.1, half, c.spoon_top_z);
  out.sensors.push_back(spoon_exit);
  SensorSpec belt_discharge;
  belt_discharge.kind = SensorSpec::Kind::plane, belt_discharge.name = "belt_discharge";
  const double x_end = c.receiving_x_max - 0.3;
  belt_discharge.point = Vec3(x_end, 0, 0), belt_discharge.normal = Vec3::UnitX();
  belt_discharge.region_min = Vec3(x_end - 0.1, -belt_half, -0.05);
  belt_discharge.region_max = Vec3(x_end + 0.1, belt_half, 0.5);
  out.sensors.push_back(belt_discharge);
  SensorSpec loading;
  loading.kind = SensorSpec::Kind::box, loading.name = "loading_zone", loading.across = Vec3::UnitY();
  loading.region_min = Vec3(c.spoon_lip_x, -belt_half, -0.05);
  loading.region_max = Vec3(c.spoon_lip_x + std::min(1.0, c.receiving_x_max - c.spoon_lip_x - 0.4), belt_half, 0.5);
  out.sensors.push_back(loading);
}

/// The design values the report shows.
void set_design(const TransferChuteLayout& c, Generated& out) {
  const double pulley_ratio = c.feed_speed * c.feed_speed /
                              (kGravity * (c.pulley_radius + 0.5 * c.load_height));  // CEMA V^2/(g r), r = R + a1
  out.design = {
      {"feed_belt_speed_m_s", c.feed_speed},
      {"receiving_belt_speed_m_s", c.receiving_speed},
      {"feed_belt_width_m", c.feed_width},
      {"receiving_belt_width_m", c.receiving_width},
      {"troughing_angle_deg", c.feed_trough * 180 / kPi},
      {"drop_height_m", c.drop_height},
      {"pulley_diameter_m", 2 * c.pulley_radius},
      {"discharge_ratio_v2_gr", pulley_ratio},
      {"hood_radius_m", c.hood_radius},
      {"hood_distance_m", c.hood_distance},
      {"hood_top_height_m", c.hood_top_height},
      {"hood_exit_angle_deg", -c.hood_end_angle * 180 / kPi},
      {"spoon_radius_m", c.spoon_radius},
      {"spoon_lip_height_m", c.spoon_lip_height},
      {"spoon_lip_x_m", c.spoon_lip_x},
      {"chute_width_m", c.chute_width},
      {"skirt_width_m", c.skirt_width},
  };
}

}  // namespace

Generated transfer_chute(MapReader& reader, const EquipmentSpec& spec) {
  const Materials materials = read_materials(reader);
  const double margin = reader.number("margin", 0.5, 0.0, 10.0, "m");
  const TransferChuteLayout c = read_layout(reader);
  const ChuteBuild chute{c, materials, spec.location, 0.5 * c.chute_width, 0.5 * c.receiving_width};
  Generated out;
  out.camera = "side";

  add_feed_belt(chute, out);
  add_head_pulley(chute, out);
  add_hood(chute, out);
  add_spoon(chute, out);
  add_side_plates(chute, out);
  add_receiving_belt(chute, out);
  if (c.skirt_length > 0) add_skirts(chute, out);

  add_feed_port(c, out);
  add_discharge_outlet(chute, out);
  add_sensors(chute, out);

  set_domain(out, margin, -1.0);
  set_design(c, out);
  return out;
}

}  // namespace detail

TransferChuteLayout transfer_chute_layout(const EquipmentSpec& spec) {
  YAML::Node params = spec.params && *spec.params && !spec.params->IsNull() ? YAML::Node(*spec.params)
                                                                            : YAML::Node(YAML::NodeType::Map);
  MapReader reader(params, spec.file, "equipment." + spec.type);
  detail::read_materials(reader);
  reader.number("margin", 0.5, 0.0, 10.0, "m");
  TransferChuteLayout layout = detail::read_layout(reader);
  reader.finish();
  return layout;
}

}  // namespace dem::equipment
