// Reading how particles enter, leave and are measured into the CaseSpec: size distributions,
// particle sets placed at the start, clump templates, inlets, outlets and sensors.
#include <fmt/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "case/spec.h"
#include "case/spec_reading.h"
#include "case/yaml_check.h"

namespace dem {

namespace {

SizeDistributionSpec read_diameter(MapReader& parent, const std::string& file, const std::string& key = "diameter") {
  SizeDistributionSpec d;
  const YAML::Node node = parent.node(key);
  if (!node) parent.fail(key, "missing: give a diameter [m] or {distribution: normal|uniform|discrete, ...}");
  if (node.IsScalar()) {
    d.value = MapReader::scalar_number(node, parent, key);
    if (!(d.value > 0 && d.value < 10)) parent.fail(key, fmt::format("{:g} m is out of range; valid: (0, 10] m", d.value));
    return d;
  }
  MapReader map(node, file, parent.key_path(key));
  const std::string kind = map.string("distribution", "", {"normal", "uniform", "discrete"});
  if (kind.empty()) map.fail("distribution", "missing: normal, uniform or discrete");
  if (kind == "normal") {
    d.kind = SizeDistributionSpec::Kind::normal;
    d.mean = map.required_number("mean", 1e-7, 10, "m");
    d.std_dev = map.required_number("std", 0, 10, "m");
    d.min = map.number("min", std::max(d.mean - 3 * d.std_dev, 0.1 * d.mean), 1e-7, 10, "m");
    d.max = map.number("max", d.mean + 3 * d.std_dev, 1e-7, 10, "m");
    if (!(d.min <= d.mean && d.mean <= d.max)) map.fail("min", "needs min <= mean <= max");
  } else if (kind == "uniform") {
    d.kind = SizeDistributionSpec::Kind::uniform;
    d.min = map.required_number("min", 1e-7, 10, "m");
    d.max = map.required_number("max", d.min, 10, "m");
  } else {
    // Size classes with their mass fractions (a sieve analysis) or number fractions (a count,
    // an image analysis); number fractions become mass fractions n_k d_k^3 / sum n d^3.
    d.kind = SizeDistributionSpec::Kind::discrete;
    const bool by_number = map.has("number_fractions");
    if (by_number && map.has("mass_fractions")) map.fail("number_fractions", "give mass_fractions or number_fractions, not both");
    const std::string fractions_key = by_number ? "number_fractions" : "mass_fractions";
    const YAML::Node values = map.node("values"), fractions = map.node(fractions_key);
    if (!values || !values.IsSequence() || values.size() == 0) map.fail("values", "must be a list of diameters [m]");
    if (!fractions || !fractions.IsSequence() || fractions.size() != values.size())
      map.fail(fractions_key, "must be a list as long as 'values' (mass_fractions, or number_fractions)");
    double sum = 0, mass_sum = 0;
    for (size_t k = 0; k < values.size(); ++k) {
      d.values.push_back(MapReader::finite_number(values[k], map, "values"));
      d.mass_fractions.push_back(MapReader::finite_number(fractions[k], map, fractions_key));
      if (!(d.values.back() > 0 && d.values.back() <= 10)) map.fail("values", "diameters must be in (0, 10] m");
      if (!(d.mass_fractions.back() >= 0)) map.fail(fractions_key, "fractions must not be negative");
      sum += d.mass_fractions.back();
      if (by_number) d.mass_fractions.back() *= d.values.back() * d.values.back() * d.values.back();
      mass_sum += d.mass_fractions.back();
    }
    if (std::abs(sum - 1.0) > 1e-6) map.fail(fractions_key, fmt::format("sum to {:g}; they must sum to 1", sum));
    if (by_number)
      for (double& f : d.mass_fractions) f /= mass_sum;
  }
  map.finish();
  return d;
}

/// `coarse_grain: F` of an inlet or a particle set: a finite number in [1, kMostCoarseGrain]; 1
/// when absent. F < 1 would make parcels smaller than the particles they stand for (refining,
/// which the scaling law in core/coarse_grain.h does not cover); "inf" is out of range.
double read_coarse_grain(MapReader& map) { return map.number("coarse_grain", 1.0, 1.0, kMostCoarseGrain); }

/// A box {min: [x,y,z], max: [x,y,z]} under `key` of `map`.
void read_box(MapReader& map, const std::string& key, const std::string& file, Vec3& lo, Vec3& hi) {
  const YAML::Node node = map.node(key);
  if (!node) map.fail(key, "missing: the box {min: [x,y,z], max: [x,y,z]}");
  MapReader box(node, file, map.key_path(key));
  lo = box.vec3("min", Vec3::Zero());
  hi = box.vec3("max", Vec3::Zero());
  if (!(hi.array() > lo.array()).all()) box.fail("max", "each component must exceed min");
  box.finish();
}

/// What a stream profile's `bins` key is, for the messages that refuse it where it does not belong.
std::string bins_help() {
  return fmt::format("valid: bins in a box sensor, `box: {{min, max, across, bins: N, along: [x, y, z]}}`, N a whole number from 0 "
                     "(none) to {} lateral bins along `across`", kMostSensorBins);
}

/// A box sensor's stream profile: `bins` lateral bins along `across` (0: none) and the flow
/// direction `along`, by default across x up (the horizontal perpendicular to a horizontal
/// `across`; [1, 0, 0] when `across` is vertical, where bins then need `along` given).
void read_profile_bins(MapReader& box, SensorSpec& s) {
  s.bins = static_cast<int>(box.integer("bins", 0, 0, kMostSensorBins));
  const Vec3 level = s.across.normalized().cross(Vec3(0, 0, 1));
  const bool horizontal = level.norm() > 1e-6;
  s.along = box.vec3("along", horizontal ? Vec3(level.normalized()) : Vec3(1, 0, 0));
  if (s.along.norm() < 1e-12) box.fail("along", "must not be zero; give the unit direction of the flow, e.g. [1, 0, 0]");
  if (std::abs(s.along.normalized().dot(s.across.normalized())) > 0.01)
    box.fail("along", "must be perpendicular to `across` (the bins lie along `across`, the flow crosses them along `along`)");
  if (s.bins > 0 && !horizontal && !box.has("along"))
    box.fail("bins", "need `along` here: `across` is vertical, so no horizontal flow direction follows from it; give `along: [x, y, z]`");
}

}  // namespace

namespace spec_reading {

ClumpTemplateSpec read_clump(const std::string& name, const YAML::Node& node, const std::string& file, const std::string& path) {
  MapReader map(node, file, path);
  ClumpTemplateSpec c;
  c.name = name;
  c.location = map.location();
  const YAML::Node spheres = map.node("spheres");
  if (!spheres || !spheres.IsSequence() || spheres.size() == 0)
    map.fail("spheres", "must be a list of {centre: [x,y,z], diameter: D} in the clump's own frame [m]");
  for (size_t k = 0; k < spheres.size(); ++k) {
    MapReader sphere(spheres[k], file, fmt::format("{}.spheres[{}]", path, k));
    c.centres.push_back(sphere.vec3("centre", Vec3::Zero()));
    c.radii.push_back(0.5 * sphere.required_number("diameter", 1e-7, 10, "m"));
    sphere.finish();
  }
  map.finish();
  return c;
}

InletSpec read_inlet(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("inlets[{}]", index));
  InletSpec in;
  in.location = map.location();
  in.name = map.string("name", fmt::format("inlet{}", index));
  in.material = map.required_string("material", "name one of the case's materials");
  in.clump = map.string("clump", "");
  in.diameter = read_diameter(map, file);
  in.port = map.string("port", "");
  const bool tph = map.has("mass_rate_tph"), kgs = map.has("mass_rate_kgs");
  in.count = map.integer("count", 0, 1, 1'000'000'000);
  if (tph && kgs) map.fail("mass_rate_kgs", "give one of mass_rate_tph [t/h] or mass_rate_kgs [kg/s], not both");
  if (!tph && !kgs && in.count == 0)
    map.fail("mass_rate_tph", "missing: give mass_rate_tph [t/h] or mass_rate_kgs [kg/s] (a feed), or `count` alone (fill the "
                              "region at each insertion until that many particles are in)");
  if (tph || kgs)
    in.mass_rate = tph ? map.number("mass_rate_tph", 0, 1e-9, 1e6, "t/h") / 3.6 : map.number("mass_rate_kgs", 0, 1e-12, 1e6, "kg/s");
  if (in.port.empty()) read_box(map, "region", file, in.region_min, in.region_max);
  else if (map.has("region")) map.fail("region", fmt::format("give either `port: {}` (the equipment's feed point) or `region`, not both", in.port));
  in.velocity = map.vec3("velocity", in.velocity);
  in.start = map.number("start", 0.0, 0.0, 1e9, "s");
  in.stop = map.number("stop", 1e300, in.start, 1e300, "s");
  in.interval = map.number("interval", 0.0, 0.0, 1e6, "s");
  in.coarse_grain = read_coarse_grain(map);
  map.finish();
  return in;
}

OutletSpec read_outlet(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("outlets[{}]", index));
  OutletSpec out;
  out.location = map.location();
  out.name = map.string("name", fmt::format("outlet{}", index));
  const YAML::Node region = map.node("region");
  if (region && region.IsScalar()) {
    if (region.as<std::string>() != "domain")
      map.fail("region", fmt::format("'{}' is not a region; give a box {{min: [x,y,z], max: [x,y,z]}} or `domain` (what leaves the "
                                     "domain through any face)", region.as<std::string>()));
    out.domain = true;
  } else {
    read_box(map, "region", file, out.region_min, out.region_max);
  }
  out.spillage = map.boolean("spillage", false);
  map.finish();
  return out;
}

SensorSpec read_sensor(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("sensors[{}]", index));
  SensorSpec s;
  s.location = map.location();
  s.name = map.string("name", fmt::format("sensor{}", index));
  if (map.has("plane") == map.has("box"))
    map.fail("plane", "give exactly one of `plane: {point, normal, thickness}` (a flow plane) or `box: {min, max, across}`");
  if (map.has("bins"))
    map.fail("bins", fmt::format("{}; {}", map.has("box") ? "belongs inside `box:`" : "a plane sensor has no bins", bins_help()));
  if (const YAML::Node plane = map.node("plane")) {
    s.kind = SensorSpec::Kind::plane;
    MapReader p(plane, file, map.key_path("plane"));
    if (p.has("bins")) p.fail("bins", fmt::format("a plane sensor has no bins (it measures the flow through a plane); {}", bins_help()));
    s.point = p.vec3("point", Vec3::Zero());
    s.normal = p.vec3("normal", Vec3(1, 0, 0));
    if (s.normal.norm() < 1e-12) p.fail("normal", "must not be zero");
    s.thickness = p.number("thickness", 0.0, 0.0, 100.0, "m");
    p.finish();
    read_box(map, "region", file, s.region_min, s.region_max);
  } else {
    s.kind = SensorSpec::Kind::box;
    MapReader b(map.node("box"), file, map.key_path("box"));
    s.region_min = b.vec3("min", Vec3::Zero());
    s.region_max = b.vec3("max", Vec3::Zero());
    if (!(s.region_max.array() > s.region_min.array()).all()) b.fail("max", "each component must exceed min");
    s.across = b.vec3("across", s.across);
    if (s.across.norm() < 1e-12) b.fail("across", "must not be zero");
    read_profile_bins(b, s);
    b.finish();
  }
  map.finish();
  return s;
}

ParticleSetSpec read_particles(const YAML::Node& node, const std::string& file, size_t index) {
  MapReader map(node, file, fmt::format("particles[{}]", index));
  ParticleSetSpec p;
  p.location = map.location();
  p.material = map.required_string("material", "name one of the case's materials");
  p.clump = map.string("clump", "");
  p.diameter = read_diameter(map, file);
  p.velocity = map.vec3("velocity", p.velocity);
  p.angular_velocity = map.vec3("angular_velocity", p.angular_velocity);
  p.attach_to = map.string("attach_to", "");
  p.coarse_grain = read_coarse_grain(map);
  const YAML::Node positions = map.node("positions");
  if (positions) {
    if (!positions.IsSequence() || positions.size() == 0) map.fail("positions", "must be a list of [x, y, z] centres");
    for (const auto& item : positions) {
      if (!item.IsSequence() || item.size() != 3) map.fail("positions", "each entry must be [x, y, z]");
      p.positions.emplace_back(MapReader::finite_number(item[0], map, "positions"),
                               MapReader::finite_number(item[1], map, "positions"),
                               MapReader::finite_number(item[2], map, "positions"));
    }
    p.count = static_cast<int64_t>(p.positions.size());
  } else {
    p.count = map.integer("count", 0, 1, 100'000'000);
    if (p.count == 0) map.fail("count", "missing: give `count` with a `region`, or explicit `positions`");
    read_box(map, "region", file, p.region_min, p.region_max);
  }
  map.finish();
  return p;
}

}  // namespace spec_reading

double SizeDistributionSpec::largest() const {
  switch (kind) {
    case Kind::fixed: return value;
    case Kind::normal:
    case Kind::uniform: return max;
    case Kind::discrete: return *std::max_element(values.begin(), values.end());
  }
  return value;
}

double SizeDistributionSpec::smallest() const {
  switch (kind) {
    case Kind::fixed: return value;
    case Kind::normal:
    case Kind::uniform: return min;
    case Kind::discrete: return *std::min_element(values.begin(), values.end());
  }
  return value;
}

SizeDistributionSpec read_size_distribution(MapReader& parent, const std::string& file, const std::string& key) {
  return read_diameter(parent, file, key);
}

}  // namespace dem
