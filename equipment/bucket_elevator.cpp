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

Generated bucket_elevator(MapReader& reader, const EquipmentSpec& spec) {
  const Materials materials = read_materials(reader);
  const double height = reader.number("height", 3.0, 0.5, 100.0, "m");
  const double pulley_radius = 0.5 * reader.number("pulley_diameter", 0.5, 0.1, 3.0, "m");
  const double belt_thickness = reader.number("belt_thickness", 0.01, 0.0, 0.05, "m");
  const double pitch_radius = pulley_radius + 0.5 * belt_thickness;  // [m] belt centre line
  if (reader.has("belt_speed") && reader.has("head_rpm")) reader.fail("head_rpm", "give belt_speed or head_rpm, not both");
  double omega = 0;  // [rad/s] head pulley
  if (reader.has("head_rpm")) omega = reader.number("head_rpm", 0, 1.0, 2000.0, "rpm") * 2 * kPi / 60;
  else omega = reader.number("belt_speed", 1.5, 0.1, 10.0, "m/s") / pitch_radius;
  const double belt_speed = omega * pitch_radius;  // [m/s]

  MapReader bucket = sub_map(reader, "bucket");
  const double projection = bucket.number("projection", 0.14, 0.02, 1.0, "m");
  const double depth = bucket.number("depth", 0.14, 0.02, 1.0, "m");
  const double width = bucket.number("width", 0.2, 0.02, 3.0, "m");
  const double front_angle = radians(bucket.number("front_angle_deg", 20.0, 0.0, 60.0, "deg"));
  const double bottom = projection - depth * std::tan(front_angle);  // [m] where the front meets the bottom
  if (bottom < 0.3 * projection) {
    bucket.fail("front_angle_deg", fmt::format("{:g} deg leaves a bottom of {:g} m; valid: up to {:g} deg for this "
                                               "projection and depth", front_angle * 180 / kPi, bottom,
                                               std::atan(0.7 * projection / depth) * 180 / kPi));
  }
  bucket.finish();
  const double belt_width = reader.number("belt_width", width + 0.05, width, 3.0, "m");
  const double inner = pulley_radius + belt_thickness;  // [m] r_i
  const double outer = inner + projection;              // [m] r_a
  const double loop = 2 * height + 2 * kPi * inner;     // [m]
  const double wanted_spacing = reader.number("bucket_spacing", 0.3, depth + 0.01, loop / 2, "m");
  const int count = std::max(2, static_cast<int>(std::lround(loop / wanted_spacing)));
  const double spacing = loop / count;
  const double clearance = reader.number("casing_clearance", 0.05, 0.01, 1.0, "m");
  MapReader chute = sub_map(reader, "chute");
  const double chute_angle = radians(chute.number("angle_deg", 50.0, 20.0, 80.0, "deg"));
  const double chute_length = chute.number("length", 1.0, 0.2, 20.0, "m");
  const double throat_drop = chute.number("throat_drop", 0.2, 0.0, height, "m");
  chute.finish();
  const double margin = reader.number("margin", 0.3, 0.0, 10.0, "m");
  const SourceLocation& where = spec.location;
  const double path_speed = omega * inner;  // [m/s] of the bucket backs

  Generated out;
  out.camera = "side";
  // Belt legs (linear surface speed) and pulleys (surface rotation about +y: omega y x (-r x) = +omega r z
  // on the rising -x leg).
  const double half_belt = 0.5 * belt_width;
  for (const int leg : {-1, 1}) {
    MeshBuilder strip;
    const double x = leg * inner;
    strip.quad(Vec3(x, -half_belt, 0), Vec3(x, half_belt, 0), Vec3(x, half_belt, height), Vec3(x, -half_belt, height));
    MeshWallSpec wall = strip.wall(leg < 0 ? "belt_up" : "belt_down", materials.belt, where);
    wall.surface.kind = SurfaceVelocitySpec::Kind::linear;
    wall.surface.velocity = Vec3(0, 0, -leg * path_speed);
    out.meshes.push_back(std::move(wall));
  }
  for (const double z : {0.0, height}) {
    MeshBuilder pulley;
    cylinder(pulley, Vec3(0, -half_belt, z), Vec3(0, half_belt, z), inner, segments(2 * kPi * inner, 0.08, 24), true);
    MeshWallSpec wall = pulley.wall(z > 0 ? "head_pulley" : "boot_pulley", materials.belt, where);
    wall.surface.kind = SurfaceVelocitySpec::Kind::rotation;
    wall.surface.axis = Vec3::UnitY();
    wall.surface.point = Vec3(0, 0, z);
    wall.surface.angular_speed = omega;
    out.meshes.push_back(std::move(wall));
  }
  // Buckets in the local frame of the belt_loop part: x out, y along travel, z across.
  MeshBuilder shape;
  {
    const double heel = std::min({0.4 * projection, 0.4 * depth, 0.8 * bottom});
    std::vector<Vec3> profile = {Vec3(0, depth, 0)};
    for (int k = 0; k <= 4; ++k) {  // heel arc about (heel, heel) from -x to -y
      const double angle = kPi + 0.5 * kPi * k / 4;
      profile.push_back(Vec3(heel + heel * std::cos(angle), heel + heel * std::sin(angle), 0));
    }
    profile.push_back(Vec3(bottom, 0, 0));
    profile.push_back(Vec3(projection, depth, 0));
    const int pieces = static_cast<int>(profile.size()) - 1;
    const int across = segments(width, kCell);
    shape.grid([&](double u, double w) {
      Vec3 p = profile[static_cast<size_t>(std::lround(u * pieces))];
      p.z() = (w - 0.5) * width;
      return p;
    }, pieces, across);
    for (const double z : {-0.5 * width, 0.5 * width}) {
      std::vector<Vec3> side;
      for (const Vec3& p : profile) side.push_back(Vec3(p.x(), p.y(), z));
      if (z > 0) std::reverse(side.begin(), side.end());
      shape.fan(side);
    }
  }
  for (int k = 0; k < count; ++k) {
    MeshWallSpec wall = shape.wall(fmt::format("bucket_{}", k), materials.liner, where);
    MotionPart carried;
    carried.kind = MotionPart::Kind::belt_loop;
    carried.axis = Vec3::UnitY(), carried.lower = Vec3::Zero(), carried.upper = Vec3(0, 0, height);
    carried.radius = inner, carried.speed = path_speed, carried.offset = k * spacing;
    wall.motion.parts.push_back(carried);
    out.meshes.push_back(std::move(wall));
  }
  // Casing around the loop, open on +x above the chute throat; the chute continues it.
  const double x_min = -outer - clearance, x_wall = outer + clearance;
  const double z_bottom = -outer - clearance, z_top = height + outer + clearance;
  const double half = 0.5 * std::max(width, belt_width) + clearance;
  const double z_throat = height - throat_drop;
  const double x_end = x_wall + chute_length * std::cos(chute_angle);
  const double z_end = z_throat - chute_length * std::sin(chute_angle);
  {
    MeshBuilder casing;
    casing.quad(Vec3(x_min, -half, z_bottom), Vec3(x_min, half, z_bottom), Vec3(x_min, half, z_top), Vec3(x_min, -half, z_top));
    casing.quad(Vec3(x_wall, -half, z_bottom), Vec3(x_wall, -half, z_throat), Vec3(x_wall, half, z_throat), Vec3(x_wall, half, z_bottom));
    casing.quad(Vec3(x_min, -half, z_bottom), Vec3(x_wall, -half, z_bottom), Vec3(x_wall, half, z_bottom), Vec3(x_min, half, z_bottom));
    casing.quad(Vec3(x_min, -half, z_top), Vec3(x_min, half, z_top), Vec3(x_end, half, z_top), Vec3(x_end, -half, z_top));
    for (const double y : {-half, half}) {
      casing.quad(Vec3(x_min, y, z_bottom), Vec3(x_wall, y, z_bottom), Vec3(x_wall, y, z_top), Vec3(x_min, y, z_top));
      casing.quad(Vec3(x_wall, y, z_throat), Vec3(x_end, y, z_end), Vec3(x_end, y, z_top), Vec3(x_wall, y, z_top));
    }
    out.meshes.push_back(casing.wall("casing", materials.liner, where));
    MeshBuilder floor;
    floor.quad(Vec3(x_wall, -half, z_throat), Vec3(x_wall, half, z_throat), Vec3(x_end, half, z_end), Vec3(x_end, -half, z_end));
    out.meshes.push_back(floor.wall("discharge_chute", materials.liner, where));
  }
  // Feed above the rising buckets near the boot; outlet below the chute end; flow into the chute.
  const double feed_z = std::max(0.3, 0.5 * outer);
  out.ports.push_back({"boot_feed", Vec3(-inner - 0.9 * projection, -0.4 * width, feed_z),
                       Vec3(-inner - 0.1 * projection, 0.4 * width, feed_z + 0.2), Vec3::Zero()});
  OutletSpec discharge;
  discharge.name = "discharge";
  discharge.region_min = Vec3(x_end + 0.02, -half - 0.2, z_end - 0.6);
  discharge.region_max = Vec3(x_end + 0.6, half + 0.2, z_end + 0.3);
  out.outlets.push_back(discharge);
  SensorSpec chute_flow;
  chute_flow.kind = SensorSpec::Kind::plane, chute_flow.name = "chute_flow";
  chute_flow.point = Vec3(x_wall + 0.05, 0, z_throat), chute_flow.normal = Vec3::UnitX();
  chute_flow.region_min = Vec3(x_wall, -half, z_throat - 0.1), chute_flow.region_max = Vec3(x_wall + 0.1, half, z_top);
  out.sensors.push_back(chute_flow);
  set_domain(out, margin, 1e300);

  // Design values: pole distance and discharge type (e.g. Hanrahan/Fruchtbaum pole theory).
  const double pole = kGravity / (omega * omega);  // [m]
  const int type = pole > outer ? 0 : (pole < inner ? 2 : 1);
  const double heel = std::min({0.4 * projection, 0.4 * depth, 0.8 * bottom});
  const double area = 0.5 * (bottom + projection) * depth - heel * heel * (1 - kPi / 4);  // [m^2] profile
  out.design = {
      {"belt_speed_m_s", belt_speed},
      {"head_rpm", omega * 60 / (2 * kPi)},
      {"pole_distance_m", pole},
      {"inner_lip_radius_m", inner},
      {"outer_lip_radius_m", outer},
      {"discharge_type", double(type)},
      {"bucket_spacing_m", spacing},
      {"bucket_count", double(count)},
      {"bucket_volume_m3", area * width},
      {"full_volume_rate_m3_s", area * width * path_speed / spacing},
      {"height_m", height},
  };
  return out;
}

}  // namespace dem::equipment::detail
