// Kinematics of moving walls: a rigid motion of a mesh (or a group of meshes) as a function of
// time, composed from simple parts (translation, rotation about an axis, sinusoidal oscillation,
// a CSV table of positions or speeds) and read from the case YAML (read_motion, spec.h).
//
// The motion is prescribed, not integrated: pose(t) is evaluated in closed form at any t, so a
// restart from a checkpoint places the walls exactly where an uninterrupted run would, and
// velocity(t) is the exact time derivative of pose(t) (the wall velocity the contact model sees).
//
// YAML (`motion:` of a mesh). One part as a map, or a list of parts applied in order:
//
//   motion: {rotation: {axis: [0, 1, 0], point: [0, 0, 0.2], rpm: 30}, start: 0.1}
//
//   motion:
//     - {translation: {velocity: [0.1, 0, 0]}, stop: 2.0}          # [m/s]
//     - {oscillation: {amplitude: [0, 0, 0.005], frequency: 10}}  # [m], [Hz], optional phase [rad]
//     - {table: {file: lift.csv, columns: position}}              # header t,x,y,z (speed: t,vx,vy,vz)
//
//   motion: {belt_loop: {axis: [0, 1, 0], lower: [0, 0, 0], upper: [0, 0, 3], radius: 0.3, speed: 1.5, offset: 0}}
//
// Every part takes `start` (default 0) and `stop` (default .inf) [s]: before start the part rests
// in its start pose, after stop it stays frozen where it stopped. Rotation takes `axis` (any
// non-zero length), `point` on the axis [m] (default origin) and exactly one of `rpm` or
// `rad_per_s`; positive speeds turn anticlockwise looking down the axis (right-hand rule).
//
// Tables: a CSV file (relative paths from the case file's folder) whose first line is the header
// `t,x,y,z` (positions [m]) or `t,vx,vy,vz` (speeds [m/s]); blank lines and lines starting with
// `#` are skipped. Times [s] count from the part's `start` and must increase strictly.
// `columns: position | speed` is optional and, when given, must agree with the header.
// Positions are interpolated linearly; speeds are interpolated linearly and integrated exactly
// (the position is piecewise quadratic, zero at the first time). Outside the table the part rests:
// before the first time it holds the first position (a speed table: zero), after the last time it
// holds the last position. Rejected: continuing with the last speed after the table ends; a wall
// that keeps going after its profile is over runs through the rest of the plant.
//
// Belt loop (a bucket on an elevator belt): the local frame is carried around the stadium-shaped
// path of a belt over two pulleys with parallel axes along `axis`, centres `lower` and `upper`
// [m] (upper - lower perpendicular to axis), path radius `radius` [m] (where the carried point
// runs on the arcs, e.g. the belt's outer surface), at `speed` [m/s] along the path, starting
// `offset` [m] of arc length after the reference point. With e = unit(upper - lower) and
// s = e x axis, the loop runs anticlockwise about `axis` (right-hand rule): up (+e) on the +s
// straight, over the upper pulley, down on the -s straight, round the lower pulley. The reference
// point (arc length 0) is lower + radius s, where the +s straight leaves the lower pulley. The
// local frame: origin on the path, local +x outward from the loop (away from the pulleys' side of
// the belt), local +y along the direction of travel, local +z along `axis`; on the arcs it turns
// with the belt about `axis` by the arc angle (at arc length 0: x -> s, y -> e, z -> axis). A
// negative speed runs the loop backwards. The loop closes after (2 |upper - lower| + 2 pi
// radius) / |speed| seconds.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <limits>
#include <string>
#include <vector>

namespace dem {

/// A rigid placement: x_world = rotation * x_local + translation.
struct Pose {
  Eigen::Quaterniond rotation{1, 0, 0, 0};  // unit quaternion
  Eigen::Vector3d translation{0, 0, 0};     // [m] where the local origin is
};

/// Velocity of the moving body: at a world point x, v(x) = linear + angular x (x - origin).
struct RigidVelocity {
  Eigen::Vector3d linear{0, 0, 0};   // [m/s] velocity of the body point at `origin`
  Eigen::Vector3d angular{0, 0, 0};  // [rad/s]
  Eigen::Vector3d origin{0, 0, 0};   // [m] world position of the motion's reference point
  /// [m/s] velocity of the body point at world position x [m].
  Eigen::Vector3d at(const Eigen::Vector3d& x) const { return linear + angular.cross(x - origin); }
};

/// One part of a motion, active between start and stop [s] (before start: at rest in its start
/// pose; after stop: frozen where it stopped). Only the fields of its kind are used.
struct MotionPart {
  enum class Kind { translation, rotation, oscillation, table, belt_loop } kind = Kind::translation;
  double start = 0.0;                                      // [s]
  double stop = std::numeric_limits<double>::infinity();  // [s]

  // translation: x(t) = velocity (t - start)
  Eigen::Vector3d velocity{0, 0, 0};  // [m/s]

  // rotation by angular_speed (t - start) about the axis through `point`
  Eigen::Vector3d axis{0, 0, 1};   // unit
  Eigen::Vector3d point{0, 0, 0};  // [m] a point on the axis
  double angular_speed = 0.0;      // [rad/s] (YAML: rpm or rad_per_s)

  // oscillation: x(t) = amplitude sin(2 pi frequency (t - start) + phase)
  Eigen::Vector3d amplitude{0, 0, 0};  // [m]
  double frequency = 0.0;              // [Hz]
  double phase = 0.0;                  // [rad]

  // table: rows (times[i], values[i]); values are positions [m] or, with `speeds`, speeds [m/s].
  // Speed tables are integrated from the first row on each evaluation, O(rows); a cached running
  // sum was rejected so that a hand-built part needs no preparation step and cannot go stale.
  std::vector<double> times;            // [s] from `start`, strictly increasing
  std::vector<Eigen::Vector3d> values;  // [m] or [m/s], one per time
  bool speeds = false;

  // belt_loop (uses `axis` too): see the header comment for the path and the carried frame.
  Eigen::Vector3d lower{0, 0, 0};  // [m] centre of the lower pulley (arc length 0 starts here)
  Eigen::Vector3d upper{0, 0, 1};  // [m] centre of the upper pulley
  double radius = 0.0;             // [m] path radius on the pulley arcs
  double speed = 0.0;              // [m/s] along the path
  double offset = 0.0;             // [m] arc length at `start`
};

/// Length [m] of a belt_loop part's closed path: 2 |upper - lower| + 2 pi radius.
double belt_loop_length(const MotionPart& part);

/// A rigid motion composed of parts.
struct Motion {
  /// Applied in order: the pose is part_n o ... o part_1 (each later part moves everything the
  /// earlier ones produced; a later rotation's axis is fixed in the world, not carried along).
  std::vector<MotionPart> parts;

  /// True when the pose never changes (no parts, or parts that do not move); the pose may still
  /// differ from the identity (an oscillation's phase, a constant table).
  bool is_static() const;

  /// Where the mesh's local frame is at time t [s].
  Pose pose(double t) const;

  /// Exact time derivative of pose(t) [s], composed part by part (not finite differences). At a
  /// part's start the rate is the one after it (the part is moving), at its stop zero. `origin`
  /// is the reference point: the `point` of the first rotation part, read as a local coordinate
  /// and placed by pose(t) (for a drum, a point on its axis), or the local origin when no part
  /// rotates; mesh torques are taken about it.
  RigidVelocity velocity(double t) const;

  /// Largest distance [m] any point within `radius` [m] of the local origin can be from where it
  /// was at t0 when it is at t1 (an upper bound, used to decide when contact lists must be
  /// rebuilt). It compares the two poses only: |dp| + 2 |sin(dtheta/2)| radius. The path in
  /// between is not bounded (the rebuild check runs every step, so only the present matters);
  /// a path-length bound was rejected because it grows without end for a wall that oscillates.
  double max_displacement(double t0, double t1, double radius) const;
};

}  // namespace dem
