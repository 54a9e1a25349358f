// Flat-bottomed cylindrical silo with a central circular orifice (the Beverloo set-up) and an
// optional slide-gate shutter under the orifice.
//
// Layout: floor at z = 0 with the orifice centred on the z axis, wall of `diameter` up to
// `height`. With `open_at` [s] a shutter disc (orifice radius + max(5 mm, 0.1 orifice)) lies
// 1 mm below the floor and slides away along +x at shutter_speed [2 m/s] from open_at until it
// has cleared the orifice (a slide gate; a gate dropping downwards was rejected because it
// stays in the stream). Outlet `discharge` below the floor, sensor plane `orifice` (normal -z).
// The domain reaches three silo heights up so a case can pour particles in from above.
#include <fmt/format.h>

#include "generators.h"

namespace dem::equipment::detail {

Generated silo(MapReader& reader, const EquipmentSpec& spec) {
  const Materials materials = read_materials(reader);
  const double diameter = reader.number("diameter", 0.125, 0.02, 20.0, "m");
  const double height = reader.number("height", 0.16, 0.01, 50.0, "m");
  const double orifice = reader.number("orifice_diameter", 0.04, 0.005, 0.8 * diameter, "m");
  const bool shut = reader.has("open_at");
  const double open_at = reader.number("open_at", 0.0, 0.0, 1e6, "s");
  const double gate_speed = reader.number("shutter_speed", 2.0, 0.01, 100.0, "m/s");
  const double margin = reader.number("margin", 0.05, 0.0, 10.0, "m");
  const int around = static_cast<int>(reader.integer("segments", 48, 12, 360));
  // [m] longest side of the floor's cells along the radius and of the wall's up it (at least a
  // segment's width): the wear map's resolution. Default: as wide as a segment around (square
  // cells). A lab silo that keeps no wear map takes one cell from orifice to wall and one up it:
  // fewer triangles near each particle, so fewer closest-point tests a step.
  const double cell = reader.number("cell", std::min(kCell, kPi * diameter / around), 1e-4, 100.0, "m");
  // The wall and floor as exact surfaces instead of triangles (a cylinder, and a disc with the
  // orifice as its hole): one contact per sphere against each instead of the facets near it, the
  // orifice's rim a true circle, and no wear map or liner pressure of either (the lab silo's choice).
  const bool exact_wall = reader.boolean("exact_wall", false);
  const SourceLocation& where = spec.location;
  const double radius = 0.5 * diameter, hole = 0.5 * orifice;

  Generated out;
  out.camera = "side";
  if (!exact_wall) {
    MeshBuilder silo;
    silo.grid([&](double u, double w) {  // floor annulus, normal +z
      const double r = hole + u * (radius - hole), angle = 2 * kPi * w;
      return Vec3(r * std::cos(angle), r * std::sin(angle), 0);
    }, segments(radius - hole, cell), around);
    silo.grid([&](double u, double w) {  // wall, normal inward
      const double angle = 2 * kPi * w;
      return Vec3(radius * std::cos(angle), radius * std::sin(angle), u * height);
    }, segments(height, std::max(cell, 2 * kPi * radius / around)), around);
    out.meshes.push_back(silo.wall("silo", materials.liner, where));
  } else {
    PlaneWallSpec wall;
    wall.name = "silo_wall", wall.material = materials.liner, wall.location = where;
    wall.shape = PlaneWallSpec::Shape::cylinder, wall.radius = radius, wall.point = Vec3::Zero(), wall.normal = Vec3(0, 0, 1);
    out.planes.push_back(wall);
    PlaneWallSpec floor = wall;
    floor.name = "silo_floor", floor.shape = PlaneWallSpec::Shape::disc, floor.hole_radius = hole;
    out.planes.push_back(floor);
  }
  if (shut) {
    MeshBuilder gate;
    const double gate_radius = hole + std::max(0.005, 0.1 * orifice);
    std::vector<Vec3> ring;
    for (int k = 0; k < around; ++k) {
      const double angle = 2 * kPi * k / around;
      ring.push_back(Vec3(gate_radius * std::cos(angle), gate_radius * std::sin(angle), -0.001));
    }
    gate.fan(ring);
    MeshWallSpec wall = gate.wall("shutter", materials.liner, where);
    MotionPart slide;
    slide.kind = MotionPart::Kind::translation;
    slide.velocity = Vec3(gate_speed, 0, 0);
    slide.start = open_at;
    slide.stop = open_at + (hole + gate_radius + 0.005) / gate_speed;
    wall.motion.parts.push_back(slide);
    out.meshes.push_back(std::move(wall));
  }
  out.ports.push_back({"top", Vec3(-0.35 * diameter, -0.35 * diameter, height + 0.01),
                       Vec3(0.35 * diameter, 0.35 * diameter, height + 0.01 + 0.5 * diameter), Vec3::Zero()});
  OutletSpec discharge;
  discharge.name = "discharge";
  discharge.region_min = Vec3(-radius, -radius, -std::max(0.1, diameter));
  discharge.region_max = Vec3(radius, radius, -0.02);
  out.outlets.push_back(discharge);
  SensorSpec flow;
  flow.kind = SensorSpec::Kind::plane, flow.name = "orifice";
  flow.point = Vec3::Zero(), flow.normal = Vec3(0, 0, -1);
  flow.region_min = Vec3(-hole, -hole, -0.02), flow.region_max = Vec3(hole, hole, 0.02);
  out.sensors.push_back(flow);
  set_domain(out, margin, 1e300);
  out.domain_max.z() = std::max(out.domain_max.z(), 3 * height + margin);
  out.domain_max.x() = std::max(out.domain_max.x(), radius + 2 * orifice + 0.02 + margin);  // the opened gate
  out.design = {
      {"diameter_m", diameter},
      {"height_m", height},
      {"orifice_diameter_m", orifice},
      {"orifice_area_m2", kPi * hole * hole},
      {"open_at_s", shut ? open_at : 0.0},
  };
  return out;
}

}  // namespace dem::equipment::detail
