// The transfer chute's walls, internal to equipment/: one function per part, each appending its
// mesh to the generator's output; the order of the generator's calls (transfer_chute.cpp) is the
// order of the meshes. The parts of the receiving side are built in its frame and turned
// (transfer_chute_layout.h). Lengths [m], speeds [m/s].
#pragma once

#include "generators.h"
#include "transfer_chute_parts.h"

namespace dem::equipment::detail {

/// Feed belt, troughed, flattening linearly over the transition before the pulley.
void add_feed_belt(const ChuteBuild& chute, Generated& out);

/// Head pulley: omega = +V / R_p about +y moves its top (0, 0, R_p) at omega y x R z = +V x.
void add_head_pulley(const ChuteBuild& chute, Generated& out);

/// Hood arc from its top (90 deg) down to its end angle; roof from the chute back to the hood top.
void add_hood(const ChuteBuild& chute, Generated& out);

/// Rock box: the ledge from the hood back to the dam, the dam up to the impact height, and, when
/// the ledge is narrower than the chute, end plates from the dam to the hood.
void add_rock_box(const ChuteBuild& chute, Generated& out);

/// Spoon (arc or profile) and the back plate above its top edge, turned to the receiving belt.
void add_spoon(const ChuteBuild& chute, Generated& out);

/// Side plates of the inline chute, from behind the pulley to past the hood and the lip.
void add_side_plates(const ChuteBuild& chute, Generated& out);

/// The angled transfer's enclosure: the hood's box above join_z (side plates, the front plate
/// under the hood where it runs past vertical, the deck closing its floor outside the spoon's
/// box), the spoon's box below, turned (side plates, the deck closing its top outside the hood's
/// box); one mesh, like the inline chute's side plates.
void add_angled_enclosure(const ChuteBuild& chute, Generated& out);

/// Receiving belt, turned to its direction of travel.
void add_receiving_belt(const ChuteBuild& chute, Generated& out);

/// Skirts on the receiving belt from just behind the spoon lip.
void add_skirts(const ChuteBuild& chute, Generated& out);

}  // namespace dem::equipment::detail
