// Internal to equipment/: the mesh builder every generator uses, the parameter helpers, and one
// entry point per generator (one file each). Not installed; include equipment.h from outside.
#pragma once

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "case/yaml_check.h"
#include "equipment.h"

namespace dem::equipment::detail {

constexpr double kPi = std::numbers::pi;
constexpr double kGravity = 9.81;  // [m/s^2] design calculations (the case's gravity drives the run)
/// [m] longest triangle edge wanted on big parts; cells are made at most this long per side
/// divided by sqrt 2 so that their diagonals stay under it too.
constexpr double kMaxEdge = 0.25;
constexpr double kCell = kMaxEdge / 1.4143;

inline double radians(double degrees) { return degrees * kPi / 180.0; }

/// Number of segments of at most `max_length` [m] to cover `length` [m], at least `minimum`.
inline int segments(double length, double max_length, int minimum = 1) {
  return std::max(minimum, static_cast<int>(std::ceil(std::abs(length) / max_length - 1e-9)));
}

/// Triangles under construction, with consistent winding within each surface.
struct MeshBuilder {
  std::vector<std::array<double, 3>> vertices;         // [m]
  std::vector<std::array<std::int32_t, 3>> triangles;  // indices into vertices

  std::int32_t add(const Vec3& p) {
    vertices.push_back({p.x(), p.y(), p.z()});
    return static_cast<std::int32_t>(vertices.size() - 1);
  }
  void triangle(std::int32_t a, std::int32_t b, std::int32_t c) { triangles.push_back({a, b, c}); }

  /// A parametric surface p(u, w), u and w in [0, 1], as nu x nw cells of two triangles each;
  /// `keep(i, j)` may drop cells (openings). Winding: (du, dw) right-handed gives normal du x dw.
  void grid(const std::function<Vec3(double, double)>& surface, int nu, int nw,
            const std::function<bool(int, int)>& keep = {}) {
    const std::int32_t first = static_cast<std::int32_t>(vertices.size());
    for (int i = 0; i <= nu; ++i)
      for (int j = 0; j <= nw; ++j) add(surface(double(i) / nu, double(j) / nw));
    const auto at = [&](int i, int j) { return first + i * (nw + 1) + j; };
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nw; ++j) {
        if (keep && !keep(i, j)) continue;
        triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
        triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
      }
  }

  /// The planar (or bilinear) quadrilateral a b c d, cells at most `cell` [m] per side.
  void quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double cell = kCell) {
    const int nu = segments(std::max((b - a).norm(), (c - d).norm()), cell);
    const int nw = segments(std::max((d - a).norm(), (c - b).norm()), cell);
    grid([&](double u, double w) { return Vec3((1 - w) * ((1 - u) * a + u * b) + w * ((1 - u) * d + u * c)); }, nu, nw);
  }

  /// A fan over the convex polygon `ring` (closed implicitly) around its centroid.
  void fan(const std::vector<Vec3>& ring) {
    Vec3 centre = Vec3::Zero();
    for (const Vec3& p : ring) centre += p;
    centre /= double(ring.size());
    const std::int32_t c = add(centre), first = static_cast<std::int32_t>(vertices.size());
    for (const Vec3& p : ring) add(p);
    const std::int32_t n = static_cast<std::int32_t>(ring.size());
    for (std::int32_t k = 0; k < n; ++k) triangle(c, first + k, first + (k + 1) % n);
  }

  /// Adds the triangles of `other`, its vertices after this builder's (parts built in another frame).
  void append(const MeshBuilder& other) {
    const std::int32_t first = static_cast<std::int32_t>(vertices.size());
    vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
    for (const auto& t : other.triangles) triangle(first + t[0], first + t[1], first + t[2]);
  }

  /// Moves every vertex: x -> rotation x + shift.
  void transform(const Eigen::Matrix3d& rotation, const Vec3& shift) {
    for (auto& v : vertices) {
      const Vec3 p = rotation * Vec3(v[0], v[1], v[2]) + shift;
      v = {p.x(), p.y(), p.z()};
    }
  }

  MeshWallSpec wall(const std::string& name, const std::string& material, const SourceLocation& location) const {
    MeshWallSpec mesh;
    mesh.name = name, mesh.material = material, mesh.location = location;
    mesh.vertices = vertices, mesh.triangles = triangles;
    return mesh;
  }
};

/// A cylinder surface of `radius` [m] about the axis from `a` to `b` with `around` segments,
/// optionally closed at both ends by fans.
void cylinder(MeshBuilder& mesh, const Vec3& a, const Vec3& b, double radius, int around, bool caps);

/// Two unit vectors completing `axis` to a right-handed frame (u, v, axis).
std::pair<Vec3, Vec3> perpendicular_pair(const Vec3& axis);

/// The sub-map `key` of `parent` as a reader (an empty map when absent, so defaults apply).
MapReader sub_map(MapReader& parent, const std::string& key);

/// Axis-aligned box holding the corners of [lo, hi] moved by x -> rotation x (ports, outlets and
/// sensor boxes of tilted equipment).
std::pair<Vec3, Vec3> rotated_box(const Eigen::Matrix3d& rotation, const Vec3& lo, const Vec3& hi);

/// Grows the box [lo, hi] to hold p.
inline void include(Vec3& lo, Vec3& hi, const Vec3& p) {
  lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
}
/// Sets the domain of `out` to the bounding box of its meshes, ports, outlets and sensor boxes,
/// grown by `margin` [m] on every side and reaching down to at least `floor` [m].
void set_domain(Generated& out, double margin, double floor);

/// Mesh parameters shared by every generator: `liner_material`, `belt_material`.
struct Materials {
  std::string liner = "steel", belt = "rubber";
};
Materials read_materials(MapReader& reader);

Generated transfer_chute(MapReader& reader, const EquipmentSpec& spec);
Generated screw_conveyor(MapReader& reader, const EquipmentSpec& spec);
Generated bucket_elevator(MapReader& reader, const EquipmentSpec& spec);
Generated belt_conveyor(MapReader& reader, const EquipmentSpec& spec);
Generated silo(MapReader& reader, const EquipmentSpec& spec);

/// Troughed belt cross-section (3-roll idlers): the y positions and heights above the centre roll
/// of the profile points from one edge to the other, for belt width `width` [m], centre roll
/// fraction 0.38 and wing angle `trough` [rad]; `cell` [m] limits the piece lengths.
std::vector<std::pair<double, double>> trough_profile(double width, double trough, double cell);
/// Height [m] of a troughed belt's surface above its centre at lateral position y [m].
double trough_height(double width, double trough, double y);
constexpr double kCentreRollFraction = 0.38;  // [-] centre roll length / belt width (CEMA 3-roll)

}  // namespace dem::equipment::detail
