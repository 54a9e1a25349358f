#include "kinematics.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "yaml_check.h"

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

// ---------------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------------

namespace {

const std::vector<std::string> kKinds = {"translation", "rotation", "oscillation", "table", "belt_loop"};

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t\r") - first + 1);
}

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  size_t begin = 0;
  while (true) {
    const size_t comma = line.find(',', begin);
    fields.push_back(trim(line.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin)));
    if (comma == std::string::npos) return fields;
    begin = comma + 1;
  }
}

/// Reads a table CSV into `part` (times, values, speeds). Errors name the YAML key `file` and the
/// CSV file and line.
void read_table_csv(MapReader& reader, const std::string& csv_name, const std::string& base_dir,
                    const std::string& columns, MotionPart& part) {
  namespace fs = std::filesystem;
  fs::path path(csv_name);
  if (path.is_relative() && !base_dir.empty()) path = fs::path(base_dir) / path;
  const std::string shown = path.string();
  std::error_code error;
  if (!fs::exists(path, error)) reader.fail("file", fmt::format("table file '{}' not found", shown));
  if (fs::is_directory(path, error)) reader.fail("file", fmt::format("'{}' is a folder, not a CSV file", shown));
  std::ifstream in(path);
  if (!in) reader.fail("file", fmt::format("table file '{}' cannot be opened for reading", shown));

  const auto fail_line = [&](int line, const std::string& message) {
    reader.fail("file", fmt::format("{}:{}: {}", shown, line, message));
  };
  std::string line;
  int line_number = 0;
  bool have_header = false;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string text = trim(line);
    if (text.empty() || text.front() == '#') continue;
    std::vector<std::string> fields = split_fields(text);
    // The header names the columns, so a speed file cannot be read as positions by mistake.
    if (!have_header) {
      std::string header;
      for (std::string& f : fields) {
        std::transform(f.begin(), f.end(), f.begin(), [](unsigned char c) { return std::tolower(c); });
        header += (header.empty() ? "" : ",") + f;
      }
      if (header != "t,x,y,z" && header != "t,vx,vy,vz") {
        fail_line(line_number, fmt::format("header '{}' is not valid; valid: t,x,y,z (positions [m]) or "
                                           "t,vx,vy,vz (speeds [m/s])", text));
      }
      part.speeds = header == "t,vx,vy,vz";
      if (!columns.empty() && (columns == "speed") != part.speeds) {
        reader.fail("columns", fmt::format("'{}' does not match the header '{}' of {} (line {})", columns, text,
                                           shown, line_number));
      }
      have_header = true;
      continue;
    }
    if (fields.size() != 4) {
      fail_line(line_number, fmt::format("{} values; each row needs 4: time, then x, y, z", fields.size()));
    }
    double numbers[4];
    for (int k = 0; k < 4; ++k) {
      char* end = nullptr;
      numbers[k] = std::strtod(fields[k].c_str(), &end);
      if (fields[k].empty() || *end != '\0' || !std::isfinite(numbers[k])) {
        fail_line(line_number, fmt::format("'{}' is not a finite number", fields[k]));
      }
    }
    if (!part.times.empty() && !(numbers[0] > part.times.back())) {
      fail_line(line_number, fmt::format("time {:g} s is not after {:g} s on the row before; times must increase",
                                         numbers[0], part.times.back()));
    }
    part.times.push_back(numbers[0]);
    part.values.emplace_back(numbers[1], numbers[2], numbers[3]);
  }
  if (in.bad()) reader.fail("file", fmt::format("table file '{}' could not be read", shown));
  if (!have_header) reader.fail("file", fmt::format("table file '{}' is empty; it needs a header t,x,y,z", shown));
  if (part.times.size() < 2) {
    reader.fail("file", fmt::format("table file '{}' has {} rows; it needs at least 2", shown, part.times.size()));
  }
}

/// One part map: exactly one of the kinds plus optional start and stop.
MotionPart read_part(const YAML::Node& node, const std::string& file, const std::string& path,
                     const std::string& base_dir) {
  MapReader reader(node, file, path);
  MotionPart part;
  constexpr double kForever = std::numeric_limits<double>::infinity();
  part.start = reader.number("start", 0.0, 0.0, kForever, "s");
  part.stop = reader.number("stop", kForever, 0.0, kForever, "s");
  // Typos ("rotaton") are reported with a suggestion before "no kind given" is.
  reader.finish(kKinds);
  std::vector<std::string> given;
  for (const std::string& kind : kKinds)
    if (reader.has(kind)) given.push_back(kind);
  if (given.empty()) {
    throw CaseError(fmt::format("{}: {}: a motion part needs one of translation, rotation, oscillation, table, belt_loop",
                                reader.location().str(), path));
  }
  if (given.size() > 1) {
    reader.fail(given[1], fmt::format("a part is one motion, but '{}' and '{}' are both given; make a list of "
                                      "parts to compose motions", given[0], given[1]));
  }
  if (!(part.stop > part.start)) reader.fail("stop", fmt::format("{:g} s must be after start ({:g} s)", part.stop, part.start));

  const std::string& kind = given[0];
  MapReader inner(reader.node(kind), file, reader.key_path(kind));
  const auto required_vec3 = [&](const std::string& key, const char* example) -> Vector3d {
    if (!inner.has(key)) inner.fail(key, fmt::format("missing; give a list of three numbers, e.g. {}", example));
    return inner.vec3(key, Vector3d::Zero());
  };
  if (kind == "translation") {
    part.kind = MotionPart::Kind::translation;
    part.velocity = required_vec3("velocity", "[0.1, 0, 0] (m/s)");
    inner.finish();
  } else if (kind == "rotation") {
    part.kind = MotionPart::Kind::rotation;
    const Vector3d axis = required_vec3("axis", "[0, 0, 1]");
    part.point = inner.vec3("point", Vector3d::Zero());
    const double rpm = inner.number("rpm", 0.0, -1e6, 1e6, "rpm");
    const double rad_per_s = inner.number("rad_per_s", 0.0, -1e5, 1e5, "rad/s");
    inner.finish();
    if (axis.norm() == 0.0) inner.fail("axis", "must not be zero; give the axis direction, e.g. [0, 0, 1]");
    part.axis = axis.normalized();
    if (inner.has("rpm") && inner.has("rad_per_s")) inner.fail("rad_per_s", "give rpm or rad_per_s, not both");
    if (!inner.has("rpm") && !inner.has("rad_per_s")) inner.fail("rpm", "missing; give rpm or rad_per_s");
    part.angular_speed = inner.has("rpm") ? rpm * 2.0 * std::numbers::pi / 60.0 : rad_per_s;
  } else if (kind == "oscillation") {
    part.kind = MotionPart::Kind::oscillation;
    part.amplitude = required_vec3("amplitude", "[0, 0, 0.005] (m)");
    part.frequency = inner.required_number("frequency", 0.0, 1e6, "Hz");
    part.phase = inner.number("phase", 0.0, -1e3, 1e3, "rad");
    inner.finish();
    if (part.frequency == 0.0) inner.fail("frequency", "must be above 0 Hz");
  } else if (kind == "belt_loop") {
    part.kind = MotionPart::Kind::belt_loop;
    const Vector3d axis = required_vec3("axis", "[0, 1, 0]");
    part.lower = required_vec3("lower", "[0, 0, 0] (m)");
    part.upper = required_vec3("upper", "[0, 0, 3] (m)");
    part.radius = inner.required_number("radius", 0.0, 1e3, "m");
    part.speed = inner.required_number("speed", -1e3, 1e3, "m/s");
    part.offset = inner.number("offset", 0.0, -1e6, 1e6, "m");
    inner.finish();
    if (axis.norm() == 0.0) inner.fail("axis", "must not be zero; give the pulley axis direction, e.g. [0, 1, 0]");
    part.axis = axis.normalized();
    if (part.radius == 0.0) inner.fail("radius", "must be above 0 m (the path radius around the pulleys)");
    const Vector3d span = part.upper - part.lower;
    const double along_axis = std::abs(span.dot(part.axis));
    if (along_axis > 1e-9 * std::max(1.0, span.norm()) || span.norm() == 0.0) {
      inner.fail("upper", fmt::format("upper - lower must be a non-zero distance perpendicular to the axis (it has "
                                      "{:g} m along the axis and {:g} m across)", along_axis,
                                      std::sqrt(std::max(0.0, span.squaredNorm() - along_axis * along_axis))));
    }
  } else {
    part.kind = MotionPart::Kind::table;
    if (!inner.has("file")) inner.fail("file", "missing; give a CSV file with the header t,x,y,z or t,vx,vy,vz");
    const std::string csv = inner.string("file", "");
    const std::string columns = inner.string("columns", "", {"position", "speed"});
    inner.finish();
    read_table_csv(inner, csv, base_dir, columns, part);
  }
  return part;
}

}  // namespace

Motion read_motion(const YAML::Node& node, const std::string& file, const std::string& key_path,
                   const std::string& base_dir) {
  Motion motion;
  if (!node || node.IsNull()) return motion;
  if (node.IsMap()) {
    motion.parts.push_back(read_part(node, file, key_path, base_dir));
    return motion;
  }
  if (!node.IsSequence()) {
    const YAML::Mark mark = node.Mark();
    const SourceLocation where{file, mark.is_null() ? 0 : mark.line + 1, mark.is_null() ? 0 : mark.column + 1};
    throw CaseError(fmt::format("{}: {}: must be a motion part (a map such as {{rotation: {{axis: [0, 0, 1], "
                                "rpm: 30}}}}) or a list of parts", where.str(), key_path));
  }
  for (size_t i = 0; i < node.size(); ++i)
    motion.parts.push_back(read_part(node[i], file, fmt::format("{}[{}]", key_path, i), base_dir));
  return motion;
}

}  // namespace dem
