// The transfer chute's layout, internal to equipment/: the parameters read and checked, and the
// positions laid out from them (trajectory and impact point, hood, rock box, fall line, spoon,
// enclosure, belts); and the receiving side's frame, which the meshes (transfer_chute_meshes.cpp)
// and the sensors (transfer_chute_sensors.cpp) turn their parts by. The rules are in the header
// of transfer_chute.cpp. Lengths [m], angles [rad].
#pragma once

#include <Eigen/Geometry>

#include <array>
#include <utility>
#include <vector>

#include "generators.h"

namespace dem::equipment::detail {

/// The parameters, checked, and the chute laid out from them: the feed side, the hood, the
/// impact point and the rock box on it, the fall line, the spoon, the enclosure, the belt's tail.
/// `largest_particle` [m] (0: unknown) sizes the rock box's bed and the profile trough's width.
TransferChuteLayout read_layout(MapReader& reader, double largest_particle);

// ---- the receiving side's frame: laid out along +x, turned by plan_angle about the fall line ---

/// A point of the receiving side in the world: laid out as for the inline chute (x along the
/// receiving belt), turned about the fall line. Unchanged at plan_angle 0.
Vec3 turned(const TransferChuteLayout& c, const Vec3& local);

/// The receiving side's frame of a world point (the inverse of turned()).
Vec3 unturned(const TransferChuteLayout& c, const Vec3& world);

/// A direction of the receiving side in the world (a belt velocity, a sensor's normal).
Vec3 turned_direction(const TransferChuteLayout& c, const Vec3& local);

/// Moves a part of the receiving side, built in its frame, to the world.
void turn(const TransferChuteLayout& c, MeshBuilder& mesh);

/// The axis-aligned box around the receiving side's box [lo, hi] turned to the world.
std::pair<Vec3, Vec3> turned_box(const TransferChuteLayout& c, const Vec3& lo, const Vec3& hi);

// ---- the profile spoon --------------------------------------------------------------------------

/// Where the walls of a trough swept along the profile rise from each point: the segment's
/// normal (-t_z, t_x) at the ends, and at a joint the mitre m = (n1 + n2) / (1 + n1.n2), whose
/// component along both normals is 1, so that the walls keep their height through the bend.
std::vector<Vec3> profile_mitres(const std::vector<std::array<double, 2>>& profile);

}  // namespace dem::equipment::detail
