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
//    particle sizes when the case's particles are known (rule and sources at read_rock_box).
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
//    back plate (choke_section gives the reasons).
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
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <tuple>

#include "generators.h"

namespace dem::equipment {

namespace detail {

namespace {

/// [m] cell size of the chute's surfaces: finer than kCell so that the curved liners follow their
/// arcs and a chute has a few thousand triangles.
constexpr double kChuteCell = 0.12;
/// [m] cell size of an angled transfer's deck: a cell that reaches into the opening between the
/// hood's box and the spoon's narrows it by less than its diagonal.
constexpr double kDeckCell = 0.5 * kChuteCell;
constexpr size_t kMostProfilePoints = 100;

// ---- the receiving side's frame --------------------------------------------------------------

/// The turn of the receiving side: plan_angle about +z, written out so that heights stay exact.
Eigen::Matrix3d plan_rotation(const TransferChuteLayout& c) {
  const double cos_a = std::cos(c.plan_angle), sin_a = std::sin(c.plan_angle);
  Eigen::Matrix3d rotation;
  rotation << cos_a, -sin_a, 0, sin_a, cos_a, 0, 0, 0, 1;
  return rotation;
}

/// A point of the receiving side in the world: laid out as for the inline chute (x along the
/// receiving belt), turned about the fall line. Unchanged at plan_angle 0.
Vec3 turned(const TransferChuteLayout& c, const Vec3& local) {
  if (c.plan_angle == 0) return local;
  const Vec3 fall(c.fall_x, 0, 0);
  return Vec3(fall + plan_rotation(c) * (local - fall));
}

/// The receiving side's frame of a world point (the inverse of turned()).
Vec3 unturned(const TransferChuteLayout& c, const Vec3& world) {
  if (c.plan_angle == 0) return world;
  const Vec3 fall(c.fall_x, 0, 0);
  return Vec3(fall + plan_rotation(c).transpose() * (world - fall));
}

/// A direction of the receiving side in the world (a belt velocity, a sensor's normal).
Vec3 turned_direction(const TransferChuteLayout& c, const Vec3& local) {
  if (c.plan_angle == 0) return local;
  return Vec3(plan_rotation(c) * local);
}

/// Moves a part of the receiving side, built in its frame, to the world.
void turn(const TransferChuteLayout& c, MeshBuilder& mesh) {
  if (c.plan_angle == 0) return;
  const Eigen::Matrix3d rotation = plan_rotation(c);
  const Vec3 fall(c.fall_x, 0, 0);
  mesh.transform(rotation, fall - rotation * fall);
}

/// The axis-aligned box around the receiving side's box [lo, hi] turned to the world.
std::pair<Vec3, Vec3> turned_box(const TransferChuteLayout& c, const Vec3& lo, const Vec3& hi) {
  if (c.plan_angle == 0) return {lo, hi};
  const Vec3 fall(c.fall_x, 0, 0);
  const auto [a, b] = rotated_box(plan_rotation(c), lo - fall, hi - fall);
  return {Vec3(a + fall), Vec3(b + fall)};
}

/// [m] How far the stream, chute_width wide across the feed belt, reaches along the receiving
/// belt on either side of the fall line.
double stream_reach(const TransferChuteLayout& c) { return 0.5 * c.chute_width * std::abs(std::sin(c.plan_angle)); }

// ---- parameters --------------------------------------------------------------------------------

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

/// Where the walls of a trough swept along the profile rise from each point: the segment's
/// normal (-t_z, t_x) at the ends, and at a joint the mitre m = (n1 + n2) / (1 + n1.n2), whose
/// component along both normals is 1, so that the walls keep their height through the bend.
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

/// The parameters, checked, and the chute laid out from them: the feed side, the hood, the
/// impact point and the rock box on it, the fall line, the spoon, the enclosure, the belt's tail.
/// `largest_particle` [m] (0: unknown) sizes the rock box's bed and the profile trough's width.
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

// ---- meshes ------------------------------------------------------------------------------------

/// A troughed belt from x0 to x1 with surface at z (centre), wing angle trough(x) [rad].
void troughed_belt(MeshBuilder& mesh, double width, double x0, double x1, double z, double max_trough,
                   const std::function<double(double)>& trough) {
  const double centre = kCentreRollFraction * width, wing = 0.5 * (width - centre);
  // Profile stations as (side, distance along the wing); side 0: on the centre roll at y = along.
  std::vector<std::pair<int, double>> stations;
  const auto profile = trough_profile(width, max_trough, kChuteCell);
  for (const auto& [y, height] : profile) {
    if (std::abs(y) <= 0.5 * centre + 1e-12) stations.push_back({0, y});
    else stations.push_back({y > 0 ? 1 : -1, (std::abs(y) - 0.5 * centre) / std::max(std::cos(max_trough), 1e-12)});
  }
  (void)wing;
  const int along = segments(x1 - x0, kChuteCell), across = static_cast<int>(stations.size()) - 1;
  // u across (-y to +y), w along +x: normal (du x dw) = y x x = -z; swap to get +z up.
  mesh.grid([&](double w, double u) {
    const double x = x0 + w * (x1 - x0);
    const auto [side, distance] = stations[static_cast<size_t>(std::lround(u * across))];
    if (side == 0) return Vec3(x, distance, z);
    const double angle = trough(x);
    return Vec3(x, side * (0.5 * centre + distance * std::cos(angle)), z + distance * std::sin(angle));
  }, along, across);
}

/// What every part of the chute is built from: its layout, the materials of its walls, where the
/// case declares it, and the half widths its walls and sensors are placed at.
struct ChuteBuild {
  const TransferChuteLayout& layout;
  const Materials& materials;
  const SourceLocation& where;
  double half;            // [m] half the chute width: the side plates' y
  double receiving_half;  // [m] half the receiving belt's width
};

/// Feed belt, troughed, flattening linearly over the transition before the pulley.
void add_feed_belt(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder belt;
  troughed_belt(belt, c.feed_width, -c.feed_length, 0.0, c.drop_height, c.feed_trough, [&](double x) {
    return c.transition_length > 0 ? c.feed_trough * std::clamp(-x / c.transition_length, 0.0, 1.0) : c.feed_trough;
  });
  MeshWallSpec wall = belt.wall("feed_belt", chute.materials.belt, chute.where);
  wall.surface.kind = SurfaceVelocitySpec::Kind::linear;
  wall.surface.velocity = Vec3(c.feed_speed, 0, 0);
  out.meshes.push_back(std::move(wall));
}

/// Head pulley: omega = +V / R_p about +y moves its top (0, 0, R_p) at omega y x R z = +V x.
void add_head_pulley(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder pulley;
  const double axis_z = c.drop_height - c.pulley_radius;
  cylinder(pulley, Vec3(0, -0.5 * c.feed_width, axis_z), Vec3(0, 0.5 * c.feed_width, axis_z), c.pulley_radius,
           segments(2 * kPi * c.pulley_radius, 0.08, 24), true);
  MeshWallSpec wall = pulley.wall("head_pulley", chute.materials.belt, chute.where);
  wall.surface.kind = SurfaceVelocitySpec::Kind::rotation;
  wall.surface.axis = Vec3::UnitY();
  wall.surface.point = Vec3(0, 0, axis_z);
  wall.surface.angular_speed = c.feed_speed / c.pulley_radius;
  out.meshes.push_back(std::move(wall));
}

/// Hood arc from its top (90 deg) down to its end angle; roof from the chute back to the hood top.
void add_hood(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double half = chute.half;
  MeshBuilder hood;
  const double sweep = kPi / 2 - c.hood_end_angle;
  hood.grid([&](double u, double w) {
    const double angle = kPi / 2 - u * sweep;
    return Vec3(c.hood_centre_x + c.hood_radius * std::cos(angle), -half + w * c.chute_width,
                c.hood_centre_z + c.hood_radius * std::sin(angle));
  }, segments(sweep * c.hood_radius, kChuteCell, 8), segments(c.chute_width, kChuteCell));
  const double roof = c.drop_height + c.hood_top_height;
  if (c.hood_centre_x > c.side_x_min + 0.01) {
    hood.quad(Vec3(c.side_x_min, -half, roof), Vec3(c.hood_centre_x, -half, roof), Vec3(c.hood_centre_x, half, roof),
              Vec3(c.side_x_min, half, roof), kChuteCell);
  }
  out.meshes.push_back(hood.wall("hood", chute.materials.liner, chute.where));
}

/// Rock box: the ledge from the hood back to the dam, the dam up to the impact height, and, when
/// the ledge is narrower than the chute, end plates from the dam to the hood.
void add_rock_box(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double y = 0.5 * c.ledge_width, top = c.impact_z;
  MeshBuilder box;
  box.quad(Vec3(c.dam_x, -y, c.ledge_z), Vec3(c.ledge_wall_x, -y, c.ledge_z), Vec3(c.ledge_wall_x, y, c.ledge_z),
           Vec3(c.dam_x, y, c.ledge_z), kChuteCell);
  box.quad(Vec3(c.dam_x, -y, c.ledge_z), Vec3(c.dam_x, y, c.ledge_z), Vec3(c.dam_x, y, top), Vec3(c.dam_x, -y, top), kChuteCell);
  if (c.ledge_width < c.chute_width - 1e-9) {
    // The hood's front at height z (the arc's side facing +x).
    const auto wall_x = [&](double z) {
      const double sine = (z - c.hood_centre_z) / c.hood_radius;
      return c.hood_centre_x + c.hood_radius * std::sqrt(std::max(0.0, 1 - sine * sine));
    };
    for (const double side : {-y, y})
      box.grid([&](double u, double w) {
        const double z = c.ledge_z + u * (top - c.ledge_z);
        return Vec3(c.dam_x + w * (wall_x(z) - c.dam_x), side, z);
      }, segments(top - c.ledge_z, kChuteCell), segments(c.ledge_wall_x - c.dam_x, kChuteCell));
  }
  out.meshes.push_back(box.wall("rock_box", chute.materials.liner, chute.where));
}

/// The arc spoon from its top edge (start angle) to the lip.
void add_arc_spoon(MeshBuilder& spoon, const TransferChuteLayout& c, double half) {
  spoon.grid([&](double u, double w) {
    const double angle = c.spoon_start_angle * (1 - u) + c.spoon_exit_angle * u;  // back to lip
    return Vec3(c.spoon_centre_x - c.spoon_radius * std::sin(angle), half - w * c.chute_width,
                c.spoon_centre_z - c.spoon_radius * std::cos(angle));
  }, segments(c.spoon_start_angle * c.spoon_radius, kChuteCell, 6), segments(c.chute_width, kChuteCell));
}

/// The trough's cross-section from its -y wall top to its +y wall top, as (across [m], up [m])
/// from the centre line: a U (a half circle of the width under straight sides) or a rectangle.
std::vector<std::array<double, 2>> trough_section(const TransferChuteLayout& c) {
  const double r = 0.5 * c.trough_width, depth = c.trough_depth;
  std::vector<std::array<double, 2>> section;
  // A straight run in pieces of at most a chute cell, with or without its end point.
  const auto run = [&](double a0, double h0, double a1, double h1, bool with_end) {
    const int n = segments(std::hypot(a1 - a0, h1 - h0), kChuteCell);
    for (int k = 0; k < n + (with_end ? 1 : 0); ++k) section.push_back({a0 + (a1 - a0) * k / n, h0 + (h1 - h0) * k / n});
  };
  if (!c.trough_u) {
    run(-r, depth, -r, 0, false);
    run(-r, 0, r, 0, false);
    run(r, 0, r, depth, true);
    return section;
  }
  if (depth > r) run(-r, depth, -r, r, false);
  const int n = segments(kPi * r, kChuteCell, 8);
  for (int k = 0; k < n; ++k) {
    const double angle = kPi * (1.0 + double(k) / n);  // from -y at mid height through the bottom
    section.push_back({r * std::cos(angle), r + r * std::sin(angle)});
  }
  if (depth > r) run(r, r, r, depth, true);
  else section.push_back({r, r});
  return section;
}

/// The profile spoon: the trough's cross-section swept along the profile, standing on each point
/// along its mitre (profile_mitres) and on the way between two points along the mitres
/// interpolated, so that the walls' tops are straight between the points' offsets; pieces at most
/// a chute cell long at the centre line and at the walls' tops.
void add_profile_spoon(MeshBuilder& spoon, const TransferChuteLayout& c) {
  const std::vector<Vec3> mitres = profile_mitres(c.spoon_profile);
  const auto point = [&](size_t k) { return Vec3(c.fall_x + c.spoon_profile[k][0], 0, c.spoon_profile[k][1]); };
  std::vector<std::pair<Vec3, Vec3>> stations;  // (centre line, up)
  for (size_t k = 0; k + 1 < c.spoon_profile.size(); ++k) {
    const Vec3 run = point(k + 1) - point(k), top_run = run + c.trough_depth * (mitres[k + 1] - mitres[k]);
    const int n = segments(std::max(run.norm(), top_run.norm()), kChuteCell);
    for (int i = 0; i < n; ++i) {
      const double s = double(i) / n;
      stations.push_back({Vec3(point(k) + s * run), Vec3((1 - s) * mitres[k] + s * mitres[k + 1])});
    }
  }
  stations.push_back({point(c.spoon_profile.size() - 1), mitres.back()});
  const std::vector<std::array<double, 2>> section = trough_section(c);
  const int along = static_cast<int>(stations.size()) - 1, across = static_cast<int>(section.size()) - 1;
  spoon.grid([&](double u, double w) {
    const auto& [centre, up] = stations[static_cast<size_t>(std::lround(u * along))];
    const auto& [side, height] = section[static_cast<size_t>(std::lround(w * across))];
    return Vec3(centre + side * Vec3::UnitY() + height * up);
  }, along, across);
}

/// Spoon (arc or profile) and the back plate above its top edge, turned to the receiving belt.
void add_spoon(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double half = chute.half;
  MeshBuilder spoon;
  if (c.spoon_profile.empty()) add_arc_spoon(spoon, c, half);
  else add_profile_spoon(spoon, c);
  spoon.quad(Vec3(c.spoon_top_x, -half, c.spoon_top_z), Vec3(c.spoon_top_x, half, c.spoon_top_z),
             Vec3(c.spoon_top_x, half, c.back_plate_top), Vec3(c.spoon_top_x, -half, c.back_plate_top), kChuteCell);
  turn(c, spoon);
  out.meshes.push_back(spoon.wall("spoon", chute.materials.liner, chute.where));
}

/// Side plates at y = +-half from x0 to x1 (the frame they are built in), z0 to z1.
void side_pair(MeshBuilder& mesh, double half, double x0, double x1, double z0, double z1) {
  for (const double y : {-half, half}) {
    const Vec3 a(x0, y, z0), b(x1, y, z0), d(x0, y, z1), e(x1, y, z1);
    if (y < 0) mesh.quad(a, b, e, d, kChuteCell);  // normals point into the chute
    else mesh.quad(a, d, e, b, kChuteCell);
  }
}

/// Side plates of the inline chute, from behind the pulley to past the hood and the lip.
void add_side_plates(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder sides;
  side_pair(sides, chute.half, c.side_x_min, c.side_x_max, c.side_z_min, c.side_z_max);
  out.meshes.push_back(sides.wall("side_plates", chute.materials.liner, chute.where));
}

/// A plan rectangle, x in [x_min, x_max], |y| <= half: the hood's box in the feed frame, the
/// spoon's in the receiving frame.
struct Footprint {
  double x_min, x_max, half;  // [m]
  /// Whether it holds p (its own frame); points on its edges count as inside.
  bool holds(const Vec3& p) const {
    constexpr double kEdge = 1e-9;  // [m]
    return p.x() >= x_min - kEdge && p.x() <= x_max + kEdge && std::abs(p.y()) <= half + kEdge;
  }
};

/// A horizontal plate at height z over `plate` (its own frame), without the cells whose four
/// corners `in_hole` finds in the opening: the cells it keeps cover all of the plate outside the
/// opening, and those on the opening's rim reach into it by less than a cell.
void deck(MeshBuilder& mesh, const Footprint& plate, double z, const std::function<bool(const Vec3&)>& in_hole) {
  const int nu = segments(plate.x_max - plate.x_min, kDeckCell), nw = segments(2 * plate.half, kDeckCell);
  const auto point = [&](double u, double w) {
    return Vec3(plate.x_min + u * (plate.x_max - plate.x_min), -plate.half + w * 2 * plate.half, z);
  };
  const auto corner_in_hole = [&](int i, int j) { return in_hole(point(double(i) / nu, double(j) / nw)); };
  mesh.grid(point, nu, nw, [&](int i, int j) {
    return !(corner_in_hole(i, j) && corner_in_hole(i + 1, j) && corner_in_hole(i + 1, j + 1) && corner_in_hole(i, j + 1));
  });
}

/// The angled transfer's enclosure: the hood's box above join_z (side plates, the front plate
/// under the hood where it runs past vertical, the deck closing its floor outside the spoon's
/// box), the spoon's box below, turned (side plates, the deck closing its top outside the hood's
/// box); one mesh, like the inline chute's side plates.
void add_angled_enclosure(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double half = chute.half;
  const Footprint hood_box{c.side_x_min, c.hood_box_x_max, half}, spoon_box{c.spoon_top_x, c.spoon_box_x_max, half};
  MeshBuilder walls;
  side_pair(walls, half, c.side_x_min, c.hood_box_x_max, c.join_z, c.side_z_max);
  if (c.hood_end_angle < 0)
    walls.quad(Vec3(c.hood_distance, -half, c.join_z), Vec3(c.hood_distance, half, c.join_z),
               Vec3(c.hood_distance, half, c.hood_centre_z), Vec3(c.hood_distance, -half, c.hood_centre_z), kChuteCell);
  deck(walls, hood_box, c.join_z, [&](const Vec3& p) { return spoon_box.holds(unturned(c, p)); });
  MeshBuilder lower;
  side_pair(lower, half, c.spoon_top_x, c.spoon_box_x_max, c.side_z_min, c.join_z);
  deck(lower, spoon_box, c.join_z, [&](const Vec3& p) { return hood_box.holds(turned(c, p)); });
  turn(c, lower);
  walls.append(lower);
  out.meshes.push_back(walls.wall("side_plates", chute.materials.liner, chute.where));
}

/// Receiving belt, turned to its direction of travel.
void add_receiving_belt(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder belt;
  troughed_belt(belt, c.receiving_width, c.receiving_x_min, c.receiving_x_max, 0.0, c.receiving_trough,
                [&](double) { return c.receiving_trough; });
  turn(c, belt);
  MeshWallSpec wall = belt.wall("receiving_belt", chute.materials.belt, chute.where);
  wall.surface.kind = SurfaceVelocitySpec::Kind::linear;
  wall.surface.velocity = turned_direction(c, Vec3(c.receiving_speed, 0, 0));
  out.meshes.push_back(std::move(wall));
}

/// Skirts on the receiving belt from just behind the spoon lip.
void add_skirts(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder skirts;
  const double y = 0.5 * c.skirt_width;
  const double bottom = trough_height(c.receiving_width, c.receiving_trough, y) + 0.01;
  const double x0 = c.spoon_lip_x - 0.05, x1 = c.spoon_lip_x + c.skirt_length;
  skirts.quad(Vec3(x0, -y, bottom), Vec3(x1, -y, bottom), Vec3(x1, -y, bottom + c.skirt_height), Vec3(x0, -y, bottom + c.skirt_height), kChuteCell);
  skirts.quad(Vec3(x0, y, bottom), Vec3(x0, y, bottom + c.skirt_height), Vec3(x1, y, bottom + c.skirt_height), Vec3(x1, y, bottom), kChuteCell);
  turn(c, skirts);
  out.meshes.push_back(skirts.wall("skirts", chute.materials.liner, chute.where));
}

/// Feed port over the tail of the feed belt: 70 % of the belt width, above the wing tops (the
/// particles drop into the trough), long enough to take a batch at the design rate (a box the
/// belt empties every length / speed seconds holds about 30 % solid).
void add_feed_port(const TransferChuteLayout& c, Generated& out) {
  const double port_half_width = 0.35 * c.feed_width;
  const double port_bottom = c.drop_height + trough_height(c.feed_width, c.feed_trough, port_half_width) + 0.01;
  const double port_length = std::min(1.0, 0.4 * c.feed_length);
  out.ports.push_back({"feed_belt", Vec3(-c.feed_length + 0.1, -port_half_width, port_bottom),
                       Vec3(-c.feed_length + 0.1 + port_length, port_half_width, port_bottom + c.feed_port_height),
                       Vec3(c.feed_speed, 0, 0)});
}

/// Outlet beyond the end of the receiving belt; a turned belt's lies below its surface (see the
/// file's header).
void add_discharge_outlet(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double belt_half = chute.receiving_half;
  OutletSpec discharge;
  discharge.name = "discharge";
  Vec3 lo(c.receiving_x_max + 0.02, -belt_half - 0.5, -1.0), hi(c.receiving_x_max + 1.0, belt_half + 0.5, 0.6);
  if (c.plan_angle != 0) hi.x() = c.receiving_x_max + 2.0, hi.z() = -0.1;
  std::tie(discharge.region_min, discharge.region_max) = turned_box(c, lo, hi);
  out.outlets.push_back(discharge);
}

/// [m] Where the loading zone (the load box after the spoon lip) ends along the receiving belt:
/// 1 m past the lip, or 0.4 m short of the belt's end on a shorter belt.
double loading_zone_end(const TransferChuteLayout& c) { return c.spoon_lip_x + std::min(1.0, c.receiving_x_max - c.spoon_lip_x - 0.4); }

/// [m] The belt_discharge plane along the receiving belt: 0.3 m before its end.
double discharge_plane_x(const TransferChuteLayout& c) { return c.receiving_x_max - 0.3; }

/// Sensors: flow through the spoon lip and near the belt end; load on the belt after the lip.
void add_sensors(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  const double half = chute.half, belt_half = chute.receiving_half;
  SensorSpec spoon_exit;
  spoon_exit.kind = SensorSpec::Kind::plane, spoon_exit.name = "spoon_exit";
  spoon_exit.point = turned(c, Vec3(c.spoon_lip_x, 0, c.spoon_lip_height));
  spoon_exit.normal = turned_direction(c, Vec3::UnitX());
  std::tie(spoon_exit.region_min, spoon_exit.region_max) =
      turned_box(c, Vec3(c.spoon_lip_x - 0.1, -half, -0.05), Vec3(c.spoon_lip_x + 0.1, half, c.spoon_top_z));
  out.sensors.push_back(spoon_exit);
  SensorSpec belt_discharge;
  belt_discharge.kind = SensorSpec::Kind::plane, belt_discharge.name = "belt_discharge";
  const double x_end = discharge_plane_x(c);
  belt_discharge.point = turned(c, Vec3(x_end, 0, 0));
  belt_discharge.normal = turned_direction(c, Vec3::UnitX());
  std::tie(belt_discharge.region_min, belt_discharge.region_max) =
      turned_box(c, Vec3(x_end - 0.1, -belt_half, -0.05), Vec3(x_end + 0.1, belt_half, 0.5));
  out.sensors.push_back(belt_discharge);
  SensorSpec loading;
  loading.kind = SensorSpec::Kind::box, loading.name = "loading_zone";
  loading.across = turned_direction(c, Vec3::UnitY());
  const double loading_end = loading_zone_end(c);
  std::tie(loading.region_min, loading.region_max) =
      turned_box(c, Vec3(c.spoon_lip_x, -belt_half, -0.05), Vec3(loading_end, belt_half, 0.5));
  out.sensors.push_back(loading);
}

// ---- the narrowest section and the stream profiles -------------------------------------------

/// Lateral bins of the stream profile sensors (stream_chute, stream_belt): a 0.7 m chute in 58 mm
/// bins, a 1.2 m belt in 100 mm bins.
constexpr int kStreamBins = 12;
/// [m] How far the stream_chute box reaches along the fall line on either side of the hood's exit
/// height, at most: long enough to hold a few particles' centres, short enough that the section
/// stays the throat's.
constexpr double kChokeReach = 0.1;

/// A convex polygon in plan (x, y), counter-clockwise.
using PlanPolygon = std::vector<Eigen::Vector2d>;

/// The part of convex `subject` on the left of the directed line a -> b (Sutherland-Hodgman).
PlanPolygon clip_left_of(const PlanPolygon& subject, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const auto side = [&](const Eigen::Vector2d& p) { return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x()); };
  PlanPolygon out;
  for (size_t k = 0; k < subject.size(); ++k) {
    const Eigen::Vector2d& p = subject[k];
    const Eigen::Vector2d& q = subject[(k + 1) % subject.size()];
    const double at_p = side(p), at_q = side(q);
    if (at_p >= 0) out.push_back(p);
    if ((at_p >= 0) != (at_q >= 0)) out.push_back(Eigen::Vector2d(p + (at_p / (at_p - at_q)) * (q - p)));
  }
  return out;
}

/// [m^2] Area of a plan polygon (shoelace).
double plan_area(const PlanPolygon& polygon) {
  double twice = 0;
  for (size_t k = 0; k < polygon.size(); ++k) {
    const Eigen::Vector2d& p = polygon[k];
    const Eigen::Vector2d& q = polygon[(k + 1) % polygon.size()];
    twice += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * std::abs(twice);
}

/// The chute's narrowest section: its free plan area at the hood's exit height, and the box of
/// the stream_chute sensor around it, `length` along the fall line.
struct ChokeSection {
  double area = 0;    // [m^2] 0: none found (a degenerate layout)
  double height = 0;  // [m] the hood exit's
  double length = 0;  // [m] the box's extent along the fall line
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};  // [m]
};

/// The free plan section at the hood's exit height: the hood's box (from behind the pulley, or
/// from the pulley's front when the exit lies at the pulley's height, to the hood's exit) clipped
/// to the spoon's (from its back plate forward between the side plates, turned about the fall
/// line). Inline, the spoon's reaches to the side plates' end. Angled, the deck's cells on the
/// opening's rim narrow it by less than a cell (kDeckCell); they are left out of the area.
PlanPolygon choke_plan(const TransferChuteLayout& c) {
  const double half = 0.5 * c.chute_width;
  const double back = c.hood_exit_z > c.drop_height - 2 * c.pulley_radius ? c.pulley_radius : c.side_x_min;
  if (!(c.hood_exit_x > back)) return {};
  PlanPolygon section = {Eigen::Vector2d(back, -half), Eigen::Vector2d(c.hood_exit_x, -half), Eigen::Vector2d(c.hood_exit_x, half),
                         Eigen::Vector2d(back, half)};
  // The spoon's plan rectangle, counter-clockwise in its frame and so in the world once turned.
  const double front = c.plan_angle == 0 ? c.side_x_max : c.spoon_box_x_max;
  const Vec3 corners[4] = {turned(c, Vec3(c.spoon_top_x, -half, 0)), turned(c, Vec3(front, -half, 0)), turned(c, Vec3(front, half, 0)),
                           turned(c, Vec3(c.spoon_top_x, half, 0))};
  for (int k = 0; k < 4 && !section.empty(); ++k) {
    const Vec3& a = corners[k];
    const Vec3& b = corners[(k + 1) % 4];
    section = clip_left_of(section, Eigen::Vector2d(a.x(), a.y()), Eigen::Vector2d(b.x(), b.y()));
  }
  return section;
}

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
ChokeSection choke_section(const TransferChuteLayout& c) {
  ChokeSection choke;
  const PlanPolygon plan = choke_plan(c);
  if (plan.size() < 3 || plan_area(plan) < 1e-6) return choke;
  choke.area = plan_area(plan);
  choke.height = c.hood_exit_z;
  const double below = std::min(kChokeReach, c.hood_exit_z - c.spoon_top_z);
  double above = c.hood_end_angle <= 0 ? kChokeReach : 0.0;
  if (c.plan_angle == 0) above = std::min(above, c.back_plate_top - c.hood_exit_z);
  if (c.rock_box) above = std::min(above, std::max(c.ledge_z - c.hood_exit_z, 0.0));
  above = std::min(above, std::max(c.drop_height - 2 * c.pulley_radius - c.hood_exit_z, 0.0));
  choke.length = below + above;
  Eigen::Vector2d lo = plan[0], hi = plan[0];
  for (const Eigen::Vector2d& p : plan) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  choke.lo = Vec3(lo.x(), lo.y(), c.hood_exit_z - below);
  choke.hi = Vec3(hi.x(), hi.y(), c.hood_exit_z + above);
  return choke;
}

/// Stream profile sensors: `stream_chute` across the chute's narrowest section, down the fall
/// line; `stream_belt` across the receiving belt after the loading zone, along the belt (over
/// the loading zone itself on a belt too short for both).
void add_stream_sensors(const ChuteBuild& chute, const ChokeSection& choke, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  if (choke.area > 0 && choke.length > 0) {
    SensorSpec section;
    section.kind = SensorSpec::Kind::box, section.name = "stream_chute";
    section.region_min = choke.lo, section.region_max = choke.hi;
    section.across = Vec3::UnitY(), section.along = Vec3(0, 0, -1), section.bins = kStreamBins;
    out.sensors.push_back(section);
  }
  double from = loading_zone_end(c), to = std::min(from + 0.5, discharge_plane_x(c) - 0.1);  // [m] along the belt
  if (to - from < 0.1) from = c.spoon_lip_x, to = loading_zone_end(c);
  SensorSpec belt;
  belt.kind = SensorSpec::Kind::box, belt.name = "stream_belt";
  belt.across = turned_direction(c, Vec3::UnitY()), belt.along = turned_direction(c, Vec3::UnitX()), belt.bins = kStreamBins;
  std::tie(belt.region_min, belt.region_max) = turned_box(c, Vec3(from, -chute.receiving_half, -0.05), Vec3(to, chute.receiving_half, 0.5));
  out.sensors.push_back(belt);
}

/// The design values of the chute's narrowest section: its free area, the stream_chute box's
/// length along the fall line, and its height (the hood exit's); the report's choke fill is the
/// box's mass over bulk density x area x length.
void choke_design(const ChokeSection& choke, std::vector<std::pair<std::string, double>>& design) {
  if (!(choke.area > 0 && choke.length > 0)) return;
  design.push_back({"choke_section_area_m2", choke.area});
  design.push_back({"choke_section_length_m", choke.length});
  design.push_back({"choke_section_at_height_m", choke.height});
}

/// The design values of a profile spoon: its points, trough and the slope it leaves the lip at.
void profile_design(const TransferChuteLayout& c, std::vector<std::pair<std::string, double>>& design) {
  const auto& last = c.spoon_profile.back();
  const auto& before = c.spoon_profile[c.spoon_profile.size() - 2];
  design.push_back({"spoon_profile_points", double(c.spoon_profile.size())});
  design.push_back({"spoon_trough_width_m", c.trough_width});
  design.push_back({"spoon_trough_depth_m", c.trough_depth});
  design.push_back({"spoon_trough_u", c.trough_u ? 1.0 : 0.0});
  design.push_back({"spoon_exit_angle_deg", std::atan2(before[1] - last[1], last[0] - before[0]) * 180 / kPi});
}

/// The design values of a rock box: where the stream meets the hood, the box, its volume up to
/// the dam's top (ledge_width times the area between dam, ledge and hood), and, with the case's
/// particles known, the bed's depth in top sizes.
void rock_box_design(const TransferChuteLayout& c, double largest_particle, std::vector<std::pair<std::string, double>>& design) {
  const double area = 0.5 * c.rock_box_height * ((c.ledge_wall_x - c.dam_x) + (c.impact_x - c.dam_x));  // [m^2]
  design.push_back({"impact_x_m", c.impact_x});
  design.push_back({"impact_height_m", c.impact_z});
  design.push_back({"rock_box_height_m", c.rock_box_height});
  design.push_back({"rock_box_ledge_depth_m", c.ledge_depth});
  design.push_back({"rock_box_ledge_width_m", c.ledge_width});
  design.push_back({"rock_box_volume_m3", area * c.ledge_width});
  if (largest_particle > 0) design.push_back({"rock_box_bed_top_sizes", c.rock_box_height / largest_particle});
}

/// The design values the report shows.
void set_design(const TransferChuteLayout& c, double largest_particle, Generated& out) {
  const double pulley_ratio = c.feed_speed * c.feed_speed /
                              (kGravity * (c.pulley_radius + 0.5 * c.load_height));  // CEMA V^2/(g r), r = R + a1
  const Vec3 lip = turned(c, Vec3(c.spoon_lip_x, 0, c.spoon_lip_height));
  out.design = {
      {"feed_belt_speed_m_s", c.feed_speed},
      {"receiving_belt_speed_m_s", c.receiving_speed},
      {"feed_belt_width_m", c.feed_width},
      {"receiving_belt_width_m", c.receiving_width},
      {"troughing_angle_deg", c.feed_trough * 180 / kPi},  // the feed belt's, as feed_belt_troughing_angle_deg
      {"feed_belt_troughing_angle_deg", c.feed_trough * 180 / kPi},
      {"receiving_belt_troughing_angle_deg", c.receiving_trough * 180 / kPi},
      {"drop_height_m", c.drop_height},
      {"pulley_diameter_m", 2 * c.pulley_radius},
      {"discharge_ratio_v2_gr", pulley_ratio},
      {"hood_radius_m", c.hood_radius},
      {"hood_distance_m", c.hood_distance},
      {"hood_top_height_m", c.hood_top_height},
      {"hood_exit_angle_deg", -c.hood_end_angle * 180 / kPi},
  };
  if (c.spoon_profile.empty()) out.design.push_back({"spoon_radius_m", c.spoon_radius});
  else profile_design(c, out.design);
  out.design.push_back({"spoon_lip_height_m", c.spoon_lip_height});
  out.design.push_back({"spoon_lip_x_m", lip.x()});
  out.design.push_back({"chute_width_m", c.chute_width});
  out.design.push_back({"skirt_width_m", c.skirt_width});
  if (c.plan_angle != 0) {
    out.design.push_back({"plan_angle_deg", c.plan_angle * 180 / kPi});
    out.design.push_back({"spoon_lip_y_m", lip.y()});
    out.design.push_back({"fall_line_x_m", c.fall_x});
    out.design.push_back({"hood_exit_height_m", c.hood_exit_z});
  }
  if (c.rock_box) rock_box_design(c, largest_particle, out.design);
}

}  // namespace

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
