// The transfer chute's walls: the feed belt and its head pulley, the hood (with its roof), the
// rock box, the spoon (arc or profile trough) with its back plate, the enclosure (the inline
// chute's side plates, or the angled transfer's two boxes and their deck), the receiving belt and
// its skirts. Positions come from the layout (transfer_chute_layout.cpp); this file only places
// triangles on them.
#include "transfer_chute_meshes.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <utility>
#include <vector>

#include "generators.h"
#include "transfer_chute_layout.h"
#include "transfer_chute_parts.h"

namespace dem::equipment::detail {

namespace {

/// [m] cell size of the chute's surfaces: finer than kCell so that the curved liners follow their
/// arcs and a chute has a few thousand triangles.
constexpr double kChuteCell = 0.12;
/// [m] cell size of an angled transfer's deck: a cell that reaches into the opening between the
/// hood's box and the spoon's narrows it by less than its diagonal.
constexpr double kDeckCell = 0.5 * kChuteCell;

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

}  // namespace

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

namespace {

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

}  // namespace

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

namespace {

/// Side plates at y = +-half from x0 to x1 (the frame they are built in), z0 to z1.
void side_pair(MeshBuilder& mesh, double half, double x0, double x1, double z0, double z1) {
  for (const double y : {-half, half}) {
    const Vec3 a(x0, y, z0), b(x1, y, z0), d(x0, y, z1), e(x1, y, z1);
    if (y < 0) mesh.quad(a, b, e, d, kChuteCell);  // normals point into the chute
    else mesh.quad(a, d, e, b, kChuteCell);
  }
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

}  // namespace

void add_side_plates(const ChuteBuild& chute, Generated& out) {
  const TransferChuteLayout& c = chute.layout;
  MeshBuilder sides;
  side_pair(sides, chute.half, c.side_x_min, c.side_x_max, c.side_z_min, c.side_z_max);
  out.meshes.push_back(sides.wall("side_plates", chute.materials.liner, chute.where));
}

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

}  // namespace dem::equipment::detail
