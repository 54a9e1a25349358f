// Belt loading against CEMA capacity: the load cross-section of a belt on three equal-length
// troughing rolls, the capacity at the belt's speed and the material's bulk density, and the run's
// throughput onto each receiving belt against it (belt_capacity.h). The belt's width, troughing
// and speed come from the generator's design values, else from the belt mesh; the material's bulk
// density from the design values, its calibration's measurements or its library file's source,
// else 0.6 of its solid density, assumed.
#include "report/belt_capacity.h"

#include <fmt/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <optional>
#include <regex>
#include <system_error>

#include "case/spec.h"
#include "core/model.h"
#include "lab/measurements.h"
#include "model/library.h"
#include "output/run.h"
#include "pages/html.h"
#include "report/report_analysis.h"

namespace dem::report {
namespace {

namespace fs = std::filesystem;
using html::num;
using Design = std::vector<std::pair<std::string, double>>;

constexpr double kInch = 0.0254;                      // [m]
constexpr double kDegree = std::numbers::pi / 180.0;  // [rad]
constexpr double kTonnesPerHourPerKgPerSecond = 3.6;  // 1 kg/s = 3600 kg/h = 3.6 t/h
/// [-] Bulk over solid density assumed when nothing better is known: a loose packing of angular
/// particles (about 40 % voids).
constexpr double kAssumedPacking = 0.6;
/// [deg] A face of the belt mesh sloping more than this across the travel is not a troughing roll
/// (CEMA's deepest three-roll troughs are 45 deg): an edge or a skirt seal, left out.
constexpr double kSteepestWing = 60.0;

// ---- design values ---------------------------------------------------------------------------

/// The design value named exactly `name`, or NaN.
double design_exact(const Design& design, const std::string& name) {
  for (const auto& [n, value] : design)
    if (n == name) return value;
  return kNaN;
}

bool ends_with(const std::string& text, const std::string& tail) {
  return text.size() >= tail.size() && text.compare(text.size() - tail.size(), tail.size(), tail) == 0;
}

/// How many belts the design values give a speed of (names ending in belt_speed_m_s).
std::size_t belts_with_speed(const Design& design) {
  return static_cast<std::size_t>(std::count_if(design.begin(), design.end(), [](const auto& d) { return ends_with(d.first, "belt_speed_m_s"); }));
}

/// The belt's name from its speed's design value: "receiving_belt" from "receiving_belt_speed_m_s".
std::string belt_label(const std::string& speed_key) {
  const std::string tail = "_speed_m_s";
  return ends_with(speed_key, tail) ? speed_key.substr(0, speed_key.size() - tail.size()) : speed_key;
}

// ---- the belt mesh ----------------------------------------------------------------------------

/// Axis-aligned bounds [m] of a mesh at its pose at t = 0.
struct Bounds {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  bool contains(const Eigen::Vector3d& p, double margin) const {
    return (p.array() >= lo.array() - margin).all() && (p.array() <= hi.array() + margin).all();
  }
};

Bounds mesh_bounds(const MeshWall& mesh) {
  Bounds b;
  const Pose pose = mesh.motion.pose(0.0);
  for (const auto& v : mesh.surface->vertices) {
    const Eigen::Vector3d p = pose.rotation * Eigen::Vector3d(v[0], v[1], v[2]) + pose.translation;
    b.lo = b.lo.cwiseMin(p), b.hi = b.hi.cwiseMax(p);
  }
  return b;
}

bool is_belt(const MeshWall& mesh) {
  return mesh.surface && mesh.surface_velocity.kind == SurfaceVelocitySpec::Kind::linear && mesh.surface_velocity.velocity.norm() > 0;
}

/// The belt mesh called `label`, else a belt mesh whose bounds reach into the box sensor's region;
/// nullptr when neither exists.
const MeshWall* belt_mesh(const Model& model, const std::string& label, const SensorSpec* box) {
  for (const MeshWall& m : model.meshes)
    if (m.name == label && is_belt(m)) return &m;
  if (!box) return nullptr;
  for (const MeshWall& m : model.meshes) {
    if (!is_belt(m)) continue;
    const Bounds b = mesh_bounds(m);
    if ((b.lo.array() <= box->region_max.array()).all() && (b.hi.array() >= box->region_min.array()).all()) return &m;
  }
  return nullptr;
}

/// The belt as its mesh gives it: the steepest slope of its surface across the travel [deg] (the
/// wing rolls' troughing angle; flat: 0) and its width [m], its area over its length along the
/// travel (a troughed profile keeps its width along the surface).
struct MeshBelt {
  double troughing = kNaN, width = kNaN;
};

MeshBelt measure_belt(const MeshWall& mesh, const Eigen::Vector3d& up) {
  const Eigen::Vector3d travel = mesh.surface_velocity.velocity.normalized();
  Eigen::Vector3d belt_up = up - up.dot(travel) * travel;  // square to the travel: an inclined belt's normal
  if (belt_up.norm() < 1e-9) return {};
  belt_up.normalize();
  const Eigen::Vector3d across = travel.cross(belt_up);
  const Pose pose = mesh.motion.pose(0.0);
  const TriangleSurface& surface = *mesh.surface;
  double slope = 0, area = 0, first = std::numeric_limits<double>::infinity(), last = -first;
  for (const auto& v : surface.vertices) {
    const double along = (pose.rotation * Eigen::Vector3d(v[0], v[1], v[2]) + pose.translation).dot(travel);
    first = std::min(first, along), last = std::max(last, along);
  }
  for (std::size_t t = 0; t < surface.size() && t < surface.normals.size(); ++t) {
    area += surface.areas[t];
    const Eigen::Vector3d n = pose.rotation * Eigen::Vector3d(surface.normals[t][0], surface.normals[t][1], surface.normals[t][2]);
    const double tilt = std::atan2(std::abs(n.dot(across)), std::abs(n.dot(belt_up))) / kDegree;  // [deg]
    if (tilt < kSteepestWing) slope = std::max(slope, tilt);
  }
  return {slope, last > first ? area / (last - first) : kNaN};
}

// ---- the material on the belt -------------------------------------------------------------------

/// The material the inlets feed (the inlet of the largest mass rate), else the first particle
/// set's; -1 without either.
int fed_material(const Model& model) {
  const Inlet* fed = nullptr;
  for (const Inlet& inlet : model.inlets)
    if (!fed || inlet.spec.mass_rate > fed->spec.mass_rate) fed = &inlet;
  if (fed) return fed->material;
  return model.sources.empty() ? -1 : model.sources.front().material;
}

/// The case's entry of material `name` as its text reads (library file, sources, calibration);
/// none when the report has no case text or the text does not read.
std::optional<MaterialSpec> material_spec(const RunReportInput& in, const std::string& name) {
  if (in.case_text.empty()) return std::nullopt;
  try {
    const CaseSpec spec = parse_case_text(in.case_text, in.case_path.empty() ? std::string("<report>") : in.case_path, materials::library_lookup());
    for (const MaterialSpec& m : spec.materials)
      if (m.name == name) return m;
  } catch (const std::exception&) {
    // A case that no longer reads (edited after the run): the report goes on without it.
  }
  return std::nullopt;
}

/// The measurement file a calibrated material was fitted to, as its record names it: from the
/// working directory, beside the material file, or one folder up (the repository of a shipped
/// material); "" when none exists.
std::string measurement_file(const MaterialSpec& m) {
  const fs::path given = m.calibration->measurements;
  std::vector<fs::path> candidates{given};
  if (!m.library_file.empty()) {
    const fs::path folder = fs::path(m.library_file).parent_path();
    candidates.push_back(folder / given), candidates.push_back(folder.parent_path() / given);
  }
  for (const fs::path& p : candidates) {
    std::error_code error;
    if (!given.empty() && fs::is_regular_file(p, error)) return p.string();
  }
  return "";
}

/// Mean of `observable` over the experiments of `test` that report no outcome (a heap that did
/// not form reports one); NaN without any.
double mean_observed(const materials::MeasurementSet& set, const std::string& test, const std::string& observable) {
  double sum = 0;
  int count = 0;
  for (const materials::Experiment& e : set.experiments) {
    const auto it = e.observed.find(observable);
    if (e.setup.test != test || !e.outcome.empty() || it == e.observed.end()) continue;
    sum += it->second.value, ++count;
  }
  return count ? sum / count : kNaN;
}

/// A calibrated material's measured poured bulk density and angle of repose, from the
/// measurement file of its calibration.
void measured_facts(const MaterialSpec& spec, MaterialFacts& facts) {
  const std::string file = measurement_file(spec);
  if (file.empty()) return;
  try {
    const materials::MeasurementSet set = materials::read_measurements(file);
    const double bulk = mean_observed(set, "bulk_density", "bulk_density");
    if (!std::isnan(bulk)) facts.bulk_density = bulk, facts.bulk_source = fmt::format("measured: the poured bulk density tests of {}", file);
    facts.repose = mean_observed(set, "angle_of_repose_cylinder", "angle_deg");
    if (!std::isnan(facts.repose)) facts.repose_source = fmt::format("the angle of repose measured in {}", file);
  } catch (const std::exception&) {
    // A measurement file that no longer reads: the material's other statements stand.
  }
}

}  // namespace

// The fed material's bulk density: a design value bulk_density_kg_m3, else measured for its
// calibration, else stated in its library file's source of `density`, else kAssumedPacking x its
// solid density (assumed); and its measured angle of repose.
MaterialFacts material_facts(const RunReportInput& in) {
  const Model& model = *in.model;
  MaterialFacts facts;
  const int k = fed_material(model);
  if (k < 0 || k >= model.n_materials()) return facts;
  facts.name = model.materials[k].name;
  const std::optional<MaterialSpec> spec = material_spec(in, facts.name);
  if (spec && spec->calibration) measured_facts(*spec, facts);
  const double given = design_exact(in.design, "bulk_density_kg_m3");
  if (given > 0) facts.bulk_density = given, facts.bulk_source = "from the design value bulk_density_kg_m3";
  if (std::isnan(facts.bulk_density) && spec && spec->sources.count("density")) {
    facts.bulk_density = stated_bulk_density(spec->sources.at("density"));
    facts.bulk_source = fmt::format("stated in {} (sources.density: \"{}\")", spec->library_file, spec->sources.at("density"));
  }
  if (std::isnan(facts.bulk_density)) {
    const double solid = model.materials[k].density / model.mass_scaling;  // [kg/m^3] the real particles'
    facts.bulk_density = kAssumedPacking * solid, facts.bulk_assumed = true;
    facts.bulk_source = fmt::format("assumed: {} x the solid density {} kg/m^3 (no measured or stated bulk density)", kAssumedPacking, num(solid, 4));
  }
  return facts;
}

namespace {

// ---- one belt -------------------------------------------------------------------------------

/// The belt's width, troughing and surcharge angle with where each comes from; `missing` set
/// when the width or the troughing is unknown.
void belt_geometry(const RunReportInput& in, const MeshWall* mesh, const MaterialFacts& material, BeltCapacity& b) {
  const Eigen::Vector3d gravity(in.model->gravity[0], in.model->gravity[1], in.model->gravity[2]);
  const Eigen::Vector3d up = gravity.norm() > 0 ? Eigen::Vector3d(-gravity.normalized()) : Eigen::Vector3d(0, 0, 1);
  const MeshBelt measured = mesh ? measure_belt(*mesh, up) : MeshBelt{};
  const std::string mesh_name = mesh ? mesh->name : "";
  // Width: the generator's design value, else the mesh.
  if (const double w = design_exact(in.design, b.belt + "_width_m"); w > 0) b.width = w, b.width_source = "design value " + b.belt + "_width_m";
  else if (measured.width > 0) b.width = measured.width, b.width_source = "belt mesh " + mesh_name + " (area / length)";
  // Troughing: the belt's own design value, the only belt's, else the mesh's wing slope.
  const double own = design_exact(in.design, b.belt + "_troughing_angle_deg"), only = design_exact(in.design, "troughing_angle_deg");
  if (own >= 0) b.troughing = own, b.troughing_source = "design value " + b.belt + "_troughing_angle_deg";
  else if (only >= 0 && belts_with_speed(in.design) == 1) b.troughing = only, b.troughing_source = "design value troughing_angle_deg";
  else if (measured.troughing >= 0) b.troughing = measured.troughing, b.troughing_source = "belt mesh " + mesh_name + " (steepest wing slope)";
  // Surcharge: a design value, else the CEMA class of a measured angle of repose, else assumed.
  const double own_surcharge = design_exact(in.design, b.belt + "_surcharge_angle_deg"), surcharge = design_exact(in.design, "surcharge_angle_deg");
  const FlowabilityClass& flow = cema_flowability(material.repose);
  if (own_surcharge >= 0) b.surcharge = own_surcharge, b.surcharge_source = "from the design value " + b.belt + "_surcharge_angle_deg";
  else if (surcharge >= 0) b.surcharge = surcharge, b.surcharge_source = "from the design value surcharge_angle_deg";
  else {
    b.surcharge = flow.surcharge, b.surcharge_assumed = std::isnan(material.repose);
    b.surcharge_source = b.surcharge_assumed
                             ? fmt::format("assumed: CEMA's {} class (angle of repose {}-{} deg); no measured angle of repose", flow.name,
                                           num(flow.repose_min, 2), num(flow.repose_max - 1, 2))
                             : fmt::format("from CEMA's {} class for an angle of repose of {} deg ({})", flow.name, num(material.repose, 3),
                                           material.repose_source);
  }
  if (std::isnan(b.width)) b.missing = fmt::format("no belt width: no design value {}_width_m and no belt mesh under {}", b.belt, b.sensor);
  else if (std::isnan(b.troughing)) b.missing = fmt::format("no troughing angle: no design value {}_troughing_angle_deg and no belt mesh", b.belt);
}

/// The run's flow onto the belt [t/h] over the run's interval: the plane sensor across the belt
/// (its point within 0.5 m of the belt mesh, its normal within 30 deg of the travel) furthest
/// along the travel, which counts what the belt carries away; else the intended outlets'.
const Quantity* belt_flow(const RunReportInput& in, const RunAnalysis& run, const MeshWall* mesh, std::string& source) {
  const Quantity* best = nullptr;
  if (mesh) {
    const Bounds bounds = mesh_bounds(*mesh);
    const Eigen::Vector3d travel = mesh->surface_velocity.velocity.normalized();
    double furthest = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0, plane = 0; k < in.sensors.size(); ++k) {
      const SensorSpec& s = in.sensors[k];
      if (s.kind != SensorSpec::Kind::plane) continue;
      const std::size_t j = plane++;
      if (j >= run.plane_sensors.size() || !bounds.contains(s.point, 0.5) || std::abs(s.normal.normalized().dot(travel)) < std::cos(30 * kDegree)) continue;
      if (s.point.dot(travel) > furthest) furthest = s.point.dot(travel), best = &run.plane_sensors[j], source = "plane sensor " + s.name + " across the belt";
    }
  }
  if (!best && !in.model->outlets.empty() && run.primary.unit == "t/h")
    best = &run.primary, source = "intended outlets' throughput (no plane sensor across the belt)";
  return best;
}

/// The belt under the load box `box`: its CEMA capacity and the run's loading of it.
BeltCapacity belt_capacity(const RunReportInput& in, const RunAnalysis& run, const BoxResult& box, const MaterialFacts& material) {
  BeltCapacity b;
  b.belt = belt_label(box.belt_name), b.sensor = box.name;
  b.speed = box.belt_speed, b.speed_source = "design value " + box.belt_name;
  const auto sensor = std::find_if(in.sensors.begin(), in.sensors.end(), [&](const SensorSpec& s) { return s.name == box.name; });
  const MeshWall* mesh = belt_mesh(*in.model, b.belt, sensor == in.sensors.end() ? nullptr : &*sensor);
  b.material = material.name;
  b.bulk_density = material.bulk_density, b.bulk_density_source = material.bulk_source, b.bulk_density_assumed = material.bulk_assumed;
  belt_geometry(in, mesh, material, b);
  if (!b.missing.empty()) return b;
  b.section = cema_cross_section(b.width, b.troughing, b.surcharge);
  b.capacity = belt_capacity_t_h(b.section.area, b.speed, b.bulk_density);
  // The run's tonnes are the model's: a mass-scaled particle weighs mass_scaling times the real one.
  if (const Quantity* flow = belt_flow(in, run, mesh, b.throughput_source)) {
    const double scaling = in.model->mass_scaling;
    b.throughput = flow->at_run.mean / scaling, b.throughput_error = flow->at_run.std_error / scaling;
    if (scaling != 1) b.throughput_source += fmt::format(", divided by the mass scaling {}", num(scaling, 3));
  }
  if (b.capacity > 0) b.loading = 100 * b.throughput / b.capacity, b.loading_error = 100 * b.throughput_error / b.capacity;
  b.verdict = loading_verdict(b.loading);
  return b;
}

/// `text` as a quoted CSV field (double quotes inside become single quotes).
std::string quoted(std::string text) {
  std::replace(text.begin(), text.end(), '"', '\'');
  return "\"" + text + "\"";
}

}  // namespace

// ---- the CEMA cross-section and capacity --------------------------------------------------------

double cema_edge_distance(double belt_width) { return 0.055 * belt_width + 0.9 * kInch; }

double cema_centre_roll(double belt_width) { return 0.371 * belt_width + 0.25 * kInch; }

BeltCrossSection cema_cross_section(double belt_width, double troughing_deg, double surcharge_deg) {
  BeltCrossSection s;
  // NaN fails every comparison, so NaN inputs land here too.
  if (!(belt_width > 0) || !(troughing_deg >= 0 && troughing_deg <= 90) || !(surcharge_deg >= 0 && surcharge_deg < 90)) {
    s.edge_distance = s.usable_width = s.centre_roll = s.wing_load = s.chord = s.trapezoid = s.surcharge = s.area = kNaN;
    return s;
  }
  const double beta = troughing_deg * kDegree, theta = surcharge_deg * kDegree;  // [rad]
  s.edge_distance = cema_edge_distance(belt_width);
  s.usable_width = std::max(belt_width - 2 * s.edge_distance, 0.0);
  // A belt too narrow for its centre roll carries its load on that roll alone.
  s.centre_roll = std::min(cema_centre_roll(belt_width), s.usable_width);
  s.wing_load = 0.5 * (s.usable_width - s.centre_roll);
  // Below the load's edges: the trapezoid of the centre roll and the two loaded wings.
  s.chord = s.centre_roll + 2 * s.wing_load * std::cos(beta);
  s.trapezoid = (s.centre_roll + s.wing_load * std::cos(beta)) * s.wing_load * std::sin(beta);
  // Above them: the circular segment on the chord whose arc meets the edges at theta, radius
  // r = chord / (2 sin theta) over a central angle 2 theta, area r^2 (theta - sin theta cos theta).
  const double sine = std::sin(theta);
  s.surcharge = sine > 1e-12 ? s.chord * s.chord * (theta - sine * std::cos(theta)) / (4 * sine * sine) : 0.0;
  s.area = s.trapezoid + s.surcharge;
  return s;
}

double stated_bulk_density(const std::string& text) {
  // "bulk", then the first number or range of numbers with a unit of density.
  static const std::regex pattern(R"(bulk[^0-9]*?([0-9]+(?:\.[0-9]+)?)(?:\s*-\s*([0-9]+(?:\.[0-9]+)?))?\s*(t/m\^?3|g/cm\^?3|kg/m\^?3))",
                                  std::regex::icase);
  std::smatch m;
  if (!std::regex_search(text, m, pattern)) return kNaN;
  const double low = std::stod(m[1].str()), high = m[2].matched ? std::stod(m[2].str()) : low;
  const double scale = (m[3].str()[0] == 'k' || m[3].str()[0] == 'K') ? 1.0 : 1000.0;  // t/m^3 = g/cm^3 = 1000 kg/m^3
  return 0.5 * (low + high) * scale;
}

double belt_capacity_t_h(double area, double speed, double bulk_density) {
  // A [m^2] v [m/s] rho [kg/m^3] is a mass flow in kg/s.
  return area * speed * bulk_density * kTonnesPerHourPerKgPerSecond;
}

LoadingVerdict loading_verdict(double loading_percent) {
  if (std::isnan(loading_percent)) return LoadingVerdict::unknown;
  if (loading_percent <= 80) return LoadingVerdict::fine;
  if (loading_percent <= 100) return LoadingVerdict::near_full;
  return LoadingVerdict::overloaded;
}

const char* loading_verdict_text(LoadingVerdict verdict) {
  switch (verdict) {
    case LoadingVerdict::fine: return "fine";
    case LoadingVerdict::near_full: return "near full";
    case LoadingVerdict::overloaded: return "overloaded: spillage expected";
    case LoadingVerdict::unknown: break;
  }
  return "unknown";
}

const std::vector<FlowabilityClass>& cema_flowability_classes() {
  // Angle of repose [deg] from, to (excluded), and the surcharge angle [deg] CEMA gives the class.
  static const std::vector<FlowabilityClass> classes = {
      {"very free flowing", 0, 20, 5},
      {"free flowing", 20, 30, 10},
      {"average flowing", 30, 35, 20},
      {"sluggish", 35, 40, 25},
      {"sluggish, angle of repose 40 deg and up", 40, 90, 30},
  };
  return classes;
}

const FlowabilityClass& cema_flowability(double repose_deg) {
  const std::vector<FlowabilityClass>& classes = cema_flowability_classes();
  if (std::isnan(repose_deg)) return classes[2];
  if (repose_deg >= classes.back().repose_min) return classes.back();
  for (const FlowabilityClass& c : classes)
    if (repose_deg < c.repose_max) return c;
  return classes.back();
}

// ---- the report's belts -----------------------------------------------------------------------

void find_belt_capacities(const RunReportInput& in, RunAnalysis& run) {
  bool any = false;
  for (const BoxResult& box : run.boxes) any = any || (box.belt_speed > 0);
  if (!any) return;
  const MaterialFacts material = material_facts(in);
  for (const BoxResult& box : run.boxes) {
    if (!(box.belt_speed > 0)) continue;
    // One row per belt: a second load box on the same belt adds nothing to its capacity.
    const std::string label = belt_label(box.belt_name);
    if (std::any_of(run.belts.begin(), run.belts.end(), [&](const BeltCapacity& b) { return b.belt == label; })) continue;
    run.belts.push_back(belt_capacity(in, run, box, material));
  }
}

void add_belt_capacity_metrics(RunAnalysis& run) {
  for (const BeltCapacity& b : run.belts) {
    if (!b.missing.empty()) continue;
    run.metrics.values.emplace_back(key("belt_capacity_" + b.belt + "_t_h"), b.capacity);
    if (!std::isnan(b.loading)) run.metrics.values.emplace_back(key("belt_loading_" + b.belt + "_percent"), b.loading);
  }
}

void write_belt_capacity_csv(const RunAnalysis& run, const std::string& report_dir) {
  std::string csv =
      "belt,sensor,width_m,width_source,troughing_deg,troughing_source,surcharge_deg,surcharge_source,surcharge_assumed,material,"
      "bulk_density_kg_m3,bulk_density_source,bulk_density_assumed,speed_m_s,edge_distance_m,centre_roll_m,area_m2,capacity_t_h,"
      "throughput_t_h,throughput_std_error_t_h,throughput_source,loading_percent,loading_std_error_percent,verdict\n";
  bool rows = false;
  for (const BeltCapacity& b : run.belts) {
    if (!b.missing.empty()) continue;
    rows = true;
    csv += fmt::format("{},{},{:.6g},{},{:.6g},{},{:.6g},{},{},{},{:.6g},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{},{:.6g},{:.6g},{}\n",
                       quoted(b.belt), quoted(b.sensor), b.width, quoted(b.width_source), b.troughing, quoted(b.troughing_source), b.surcharge,
                       quoted(b.surcharge_source), b.surcharge_assumed ? 1 : 0, quoted(b.material), b.bulk_density, quoted(b.bulk_density_source),
                       b.bulk_density_assumed ? 1 : 0, b.speed, b.section.edge_distance, b.section.centre_roll, b.section.area, b.capacity,
                       b.throughput, b.throughput_error, quoted(b.throughput_source), b.loading, b.loading_error,
                       quoted(loading_verdict_text(b.verdict)));
  }
  if (rows) write_file_atomically((fs::path(report_dir) / "belt_capacity.csv").string(), csv);
}

}  // namespace dem::report
