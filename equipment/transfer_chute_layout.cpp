// The transfer chute's layout: its parameters read and checked one sub-map at a time (feed belt,
// hood, spoon, receiving belt, rock box), and the chute laid out from them in the order each
// position needs the ones before it: hood, impact point, rock box, fall line, spoon, enclosure,
// the receiving belt's ends. The rules, with their defaults, are in the header of
// transfer_chute.cpp; lengths [m], angles [rad], speeds [m/s].
#include "transfer_chute_layout.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "generators.h"

namespace dem::equipment::detail {

namespace {

/// The turn of the receiving side: plan_angle about +z, written out so that heights stay exact.
Eigen::Matrix3d plan_rotation(const TransferChuteLayout& c) {
  const double cos_a = std::cos(c.plan_angle), sin_a = std::sin(c.plan_angle);
  Eigen::Matrix3d rotation;
  rotation << cos_a, -sin_a, 0, sin_a, cos_a, 0, 0, 0, 1;
  return rotation;
}

/// [m] How far the stream, chute_width wide across the feed belt, reaches along the receiving
/// belt on either side of the fall line.
double stream_reach(const TransferChuteLayout& c) { return 0.5 * c.chute_width * std::abs(std::sin(c.plan_angle)); }

}  // namespace

// ---- the receiving side's frame --------------------------------------------------------------

Vec3 turned(const TransferChuteLayout& c, const Vec3& local) {
  if (c.plan_angle == 0) return local;
  const Vec3 fall(c.fall_x, 0, 0);
  return Vec3(fall + plan_rotation(c) * (local - fall));
}

Vec3 unturned(const TransferChuteLayout& c, const Vec3& world) {
  if (c.plan_angle == 0) return world;
  const Vec3 fall(c.fall_x, 0, 0);
  return Vec3(fall + plan_rotation(c).transpose() * (world - fall));
}

Vec3 turned_direction(const TransferChuteLayout& c, const Vec3& local) {
  if (c.plan_angle == 0) return local;
  return Vec3(plan_rotation(c) * local);
}

void turn(const TransferChuteLayout& c, MeshBuilder& mesh) {
  if (c.plan_angle == 0) return;
  const Eigen::Matrix3d rotation = plan_rotation(c);
  const Vec3 fall(c.fall_x, 0, 0);
  mesh.transform(rotation, fall - rotation * fall);
}

std::pair<Vec3, Vec3> turned_box(const TransferChuteLayout& c, const Vec3& lo, const Vec3& hi) {
  if (c.plan_angle == 0) return {lo, hi};
  const Vec3 fall(c.fall_x, 0, 0);
  const auto [a, b] = rotated_box(plan_rotation(c), lo - fall, hi - fall);
  return {Vec3(a + fall), Vec3(b + fall)};
}

// ---- the profile spoon's walls -----------------------------------------------------------------

std::vector<Vec3> profile_mitres(const std::vector<std::array<double, 2>>& profile) {
  std::vector<Vec3> normals;
  for (size_t k = 0; k + 1 < profile.size(); ++k) {
    const Vec3 t = Vec3(profile[k + 1][0] - profile[k][0], 0, profile[k + 1][1] - profile[k][1]).normalized();
    normals.push_back(Vec3(-t.z(), 0, t.x()));
  }
  std::vector<Vec3> mitres = {normals.front()};
  for (size_t k = 1; k < normals.size(); ++k)
    mitres.push_back((normals[k - 1] + normals[k]) / (1 + normals[k - 1].dot(normals[k])));
  mitres.push_back(normals.back());
  return mitres;
}

namespace {

// ---- parameters --------------------------------------------------------------------------------

/// Most points a profile spoon may have.
constexpr size_t kMostProfilePoints = 100;

/// feed_belt: width, speed, length, troughing, transition, pulley, load height, port height.
void read_feed_belt(MapReader& reader, TransferChuteLayout& c) {
  MapReader feed = sub_map(reader, "feed_belt");
  c.feed_width = feed.number("width", 0.8, 0.3, 3.0, "m");
  c.feed_speed = feed.number("speed", 2.5, 0.1, 10.0, "m/s");
  c.feed_length = feed.number("length", 3.0, 1.0, 50.0, "m");
  c.feed_trough = radians(feed.number("troughing_angle_deg", 30.0, 0.0, 45.0, "deg"));
  c.transition_length = feed.number("transition_length", 0.8, 0.0, c.feed_length - 0.5, "m");
  c.pulley_radius = 0.5 * feed.number("pulley_diameter", 0.5, 0.1, 2.0, "m");
  c.load_height = feed.number("load_height", 0.1, 0.01, 1.0, "m");
  c.feed_port_height = feed.number("port_height", 0.25, 0.01, 2.0, "m");
  feed.finish();
}

/// hood: radius, top height, exit angle, distance (default: on the trajectory). Returns the
/// highest angle [rad] the hood's end may have: 5 deg below the impact point, or 45 deg above the
/// centre when the distance is given.
double read_hood(MapReader& hood, TransferChuteLayout& c) {
  c.hood_radius = hood.number("radius", 1.0, 0.2, 5.0, "m");
  c.hood_top_height = hood.number("top_height", c.load_height + 0.15, 0.05, c.hood_radius, "m");
  c.hood_exit_angle = radians(hood.number("exit_angle_deg", 15.0, 0.0, 60.0, "deg"));
  // Default distance: the arc point 30 deg above the centre lies on the high-speed trajectory.
  const double rise = std::sin(radians(30.0));
  const double drop = std::max(c.hood_radius * (1 - rise) - c.hood_top_height, 0.05);  // [m] below the belt
  const double impact_sine = (c.hood_radius - c.hood_top_height - drop) / c.hood_radius;
  const double impact_x = c.feed_speed * std::sqrt(2 * drop / kGravity);
  const double fitted = impact_x - c.hood_radius * std::sqrt(1 - impact_sine * impact_sine) + c.hood_radius;
  c.hood_distance = hood.number("distance", std::max(fitted, 0.05), 0.05, 10.0, "m");
  // The hood must reach at least 5 deg below the impact point (45 deg above its centre when the
  // distance is given).
  return hood.has("distance") ? radians(45.0) : std::asin(impact_sine) - radians(5.0);
}

/// spoon (arc): radius, lip height, setback, exit angle.
void read_arc_spoon(MapReader& spoon, TransferChuteLayout& c) {
  c.spoon_radius = spoon.number("radius", 0.8, 0.2, 5.0, "m");
  c.spoon_lip_height = spoon.number("lip_height", 0.15, 0.02, 2.0, "m");
  c.spoon_setback = spoon.number("setback", 0.15, 0.0, 1.0, "m");
  // The arc ends this far before its lowest point, so the stream leaves the lip sloping down onto
  // the belt instead of having to be pushed out of a flat bottom (a dead bed forms there).
  c.spoon_exit_angle = radians(spoon.number("exit_angle_deg", 15.0, 0.0, 45.0, "deg"));
}

/// spoon.profile: 2 to 100 points [x, z] [m], x from the fall line along the receiving belt, z
/// above its surface, from the chute's top to its lip. Each point lies lower than the one before
/// (a chute descends monotonically) and not behind it (the stream stays on the trough's floor);
/// the first lies at or behind the fall line, where the stream comes down.
std::vector<std::array<double, 2>> read_profile(MapReader& spoon, double drop_height) {
  const YAML::Node list = spoon.node("profile");
  if (!list.IsSequence() || list.size() < 2 || list.size() > kMostProfilePoints)
    spoon.fail("profile", fmt::format("must be a list of 2 to {} points [x, z] [m] from the chute's top to its lip, "
                                      "e.g. [[-0.3, 1.2], [0.1, 0.5], [0.7, 0.2]]", kMostProfilePoints));
  const auto fail_at = [&](size_t k, const std::string& message) {
    throw CaseError(fmt::format("{}: {}[{}]: {}", spoon.at(list[k]).str(), spoon.key_path("profile"), k, message));
  };
  std::vector<std::array<double, 2>> points;
  for (size_t k = 0; k < list.size(); ++k) {
    const YAML::Node p = list[k];
    if (!p.IsSequence() || p.size() != 2) fail_at(k, "must be a point [x, z] [m]");
    const double x = MapReader::finite_number(p[0], spoon, "profile"), z = MapReader::finite_number(p[1], spoon, "profile");
    if (std::abs(x) > 20.0) fail_at(k, fmt::format("x = {:g} m is out of range; valid: [-20, 20] m", x));
    if (z < 0.02 || z > drop_height)
      fail_at(k, fmt::format("z = {:g} m is out of range; valid: [0.02, {:g}] m, above the receiving belt and below the feed belt", z, drop_height));
    if (k > 0) {
      const double before_x = points.back()[0], before_z = points.back()[1];
      if (z >= before_z)
        fail_at(k, fmt::format("z = {:g} m rises or runs level from the point before (z = {:g} m): a chute profile must "
                               "descend monotonically; valid: z < {:g} m", z, before_z, before_z));
      if (x < before_x)
        fail_at(k, fmt::format("x = {:g} m runs back from the point before (x = {:g} m): the stream would leave the "
                               "trough's floor; valid: x >= {:g} m", x, before_x, before_x));
      if (std::hypot(x - before_x, z - before_z) < 0.02) fail_at(k, "lies within 0.02 m of the point before; valid: points at least 0.02 m apart");
    }
    points.push_back({x, z});
  }
  if (points[0][0] > 0)
    fail_at(0, fmt::format("x = {:g} m lies ahead of the fall line (x = 0, where the stream comes down from the hood): "
                           "the stream would fall behind the chute's top; valid: x <= 0", points[0][0]));
  return points;
}

/// The walls' tops at depth follow the points moved along their mitres; on the inside of a bend
/// they draw closer, and a segment whose top would turn back on itself is refused.
void check_profile_bends(MapReader& spoon, const TransferChuteLayout& c) {
  const std::vector<Vec3> mitres = profile_mitres(c.spoon_profile);
  for (size_t k = 0; k + 1 < c.spoon_profile.size(); ++k) {
    const Vec3 run(c.spoon_profile[k + 1][0] - c.spoon_profile[k][0], 0, c.spoon_profile[k + 1][1] - c.spoon_profile[k][1]);
    const double top_run = run.normalized().dot(run + c.trough_depth * (mitres[k + 1] - mitres[k]));  // [m]
    if (top_run < 0.02)
      spoon.fail("depth", fmt::format("{:g} m high walls fold over on the inside of the bends at profile points {} and {} "
                                      "({:.3g} m apart); valid: lower walls, longer segments or gentler bends",
                                      c.trough_depth, k, k + 1, run.norm()));
  }
}

/// spoon (profile): the points, the trough's width, shape and wall height. Width rule of thumb: a
/// trough less than 3 top particle sizes wide can lock lumps across it (mechanical arching).
void read_profile_spoon(MapReader& spoon, TransferChuteLayout& c, double largest_particle) {
  for (const char* key : {"radius", "lip_height", "setback", "exit_angle_deg"})
    if (spoon.has(key))
      spoon.fail(key, "shapes the arc spoon, but `profile` is given: a profile spoon takes its top, slope and lip from "
                      "its points; give `profile` (with width, shape, depth) or the arc's keys, not both");
  c.spoon_profile = read_profile(spoon, c.drop_height);
  c.trough_width = spoon.number("width", c.chute_width, 0.1, c.chute_width, "m");
  if (largest_particle > 0 && c.trough_width <= 3 * largest_particle)
    spoon.fail("width", fmt::format("{:g} m is not more than 3 times the largest particle ({:g} m): lumps could lock "
                                    "across the trough; valid: more than {:g} m", c.trough_width, largest_particle, 3 * largest_particle));
  c.trough_u = spoon.string("shape", "U", {"U", "rectangular"}) == "U";
  c.trough_depth = spoon.number("depth", 0.5 * c.trough_width, 0.05, 2.0, "m");
  if (c.trough_u && c.trough_depth < 0.5 * c.trough_width)
    spoon.fail("depth", fmt::format("{:g} m is lower than a U trough's half circle; valid: at least half the width, {:g} m",
                                    c.trough_depth, 0.5 * c.trough_width));
  check_profile_bends(spoon, c);
  c.spoon_lip_height = c.spoon_profile.back()[1];
}

/// receiving_belt: width, speed, troughing, length, skirts (the tail is read once the chute is
/// laid out). Returns the length [m].
double read_receiving_belt(MapReader& receiving, TransferChuteLayout& c) {
  c.receiving_width = receiving.number("width", 0.8, 0.3, 3.0, "m");
  c.receiving_speed = receiving.number("speed", 3.0, 0.1, 10.0, "m/s");
  c.receiving_trough = radians(receiving.number("troughing_angle_deg", 30.0, 0.0, 45.0, "deg"));
  const double length = receiving.number("length", 3.0, 0.5, 50.0, "m");
  c.skirt_width = receiving.number("skirt_width", std::min(c.chute_width, 0.9 * c.receiving_width), 0.1,
                                   c.receiving_width, "m");
  c.skirt_length = receiving.number("skirt_length", 1.5, 0.0, length, "m");
  c.skirt_height = receiving.number("skirt_height", 0.3, 0.05, 2.0, "m");
  return length;
}

// ---- layout ------------------------------------------------------------------------------------

/// Hood: centre below its top by the radius, vertical tangent at hood_distance; its end cut
/// above the spoon.
void lay_out_hood(MapReader& reader, TransferChuteLayout& c, double lowest_end) {
  c.hood_centre_x = c.hood_distance - c.hood_radius;
  c.hood_centre_z = c.drop_height + c.hood_top_height - c.hood_radius;
  const bool arc = c.spoon_profile.empty();
  const double floor = arc ? c.spoon_lip_height + 0.15 * c.spoon_radius + 0.05 : c.spoon_profile[0][1] + 0.05;  // [m] lowest hood end
  c.hood_end_angle = -c.hood_exit_angle;
  if (c.hood_centre_z + c.hood_radius * std::sin(c.hood_end_angle) < floor) {
    c.hood_end_angle = std::asin(std::clamp((floor - c.hood_centre_z) / c.hood_radius, -1.0, 1.0));
  }
  if (c.hood_end_angle > lowest_end || floor > c.drop_height) {
    const std::string spoon = arc ? fmt::format("a spoon of radius {:g} m with its lip {:g} m above the receiving belt",
                                                c.spoon_radius, c.spoon_lip_height)
                                  : fmt::format("a profile spoon whose top is {:g} m above the receiving belt", c.spoon_profile[0][1]);
    const std::string remedy = arc ? "a smaller hood.radius or spoon.radius" : "a smaller hood.radius or a lower first profile point";
    reader.fail("drop_height", fmt::format("{:g} m leaves no room for a hood of radius {:g} m above {}; valid: a larger "
                                           "drop height, or {}", c.drop_height, c.hood_radius, spoon, remedy));
  }
  c.hood_exit_x = c.hood_centre_x + c.hood_radius * std::cos(c.hood_end_angle);
  c.hood_exit_z = c.hood_centre_z + c.hood_radius * std::sin(c.hood_end_angle);
}

/// [m] Where the CEMA high-speed trajectory from the pulley top, z = H - g x^2 / (2 V^2)
/// (material leaving at top dead centre; CEMA, Belt Conveyors for Bulk Materials, 7th ed.,
/// ch. 12), first leaves the hood's circle: found in 1 mm steps, refined by bisection. NAN when
/// the pulley top lies outside the circle.
Vec3 trajectory_meets_hood(const TransferChuteLayout& c) {
  const auto height = [&](double x) { return c.drop_height - kGravity * x * x / (2 * c.feed_speed * c.feed_speed); };
  const auto outside = [&](double x) {
    return std::hypot(x - c.hood_centre_x, height(x) - c.hood_centre_z) >= c.hood_radius;
  };
  if (outside(0)) return Vec3::Constant(NAN);
  double lo = 0, hi = 0;
  while (!outside(hi)) lo = hi, hi += 0.001;  // ends: the trajectory falls without bound
  for (int k = 0; k < 60; ++k) (outside(0.5 * (lo + hi)) ? hi : lo) = 0.5 * (lo + hi);
  return Vec3(hi, 0, height(hi));
}

/// The rock box's ledge and dam: the dam's top at the impact height, the ledge `height` below it,
/// reaching ledge_depth back from the hood, at least 5 deg above the hood's end. The dam stands
/// behind the impact point and 0.05 m under the trajectory (x^2 <= x_i^2 - 0.1 V^2 / g), where
/// the stream passes over it into the bed, and in front of the head pulley.
void lay_out_rock_box(MapReader& box, TransferChuteLayout& c) {
  c.ledge_z = c.impact_z - c.rock_box_height;
  const double lowest_sine = std::sin(c.hood_end_angle + radians(5.0));
  const double sine = (c.ledge_z - c.hood_centre_z) / c.hood_radius;
  if (sine < lowest_sine)
    box.fail("height", fmt::format("{:g} m puts the ledge below the hood's end; valid: at most {:g} m", c.rock_box_height,
                                   c.impact_z - c.hood_centre_z - c.hood_radius * lowest_sine));
  c.ledge_wall_x = c.hood_centre_x + c.hood_radius * std::sqrt(1 - sine * sine);
  c.dam_x = c.ledge_wall_x - c.ledge_depth;
  const double clear_square = c.impact_x * c.impact_x - 0.1 * c.feed_speed * c.feed_speed / kGravity;  // [m^2]
  const double dam_max = std::min(c.impact_x - 0.05, std::sqrt(std::max(clear_square, 0.0)));      // [m]
  const double dam_min = c.pulley_radius + 0.05;                                                      // [m]
  if (dam_max <= dam_min)
    box.fail("ledge_depth", fmt::format("no ledge depth fits: the stream meets the hood at x = {:g} m, too close to the "
                                        "head pulley (radius {:g} m) for a dam between them; valid: a hood that meets the "
                                        "stream farther out (a larger hood.radius or a faster feed belt)",
                                        c.impact_x, c.pulley_radius));
  if (c.dam_x > dam_max || c.dam_x < dam_min)
    box.fail("ledge_depth", fmt::format("{:g} m puts the dam at x = {:g} m; valid: [{:g}, {:g}] m, so that the dam "
                                        "stands behind the impact point (x = {:g} m) and 0.05 m under the trajectory, "
                                        "where the stream passes over it into the bed, and in front of the head pulley",
                                        c.ledge_depth, c.dam_x, c.ledge_wall_x - dam_max, c.ledge_wall_x - dam_min, c.impact_x));
}

/// rock_box: a ledge across the hood below the impact point with a dam at its inner edge; the
/// box fills with the conveyed material and the stream strikes that dead bed, not the liner:
/// material wears on material.
///
/// Design rule (a rule of thumb of chute practice, not a published standard): the bed must hold
/// the largest lumps, not carry them on its surface, so the dam and the ledge are at least 2
/// (practice: 2-3) top particle sizes deep; refused below 2 when the case's particles are known.
/// The practice, qualitatively: West River Conveyors, "Transfer chutes" (a rock box is a ledge
/// on which rocks collect so that the ore flow does not wear the chute;
/// westriverconveyors.com/products/terminal-equipment/transfer-chutes); WEAR-X, "WEARBACK"
/// (ledges on which material builds up as the wear medium, rock on rock; wearx.com/solution/
/// wearback-2); ASGCO, "Enhances chute performance and longevity" (a 6-inch dead bed taking the
/// impact; asgco.com/case_study). Rejected: a rock box at the spoon, which would take the stream
/// after the hood has already taken its hardest impact.
void read_rock_box(MapReader& reader, TransferChuteLayout& c, double largest_particle) {
  MapReader box = sub_map(reader, "rock_box");
  c.rock_box = true;
  c.rock_box_height = box.number("height", 0.25, 0.05, 2.0, "m");
  c.ledge_depth = box.number("ledge_depth", 0.3, 0.05, 2.0, "m");
  c.ledge_width = box.number("ledge_width", c.chute_width, 0.1, c.chute_width, "m");
  box.finish();
  if (std::isnan(c.impact_x))
    reader.fail("rock_box", "the trajectory starts outside the hood (hood.distance is short of the pulley top), so "
                            "there is no impact point to put the ledge under; valid: a hood over the pulley top");
  const std::pair<const char*, double> depths[] = {{"height", c.rock_box_height}, {"ledge_depth", c.ledge_depth}};
  for (const auto& [key, value] : depths)
    if (largest_particle > 0 && value < 2 * largest_particle)
      box.fail(key, fmt::format("{:g} m is less than 2 top sizes of the case's particles ({:g} m): the largest lumps "
                                "would lie on the ledge instead of in a dead bed; valid: at least {:g} m (practice: "
                                "2-3 top sizes)", value, largest_particle, 2 * largest_particle));
  lay_out_rock_box(box, c);
}

/// Spoon: the arc under the hood with its top edge `setback` behind the fall line (and the
/// stream's reach along a turned spoon), or the profile's points from the fall line. The back
/// plate rises to 0.1 above the hood's exit, or, angled, to the deck at the exit's height.
void lay_out_spoon(MapReader& spoon, TransferChuteLayout& c) {
  c.back_plate_top = c.plan_angle == 0 ? c.hood_exit_z + 0.1 : c.hood_exit_z;
  if (!c.spoon_profile.empty()) {
    c.spoon_top_x = c.fall_x + c.spoon_profile.front()[0];
    c.spoon_top_z = c.spoon_profile.front()[1];
    c.spoon_lip_x = c.fall_x + c.spoon_profile.back()[0];
    return;
  }
  // Top edge `setback` behind the fall line and at least 0.05 below the hood exit.
  c.spoon_centre_z = c.spoon_lip_height + c.spoon_radius * std::cos(c.spoon_exit_angle);
  c.spoon_top_z = std::min(c.spoon_centre_z, c.hood_exit_z - 0.05);
  c.spoon_start_angle = std::acos(std::clamp((c.spoon_centre_z - c.spoon_top_z) / c.spoon_radius, -1.0, 1.0));
  if (c.spoon_start_angle < c.spoon_exit_angle + radians(20.0))
    spoon.fail("exit_angle_deg", fmt::format("leaves a spoon arc of {:.0f} deg under the hood; valid: a smaller exit angle, a "
                                             "smaller spoon radius or a larger drop height",
                                             (c.spoon_start_angle - c.spoon_exit_angle) * 180 / kPi));
  c.spoon_top_x = c.fall_x - c.spoon_setback - stream_reach(c);
  c.spoon_centre_x = c.spoon_top_x + c.spoon_radius * std::sin(c.spoon_start_angle);
  c.spoon_lip_x = c.spoon_centre_x - c.spoon_radius * std::sin(c.spoon_exit_angle);
}

/// Side plates: from behind the pulley to past the hood and the lip, from the belt to the roof.
/// Angled: the hood's box ends at its front, the spoon's box reaches past the lip and the stream.
void lay_out_enclosure(TransferChuteLayout& c) {
  const double hood_front = c.hood_end_angle < 0 ? c.hood_distance : c.hood_exit_x;
  c.side_x_min = -c.pulley_radius - 0.2;
  c.side_x_max = std::max(hood_front, c.spoon_lip_x) + 0.1;
  const double edge = std::min(0.5 * c.chute_width, 0.5 * c.receiving_width);
  c.side_z_min = trough_height(c.receiving_width, c.receiving_trough, edge) + 0.01;
  c.side_z_max = c.drop_height + c.hood_top_height + 0.05;
  c.join_z = c.hood_exit_z;
  c.hood_box_x_max = hood_front;
  c.spoon_box_x_max = std::max(c.spoon_lip_x, c.fall_x + stream_reach(c)) + 0.1;
}

}  // namespace

TransferChuteLayout read_layout(MapReader& reader, double largest_particle) {
  TransferChuteLayout c;
  c.drop_height = reader.number("drop_height", 1.5, 0.3, 20.0, "m");
  c.chute_width = reader.number("chute_width", 0.7, 0.1, 5.0, "m");
  c.plan_angle = radians(reader.number("plan_angle_deg", 0.0, 0.0, 180.0, "deg"));
  read_feed_belt(reader, c);
  MapReader hood = sub_map(reader, "hood");
  const double lowest_end = read_hood(hood, c);
  hood.finish();
  MapReader spoon = sub_map(reader, "spoon");
  if (spoon.has("profile")) read_profile_spoon(spoon, c, largest_particle);
  else read_arc_spoon(spoon, c);
  spoon.finish();
  MapReader receiving = sub_map(reader, "receiving_belt");
  const double length = read_receiving_belt(receiving, c);

  lay_out_hood(reader, c, lowest_end);
  const Vec3 impact = trajectory_meets_hood(c);
  c.impact_x = impact.x(), c.impact_z = impact.z();
  if (reader.has("rock_box")) read_rock_box(reader, c, largest_particle);
  // The stream comes down where it leaves the hood: its exit, or the rock box's dam behind it.
  c.fall_x = c.rock_box ? std::min(c.hood_exit_x, c.dam_x) : c.hood_exit_x;
  lay_out_spoon(spoon, c);
  lay_out_enclosure(c);

  // The receiving belt runs on 0.5 behind the chute: behind the pulley, or behind a turned spoon.
  const double back = c.plan_angle == 0 ? c.side_x_min : c.spoon_top_x;
  const double tail = receiving.number("tail_length", c.spoon_lip_x - back + 0.5, 0.1, 50.0, "m");
  receiving.finish();
  c.receiving_x_min = c.spoon_lip_x - tail;
  c.receiving_x_max = c.spoon_lip_x + length;
  return c;
}

}  // namespace dem::equipment::detail
