// What the case sees around the transfer chute, internal to equipment/: the feed port, the
// discharge outlet, the sensors (flow planes, load boxes, the stream profiles across the chute's
// narrowest section and across the receiving belt) and the design values the report shows. The
// generator (transfer_chute.cpp) calls them after the meshes; the order of its calls is the order
// of the sensors and design values in the output. Lengths [m], areas [m^2].
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "generators.h"
#include "transfer_chute_parts.h"

namespace dem::equipment::detail {

/// The chute's narrowest section: its free plan area at the hood's exit height, and the box of
/// the stream_chute sensor around it, `length` along the fall line.
struct ChokeSection {
  double area = 0;    // [m^2] 0: none found (a degenerate layout)
  double height = 0;  // [m] the hood exit's
  double length = 0;  // [m] the box's extent along the fall line
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};  // [m]
};

/// Feed port over the tail of the feed belt: 70 % of the belt width, above the wing tops (the
/// particles drop into the trough), long enough to take a batch at the design rate (a box the
/// belt empties every length / speed seconds holds about 30 % solid).
void add_feed_port(const TransferChuteLayout& c, Generated& out);

/// Outlet beyond the end of the receiving belt; a turned belt's lies below its surface (see the
/// header of transfer_chute.cpp).
void add_discharge_outlet(const ChuteBuild& chute, Generated& out);

/// Sensors: flow through the spoon lip and near the belt end; load on the belt after the lip.
void add_sensors(const ChuteBuild& chute, Generated& out);

/// The chute's narrowest section. The stream comes down the fall line from the hood's lower edge
/// past the spoon's back plate (and, angled, through the deck's opening where the hood's box meets
/// the spoon's): there it is held on all four sides, by the hood's edge in front, the back plate
/// behind (spoon.setback behind the fall line, more behind a rock box's dam or along a turned
/// spoon) and the side plates. Above, the hood's box is open back to behind the head pulley; below,
/// the hood has ended and the front is open; in the spoon the stream slides on the liner with the
/// chute's height above it. Rejected: the skirted section on the receiving belt, which is the
/// belt's (belt_capacity.csv), not the chute's. The box reaches kChokeReach below the exit (not
/// below the spoon's top edge) and, where the hood stands in front above its exit (run past
/// vertical), as far above it (under the back plate's top, the rock box's ledge and the pulley).
/// Between 0, 90 and 180 deg the box around a turned section is larger than it: the fill then
/// reads high.
ChokeSection choke_section(const TransferChuteLayout& c);

/// Stream profile sensors: `stream_chute` across the chute's narrowest section, down the fall
/// line; `stream_belt` across the receiving belt after the loading zone, along the belt (over
/// the loading zone itself on a belt too short for both).
void add_stream_sensors(const ChuteBuild& chute, const ChokeSection& choke, Generated& out);

/// The design values the report shows.
void set_design(const TransferChuteLayout& c, double largest_particle, Generated& out);

/// The design values of the chute's narrowest section: its free area, the stream_chute box's
/// length along the fall line, and its height (the hood exit's); the report's choke fill is the
/// box's mass over bulk density x area x length.
void choke_design(const ChokeSection& choke, std::vector<std::pair<std::string, double>>& design);

}  // namespace dem::equipment::detail
