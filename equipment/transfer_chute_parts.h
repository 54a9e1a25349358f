// What the parts of the transfer chute are built from, internal to equipment/: the layout, the
// walls' materials and the case's location, set up once by the generator (transfer_chute.cpp)
// and handed to the meshes (transfer_chute_meshes.cpp) and the sensors
// (transfer_chute_sensors.cpp).
#pragma once

#include "generators.h"

namespace dem::equipment::detail {

/// What every part of the chute is built from: its layout, the materials of its walls, where the
/// case declares it, and the half widths its walls and sensors are placed at.
struct ChuteBuild {
  const TransferChuteLayout& layout;
  const Materials& materials;
  const SourceLocation& where;
  double half;            // [m] half the chute width: the side plates' y
  double receiving_half;  // [m] half the receiving belt's width
};

}  // namespace dem::equipment::detail
