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
// transfer_chute.cpp, screw_conveyor.cpp, bucket_elevator.cpp (buckets ride a belt_loop motion,
// kinematics.h), belt_conveyor.cpp, silo.cpp. Every parameter has a default (`transfer_chute: {}`
// works); `liner_material` (steel) and `belt_material` (rubber) name the case materials.
#pragma once

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

/// The transfer chute's layout in the x-z plane (centre line y = 0) [m, rad, m/s]: the parameters
/// with defaults filled in and the derived positions. Feed belt surface at z = drop_height, ending
/// at the head pulley top at x = 0; receiving belt surface at z = 0. Arc angles are measured at
/// the arc's centre from +x towards +z.
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
};

/// Reads a transfer_chute spec's parameters (CaseError for bad ones) and lays the chute out.
TransferChuteLayout transfer_chute_layout(const EquipmentSpec& spec);

/// Runs the generator named by `spec` (throws CaseError naming file, line and key for bad
/// parameters). Parameters `liner_material` (default steel) and `belt_material` (default rubber)
/// name the case materials of the steel parts and of the belts.
Generated generate(const EquipmentSpec& spec);

/// Expands spec.equipment (if any) into the spec: meshes, outlets and sensors appended, inlet
/// ports resolved (an unknown port is a CaseError listing the valid ones), domain set when the
/// case has none, design values and camera recorded.
void expand_equipment(CaseSpec& spec);

/// Writes every inline mesh of the spec as binary STL into `directory` (created), one file per
/// mesh, named after it; returns the paths.
std::vector<std::string> write_equipment_meshes(const CaseSpec& spec, const std::string& directory);

/// Names of the generators, for errors and documentation.
std::vector<std::string> generator_names();

}  // namespace dem::equipment
