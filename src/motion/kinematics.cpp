#include "motion/kinematics.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace dem {

using Eigen::Quaterniond;
using Eigen::Vector3d;

namespace {

/// Placement of one part at time t and its rate: rotation R, translation p and their derivatives
/// as the world angular velocity w (dR/dt = [w]x R) and dp/dt.
struct PartPose {
  Quaterniond rotation = Quaterniond::Identity();
  Vector3d translation = Vector3d::Zero();        // [m]
  Vector3d angular = Vector3d::Zero();            // [rad/s]
  Vector3d translation_rate = Vector3d::Zero();   // [m/s]
};

/// Row i of a table such that times[i] <= s < times[i + 1]; s must lie inside the table.
size_t table_segment(const std::vector<double>& times, double s) {
  const auto above = std::upper_bound(times.begin(), times.end(), s);
  return std::min<size_t>(std::max<ptrdiff_t>(above - times.begin() - 1, 0), times.size() - 2);
}

/// Table part at s [s] since start: position and rate. Speeds v(s) are linear on each row
/// interval, so the position is the trapezoid area up to the row plus v_i u + (v_i+1 - v_i) u^2 / 2h.
void table_pose(const MotionPart& part, double s, bool moving, PartPose& out) {
  const auto& t = part.times;
  const auto& v = part.values;
  const size_t n = t.size();
  if (n == 0) return;
  if (n == 1) {
    if (!part.speeds) out.translation = v[0];
    return;
  }
  if (!(s >= t[0])) {  // before the first row: at rest (a NaN time rests too)
    if (!part.speeds) out.translation = v[0];
    return;
  }
  const bool inside = s < t[n - 1];
  const double clamped = std::min(s, t[n - 1]);
  const size_t i = table_segment(t, clamped);
  const double h = t[i + 1] - t[i];
  const double u = clamped - t[i];
  const Vector3d slope = (v[i + 1] - v[i]) / h;
  if (!part.speeds) {
    out.translation = v[i] + slope * u;
    if (moving && inside) out.translation_rate = slope;
    return;
  }
  Vector3d area = Vector3d::Zero();
  for (size_t j = 0; j < i; ++j) area += 0.5 * (v[j] + v[j + 1]) * (t[j + 1] - t[j]);
  out.translation = area + v[i] * u + 0.5 * slope * u * u;
  if (moving && inside) out.translation_rate = v[i] + slope * u;
}

/// Belt-loop part at `travelled` [m] of arc length since start: the carried frame and its rate
/// (`moving`: the belt runs). Path and frame as documented in kinematics.h.
void belt_loop_pose(const MotionPart& part, double travelled, bool moving, PartPose& out) {
  const Vector3d axis = part.axis.normalized();
  const Vector3d span = part.upper - part.lower;
  const Vector3d along = (span - span.dot(axis) * axis);
  const double straight = along.norm();  // [m]
  const Vector3d e = along / straight;    // up the loop
  const Vector3d s = e.cross(axis);       // outward on the up-going straight
  const double r = part.radius;
  const double arc = std::numbers::pi * r;  // [m] one half turn
  const double loop = 2 * straight + 2 * arc;
  double u = std::fmod(part.offset + travelled, loop);
  if (u < 0) u += loop;
  // Four pieces: up straight, upper arc, down straight, lower arc; theta is the frame's turn.
  double theta = 0;         // [rad] about axis
  double turn_rate = 0;     // [rad/m] dtheta/du
  Vector3d point, tangent;  // path point [m] and unit tangent
  if (u < straight) {
    point = part.lower + r * s + u * e, tangent = e, theta = 0;
  } else if (u < straight + arc) {
    theta = (u - straight) / r, turn_rate = 1 / r;
    point = part.lower + along + r * (std::cos(theta) * s + std::sin(theta) * e);
    tangent = -std::sin(theta) * s + std::cos(theta) * e;
  } else if (u < 2 * straight + arc) {
    point = part.lower + along - r * s - (u - straight - arc) * e, tangent = -e, theta = std::numbers::pi;
  } else {
    theta = std::numbers::pi + (u - 2 * straight - arc) / r, turn_rate = 1 / r;
    point = part.lower + r * (std::cos(theta) * s + std::sin(theta) * e);
    tangent = -std::sin(theta) * s + std::cos(theta) * e;
  }
  // Local frame at arc length 0: x -> s, y -> e, z -> axis; then turned by theta about axis.
  Eigen::Matrix3d start_frame;
  start_frame.col(0) = s, start_frame.col(1) = e, start_frame.col(2) = axis;
  out.rotation = Quaterniond(Eigen::AngleAxisd(theta, axis)) * Quaterniond(start_frame);
  out.translation = point;
  if (moving) {
    out.translation_rate = part.speed * tangent;
    out.angular = part.speed * turn_rate * axis;
  }
}

/// The pose of one part at time t [s] and its rate.
PartPose part_pose(const MotionPart& part, double t) {
  // Time is clamped into [start, stop]: at rest before, frozen after. The rate is that of the
  // clamped time, one-sided at the ends (moving from start on, zero from stop on).
  const double clamped = std::clamp(t, part.start, std::max(part.start, part.stop));
  const double elapsed = clamped - part.start;  // [s]
  const bool moving = t >= part.start && t < part.stop;
  PartPose out;
  switch (part.kind) {
    case MotionPart::Kind::translation:
      out.translation = part.velocity * elapsed;
      if (moving) out.translation_rate = part.velocity;
      break;
    case MotionPart::Kind::rotation: {
      // x -> R (x - point) + point: p = point - R point, dp/dt = -w x (R point).
      out.rotation = Quaterniond(Eigen::AngleAxisd(part.angular_speed * elapsed, part.axis.normalized()));
      const Vector3d turned = out.rotation * part.point;
      out.translation = part.point - turned;
      if (moving) {
        out.angular = part.angular_speed * part.axis.normalized();
        out.translation_rate = -out.angular.cross(turned);
      }
      break;
    }
    case MotionPart::Kind::oscillation: {
      const double omega = 2.0 * std::numbers::pi * part.frequency;  // [rad/s]
      const double argument = omega * elapsed + part.phase;
      out.translation = part.amplitude * std::sin(argument);
      if (moving) out.translation_rate = part.amplitude * (omega * std::cos(argument));
      break;
    }
    case MotionPart::Kind::table:
      table_pose(part, elapsed, moving, out);
      break;
    case MotionPart::Kind::belt_loop:
      belt_loop_pose(part, part.speed * elapsed, moving, out);
      break;
  }
  return out;
}

/// The local point whose world position is the velocity's reference: see Motion::velocity.
Vector3d reference_point(const Motion& motion) {
  for (const MotionPart& part : motion.parts)
    if (part.kind == MotionPart::Kind::rotation) return part.point;
  return Vector3d::Zero();
}

}  // namespace

bool Motion::is_static() const {
  for (const MotionPart& part : parts) {
    if (!(part.stop > part.start)) continue;
    switch (part.kind) {
      case MotionPart::Kind::translation:
        if (!part.velocity.isZero(0.0)) return false;
        break;
      case MotionPart::Kind::rotation:
        if (part.angular_speed != 0.0) return false;
        break;
      case MotionPart::Kind::oscillation:
        if (!part.amplitude.isZero(0.0) && part.frequency != 0.0) return false;
        break;
      case MotionPart::Kind::table:
        for (const Vector3d& value : part.values)
          if (part.speeds ? !value.isZero(0.0) : value != part.values.front()) return false;
        break;
      case MotionPart::Kind::belt_loop:
        if (part.speed != 0.0) return false;
        break;
    }
  }
  return true;
}

double belt_loop_length(const MotionPart& part) {
  const Vector3d axis = part.axis.normalized();
  const Vector3d span = part.upper - part.lower;
  return 2 * (span - span.dot(axis) * axis).norm() + 2 * std::numbers::pi * part.radius;
}

Pose Motion::pose(double t) const {
  // T = T_n o ... o T_1: applying (R_k, p_k) to (R, p) gives (R_k R, R_k p + p_k).
  Pose total;
  for (const MotionPart& part : parts) {
    const PartPose step = part_pose(part, t);
    total.rotation = step.rotation * total.rotation;
    total.translation = step.rotation * total.translation + step.translation;
  }
  total.rotation.normalize();
  return total;
}

RigidVelocity Motion::velocity(double t) const {
  // Velocity field of the parts so far, v(x) = c + W x (c: velocity of the body point at the world
  // origin). Part k maps x -> R_k x + p_k with rates (w_k, dp_k/dt); differentiating
  // x' = R_k x + p_k with x moving in the field gives
  //   v'(x') = [dp_k/dt - w_k x p_k + R_k c - (R_k W) x p_k] + (w_k + R_k W) x x',
  // the adjoint map of rigid-body twists (Murray, Li & Sastry 1994, A Mathematical Introduction
  // to Robotic Manipulation, sec. 2.4, eq. 2.58 in spatial form).
  Quaterniond rotation = Quaterniond::Identity();
  Vector3d translation = Vector3d::Zero();  // [m]
  Vector3d angular = Vector3d::Zero();      // [rad/s] W
  Vector3d at_origin = Vector3d::Zero();    // [m/s] c
  for (const MotionPart& part : parts) {
    const PartPose step = part_pose(part, t);
    const Vector3d carried = step.rotation * angular;
    at_origin = step.translation_rate - step.angular.cross(step.translation) + step.rotation * at_origin -
                carried.cross(step.translation);
    angular = step.angular + carried;
    rotation = step.rotation * rotation;
    translation = step.rotation * translation + step.translation;
  }
  RigidVelocity out;
  out.origin = rotation.normalized() * reference_point(*this) + translation;
  out.angular = angular;
  out.linear = at_origin + angular.cross(out.origin);
  return out;
}

double Motion::max_displacement(double t0, double t1, double radius) const {
  // x1 - x0 = (R1 - R0) x + (p1 - p0) and |R1 - R0| = |R1 R0^T - I| = 2 |sin(theta/2)|, which is
  // twice the norm of the vector part of the relative unit quaternion.
  // A margin of a few round-offs of the coordinates keeps it a bound in floating point too (a
  // pure translation is otherwise matched exactly, and rounding may land either side).
  const Pose a = pose(t0), b = pose(t1);
  const Quaterniond relative = b.rotation * a.rotation.conjugate();
  const double bound = (b.translation - a.translation).norm() + 2.0 * relative.vec().norm() * radius;
  const double round_off = 16 * std::numeric_limits<double>::epsilon() *
                           (a.translation.norm() + b.translation.norm() + radius);
  return bound * (1 + 1e-12) + round_off;
}

}  // namespace dem
