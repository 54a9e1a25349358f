// The transfer chute's feed port, discharge outlet, sensors and design values. The receiving
// side's are placed in its frame and turned (transfer_chute_layout.h); the stream_chute sensor
// and the choke design values share the chute's narrowest section, found here in plan by
// clipping the hood's box to the spoon's.
#include "transfer_chute_sensors.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "generators.h"
#include "transfer_chute_layout.h"
#include "transfer_chute_parts.h"

namespace dem::equipment::detail {

// ---- the feed port, the discharge outlet, the flow planes and the loading zone -----------------

namespace {

/// [m] Where the loading zone (the load box after the spoon lip) ends along the receiving belt:
/// 1 m past the lip, or 0.4 m short of the belt's end on a shorter belt.
double loading_zone_end(const TransferChuteLayout& c) { return c.spoon_lip_x + std::min(1.0, c.receiving_x_max - c.spoon_lip_x - 0.4); }

/// [m] The belt_discharge plane along the receiving belt: 0.3 m before its end.
double discharge_plane_x(const TransferChuteLayout& c) { return c.receiving_x_max - 0.3; }

}  // namespace

void add_feed_port(const TransferChuteLayout& c, Generated& out) {
  const double port_half_width = 0.35 * c.feed_width;
  const double port_bottom = c.drop_height + trough_height(c.feed_width, c.feed_trough, port_half_width) + 0.01;
  const double port_length = std::min(1.0, 0.4 * c.feed_length);
  out.ports.push_back({"feed_belt", Vec3(-c.feed_length + 0.1, -port_half_width, port_bottom),
                       Vec3(-c.feed_length + 0.1 + port_length, port_half_width, port_bottom + c.feed_port_height),
                       Vec3(c.feed_speed, 0, 0)});
}

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

namespace {

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

/// The free plan section at the hood's exit height: the hood's box (from behind the pulley, or
/// from the pulley's front when the exit lies at the pulley's height, to the hood's exit) clipped
/// to the spoon's (from its back plate forward between the side plates, turned about the fall
/// line). Inline, the spoon's reaches to the side plates' end. Angled, the deck's cells on the
/// opening's rim narrow it by less than a cell (kDeckCell, transfer_chute_meshes.cpp); they are
/// left out of the area.
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

}  // namespace

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

// ---- design values -----------------------------------------------------------------------------

void choke_design(const ChokeSection& choke, std::vector<std::pair<std::string, double>>& design) {
  if (!(choke.area > 0 && choke.length > 0)) return;
  design.push_back({"choke_section_area_m2", choke.area});
  design.push_back({"choke_section_length_m", choke.length});
  design.push_back({"choke_section_at_height_m", choke.height});
}

namespace {

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

}  // namespace

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

}  // namespace dem::equipment::detail
