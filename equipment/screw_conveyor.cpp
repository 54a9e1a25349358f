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

namespace {

/// The screw conveyor's parameters with defaults filled in [m, rpm, deg] and its frame.
struct ScrewConveyor {
  Materials materials;
  double diameter = 0, shaft = 0, pitch = 0, length = 0;  // [m] flight, shaft, pitch, length
  double thickness = 0;    // [m] flight thickness
  double clearance = 0;    // [m] between flight tip and trough
  double rpm = 0;          // positive conveys +x
  std::string trough;      // "U" or "tubular"
  double radius = 0;       // [m] trough radius
  double trough_top = 0;   // [m] top of a U trough's sides
  double inclination = 0;  // [deg] the +x end raised about y
  bool periodic = false;
  int per_turn = 0;        // flight segments per turn
  double margin = 0;       // [m] domain around the plant
  // Frame, from the parameters.
  double axis_z = 0;          // [m] trough bottom at z = 0
  double begin = 0, end = 0;  // [m] x range of flight and shaft
  Eigen::Matrix3d tilt = Eigen::Matrix3d::Identity();  // raises the +x end: x -> (cos, 0, sin)
};

/// Every parameter, in the order they are read (the case-key reference records that order).
ScrewConveyor read_screw_conveyor(MapReader& reader) {
  ScrewConveyor screw;
  screw.materials = read_materials(reader);
  screw.diameter = reader.number("diameter", 0.1, 0.02, 2.0, "m");
  screw.shaft = reader.number("shaft_diameter", 0.3 * screw.diameter, 0.005, 0.9 * screw.diameter, "m");
  screw.pitch = reader.number("pitch", screw.diameter, 0.1 * screw.diameter, 3.0 * screw.diameter, "m");
  screw.length = reader.number("length", 4 * screw.pitch, 2 * screw.pitch, 1000 * screw.pitch, "m");
  screw.thickness = reader.number("flight_thickness", 0.0, 0.0, 0.25 * screw.pitch, "m");
  screw.clearance = reader.number("clearance", std::min(0.005, 0.1 * screw.diameter), 0.0, screw.diameter, "m");
  screw.rpm = reader.number("rpm", 30.0, -3000.0, 3000.0, "rpm");
  screw.trough = reader.string("trough", "U", {"U", "tubular"});
  screw.radius = 0.5 * screw.diameter + screw.clearance;  // [m] trough radius
  screw.trough_top = reader.number("trough_height", 1.2 * screw.diameter, screw.radius, 20 * screw.diameter, "m");
  screw.inclination = reader.number("inclination_deg", 0.0, -90.0, 90.0, "deg");
  screw.periodic = reader.boolean("periodic", false);
  screw.per_turn = static_cast<int>(reader.integer("segments_per_turn", 32, 12, 96));
  screw.margin = reader.number("margin", 0.2, 0.0, 10.0, "m");
  return screw;
}

/// A periodic screw: a whole number of pitches (the flight continuous across the wrap), level.
void check_periodic(MapReader& reader, const ScrewConveyor& screw) {
  const double turns = screw.length / screw.pitch;
  if (std::abs(turns - std::round(turns)) > 1e-9 * turns) {
    reader.fail("length", fmt::format("{:g} m is {:g} pitches; a periodic screw needs a whole number (valid: e.g. {:g} m)",
                                      screw.length, turns, std::max(1.0, std::round(turns)) * screw.pitch));
  }
  if (screw.inclination != 0.0) {
    reader.fail("inclination_deg", "must be 0 for a periodic screw; tilt simulation.gravity instead");
  }
}

/// The axis height, the x range of flight and shaft, and the tilt.
void set_frame(ScrewConveyor& screw) {
  screw.axis_z = screw.radius;  // [m] trough bottom at z = 0
  screw.begin = screw.periodic ? -screw.pitch : 0.0;
  screw.end = screw.periodic ? screw.length + screw.pitch : screw.length;
  const double theta = radians(screw.inclination);
  screw.tilt << std::cos(theta), 0, -std::sin(theta), 0, 1, 0, std::sin(theta), 0, std::cos(theta);
}

/// Flight (helicoid, both faces and the rim when thick) and shaft, tilted.
MeshBuilder flight_and_shaft(const ScrewConveyor& screw) {
  MeshBuilder rotor;
  const double turns = (screw.end - screw.begin) / screw.pitch;
  const int around = std::max(1, static_cast<int>(std::ceil(turns * screw.per_turn - 1e-9)));
  const int radial = std::max(2, segments(0.5 * (screw.diameter - screw.shaft), kPi * screw.diameter / screw.per_turn));
  const double sweep = 2 * kPi * turns;
  const auto helicoid = [&](double shift) {
    rotor.grid([&, shift](double u, double w) {
      const double phi = u * sweep, r = 0.5 * screw.shaft + w * 0.5 * (screw.diameter - screw.shaft);
      return Vec3(screw.begin + screw.pitch * phi / (2 * kPi) + shift, r * std::cos(phi), screw.axis_z + r * std::sin(phi));
    }, around, radial);
  };
  helicoid(-0.5 * screw.thickness);
  if (screw.thickness > 0) {
    helicoid(0.5 * screw.thickness);
    const double tip = 0.5 * screw.diameter;
    rotor.grid([&](double u, double w) {  // rim band at the flight tip
      const double phi = u * sweep;
      return Vec3(screw.begin + screw.pitch * phi / (2 * kPi) + (w - 0.5) * screw.thickness, tip * std::cos(phi),
                  screw.axis_z + tip * std::sin(phi));
    }, around, 1);
    for (const double phi : {0.0, sweep}) {  // ends of the flight
      const Vec3 inner(0, 0.5 * screw.shaft * std::cos(phi), screw.axis_z + 0.5 * screw.shaft * std::sin(phi));
      const Vec3 outer(0, tip * std::cos(phi), screw.axis_z + tip * std::sin(phi));
      const Vec3 at(screw.begin + screw.pitch * phi / (2 * kPi), 0, 0), half(0.5 * screw.thickness, 0, 0);
      rotor.quad(inner + at - half, outer + at - half, outer + at + half, inner + at + half,
                 kPi * screw.diameter / screw.per_turn);
    }
  }
  cylinder(rotor, Vec3(screw.begin, 0, screw.axis_z), Vec3(screw.end, 0, screw.axis_z), 0.5 * screw.shaft,
           std::max(12, screw.per_turn / 2), false);
  rotor.transform(screw.tilt, Vec3::Zero());
  return rotor;
}

/// Flight and shaft: one mesh turning about the tilted axis.
void add_screw(Generated& out, const ScrewConveyor& screw, const SourceLocation& where) {
  MeshWallSpec wall = flight_and_shaft(screw).wall("screw", screw.materials.liner, where);
  MotionPart turn;
  turn.kind = MotionPart::Kind::rotation;
  turn.axis = screw.tilt * Vec3::UnitX();
  turn.point = screw.tilt * Vec3(0, 0, screw.axis_z);
  turn.angular_speed = -screw.rpm * 2 * kPi / 60;  // clockwise about +x conveys +x (right-handed flight)
  wall.motion.parts.push_back(turn);
  out.meshes.push_back(std::move(wall));
}

/// The trough's cross-section: a U's lower half circle or a tube's full circle, angles
/// anticlockwise about +x from +y.
struct TroughShape {
  bool tube = false;
  int around = 0;              // segments of the arc
  double first = 0, span = 0;  // [rad] start and extent of the arc
  double axial_cell = 0;       // [m] cell length along x
};

TroughShape trough_shape(const ScrewConveyor& screw) {
  TroughShape shape;
  shape.tube = screw.trough == "tubular";
  shape.around = shape.tube ? screw.per_turn : screw.per_turn / 2;
  shape.first = shape.tube ? 0.0 : kPi, shape.span = shape.tube ? 2 * kPi : kPi;
  shape.axial_cell = std::min(kCell, 0.25 * screw.pitch);
  return shape;
}

/// The trough's arc along x, with the inlet and outlet openings.
void add_trough_arc(MeshBuilder& shell, const ScrewConveyor& screw, const TroughShape& shape) {
  // Pieces along x: [begin, end] when periodic; else first pitch (tube: top opening), middle,
  // last half pitch (bottom opening).
  struct Piece { double x0, x1, open_centre; };  // open_centre: angle of a 120 deg opening, or NAN
  std::vector<Piece> pieces;
  if (screw.periodic) pieces.push_back({screw.begin, screw.end, NAN});
  else {
    const double inlet_end = shape.tube ? screw.pitch : 0.0;
    if (shape.tube) pieces.push_back({0.0, inlet_end, 0.5 * kPi});
    pieces.push_back({inlet_end, screw.length - 0.5 * screw.pitch, NAN});
    pieces.push_back({screw.length - 0.5 * screw.pitch, screw.length, 1.5 * kPi});
  }
  for (const Piece& piece : pieces) {
    const int along = segments(piece.x1 - piece.x0, shape.axial_cell);
    shell.grid([&](double w, double u) {  // normals inward, towards the axis
      const double angle = shape.first + u * shape.span;
      return Vec3(piece.x0 + w * (piece.x1 - piece.x0), screw.radius * std::cos(angle),
                  screw.axis_z + screw.radius * std::sin(angle));
    }, along, shape.around, [&](int, int j) {
      if (std::isnan(piece.open_centre)) return true;
      const double mid = shape.first + (j + 0.5) * shape.span / shape.around;
      return std::abs(std::remainder(mid - piece.open_centre, 2 * kPi)) > kPi / 3;
    });
  }
}

/// A U trough's vertical sides from the axis up to its top.
void add_trough_sides(MeshBuilder& shell, const ScrewConveyor& screw, const TroughShape& shape) {
  for (const double y : {-screw.radius, screw.radius}) {
    const Vec3 a(screw.begin, y, screw.axis_z), b(screw.end, y, screw.axis_z), c(screw.end, y, screw.trough_top),
        d(screw.begin, y, screw.trough_top);
    if (y < 0) shell.quad(a, b, c, d, shape.axial_cell);
    else shell.quad(a, d, c, b, shape.axial_cell);
  }
}

/// End plates at x = 0 and x = length (a U trough's up to its top).
void add_end_plates(MeshBuilder& shell, const ScrewConveyor& screw, const TroughShape& shape) {
  for (const double x : {0.0, screw.length}) {
    std::vector<Vec3> ring;
    for (int k = 0; k <= shape.around - (shape.tube ? 1 : 0); ++k) {
      const double angle = shape.first + shape.span * k / shape.around;
      ring.push_back(Vec3(x, screw.radius * std::cos(angle), screw.axis_z + screw.radius * std::sin(angle)));
    }
    if (!shape.tube)
      ring.push_back(Vec3(x, screw.radius, screw.trough_top)), ring.push_back(Vec3(x, -screw.radius, screw.trough_top));
    if (x > 0) std::reverse(ring.begin(), ring.end());
    shell.fan(ring);
  }
}

/// Trough: U (half cylinder below the axis plus vertical sides) or tube, with its openings.
void add_trough(Generated& out, const ScrewConveyor& screw, const SourceLocation& where) {
  MeshBuilder shell;
  const TroughShape shape = trough_shape(screw);
  add_trough_arc(shell, screw, shape);
  if (!shape.tube && screw.trough_top > screw.axis_z) add_trough_sides(shell, screw, shape);
  if (!screw.periodic) add_end_plates(shell, screw, shape);
  shell.transform(screw.tilt, Vec3::Zero());
  out.meshes.push_back(shell.wall("trough", screw.materials.liner, where));
}

/// The inlet port above the first pitch and the discharge outlet under the last half pitch.
void add_inlet_and_discharge(Generated& out, const ScrewConveyor& screw) {
  const auto [inlet_min, inlet_max] =
      rotated_box(screw.tilt, Vec3(0.15 * screw.pitch, -0.35 * screw.diameter, screw.axis_z + screw.radius + 0.01),
                  Vec3(0.85 * screw.pitch, 0.35 * screw.diameter, screw.axis_z + screw.radius + 0.01 + 0.5 * screw.diameter));
  out.ports.push_back({"inlet", inlet_min, inlet_max, Vec3::Zero()});
  OutletSpec discharge;
  discharge.name = "discharge";
  std::tie(discharge.region_min, discharge.region_max) =
      rotated_box(screw.tilt, Vec3(screw.length - 0.5 * screw.pitch, -screw.radius, -screw.diameter - 0.1),
                  Vec3(screw.length, screw.radius, -0.01));
  out.outlets.push_back(discharge);
}

/// Flow plane across the trough at half length.
void add_mid_flow_sensor(Generated& out, const ScrewConveyor& screw) {
  SensorSpec mid;
  mid.kind = SensorSpec::Kind::plane, mid.name = "mid_flow";
  mid.point = screw.tilt * Vec3(0.5 * screw.length, 0, screw.axis_z), mid.normal = screw.tilt * Vec3::UnitX();
  std::tie(mid.region_min, mid.region_max) =
      rotated_box(screw.tilt, Vec3(0.5 * screw.length - 0.25 * screw.pitch, -screw.radius, 0.0),
                  Vec3(0.5 * screw.length + 0.25 * screw.pitch, screw.radius, std::max(screw.trough_top, 2 * screw.radius)));
  out.sensors.push_back(mid);
}

std::vector<std::pair<std::string, double>> design_values(const ScrewConveyor& screw) {
  const double swept = kPi / 4 * (screw.diameter * screw.diameter - screw.shaft * screw.shaft);  // [m^2]
  return {
      {"diameter_m", screw.diameter},
      {"shaft_diameter_m", screw.shaft},
      {"pitch_m", screw.pitch},
      {"length_m", screw.length},
      {"clearance_m", screw.clearance},
      {"rpm", screw.rpm},
      {"inclination_deg", screw.inclination},
      {"swept_area_m2", swept},
      {"theoretical_volume_rate_m3_s", swept * screw.pitch * std::abs(screw.rpm) / 60},
  };
}

}  // namespace

Generated screw_conveyor(MapReader& reader, const EquipmentSpec& spec) {
  ScrewConveyor screw = read_screw_conveyor(reader);
  if (screw.periodic) check_periodic(reader, screw);
  set_frame(screw);
  const SourceLocation& where = spec.location;

  Generated out;
  out.camera = "iso";
  add_screw(out, screw, where);
  add_trough(out, screw, where);
  if (!screw.periodic) add_inlet_and_discharge(out, screw);
  add_mid_flow_sensor(out, screw);
  set_domain(out, screw.margin, 1e300);  // no floor
  if (screw.periodic) out.domain_min.x() = 0.0, out.domain_max.x() = screw.length;
  out.design = design_values(screw);
  return out;
}

}  // namespace dem::equipment::detail
