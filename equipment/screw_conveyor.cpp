// Screw conveyor: a right-handed helicoid flight on a shaft turning in a U or tubular trough,
// along +x (optionally inclined: the +x end raised by inclination_deg about y).
//
// Layout (local, before inclination): screw axis along x at height z = D/2 + clearance, so the
// trough bottom is at z = 0; flight and shaft from x = 0 to length (one pitch further at both ends
// when periodic). The flight x = s phi / 2 pi (phi anticlockwise about +x from +y) is
// right-handed, so it conveys +x when it turns clockwise about +x: the mesh's rotation has
// angular speed -rpm 2 pi / 60 about +x (positive rpm conveys +x, negative back).
// Not periodic: end plates at x = 0 and x = length; the trough bottom is open (the lowest 120 deg)
// over the last half pitch with the outlet box below it; a tubular trough is also open at the top
// (the highest 120 deg) over the first pitch under the inlet port.
// Periodic (`periodic: true`, for simulation.periodic [x] with domain x in [0, length]): length
// must be a whole number of pitches so the flight is continuous across the wrap, the inclination
// must be 0 (tilt gravity instead), and there are no end plates, openings, inlet or outlet.
#include <fmt/format.h>

#include "generators.h"

namespace dem::equipment::detail {

Generated screw_conveyor(MapReader& reader, const EquipmentSpec& spec) {
  const Materials materials = read_materials(reader);
  const double diameter = reader.number("diameter", 0.1, 0.02, 2.0, "m");
  const double shaft = reader.number("shaft_diameter", 0.3 * diameter, 0.005, 0.9 * diameter, "m");
  const double pitch = reader.number("pitch", diameter, 0.1 * diameter, 3.0 * diameter, "m");
  const double length = reader.number("length", 4 * pitch, 2 * pitch, 1000 * pitch, "m");
  const double thickness = reader.number("flight_thickness", 0.0, 0.0, 0.25 * pitch, "m");
  const double clearance = reader.number("clearance", std::min(0.005, 0.1 * diameter), 0.0, diameter, "m");
  const double rpm = reader.number("rpm", 30.0, -3000.0, 3000.0, "rpm");
  const std::string trough = reader.string("trough", "U", {"U", "tubular"});
  const double radius = 0.5 * diameter + clearance;  // [m] trough radius
  const double trough_top = reader.number("trough_height", 1.2 * diameter, radius, 20 * diameter, "m");
  const double inclination = reader.number("inclination_deg", 0.0, -90.0, 90.0, "deg");
  const bool periodic = reader.boolean("periodic", false);
  const int per_turn = static_cast<int>(reader.integer("segments_per_turn", 32, 12, 96));
  const double margin = reader.number("margin", 0.2, 0.0, 10.0, "m");
  if (periodic) {
    const double turns = length / pitch;
    if (std::abs(turns - std::round(turns)) > 1e-9 * turns) {
      reader.fail("length", fmt::format("{:g} m is {:g} pitches; a periodic screw needs a whole number (valid: e.g. {:g} m)",
                                        length, turns, std::max(1.0, std::round(turns)) * pitch));
    }
    if (inclination != 0.0) {
      reader.fail("inclination_deg", "must be 0 for a periodic screw; tilt simulation.gravity instead");
    }
  }
  const SourceLocation& where = spec.location;
  const double axis_z = radius;  // [m] trough bottom at z = 0
  const double begin = periodic ? -pitch : 0.0, end = periodic ? length + pitch : length;
  const double theta = radians(inclination);
  Eigen::Matrix3d tilt;  // raises the +x end: x -> (cos, 0, sin)
  tilt << std::cos(theta), 0, -std::sin(theta), 0, 1, 0, std::sin(theta), 0, std::cos(theta);

  Generated out;
  out.camera = "iso";
  // Flight (helicoid, both faces and the rim when thick) and shaft: one rotating mesh.
  {
    MeshBuilder screw;
    const double turns = (end - begin) / pitch;
    const int around = std::max(1, static_cast<int>(std::ceil(turns * per_turn - 1e-9)));
    const int radial = std::max(2, segments(0.5 * (diameter - shaft), kPi * diameter / per_turn));
    const double sweep = 2 * kPi * turns;
    const auto helicoid = [&](double shift) {
      screw.grid([&, shift](double u, double w) {
        const double phi = u * sweep, r = 0.5 * shaft + w * 0.5 * (diameter - shaft);
        return Vec3(begin + pitch * phi / (2 * kPi) + shift, r * std::cos(phi), axis_z + r * std::sin(phi));
      }, around, radial);
    };
    helicoid(-0.5 * thickness);
    if (thickness > 0) {
      helicoid(0.5 * thickness);
      const double tip = 0.5 * diameter;
      screw.grid([&](double u, double w) {  // rim band at the flight tip
        const double phi = u * sweep;
        return Vec3(begin + pitch * phi / (2 * kPi) + (w - 0.5) * thickness, tip * std::cos(phi),
                    axis_z + tip * std::sin(phi));
      }, around, 1);
      for (const double phi : {0.0, sweep}) {  // ends of the flight
        const Vec3 inner(0, 0.5 * shaft * std::cos(phi), axis_z + 0.5 * shaft * std::sin(phi));
        const Vec3 outer(0, tip * std::cos(phi), axis_z + tip * std::sin(phi));
        const Vec3 at(begin + pitch * phi / (2 * kPi), 0, 0), half(0.5 * thickness, 0, 0);
        screw.quad(inner + at - half, outer + at - half, outer + at + half, inner + at + half, kPi * diameter / per_turn);
      }
    }
    cylinder(screw, Vec3(begin, 0, axis_z), Vec3(end, 0, axis_z), 0.5 * shaft, std::max(12, per_turn / 2), false);
    screw.transform(tilt, Vec3::Zero());
    MeshWallSpec wall = screw.wall("screw", materials.liner, where);
    MotionPart turn;
    turn.kind = MotionPart::Kind::rotation;
    turn.axis = tilt * Vec3::UnitX();
    turn.point = tilt * Vec3(0, 0, axis_z);
    turn.angular_speed = -rpm * 2 * kPi / 60;  // clockwise about +x conveys +x (right-handed flight)
    wall.motion.parts.push_back(turn);
    out.meshes.push_back(std::move(wall));
  }
  // Trough: U (half cylinder below the axis plus vertical sides) or tube, with its openings.
  {
    MeshBuilder shell;
    const bool tube = trough == "tubular";
    const int around = tube ? per_turn : per_turn / 2;
    const double first = tube ? 0.0 : kPi, span = tube ? 2 * kPi : kPi;
    const double axial_cell = std::min(kCell, 0.25 * pitch);
    // Pieces along x: [begin, end] when periodic; else first pitch (tube: top opening), middle,
    // last half pitch (bottom opening).
    struct Piece { double x0, x1, open_centre; };  // open_centre: angle of a 120 deg opening, or NAN
    std::vector<Piece> pieces;
    if (periodic) pieces.push_back({begin, end, NAN});
    else {
      const double inlet_end = tube ? pitch : 0.0;
      if (tube) pieces.push_back({0.0, inlet_end, 0.5 * kPi});
      pieces.push_back({inlet_end, length - 0.5 * pitch, NAN});
      pieces.push_back({length - 0.5 * pitch, length, 1.5 * kPi});
    }
    for (const Piece& piece : pieces) {
      const int along = segments(piece.x1 - piece.x0, axial_cell);
      shell.grid([&](double w, double u) {  // normals inward, towards the axis
        const double angle = first + u * span;
        return Vec3(piece.x0 + w * (piece.x1 - piece.x0), radius * std::cos(angle), axis_z + radius * std::sin(angle));
      }, along, around, [&](int, int j) {
        if (std::isnan(piece.open_centre)) return true;
        const double mid = first + (j + 0.5) * span / around;
        return std::abs(std::remainder(mid - piece.open_centre, 2 * kPi)) > kPi / 3;
      });
    }
    if (!tube && trough_top > axis_z) {
      for (const double y : {-radius, radius}) {
        const Vec3 a(begin, y, axis_z), b(end, y, axis_z), c(end, y, trough_top), d(begin, y, trough_top);
        if (y < 0) shell.quad(a, b, c, d, axial_cell);
        else shell.quad(a, d, c, b, axial_cell);
      }
    }
    if (!periodic) {
      for (const double x : {0.0, length}) {
        std::vector<Vec3> ring;
        for (int k = 0; k <= around - (tube ? 1 : 0); ++k) {
          const double angle = first + span * k / around;
          ring.push_back(Vec3(x, radius * std::cos(angle), axis_z + radius * std::sin(angle)));
        }
        if (!tube) ring.push_back(Vec3(x, radius, trough_top)), ring.push_back(Vec3(x, -radius, trough_top));
        if (x > 0) std::reverse(ring.begin(), ring.end());
        shell.fan(ring);
      }
    }
    shell.transform(tilt, Vec3::Zero());
    out.meshes.push_back(shell.wall("trough", materials.liner, where));
  }
  if (!periodic) {
    const auto [inlet_min, inlet_max] = rotated_box(tilt, Vec3(0.15 * pitch, -0.35 * diameter, axis_z + radius + 0.01),
                                                     Vec3(0.85 * pitch, 0.35 * diameter, axis_z + radius + 0.01 + 0.5 * diameter));
    out.ports.push_back({"inlet", inlet_min, inlet_max, Vec3::Zero()});
    OutletSpec discharge;
    discharge.name = "discharge";
    std::tie(discharge.region_min, discharge.region_max) =
        rotated_box(tilt, Vec3(length - 0.5 * pitch, -radius, -diameter - 0.1), Vec3(length, radius, -0.01));
    out.outlets.push_back(discharge);
  }
  SensorSpec mid;
  mid.kind = SensorSpec::Kind::plane, mid.name = "mid_flow";
  mid.point = tilt * Vec3(0.5 * length, 0, axis_z), mid.normal = tilt * Vec3::UnitX();
  std::tie(mid.region_min, mid.region_max) = rotated_box(
      tilt, Vec3(0.5 * length - 0.25 * pitch, -radius, 0.0), Vec3(0.5 * length + 0.25 * pitch, radius, std::max(trough_top, 2 * radius)));
  out.sensors.push_back(mid);

  set_domain(out, margin, 1e300);  // no floor
  if (periodic) out.domain_min.x() = 0.0, out.domain_max.x() = length;
  const double swept = kPi / 4 * (diameter * diameter - shaft * shaft);  // [m^2]
  out.design = {
      {"diameter_m", diameter},
      {"shaft_diameter_m", shaft},
      {"pitch_m", pitch},
      {"length_m", length},
      {"clearance_m", clearance},
      {"rpm", rpm},
      {"inclination_deg", inclination},
      {"swept_area_m2", swept},
      {"theoretical_volume_rate_m3_s", swept * pitch * std::abs(rpm) / 60},
  };
  return out;
}

}  // namespace dem::equipment::detail
