// Parametric equipment: generators that turn a few design parameters (drop height, spoon radius,
// screw pitch, bucket spacing, belt speed, ...) into triangle meshes with their motions, and the
// named ports, outlets and sensors a case needs around them. A case says
//
//   equipment:
//     transfer_chute: {drop_height: 2.0, spoon: {radius: 1.2}, ...}
//   inlets:
//     - {name: feed, port: feed_belt, material: ore, mass_rate_tph: 800, diameter: {...}}
//
// and `expand_equipment(spec)` appends the generated meshes, outlets and sensors to the spec,
// fills every inlet's region and velocity from its port, sets the domain when the case gives none,
// and records the design values the report shows. The generated meshes are inline triangles, so
// they need no files; `write_equipment_meshes` saves them as STL beside the results.
//
// Generators (one file each, layout rules and defaults in the file's header comment):
// transfer_chute.cpp (inline or angled, with an optional rock box and profile spoon),
// screw_conveyor.cpp, bucket_elevator.cpp (buckets ride a belt_loop motion, kinematics.h),
// belt_conveyor.cpp, silo.cpp. Every parameter has a default (`transfer_chute: {}` works);
// `liner_material` (steel) and `belt_material` (rubber) name the case materials.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "case/spec.h"

namespace dem::equipment {

/// Where material enters: a box to insert particles in, and their initial velocity.
struct Port {
  std::string name;
  Vec3 region_min{0, 0, 0}, region_max{0, 0, 0};  // [m]
  Vec3 velocity{0, 0, 0};                          // [m/s]
};

/// What a generator produces.
struct Generated {
  std::vector<MeshWallSpec> meshes;   ///< inline triangles [m], with motion / surface velocity
  std::vector<PlaneWallSpec> planes;  ///< exact walls (planes, cylinders) where triangles are not needed
  std::vector<Port> ports;            ///< feed points for inlets
  std::vector<OutletSpec> outlets;    ///< the intended outlets (material leaving elsewhere is spillage)
  std::vector<SensorSpec> sensors;    ///< flow planes and boxes the report uses
  Vec3 domain_min{0, 0, 0}, domain_max{0, 0, 0};  // [m] box holding the plant
  std::string camera = "side";        ///< render preset that suits the equipment
  std::vector<std::pair<std::string, double>> design;  ///< named design values, unit in the name
};

/// The transfer chute's layout [m, rad, m/s]: the parameters with defaults filled in and the
/// derived positions. Feed belt surface at z = drop_height, ending at the head pulley top at
/// x = 0; receiving belt surface at z = 0. Arc angles are measured at the arc's centre from +x
/// towards +z. The feed side (feed belt, pulley, hood, rock box) lies in the x-z plane about
/// y = 0. The receiving side (spoon, receiving belt, skirts) is laid out in the same way, x along
/// the receiving belt, and then turned by plan_angle about the vertical through (fall_x, 0): its
/// x values below (spoon_*, receiving_x_*, spoon_box_x_max) are in that frame; at plan_angle 0
/// it is the world.
struct TransferChuteLayout {
  double drop_height = 0, chute_width = 0;
  double feed_width = 0, feed_speed = 0, feed_length = 0, feed_trough = 0, transition_length = 0;
  double pulley_radius = 0, load_height = 0, feed_port_height = 0;
  double hood_radius = 0, hood_distance = 0, hood_top_height = 0, hood_exit_angle = 0;  ///< exit_angle: past vertical
  double hood_centre_x = 0, hood_centre_z = 0;
  double hood_end_angle = 0;       ///< [rad] where the hood arc ends (-exit_angle unless cut by the spoon)
  double hood_exit_x = 0, hood_exit_z = 0;
  double spoon_radius = 0, spoon_lip_height = 0, spoon_setback = 0;
  double spoon_centre_x = 0, spoon_centre_z = 0;
  double spoon_start_angle = 0;    ///< [rad] from the bottom of the arc (0) towards the back (pi/2); pi/2: full quarter
  double spoon_exit_angle = 0;     ///< [rad] where the arc ends, before its bottom: the lip's slope below horizontal
  double spoon_top_x = 0, spoon_top_z = 0, spoon_lip_x = 0;
  double back_plate_top = 0;       ///< the back plate spans x = spoon_top_x, z in [spoon_top_z, back_plate_top]
  double side_x_min = 0, side_x_max = 0, side_z_min = 0, side_z_max = 0;
  double receiving_width = 0, receiving_speed = 0, receiving_trough = 0;
  double receiving_x_min = 0, receiving_x_max = 0;
  double skirt_width = 0, skirt_length = 0, skirt_height = 0;

  /// [rad] the receiving belt's direction of travel, turned about +z from the feed belt's (+x);
  /// 0: the inline chute, pi/2: a right-angle transfer.
  double plan_angle = 0;
  /// [m] the vertical x = fall_x, y = 0 the stream comes down from the hood on: the hood's exit, or
  /// the rock box's dam when that lies behind it. The receiving side turns about it.
  double fall_x = 0;
  double impact_x = 0, impact_z = 0;  ///< [m] where the CEMA trajectory meets the hood (NAN: the pulley top lies outside it)

  // Angled transfer (plan_angle > 0): the hood's enclosure above z = join_z, in the feed frame;
  // the spoon's below it, in the receiving frame; a deck at join_z closes what one has and the
  // other has not.
  double join_z = 0;           ///< [m] the hood's exit height
  double hood_box_x_max = 0;   ///< [m] front of the hood's enclosure (its front plate when the hood runs past vertical)
  double spoon_box_x_max = 0;  ///< [m] front of the spoon's enclosure, receiving frame

  // Rock box: a ledge across the hood below the impact point with a dam at its inner edge.
  bool rock_box = false;
  double rock_box_height = 0;   ///< [m] the dam's height: the dead bed's depth at the dam
  double ledge_depth = 0;       ///< [m] how far the ledge reaches from the hood into the chute, at its own height
  double ledge_width = 0;       ///< [m] across the chute, centred on y = 0
  double ledge_z = 0;           ///< [m] the ledge; the dam's top is at impact_z
  double ledge_wall_x = 0;      ///< [m] where the ledge meets the hood
  double dam_x = 0;             ///< [m] the dam, ledge_wall_x - ledge_depth

  // Profile spoon (spoon.profile): a trough swept along a polyline instead of the arc.
  std::vector<std::array<double, 2>> spoon_profile;  ///< [m] (x from fall_x along the receiving belt, z above it); empty: the arc spoon
  double trough_width = 0, trough_depth = 0;          ///< [m] across, and the side walls' height above the centre line
  bool trough_u = false;                              ///< U (half circle of the width, then straight sides) or rectangular
};

/// Reads a transfer_chute spec's parameters (CaseError for bad ones) and lays the chute out.
TransferChuteLayout transfer_chute_layout(const EquipmentSpec& spec);

/// Runs the generator named by `spec` (throws CaseError naming file, line and key for bad
/// parameters). Parameters `liner_material` (default steel) and `belt_material` (default rubber)
/// name the case materials of the steel parts and of the belts.
Generated generate(const EquipmentSpec& spec);

/// Expands spec.equipment (if any) into the spec: meshes, outlets and sensors appended, inlet
/// ports resolved (an unknown port is a CaseError listing the valid ones), domain set when the
/// case has none, design values and camera recorded. The generator sees the largest particle the
/// case's inlets and particle sets draw (EquipmentSpec::largest_particle) to check openings and
/// beds against.
void expand_equipment(CaseSpec& spec);

/// Writes every inline mesh of the spec as binary STL into `directory` (created), one file per
/// mesh, named after it; returns the paths.
std::vector<std::string> write_equipment_meshes(const CaseSpec& spec, const std::string& directory);

/// Names of the generators, for errors and documentation.
std::vector<std::string> generator_names();

}  // namespace dem::equipment
