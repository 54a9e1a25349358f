// Belt-to-belt transfer: troughed feed belt over a head pulley, a hood that catches the
// trajectory (optionally with a rock box at the impact point), a spoon that turns the stream onto
// the receiving belt, side and back plates, skirts. The receiving belt runs on in the feed belt's
// direction (inline, plan_angle_deg 0, the default) or turned from it by plan_angle_deg about the
// vertical (an angled transfer; 90: a right-angle transfer).
//
// Layout rules (defaults in brackets; all lengths in metres). The feed side lies in the x-z
// plane, extruded along y about y = 0:
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
//    (the spoon keeps at least a 32 deg arc), or than 0.05 above a profile spoon's first point; an
//    error when that leaves less than 5 deg of hood below the impact point.
//  - Rock box (rock_box: {height [0.25], ledge_depth [0.3], ledge_width [chute_width]}, absent: none):
//    a horizontal ledge across the hood `height` below the point where the trajectory meets the
//    hood, reaching ledge_depth back from the hood, with a dam at its inner edge whose top is at
//    the impact height. Material fills the box and the stream strikes that dead bed instead of
//    the liner. The dam stands behind the impact point, 0.05 m under the trajectory (the stream
//    passes over it) and in front of the head pulley; height and ledge_depth are at least 2 top
//    particle sizes when the case's particles are known (rule and sources at read_rock_box in
//    transfer_chute_layout.cpp).
//  - The stream comes down from the hood on the fall line x = fall_x, y = 0: the hood's exit, or
//    the rock box's dam when that lies behind the exit.
//  - Spoon: arc of spoon.radius [0.8] from vertical (at its back, -x) to spoon.exit_angle_deg [15]
//    before horizontal at its lip, spoon.lip_height [0.15] above the receiving belt. Its top edge
//    lies spoon.setback [0.15] behind (-x of) the fall line and at most 0.05 below the hood exit:
//    when the full quarter would reach higher, the arc starts lower (its vertical-tangent point is
//    then virtual, above the top edge). A vertical back plate rises from the spoon top edge to 0.1
//    above the hood exit.
//  - Profile spoon (spoon.profile instead of radius, lip_height, setback, exit_angle_deg): a
//    trough of spoon.width [chute_width] and spoon.shape [U] (a half circle of the width with
//    straight sides, or rectangular), its walls spoon.depth [width / 2] high, swept along the
//    polyline of spoon.profile points [x, z]: x from the fall line along the receiving belt, z
//    above it; at least 2 points, each lower than the one before, none behind the one before,
//    the first at or behind the fall line, the last the lip; wider than 3 top particle sizes.
//  - Side plates at y = +-chute_width/2 [0.7] from x = -R_p - 0.2 to 0.1 past the hood or the
//    spoon lip, from just above the receiving belt surface there to 0.05 above the hood top; a
//    roof closes the gap between the chute's back and the hood top.
//  - Receiving belt surface at z = 0 from the spoon lip - tail_length [to 0.5 behind the chute]
//    to the lip + length [3]; skirts at y = +-skirt_width/2 [min(chute_width, 0.9 width)] from
//    0.05 behind the lip for skirt_length [1.5], skirt_height [0.3] high.
//  - Sensors: flow planes at the spoon lip (spoon_exit) and 0.3 before the belt's end
//    (belt_discharge); load boxes on the belt from the lip for 1 m (loading_zone) and for 0.5 m
//    after it (stream_belt, 12 bins across the belt; over the loading zone on a belt too short
//    for both); and a box across the chute's narrowest section (stream_chute, 12 bins across the
//    chute): the throat at the hood's exit height between the hood's lower edge and the spoon's
//    back plate (choke_section in transfer_chute_sensors.h gives the reasons).
//
// Angled transfer (plan_angle_deg in (0, 180]): the receiving side (spoon, receiving belt, skirts,
// discharge outlet, sensors) is laid out as above with x along the receiving belt and turned by
// plan_angle about the fall line, so that the spoon delivers in the receiving belt's direction of
// travel, centred on it. The stream is as wide across the feed belt as the chute, and that width
// now lies partly along the spoon: the spoon's top edge moves back by chute_width/2 |sin
// plan_angle| more, and its enclosure reaches as far forward. The chute is two boxes: the hood's,
// side plates at y = +-chute_width/2 from the hood's exit height (join_z) to above the hood, with
// a front plate under the hood where it runs past vertical; and the spoon's, turned, side plates
// from just above the receiving belt up to join_z, the back plate from the spoon's top edge to
// join_z. A deck at join_z closes the hood box's floor outside the spoon box and the spoon box's
// top outside the hood box (cells of half the chute cell, so that those that reach into the
// opening between the boxes narrow it by less than a cell's diagonal, 0.085 m). Rejected: one pair of side plates
// spanning hood and spoon, which at any angle but 0 and 180 deg would stand across the stream.
// Boxes (discharge outlet, sensor regions) are axis-aligned, so a turned one is the box around it:
// exact at 90 and 180 deg, larger in between; the discharge outlet then lies below the belt's
// surface (z < -0.1), from 0.02 to 2 m past the belt's end, so that it holds nothing riding on the
// belt.
//
// The generator below lists the chute's parts in the order they are appended; each concern has its
// own file: transfer_chute_layout.cpp reads the parameters and lays the chute out,
// transfer_chute_meshes.cpp builds the walls, transfer_chute_sensors.cpp places the feed port,
// the discharge outlet and the sensors and sets the design values; transfer_chute_parts.h holds
// what the meshes and the sensors are built from.
#include <yaml-cpp/yaml.h>

#include <string>

#include "generators.h"
#include "transfer_chute_layout.h"
#include "transfer_chute_meshes.h"
#include "transfer_chute_parts.h"
#include "transfer_chute_sensors.h"

namespace dem::equipment {

namespace detail {

Generated transfer_chute(MapReader& reader, const EquipmentSpec& spec) {
  const Materials materials = read_materials(reader);
  const double margin = reader.number("margin", 0.5, 0.0, 10.0, "m");
  const TransferChuteLayout c = read_layout(reader, spec.largest_particle);
  const ChuteBuild chute{c, materials, spec.location, 0.5 * c.chute_width, 0.5 * c.receiving_width};
  Generated out;
  out.camera = c.plan_angle == 0 ? "side" : "iso";

  add_feed_belt(chute, out);
  add_head_pulley(chute, out);
  add_hood(chute, out);
  if (c.rock_box) add_rock_box(chute, out);
  add_spoon(chute, out);
  if (c.plan_angle == 0) add_side_plates(chute, out);
  else add_angled_enclosure(chute, out);
  add_receiving_belt(chute, out);
  if (c.skirt_length > 0) add_skirts(chute, out);

  add_feed_port(c, out);
  add_discharge_outlet(chute, out);
  add_sensors(chute, out);
  const ChokeSection choke = choke_section(c);
  add_stream_sensors(chute, choke, out);

  set_domain(out, margin, -1.0);
  set_design(c, spec.largest_particle, out);
  choke_design(choke, out.design);
  return out;
}

}  // namespace detail

// Reads every key the generator reads, in the same order, so that finish() refuses exactly the
// keys the generator would.
TransferChuteLayout transfer_chute_layout(const EquipmentSpec& spec) {
  YAML::Node params = spec.params && *spec.params && !spec.params->IsNull() ? YAML::Node(*spec.params)
                                                                            : YAML::Node(YAML::NodeType::Map);
  MapReader reader(params, spec.file, "equipment." + spec.type);
  detail::read_materials(reader);
  reader.number("margin", 0.5, 0.0, 10.0, "m");
  TransferChuteLayout layout = detail::read_layout(reader, spec.largest_particle);
  reader.finish();
  return layout;
}

}  // namespace dem::equipment
