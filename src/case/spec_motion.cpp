// Reading a `motion:` value of a case (meshes[].motion) into a Motion (motion/kinematics.h):
// one part map or a list of them, with tables of positions or speeds from CSV files. The layout
// of the YAML is described at the top of kinematics.h.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>

#include "case/spec.h"
#include "case/yaml_check.h"
#include "motion/kinematics.h"

namespace dem {

using Eigen::Vector3d;

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
