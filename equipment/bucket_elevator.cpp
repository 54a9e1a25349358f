// Vertical bucket elevator: a belt over a boot pulley (axis along y through the origin) and a
// head pulley `height` above it, buckets on the belt's outside, a casing, and a discharge chute.
//
// Layout: the belt runs anticlockwise about +y, so the buckets rise on the -x leg (x = -r_i),
// pass over the head towards +x and return down the +x leg, openings facing the direction of
// travel. They throw (or drop) material over the head towards +x into the discharge chute, an
// inclined plate from the throat at (r_a + casing_clearance, height - chute.throat_drop) going
// down and out at chute.angle_deg for chute.length. r_i = R_p + belt_thickness is the path of
// the bucket backs (the belt's outer surface), r_a = r_i + projection the outer lip radius.
// Each bucket is its own mesh `bucket_k` with a belt_loop motion part (kinematics.h) starting
// k * spacing along the loop; the spacing is rounded so a whole number of buckets fills the loop.
// Bucket profile (local x out from the belt, y along travel, z across): back plate on the belt
// from the rim down, a rounded heel, a flat bottom and a front rising at front_angle_deg from
// the belt normal to the lip at x = projection, y = depth (a DIN 15231-like deep bucket).
//
// Discharge classification (pole distance h_p = g / omega^2 of the head pulley): h_p > r_a:
// gravity (0); h_p < r_i: centrifugal (2); in between: mixed (1).
#include <fmt/format.h>

#include "generators.h"

namespace dem::equipment::detail {

namespace {

/// The elevator's parameters with defaults filled in [m, rad, rad/s, m/s] and the values derived
/// from them.
struct BucketElevator {
  Materials materials;
  double height = 0;                                  // [m] boot to head pulley axis
  double pulley_radius = 0, belt_thickness = 0;       // [m]
  double omega = 0;                                   // [rad/s] head pulley
  double belt_speed = 0;                              // [m/s] of the belt centre line
  double projection = 0, depth = 0, width = 0;        // [m] bucket
  double front_angle = 0;                             // [rad] bucket front from the belt normal
  double bottom = 0;                                  // [m] where the front meets the bottom
  double belt_width = 0;                              // [m]
  double inner = 0, outer = 0;                        // [m] r_i, r_a
  int count = 0;                                      // buckets on the loop
  double spacing = 0;                                 // [m] along the loop
  double clearance = 0;                               // [m] casing around the lips
  double chute_angle = 0, chute_length = 0, throat_drop = 0;  // [rad, m, m]
  double margin = 0;                                  // [m] domain around the plant
  double path_speed = 0;                              // [m/s] of the bucket backs
};

/// The `bucket` sub-map: profile and width, checked for a usable bottom.
void read_bucket(MapReader& reader, BucketElevator& elevator) {
  MapReader bucket = sub_map(reader, "bucket");
  elevator.projection = bucket.number("projection", 0.14, 0.02, 1.0, "m");
  elevator.depth = bucket.number("depth", 0.14, 0.02, 1.0, "m");
  elevator.width = bucket.number("width", 0.2, 0.02, 3.0, "m");
  elevator.front_angle = radians(bucket.number("front_angle_deg", 20.0, 0.0, 60.0, "deg"));
  // [m] where the front meets the bottom
  elevator.bottom = elevator.projection - elevator.depth * std::tan(elevator.front_angle);
  if (elevator.bottom < 0.3 * elevator.projection) {
    bucket.fail("front_angle_deg", fmt::format("{:g} deg leaves a bottom of {:g} m; valid: up to {:g} deg for this "
                                               "projection and depth", elevator.front_angle * 180 / kPi, elevator.bottom,
                                               std::atan(0.7 * elevator.projection / elevator.depth) * 180 / kPi));
  }
  bucket.finish();
}

/// The `chute` sub-map.
void read_chute(MapReader& reader, BucketElevator& elevator) {
  MapReader chute = sub_map(reader, "chute");
  elevator.chute_angle = radians(chute.number("angle_deg", 50.0, 20.0, 80.0, "deg"));
  elevator.chute_length = chute.number("length", 1.0, 0.2, 20.0, "m");
  elevator.throat_drop = chute.number("throat_drop", 0.2, 0.0, elevator.height, "m");
  chute.finish();
}

/// Every parameter, in the order they are read (the case-key reference records that order); the
/// spacing rounded so a whole number of buckets fills the loop.
BucketElevator read_bucket_elevator(MapReader& reader) {
  BucketElevator elevator;
  elevator.materials = read_materials(reader);
  elevator.height = reader.number("height", 3.0, 0.5, 100.0, "m");
  elevator.pulley_radius = 0.5 * reader.number("pulley_diameter", 0.5, 0.1, 3.0, "m");
  elevator.belt_thickness = reader.number("belt_thickness", 0.01, 0.0, 0.05, "m");
  const double pitch_radius = elevator.pulley_radius + 0.5 * elevator.belt_thickness;  // [m] belt centre line
  if (reader.has("belt_speed") && reader.has("head_rpm")) reader.fail("head_rpm", "give belt_speed or head_rpm, not both");
  if (reader.has("head_rpm")) elevator.omega = reader.number("head_rpm", 0, 1.0, 2000.0, "rpm") * 2 * kPi / 60;
  else elevator.omega = reader.number("belt_speed", 1.5, 0.1, 10.0, "m/s") / pitch_radius;
  elevator.belt_speed = elevator.omega * pitch_radius;  // [m/s]

  read_bucket(reader, elevator);
  elevator.belt_width = reader.number("belt_width", elevator.width + 0.05, elevator.width, 3.0, "m");
  elevator.inner = elevator.pulley_radius + elevator.belt_thickness;  // [m] r_i
  elevator.outer = elevator.inner + elevator.projection;              // [m] r_a
  const double loop = 2 * elevator.height + 2 * kPi * elevator.inner;  // [m]
  const double wanted_spacing = reader.number("bucket_spacing", 0.3, elevator.depth + 0.01, loop / 2, "m");
  elevator.count = std::max(2, static_cast<int>(std::lround(loop / wanted_spacing)));
  elevator.spacing = loop / elevator.count;
  elevator.clearance = reader.number("casing_clearance", 0.05, 0.01, 1.0, "m");
  read_chute(reader, elevator);
  elevator.margin = reader.number("margin", 0.3, 0.0, 10.0, "m");
  elevator.path_speed = elevator.omega * elevator.inner;  // [m/s] of the bucket backs
  return elevator;
}

/// Belt legs (linear surface speed) and pulleys (surface rotation about +y: omega y x (-r x) = +omega r z
/// on the rising -x leg).
void add_belt_and_pulleys(Generated& out, const BucketElevator& elevator, const SourceLocation& where) {
  const double half_belt = 0.5 * elevator.belt_width;
  for (const int leg : {-1, 1}) {
    MeshBuilder strip;
    const double x = leg * elevator.inner;
    strip.quad(Vec3(x, -half_belt, 0), Vec3(x, half_belt, 0), Vec3(x, half_belt, elevator.height),
               Vec3(x, -half_belt, elevator.height));
    MeshWallSpec wall = strip.wall(leg < 0 ? "belt_up" : "belt_down", elevator.materials.belt, where);
    wall.surface.kind = SurfaceVelocitySpec::Kind::linear;
    wall.surface.velocity = Vec3(0, 0, -leg * elevator.path_speed);
    out.meshes.push_back(std::move(wall));
  }
  for (const double z : {0.0, elevator.height}) {
    MeshBuilder pulley;
    cylinder(pulley, Vec3(0, -half_belt, z), Vec3(0, half_belt, z), elevator.inner,
             segments(2 * kPi * elevator.inner, 0.08, 24), true);
    MeshWallSpec wall = pulley.wall(z > 0 ? "head_pulley" : "boot_pulley", elevator.materials.belt, where);
    wall.surface.kind = SurfaceVelocitySpec::Kind::rotation;
    wall.surface.axis = Vec3::UnitY();
    wall.surface.point = Vec3(0, 0, z);
    wall.surface.angular_speed = elevator.omega;
    out.meshes.push_back(std::move(wall));
  }
}

/// A bucket in the local frame of the belt_loop part: x out, y along travel, z across.
MeshBuilder bucket_shape(const BucketElevator& elevator) {
  MeshBuilder shape;
  const double heel = std::min({0.4 * elevator.projection, 0.4 * elevator.depth, 0.8 * elevator.bottom});
  std::vector<Vec3> profile = {Vec3(0, elevator.depth, 0)};
  for (int k = 0; k <= 4; ++k) {  // heel arc about (heel, heel) from -x to -y
    const double angle = kPi + 0.5 * kPi * k / 4;
    profile.push_back(Vec3(heel + heel * std::cos(angle), heel + heel * std::sin(angle), 0));
  }
  profile.push_back(Vec3(elevator.bottom, 0, 0));
  profile.push_back(Vec3(elevator.projection, elevator.depth, 0));
  const int pieces = static_cast<int>(profile.size()) - 1;
  const int across = segments(elevator.width, kCell);
  shape.grid([&](double u, double w) {
    Vec3 p = profile[static_cast<size_t>(std::lround(u * pieces))];
    p.z() = (w - 0.5) * elevator.width;
    return p;
  }, pieces, across);
  for (const double z : {-0.5 * elevator.width, 0.5 * elevator.width}) {
    std::vector<Vec3> side;
    for (const Vec3& p : profile) side.push_back(Vec3(p.x(), p.y(), z));
    if (z > 0) std::reverse(side.begin(), side.end());
    shape.fan(side);
  }
  return shape;
}

/// Bucket k: the shape carried by a belt_loop part k * spacing along the loop.
void add_buckets(Generated& out, const BucketElevator& elevator, const MeshBuilder& shape, const SourceLocation& where) {
  for (int k = 0; k < elevator.count; ++k) {
    MeshWallSpec wall = shape.wall(fmt::format("bucket_{}", k), elevator.materials.liner, where);
    MotionPart carried;
    carried.kind = MotionPart::Kind::belt_loop;
    carried.axis = Vec3::UnitY(), carried.lower = Vec3::Zero(), carried.upper = Vec3(0, 0, elevator.height);
    carried.radius = elevator.inner, carried.speed = elevator.path_speed, carried.offset = k * elevator.spacing;
    wall.motion.parts.push_back(carried);
    out.meshes.push_back(std::move(wall));
  }
}

/// [m] The casing box around the loop and the chute from its throat on the +x wall to its end.
struct CasingLayout {
  double x_min = 0, x_wall = 0;    // -x and +x walls
  double z_bottom = 0, z_top = 0;  // floor and roof
  double half = 0;                 // half width across y
  double z_throat = 0;             // chute throat on the +x wall
  double x_end = 0, z_end = 0;     // chute end
};

CasingLayout casing_layout(const BucketElevator& elevator) {
  CasingLayout casing;
  casing.x_min = -elevator.outer - elevator.clearance;
  casing.x_wall = elevator.outer + elevator.clearance;
  casing.z_bottom = -elevator.outer - elevator.clearance;
  casing.z_top = elevator.height + elevator.outer + elevator.clearance;
  casing.half = 0.5 * std::max(elevator.width, elevator.belt_width) + elevator.clearance;
  casing.z_throat = elevator.height - elevator.throat_drop;
  casing.x_end = casing.x_wall + elevator.chute_length * std::cos(elevator.chute_angle);
  casing.z_end = casing.z_throat - elevator.chute_length * std::sin(elevator.chute_angle);
  return casing;
}

/// Casing around the loop, open on +x above the chute throat; the chute continues it.
void add_casing_and_chute(Generated& out, const BucketElevator& elevator, const CasingLayout& casing,
                          const SourceLocation& where) {
  const double x_min = casing.x_min, x_wall = casing.x_wall, z_bottom = casing.z_bottom, z_top = casing.z_top;
  const double half = casing.half, z_throat = casing.z_throat, x_end = casing.x_end, z_end = casing.z_end;
  MeshBuilder box;
  box.quad(Vec3(x_min, -half, z_bottom), Vec3(x_min, half, z_bottom), Vec3(x_min, half, z_top), Vec3(x_min, -half, z_top));
  box.quad(Vec3(x_wall, -half, z_bottom), Vec3(x_wall, -half, z_throat), Vec3(x_wall, half, z_throat), Vec3(x_wall, half, z_bottom));
  box.quad(Vec3(x_min, -half, z_bottom), Vec3(x_wall, -half, z_bottom), Vec3(x_wall, half, z_bottom), Vec3(x_min, half, z_bottom));
  box.quad(Vec3(x_min, -half, z_top), Vec3(x_min, half, z_top), Vec3(x_end, half, z_top), Vec3(x_end, -half, z_top));
  for (const double y : {-half, half}) {
    box.quad(Vec3(x_min, y, z_bottom), Vec3(x_wall, y, z_bottom), Vec3(x_wall, y, z_top), Vec3(x_min, y, z_top));
    box.quad(Vec3(x_wall, y, z_throat), Vec3(x_end, y, z_end), Vec3(x_end, y, z_top), Vec3(x_wall, y, z_top));
  }
  out.meshes.push_back(box.wall("casing", elevator.materials.liner, where));
  MeshBuilder floor;
  floor.quad(Vec3(x_wall, -half, z_throat), Vec3(x_wall, half, z_throat), Vec3(x_end, half, z_end), Vec3(x_end, -half, z_end));
  out.meshes.push_back(floor.wall("discharge_chute", elevator.materials.liner, where));
}

/// Feed above the rising buckets near the boot; outlet below the chute end; flow into the chute.
void add_feed_discharge_and_sensor(Generated& out, const BucketElevator& elevator, const CasingLayout& casing) {
  const double feed_z = std::max(0.3, 0.5 * elevator.outer);
  out.ports.push_back({"boot_feed", Vec3(-elevator.inner - 0.9 * elevator.projection, -0.4 * elevator.width, feed_z),
                       Vec3(-elevator.inner - 0.1 * elevator.projection, 0.4 * elevator.width, feed_z + 0.2), Vec3::Zero()});
  OutletSpec discharge;
  discharge.name = "discharge";
  discharge.region_min = Vec3(casing.x_end + 0.02, -casing.half - 0.2, casing.z_end - 0.6);
  discharge.region_max = Vec3(casing.x_end + 0.6, casing.half + 0.2, casing.z_end + 0.3);
  out.outlets.push_back(discharge);
  SensorSpec chute_flow;
  chute_flow.kind = SensorSpec::Kind::plane, chute_flow.name = "chute_flow";
  chute_flow.point = Vec3(casing.x_wall + 0.05, 0, casing.z_throat), chute_flow.normal = Vec3::UnitX();
  chute_flow.region_min = Vec3(casing.x_wall, -casing.half, casing.z_throat - 0.1);
  chute_flow.region_max = Vec3(casing.x_wall + 0.1, casing.half, casing.z_top);
  out.sensors.push_back(chute_flow);
}

/// Design values: pole distance and discharge type (e.g. Hanrahan/Fruchtbaum pole theory).
std::vector<std::pair<std::string, double>> design_values(const BucketElevator& elevator) {
  const double pole = kGravity / (elevator.omega * elevator.omega);  // [m]
  const int type = pole > elevator.outer ? 0 : (pole < elevator.inner ? 2 : 1);
  const double heel = std::min({0.4 * elevator.projection, 0.4 * elevator.depth, 0.8 * elevator.bottom});
  // [m^2] profile
  const double area = 0.5 * (elevator.bottom + elevator.projection) * elevator.depth - heel * heel * (1 - kPi / 4);
  return {
      {"belt_speed_m_s", elevator.belt_speed},
      {"head_rpm", elevator.omega * 60 / (2 * kPi)},
      {"pole_distance_m", pole},
      {"inner_lip_radius_m", elevator.inner},
      {"outer_lip_radius_m", elevator.outer},
      {"discharge_type", double(type)},
      {"bucket_spacing_m", elevator.spacing},
      {"bucket_count", double(elevator.count)},
      {"bucket_volume_m3", area * elevator.width},
      {"full_volume_rate_m3_s", area * elevator.width * elevator.path_speed / elevator.spacing},
      {"height_m", elevator.height},
  };
}

}  // namespace

Generated bucket_elevator(MapReader& reader, const EquipmentSpec& spec) {
  const BucketElevator elevator = read_bucket_elevator(reader);
  const SourceLocation& where = spec.location;

  Generated out;
  out.camera = "side";
  add_belt_and_pulleys(out, elevator, where);
  add_buckets(out, elevator, bucket_shape(elevator), where);
  const CasingLayout casing = casing_layout(elevator);
  add_casing_and_chute(out, elevator, casing, where);
  add_feed_discharge_and_sensor(out, elevator, casing);
  set_domain(out, elevator.margin, 1e300);
  out.design = design_values(elevator);
  return out;
}

}  // namespace dem::equipment::detail
