// The numbers of the run report: each series with its steady state and its average over the
// run's interval, the mass balance, spillage and blockage, the drives and the loads, wear per triangle,
// belt loading and the metrics; and the report's tables (steady_state.csv, mesh_loads.csv,
// drives.csv, wear_hotspots.csv, wear_life.csv, metrics.csv). report.cpp draws the plots and
// writes report.html. The liner life (depth rates, months, mm/Mt) is report_wear.cpp's; the
// receiving belts against their CEMA capacity (belt_capacity.csv) are belt_capacity.cpp's.
#include "report/report_analysis.h"

#include <fmt/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <stdexcept>

#include "pages/html.h"
#include "output/run.h"

namespace dem::report {
namespace {

namespace fs = std::filesystem;
using html::num;
constexpr double kTonnesPerHourPerKgPerSecond = 3.6;

/// Design value whose name contains all of `parts`; NaN when none.
std::pair<std::string, double> design_value(const std::vector<std::pair<std::string, double>>& design,
                                            std::initializer_list<const char*> parts) {
  for (const auto& [name, value] : design) {
    bool all = true;
    for (const char* p : parts) all = all && name.find(p) != std::string::npos;
    if (all) return {name, value};
  }
  return {"", kNaN};
}

/// Belt speed [m/s] for a box sensor: the design value "<prefix>belt_speed_m_s" whose prefix
/// appears in the sensor's name, else the only one, else the receiving belt's.
std::pair<std::string, double> belt_speed_for(const std::vector<std::pair<std::string, double>>& design,
                                              const std::string& sensor) {
  std::vector<std::pair<std::string, double>> belts;
  const std::string suffix = "belt_speed_m_s";
  for (const auto& d : design)
    if (d.first.size() >= suffix.size() && d.first.compare(d.first.size() - suffix.size(), suffix.size(), suffix) == 0)
      belts.push_back(d);
  for (const auto& b : belts) {
    std::string prefix = b.first.substr(0, b.first.size() - suffix.size());
    while (!prefix.empty() && prefix.back() == '_') prefix.pop_back();
    if (!prefix.empty() && sensor.find(prefix) != std::string::npos) return b;
  }
  if (belts.size() == 1) return belts[0];
  for (const auto& b : belts)
    if (b.first.find("receiving") != std::string::npos) return b;
  return {"", kNaN};
}

/// Mean of y over [t0, t1] with each row weighted by w (a velocity by the mass flux that carries
/// it: a row with nothing in the sensor's slab counts for nothing), its weighted standard
/// deviation, and the standard error from the weighted means of 10 consecutive batches.
IntervalStats weighted_over(const std::vector<double>& t, const std::vector<double>& y, const std::vector<double>& w, double t0, double t1) {
  IntervalStats s;
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (t[i] >= t0 && t[i] <= t1 && w[i] > 0) rows.push_back(i);
  double sw = 0, swy = 0;
  for (std::size_t i : rows) sw += w[i], swy += w[i] * y[i];
  s.samples = rows.size();
  if (sw <= 0) return s;
  s.mean = swy / sw;
  double sd = 0;
  for (std::size_t i : rows) sd += w[i] * (y[i] - s.mean) * (y[i] - s.mean);
  s.std_dev = std::sqrt(sd / sw);
  const std::size_t batches = std::min<std::size_t>(10, rows.size());
  std::vector<double> means;
  for (std::size_t b = 0; b < batches; ++b) {
    double bw = 0, bwy = 0;
    for (std::size_t k = rows.size() * b / batches; k < rows.size() * (b + 1) / batches; ++k) bw += w[rows[k]], bwy += w[rows[k]] * y[rows[k]];
    if (bw > 0) means.push_back(bwy / bw);
  }
  double spread = 0;
  for (double m : means) spread += (m - s.mean) * (m - s.mean);
  s.std_error = means.size() >= 2 ? std::sqrt(spread / double(means.size() - 1) / double(means.size())) : s.std_dev;
  return s;
}

// ---- the phases of analyse_run --------------------------------------------------------------

/// What the phases of analyse_run share besides the RunAnalysis they fill: the input, its model,
/// final state and rows, and what one phase finds for a later one that RunAnalysis does not keep.
struct AnalysisInput {
  const RunReportInput& in;
  const Model& model;
  const State& state;
  const std::vector<Scalars>& rows;
  std::vector<double> intended_cumulative;          ///< [kg] per row, out of the intended outlets
  std::vector<double> out_cumulative;               ///< [kg] per row, removed and lost
  std::vector<std::size_t> plane_index, box_index;  ///< the input's sensors of each kind, in order
};

/// A series' own steady state and its average over the run's interval (run.run_t0 to run.run_t1).
void finish_series(const RunAnalysis& run, Quantity& q) {
  q.own = find_steady_state(run.t, q.y);
  q.at_run = average_over(run.t, q.y, run.run_t0, run.run_t1);
}

/// The rows, their times, the end of the run and its last row.
void time_axis(const AnalysisInput& input, RunAnalysis& run) {
  const std::vector<Scalars>& rows = input.rows;
  run.rows = &rows;
  const std::vector<double>& t = run.t = column(rows, [](const Scalars& r) { return r.time; });
  run.t_end = t.empty() ? input.state.time : t.back();
  run.last = rows.empty() ? Scalars{} : rows.back();
}

// ---- outlets, intended or not ----------------------------------------------------------

/// Which outlets material is meant to leave by, each outlet's flow [t/h], and the mass out of
/// the intended ones per row.
void outlet_flows(AnalysisInput& input, RunAnalysis& run) {
  const RunReportInput& in = input.in;
  const Model& model = input.model;
  const std::vector<Scalars>& rows = input.rows;
  std::vector<bool>& intended = run.intended;
  intended.assign(model.outlets.size(), true);
  if (!in.outlet_intended.empty())
    for (std::size_t k = 0; k < model.outlets.size(); ++k)
      intended[k] = std::find(in.outlet_intended.begin(), in.outlet_intended.end(), model.outlets[k].name) !=
                    in.outlet_intended.end();
  std::vector<Quantity>& outlets = run.outlets;
  std::vector<double>& intended_cumulative = input.intended_cumulative;
  intended_cumulative.assign(rows.size(), 0.0);
  for (std::size_t k = 0; k < model.outlets.size(); ++k) {
    const std::vector<double> cumulative = column(rows, [k](const Scalars& r) { return at(r.outlet_mass, k); });
    if (intended[k])
      for (std::size_t i = 0; i < rows.size(); ++i) intended_cumulative[i] += cumulative[i];
    Quantity q{"outlet " + model.outlets[k].name, "t/h", rate_of(run.t, cumulative), {}, {}};
    for (double& v : q.y) v *= kTonnesPerHourPerKgPerSecond;
    outlets.push_back(std::move(q));
  }
}

/// Each plane sensor's flow [t/h]; the input's sensors sorted into plane and box sensors.
void plane_sensor_flows(AnalysisInput& input, RunAnalysis& run) {
  const RunReportInput& in = input.in;
  std::vector<Quantity>& plane_sensors = run.plane_sensors;
  for (std::size_t k = 0; k < in.sensors.size(); ++k) {
    if (in.sensors[k].kind == SensorSpec::Kind::plane) {
      Quantity q{"sensor " + in.sensors[k].name, "t/h",
                 column(input.rows, [k](const Scalars& r) { return k < r.sensors.size() ? r.sensors[k].flow * 3.6 : 0.0; }), {}, {}};
      plane_sensors.push_back(std::move(q));
      input.plane_index.push_back(k);
    } else {
      input.box_index.push_back(k);
    }
  }
}

// ---- the series that defines the run's steady state -------------------------------------

/// The throughput of the intended outlets, else the flow through the plane sensors, else the
/// kinetic energy; with its own steady state.
void primary_series(const AnalysisInput& input, RunAnalysis& run) {
  const std::vector<Scalars>& rows = input.rows;
  const std::vector<double>& t = run.t;
  const std::vector<Quantity>& plane_sensors = run.plane_sensors;
  Quantity& primary = run.primary;
  if (!input.model.outlets.empty()) {
    primary = {"throughput (intended outlets)", "t/h", rate_of(t, input.intended_cumulative), {}, {}};
    for (double& v : primary.y) v *= kTonnesPerHourPerKgPerSecond;
  } else if (!plane_sensors.empty()) {
    primary = {"flow through the plane sensors", "t/h", std::vector<double>(rows.size(), 0.0), {}, {}};
    for (const Quantity& q : plane_sensors)
      for (std::size_t i = 0; i < rows.size(); ++i) primary.y[i] += q.y[i];
  } else {
    primary = {"kinetic energy", "J", column(rows, [](const Scalars& r) { return r.kinetic_translation + r.kinetic_rotation; }), {}, {}};
  }
  primary.own = find_steady_state(t, primary.y);
}

// ---- mass balance ---------------------------------------------------------------------------

/// Inserted, removed, lost and held-up mass per row [kg], and what left (removed and lost).
void mass_balance(AnalysisInput& input, RunAnalysis& run) {
  const std::vector<Scalars>& rows = input.rows;
  const std::vector<double>& inserted = run.inserted = column(rows, [](const Scalars& r) { return r.inserted_mass; });
  const std::vector<double>& removed = run.removed = column(rows, [](const Scalars& r) { return r.removed_mass; });
  const std::vector<double>& lost = run.lost = column(rows, [](const Scalars& r) { return r.lost_mass; });
  std::vector<double>& holdup = run.holdup;
  holdup.resize(rows.size());
  std::vector<double>& out_cumulative = input.out_cumulative;
  out_cumulative.resize(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i)
    holdup[i] = inserted[i] - removed[i] - lost[i], out_cumulative[i] = removed[i] + lost[i];
}

/// Takes back the primary series' steady state while the hold-up still changes.
void check_still_filling(const AnalysisInput& input, RunAnalysis& run) {
  const std::vector<double>& t = run.t;
  const double t_end = run.t_end;
  Quantity& primary = run.primary;
  // A steady outflow is not a steady state while the plant is still filling (or emptying): the
  // hold-up must not change by more than 5 % of the mass that passed over the interval.
  if (primary.own.found && !input.model.outlets.empty() && primary.own.first + 2 < t.size()) {
    const Trend fill = trend_of(t, run.holdup, primary.own.first, t.size());
    const double duration = t_end - primary.own.t_start;
    const double change = fill.slope * duration, passed = primary.own.mean / kTonnesPerHourPerKgPerSecond * duration;
    if (std::abs(fill.t_stat) > 3 && std::abs(change) > 0.05 * std::max(passed, 1e-12)) {
      primary.own.found = false;
      const std::string share = passed > 1e-9 ? fmt::format("{} % of the {} kg that left", num(100 * std::abs(change) / passed), num(passed))
                                              : std::string("while nothing has left yet");
      primary.own.why = fmt::format("still {}: the hold-up {} by {} kg from {} s to {} s, {}; run longer",
                                    change > 0 ? "filling" : "emptying", change > 0 ? "rose" : "fell", num(std::abs(change)),
                                    num(primary.own.t_start, 3), num(t_end, 3), share);
    }
  }
}

/// Whether the run is steady, the interval the averages are taken over, and their words.
void run_interval(RunAnalysis& run) {
  const std::vector<double>& t = run.t;
  const double t_end = run.t_end;
  const Quantity& primary = run.primary;
  const bool steady = run.steady = primary.own.found;
  // Not steady: averages over the last third are given for information, marked as such.
  const double run_t0 = run.run_t0 = steady ? primary.own.t_start : (t.empty() ? 0.0 : t_end - (t_end - t.front()) / 3.0);
  const double run_t1 = run.run_t1 = t_end;
  run.interval_text = fmt::format("{} s to {} s", num(run_t0, 3), num(run_t1, 3));
  RunMetrics& metrics = run.metrics;
  metrics.steady = steady;
  metrics.steady_text = steady ? fmt::format("steady from {} s to {} s ({})", num(run_t0, 3), num(run_t1, 3), primary.name)
                               : fmt::format("no steady state ({}): {}", primary.name, primary.own.why);
}

/// The flows' own steady states and their averages over the run's interval.
void flow_statistics(RunAnalysis& run) {
  finish_series(run, run.primary);
  for (Quantity& q : run.outlets) finish_series(run, q);
  for (Quantity& q : run.plane_sensors) finish_series(run, q);
}

/// Plane sensor k's reading `field` as a series (appended to run.plane_detail, finished).
void add_plane_series(const AnalysisInput& input, RunAnalysis& run, std::size_t k, const char* what, const char* unit,
                      double SensorReading::*field) {
  const std::string& name = input.in.sensors[k].name;
  Quantity q{fmt::format("sensor {} {}", name, what), unit,
             column(input.rows, [k, field](const Scalars& r) { return k < r.sensors.size() ? r.sensors[k].*field : 0.0; }), {}, {}};
  finish_series(run, q);
  run.plane_detail.push_back(std::move(q));
}

/// Per plane sensor: the particles through it and the velocity of what crosses it.
void plane_sensor_detail(const AnalysisInput& input, RunAnalysis& run) {
  for (std::size_t j = 0; j < input.plane_index.size(); ++j) {
    const std::size_t k = input.plane_index[j];
    add_plane_series(input, run, k, "particles through", "1/s", &SensorReading::count_flow);
    add_plane_series(input, run, k, "velocity x", "m/s", &SensorReading::vx);
    add_plane_series(input, run, k, "velocity y", "m/s", &SensorReading::vy);
    add_plane_series(input, run, k, "velocity z", "m/s", &SensorReading::vz);
    // The velocity of what crosses: rows weighted by the mass flow through the plane.
    std::vector<double> carried = run.plane_sensors[j].y;
    for (double& v : carried) v = std::abs(v);
    for (std::size_t c = run.plane_detail.size() - 3; c < run.plane_detail.size(); ++c)
      run.plane_detail[c].at_run = weighted_over(run.t, run.plane_detail[c].y, carried, run.run_t0, run.run_t1);
  }
}

// ---- spillage, blockage ---------------------------------------------------------------------

/// Blockage from the outflow and the hold-up; spillage: mass lost and mass into outlets not intended.
void spillage_and_blockage(const AnalysisInput& input, RunAnalysis& run) {
  const Scalars& last = run.last;
  const std::vector<double> outflow = rate_of(run.t, input.out_cumulative);
  run.blockage = detect_blockage(run.t, outflow, run.holdup);
  double& spill_outlets = run.spill_outlets = 0;
  for (std::size_t k = 0; k < input.model.outlets.size(); ++k)
    if (!run.intended[k]) spill_outlets += at(last.outlet_mass, k);
  const double spillage = run.spillage = last.lost_mass + spill_outlets;
  run.spillage_pct = last.inserted_mass > 0 ? 100.0 * spillage / last.inserted_mass : 0.0;
}

// ---- design capacity ------------------------------------------------------------------

/// The design capacity [t/h] from the design values, else the inlets' feed rate; NaN without either.
void design_capacity(const AnalysisInput& input, RunAnalysis& run) {
  const Model& model = input.model;
  double& capacity = run.capacity = kNaN;  // [t/h]
  std::string& capacity_label = run.capacity_label;
  std::string& capacity_source = run.capacity_source;
  const auto th = design_value(input.in.design, {"capacity", "_t_h"});
  const auto kgs = design_value(input.in.design, {"capacity", "_kg_s"});
  if (!std::isnan(th.second)) capacity = th.second, capacity_label = "design capacity", capacity_source = th.first;
  else if (!std::isnan(kgs.second)) capacity = kgs.second * 3.6, capacity_label = "design capacity", capacity_source = kgs.first;
  else if (!model.inlets.empty() &&
           std::all_of(model.inlets.begin(), model.inlets.end(), [](const Inlet& inlet) { return inlet.spec.mass_rate > 0; })) {
    capacity = 0;  // an inlet that fills its region (`count` alone) has no rate
    for (const Inlet& inlet : model.inlets) capacity += inlet.spec.mass_rate * 3.6;
    capacity_label = "feed rate of the inlets", capacity_source = "sum of the inlets' mass rates";
  }
}

// ---- loads per mesh and the drives of the moving parts ---------------------------------

/// Per mesh: its power, its drive kind and the six components of its load, each a finished series.
void mesh_loads_and_power(const AnalysisInput& input, RunAnalysis& run) {
  const Model& model = input.model;
  const std::vector<Scalars>& rows = input.rows;
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    run.mesh_kind.push_back(drive_kind(model.meshes[m]));
    run.power.push_back({"power " + model.meshes[m].name, "W", column(rows, [m](const Scalars& r) { return at(r.mesh_power, m); }), {}, {}});
    finish_series(run, run.power.back());
    static constexpr const char* kComponents[6] = {"force x", "force y", "force z", "torque x", "torque y", "torque z"};
    for (int c = 0; c < 6; ++c) {
      const std::string name = fmt::format("{} on {}{}", kComponents[c], model.meshes[m].name, c < 3 ? "" : " about its motion origin");
      run.mesh_load.push_back({name, c < 3 ? "N" : "N m",
                               column(rows, [m, c](const Scalars& r) { return m < r.mesh_load.size() ? r.mesh_load[m][c] : 0.0; }), {}, {}});
      finish_series(run, run.mesh_load.back());
    }
  }
}

/// The belt_loop part that carries `mesh` round its path, or nullptr.
const MotionPart* belt_loop_of(const MeshWall& mesh) {
  for (const MotionPart& part : mesh.motion.parts)
    if (part.kind == MotionPart::Kind::belt_loop) return &part;
  return nullptr;
}

/// Whether two belt_loop parts run on one loop (the same pulleys, radius and speed).
bool same_loop(const MotionPart* a, const MotionPart* b) {
  return a && b && a->lower == b->lower && a->upper == b->upper && a->axis == b->axis && a->radius == b->radius && a->speed == b->speed;
}

/// The moving meshes grouped by drive: each on its own, except the meshes carried round one belt
/// loop (the buckets of an elevator), which one chain drives.
std::vector<std::vector<std::size_t>> drive_groups(const Model& model) {
  std::vector<std::vector<std::size_t>> groups;
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    if (drive_kind(model.meshes[m]) == DriveKind::fixed) continue;
    const MotionPart* loop = belt_loop_of(model.meshes[m]);
    const auto joined = std::find_if(groups.begin(), groups.end(), [&](const std::vector<std::size_t>& g) {
      return same_loop(loop, belt_loop_of(model.meshes[g.front()]));
    });
    if (joined != groups.end())
      joined->push_back(m);
    else
      groups.push_back({m});
  }
  return groups;
}

/// The drive of the meshes `group`: its name, and per row its effort (pull or shaft torque), its
/// power and its check power, each summed over the group and finished as a series.
Drive drive_series(const AnalysisInput& input, const RunAnalysis& run, const std::vector<std::size_t>& group) {
  const Model& model = input.model;
  const std::vector<Scalars>& rows = input.rows;
  Drive d;
  d.meshes = group;
  const MeshWall& first = model.meshes[group.front()];
  d.kind = drive_kind(first);
  d.name = group.size() == 1 ? first.name : fmt::format("{} to {}", first.name, model.meshes[group.back()].name);
  if (group.size() > 1) d.note = fmt::format("{} meshes carried round one belt loop", group.size());
  d.at_end = drive_geometry(first, run.t_end);
  std::vector<double> effort(rows.size(), 0.0), power(rows.size(), 0.0), check(rows.size(), 0.0), speed(rows.size(), 0.0);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    speed[i] = std::abs(drive_geometry(first, rows[i].time).speed);
    for (std::size_t m : group) {
      const std::array<double, 6> load = m < rows[i].mesh_load.size() ? rows[i].mesh_load[m] : std::array<double, 6>{};
      const DriveReading r = drive_reading(drive_geometry(model.meshes[m], rows[i].time), load);
      effort[i] += r.effort, check[i] += r.check_power, power[i] += at(rows[i].mesh_power, m);
    }
  }
  const bool rotating = d.kind == DriveKind::rotating;
  d.effort = {fmt::format("drive {} {}", rotating ? "torque" : "pull", d.name), rotating ? "N m" : "N", std::move(effort), {}, {}};
  d.power = {"drive power " + d.name, "W", std::move(power), {}, {}};
  d.check = {fmt::format("drive {} {}", rotating ? "T omega" : "F v", d.name), "W", std::move(check), {}, {}};
  for (Quantity* q : {&d.effort, &d.power, &d.check}) finish_series(run, *q);
  d.speed = average_over(run.t, speed, run.run_t0, run.run_t1).mean;
  return d;
}

/// The drives of the moving parts (a static mesh has none: it appears in the loads only).
void find_drives(const AnalysisInput& input, RunAnalysis& run) {
  for (const std::vector<std::size_t>& group : drive_groups(input.model)) run.drives.push_back(drive_series(input, run, group));
}

/// drives.csv: per drive its pull or shaft torque, power and check power over the run's interval,
/// with the standard error of each mean (batch means); nothing without a drive.
void write_drives_csv(const RunAnalysis& run, const std::string& report_dir) {
  if (run.drives.empty()) return;
  std::string csv = "drive,kind,quantity,unit,mean,std_error,std_dev,samples,t_start_s,t_end_s\n";
  for (const Drive& d : run.drives) {
    const std::pair<const char*, const Quantity*> rows[3] = {
        {d.kind == DriveKind::rotating ? "shaft_torque" : "pull", &d.effort}, {"power", &d.power}, {"check_power", &d.check}};
    for (const auto& [quantity, q] : rows) {
      const IntervalStats& s = q->at_run;
      csv += fmt::format("\"{}\",{},{},{},{:.6g},{:.6g},{:.6g},{},{:.6g},{:.6g}\n", d.name, key(drive_kind_name(d.kind)), quantity, q->unit,
                         s.mean, s.std_error, s.std_dev, s.samples, run.run_t0, run.run_t1);
    }
  }
  write_file_atomically((fs::path(report_dir) / "drives.csv").string(), csv);
}

/// The run's first arrivals, in the order they happened.
void events_in_order(const AnalysisInput& input, RunAnalysis& run) {
  run.events = input.in.events;
  std::stable_sort(run.events.begin(), run.events.end(), [](const RunEvent& a, const RunEvent& b) { return a.step < b.step; });
}

// ---- wear per triangle and liner life -----------------------------------------------------

/// The throughput [t/h] the wear per million tonnes is taken against: the primary flow (the
/// intended outlets, else the plane sensors) over the run's interval, else the design capacity
/// or the inlets' feed rate; NaN without any.
void find_wear_throughput(RunAnalysis& run) {
  const Quantity& primary = run.primary;
  if (primary.unit == "t/h" && primary.at_run.mean > 0) {
    run.wear_throughput = primary.at_run.mean;
    run.wear_throughput_text = fmt::format("{}, mean over {}{}", primary.name, run.interval_text, run.steady ? "" : " (not steady)");
  } else if (!std::isnan(run.capacity) && run.capacity > 0) {
    run.wear_throughput = run.capacity;
    run.wear_throughput_text = fmt::format("{} ({})", run.capacity_label, run.capacity_source);
  }
}

/// Triangle `tri` of mesh m: its centroid (at the mesh's pose at t = 0), its wear inputs per
/// area over the recording interval [s] and, with a liner, its depth rate by sliding and impact
/// together, also in mm/year at `hours` [h] a year.
Hotspot triangle_wear(const MeshWall& mesh, const Pose& pose, const TriangleRecords& rec, std::size_t m, std::size_t tri,
                      double record_time, const std::optional<Liner>& liner, double hours) {
  const TriangleSurface& surface = *mesh.surface;
  Hotspot h;
  h.mesh = m, h.triangle = tri, h.area = surface.areas[tri];
  Eigen::Vector3d c(0, 0, 0);
  for (int v = 0; v < 3; ++v) {
    const auto& p = surface.vertices[surface.triangles[tri][v]];
    c += Eigen::Vector3d(p[0], p[1], p[2]) / 3.0;
  }
  h.centroid = pose.rotation * c + pose.translation;
  h.shear_rate = rec.shear_work[tri] / (h.area * record_time);
  h.impact_rate = at(rec.impact_energy, tri) / (h.area * record_time);
  h.impacts_rate = at(rec.impacts, tri) / (h.area * record_time);
  if (liner) {
    // Depth rate [m/s] = k_s q_shear + K_i q_impact, coefficients [m^3/J] times powers per area [W/m^2].
    h.wear_rate = total_rate(depth_rate(liner->sliding_coefficient, rec.shear_work[tri], h.area, record_time),
                             depth_rate(liner->impact_coefficient, at(rec.impact_energy, tri), h.area, record_time));
    h.wear_mm_per_year = mm_per_year(h.wear_rate, hours);
  }
  return h;
}

/// Mesh m: its wear totals, its triangles as candidate hot spots, and its liner's worst
/// triangle (the highest depth rate) and mean (its wear spread over its area).
void mesh_wear_and_life(const AnalysisInput& input, RunAnalysis& run, std::size_t m) {
  const MeshWall& mesh = input.model.meshes[m];
  const TriangleRecords& rec = input.state.records[m];
  const double record_time = run.record_time, hours = run.operating_hours;  // [s], [h]
  const std::optional<Liner> liner = liner_of(input.in, mesh.name);
  const Pose pose = mesh.motion.pose(0.0);
  MeshWear& w = run.mesh_wear[m];
  if (liner) w.has_liner = true, w.liner = *liner, w.k = liner->sliding_coefficient;
  std::optional<Hotspot> worst;
  for (std::size_t tri = 0; tri < mesh.surface->size() && tri < rec.shear_work.size(); ++tri) {
    if (mesh.surface->areas[tri] <= 0) continue;
    const Hotspot h = triangle_wear(mesh, pose, rec, m, tri, record_time, liner, hours);
    w.shear_power += rec.shear_work[tri] / record_time;
    w.impact_power += at(rec.impact_energy, tri) / record_time;
    w.area += h.area;
    w.max_shear = std::max(w.max_shear, h.shear_rate);
    w.max_impact = std::max(w.max_impact, h.impact_rate);
    if (!std::isnan(h.wear_rate) && (!worst || h.wear_rate > worst->wear_rate)) worst = h;
    run.spots.push_back(h);
  }
  if (!liner) return;
  const double throughput = run.wear_throughput;  // [t/h]
  if (worst) {
    w.worst = wear_zone(*liner, rec.shear_work[worst->triangle], at(rec.impact_energy, worst->triangle), worst->area, record_time,
                        hours, throughput);
    w.worst.triangle = worst->triangle, w.worst.centroid = worst->centroid;
    w.max_wear = worst->wear_mm_per_year;
  }
  w.mean = wear_zone(*liner, w.shear_power * record_time, w.impact_power * record_time, w.area, record_time, hours, throughput);
}

/// Per mesh its wear totals and its liner's life, and the 10 triangles with the highest shear
/// power per area.
void wear_per_triangle(const AnalysisInput& input, RunAnalysis& run) {
  const RunReportInput& in = input.in;
  const Model& model = input.model;
  const State& state = input.state;
  run.record_time = state.time - in.records_from;  // [s]
  run.operating_hours = in.operating_hours_per_year, run.operating_hours_given = in.operating_hours_given;
  find_wear_throughput(run);
  run.mesh_wear.resize(model.meshes.size());
  if (run.record_time > 0)
    for (std::size_t m = 0; m < model.meshes.size() && m < state.records.size(); ++m) mesh_wear_and_life(input, run, m);
  std::vector<Hotspot>& spots = run.spots;
  std::sort(spots.begin(), spots.end(), [](const Hotspot& a, const Hotspot& b) { return a.shear_rate > b.shear_rate; });
  if (spots.size() > 10) spots.resize(10);
}

// ---- belt loading (box sensors) -------------------------------------------------------

/// Per box sensor: the offset of the load and the mass in the box, and the mean velocity of the
/// material against the belt's speed.
void belt_loading(const AnalysisInput& input, RunAnalysis& run) {
  const RunReportInput& in = input.in;
  const Model& model = input.model;
  const std::vector<Scalars>& rows = input.rows;
  const std::vector<double>& t = run.t;
  const double run_t0 = run.run_t0;
  Eigen::Vector3d up(-model.gravity[0], -model.gravity[1], -model.gravity[2]);
  up = up.norm() > 0 ? Eigen::Vector3d(up.normalized()) : Eigen::Vector3d(0, 0, 1);
  std::vector<BoxResult>& boxes = run.boxes;
  for (std::size_t k : input.box_index) {
    const SensorSpec& s = in.sensors[k];
    BoxResult b;
    b.name = s.name;
    b.offset = {"offset " + s.name, "mm", column(rows, [k](const Scalars& r) { return k < r.sensors.size() ? 1000 * r.sensors[k].offset : 0.0; }), {}, {}};
    b.mass = {"mass in " + s.name, "kg", column(rows, [k](const Scalars& r) { return k < r.sensors.size() ? r.sensors[k].mass : 0.0; }), {}, {}};
    finish_series(run, b.offset);
    finish_series(run, b.mass);
    const Eigen::Vector3d across = s.across.norm() > 0 ? Eigen::Vector3d(s.across.normalized()) : Eigen::Vector3d(0, 1, 0);
    const Eigen::Vector3d extent = s.region_max - s.region_min;
    b.width = std::abs(extent.x() * across.x()) + std::abs(extent.y() * across.y()) + std::abs(extent.z() * across.z());
    // Mean velocity of the material in the box, weighted by the rows where it held material.
    double weight = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (t[i] < run_t0 || k >= rows[i].sensors.size()) continue;
      const SensorReading& r = rows[i].sensors[k];
      if (r.mass <= 0) continue;
      b.velocity += r.mass * Eigen::Vector3d(r.vx, r.vy, r.vz);
      weight += r.mass;
    }
    if (weight > 0) b.velocity /= weight;
    b.vertical = b.velocity.dot(up);
    b.lateral = b.velocity.dot(across);
    b.along = (b.velocity - b.vertical * up - b.lateral * across).norm();
    // The box across a chute's narrowest section (choke.h) lies on no belt.
    if (s.name != kChokeSensor) std::tie(b.belt_name, b.belt_speed) = belt_speed_for(in.design, s.name);
    boxes.push_back(std::move(b));
  }
}

// ---- other series ---------------------------------------------------------------------

/// Kinetic energy, particles, hold-up and contacts, each a finished series.
void other_series(const AnalysisInput& input, RunAnalysis& run) {
  const std::vector<Scalars>& rows = input.rows;
  Quantity& kinetic = run.kinetic = {"kinetic energy", "J", column(rows, [](const Scalars& r) { return r.kinetic_translation + r.kinetic_rotation; }), {}, {}};
  Quantity& particles = run.particles = {"particles", "-", column(rows, [](const Scalars& r) { return double(r.particles); }), {}, {}};
  Quantity& holdup_q = run.holdup_q = {"hold-up (inserted - removed - lost)", "kg", run.holdup, {}, {}};
  Quantity& contacts = run.contacts = {"contacts", "-", column(rows, [](const Scalars& r) { return double(r.contacts); }), {}, {}};
  finish_series(run, kinetic);
  finish_series(run, particles);
  finish_series(run, holdup_q);
  finish_series(run, contacts);
}

// ---- metrics --------------------------------------------------------------------------

/// The run's metrics (metrics.csv), in the order they are written.
void add_metrics(const AnalysisInput& input, RunAnalysis& run) {
  const Model& model = input.model;
  RunMetrics& metrics = run.metrics;
  // A metric that is a mean over the run's records carries its batch-means standard error; 0
  // (a series without samples in the interval, or constant) says nothing of the noise: none.
  const auto metric = [&metrics](const std::string& name, double value, double std_error = kNaN) {
    metrics.values.emplace_back(key(name), value);
    if (std::isfinite(std_error) && std_error > 0) metrics.std_errors[key(name)] = std_error;
  };
  const Quantity& primary = run.primary;
  const std::vector<Quantity>& plane_sensors = run.plane_sensors;
  const std::vector<Quantity>& power = run.power;
  const double capacity = run.capacity;
  const double record_time = run.record_time;

  metric("steady_from_s", run.steady ? run.run_t0 : kNaN);
  if (!model.outlets.empty()) {
    metric("throughput_t_h", primary.at_run.mean, primary.at_run.std_error);
    metric("throughput_std_t_h", primary.at_run.std_dev);
    for (const Quantity& q : run.outlets) metric(key(q.name) + "_t_h", q.at_run.mean, q.at_run.std_error);
  }
  for (const Quantity& q : plane_sensors) metric(key(q.name) + "_t_h", q.at_run.mean, q.at_run.std_error);
  for (std::size_t j = 0; j < plane_sensors.size(); ++j) {
    const double vx = run.plane_detail[4 * j + 1].at_run.mean, vy = run.plane_detail[4 * j + 2].at_run.mean, vz = run.plane_detail[4 * j + 3].at_run.mean;
    metric(key(plane_sensors[j].name) + "_speed_m_s", std::sqrt(vx * vx + vy * vy + vz * vz));
  }
  if (!std::isnan(capacity) && capacity > 0 && !model.outlets.empty()) metric("throughput_of_capacity_pct", 100 * primary.at_run.mean / capacity);
  metric("spillage_kg", run.spillage);
  metric("spillage_pct", run.spillage_pct);
  metric("holdup_kg", run.holdup.empty() ? 0.0 : run.holdup.back());
  metric("blockage", run.blockage.blocked ? 1.0 : 0.0);
  double total_power = 0;
  for (std::size_t m = 0; m < power.size(); ++m) {
    metric("power_" + model.meshes[m].name + "_W", power[m].at_run.mean, power[m].at_run.std_error);
    total_power += power[m].at_run.mean;
    // The magnitude of the mean force, not the mean of the magnitude (which noise inflates).
    const double fx = run.mesh_load[6 * m].at_run.mean, fy = run.mesh_load[6 * m + 1].at_run.mean, fz = run.mesh_load[6 * m + 2].at_run.mean;
    metric("force_" + model.meshes[m].name + "_N", std::sqrt(fx * fx + fy * fy + fz * fz));
  }
  if (!power.empty()) metric("power_total_W", total_power);
  for (const Drive& d : run.drives) {
    metric("drive_" + d.name + "_power_W", d.power.at_run.mean, d.power.at_run.std_error);
    metric("drive_" + d.name + (d.kind == DriveKind::rotating ? "_torque_N_m" : "_pull_N"), d.effort.at_run.mean, d.effort.at_run.std_error);
  }
  if (!model.meshes.empty() && record_time > 0) {
    double max_shear = 0, max_impact = 0, max_wear = kNaN;
    for (const MeshWear& w : run.mesh_wear) {
      max_shear = std::max(max_shear, w.max_shear), max_impact = std::max(max_impact, w.max_impact);
      if (!std::isnan(w.max_wear)) max_wear = std::isnan(max_wear) ? w.max_wear : std::max(max_wear, w.max_wear);
    }
    metric("shear_power_max_W_m2", max_shear);
    metric("impact_power_max_W_m2", max_impact);
    if (!std::isnan(max_wear)) metric("wear_rate_max_mm_yr", max_wear);
    add_liner_metrics(run, model);
  }
  for (const BoxResult& b : run.boxes) {
    metric("centring_offset_" + b.name + "_pct", b.width > 0 ? 100 * b.offset.at_run.mean / (1000 * b.width) : kNaN,
           b.width > 0 ? 100 * b.offset.at_run.std_error / (1000 * b.width) : kNaN);
    metric("vertical_speed_" + b.name + "_m_s", b.vertical);
    metric("mass_in_" + b.name + "_kg", b.mass.at_run.mean, b.mass.at_run.std_error);  // a packing's bulk density times the box's volume
    if (!std::isnan(b.belt_speed) && b.belt_speed != 0) {
      metric("speed_ratio_" + b.name, b.along / b.belt_speed);
      // For ranking: how far the load's speed along the belt is from the belt's (0 is best).
      metric("speed_mismatch_" + b.name + "_pct", 100 * std::abs(1 - b.along / b.belt_speed));
    }
  }
  add_belt_capacity_metrics(run);
  add_choke_metrics(run);
  metric("kinetic_energy_J", run.kinetic.at_run.mean, run.kinetic.at_run.std_error);
}

}  // namespace

const char* drive_kind_name(DriveKind kind) {
  switch (kind) {
    case DriveKind::belt: return "belt";
    case DriveKind::rotating: return "rotating part";
    case DriveKind::path: return "carried on a path";
    case DriveKind::fixed: break;
  }
  return "static";
}

DriveKind drive_kind(const MeshWall& mesh) {
  if (!mesh.motion.is_static()) {
    for (const MotionPart& part : mesh.motion.parts)
      if (part.kind == MotionPart::Kind::rotation && part.angular_speed != 0) return DriveKind::rotating;
    return DriveKind::path;
  }
  const SurfaceVelocitySpec& surface = mesh.surface_velocity;
  if (surface.kind == SurfaceVelocitySpec::Kind::linear && surface.velocity.norm() > 0) return DriveKind::belt;
  if (surface.kind == SurfaceVelocitySpec::Kind::rotation && surface.angular_speed != 0) return DriveKind::rotating;
  return DriveKind::fixed;
}

DriveGeometry drive_geometry(const MeshWall& mesh, double time) {
  DriveGeometry g;
  g.kind = drive_kind(mesh);
  const RigidVelocity motion = mesh.motion.velocity(time);
  g.origin = motion.origin;
  const SurfaceVelocitySpec& surface = mesh.surface_velocity;
  if (g.kind == DriveKind::belt) {
    g.speed = surface.velocity.norm();
    g.direction = surface.velocity / g.speed;
  } else if (g.kind == DriveKind::rotating && mesh.motion.is_static()) {
    // A turning surface on a mesh at rest (a pulley): its own axis, not the motion origin.
    g.direction = (surface.angular_speed < 0 ? -1.0 : 1.0) * surface.axis.normalized();
    g.axis_point = surface.point;
    g.speed = std::abs(surface.angular_speed);
  } else if (g.kind == DriveKind::rotating) {
    // A turning mesh (a screw, a drum): the first rotation part's axis, through its `point`,
    // which is the motion origin (Motion::velocity).
    for (const MotionPart& part : mesh.motion.parts)
      if (part.kind == MotionPart::Kind::rotation) {
        g.direction = (part.angular_speed < 0 ? -1.0 : 1.0) * part.axis.normalized();
        break;
      }
    g.axis_point = motion.origin;
    g.speed = motion.angular.dot(g.direction);
  } else if (g.kind == DriveKind::path) {
    // Along the path: the velocity of the carried frame's origin (a bucket's attachment).
    g.speed = motion.linear.norm();
    if (g.speed > 0) g.direction = motion.linear / g.speed;
  }
  return g;
}

double belt_pull(const Eigen::Vector3d& force_on_belt, const Eigen::Vector3d& direction) { return -force_on_belt.dot(direction); }

double torque_about_axis(const Eigen::Vector3d& torque_about_origin, const Eigen::Vector3d& force, const Eigen::Vector3d& origin,
                         const Eigen::Vector3d& axis_point, const Eigen::Vector3d& axis) {
  // Moving the reference point from o to p: T_p = sum (x - p) x F_i = T_o - (p - o) x F.
  return (torque_about_origin - (axis_point - origin).cross(force)).dot(axis);
}

DriveReading drive_reading(const DriveGeometry& drive, const std::array<double, 6>& load) {
  const Eigen::Vector3d force(load[0], load[1], load[2]), torque(load[3], load[4], load[5]);
  DriveReading r;
  if (drive.kind == DriveKind::belt || drive.kind == DriveKind::path) {
    r.effort = belt_pull(force, drive.direction);
  } else if (drive.kind == DriveKind::rotating) {
    // The material's torque on the part about its axis opposes the turning when it resists:
    // the shaft must supply its negative.
    r.effort = -torque_about_axis(torque, force, drive.origin, drive.axis_point, drive.direction);
  }
  // Rate of work on the material: sum F_i . v_wall = F_t v for a belt whose surfaces contain its
  // direction of travel, and -omega . T_axis = T omega for a part turning about a fixed axis.
  r.check_power = r.effort * drive.speed;
  return r;
}

std::vector<const Quantity*> RunAnalysis::all() const {
  std::vector<const Quantity*> out{&primary};
  for (const auto* group : {&outlets, &plane_sensors})
    for (const Quantity& q : *group) out.push_back(&q);
  // The drives' series; the meshes' own power is left out (a static mesh does no work).
  for (const Drive& d : drives) out.push_back(&d.effort), out.push_back(&d.power);
  for (const Quantity& q : mesh_load) out.push_back(&q);
  // A plane's particle flux; not its velocities, whose mean is weighted by the mass flow (the page).
  for (std::size_t k = 0; k < plane_detail.size(); k += 4) out.push_back(&plane_detail[k]);
  for (const BoxResult& b : boxes) out.push_back(&b.offset), out.push_back(&b.mass);
  for (const Quantity* q : {&holdup_q, &kinetic, &particles, &contacts}) out.push_back(q);
  return out;
}

RunAnalysis analyse_run(const RunReportInput& in) {
  if (!in.model || !in.state) throw std::invalid_argument("write_run_report: model and state are required");
  RunAnalysis run;
  AnalysisInput input{in, *in.model, *in.state, in.scalars, {}, {}, {}, {}};
  time_axis(input, run);
  outlet_flows(input, run);
  plane_sensor_flows(input, run);
  primary_series(input, run);
  mass_balance(input, run);
  check_still_filling(input, run);
  run_interval(run);
  flow_statistics(run);
  plane_sensor_detail(input, run);
  spillage_and_blockage(input, run);
  design_capacity(input, run);
  mesh_loads_and_power(input, run);
  find_drives(input, run);
  events_in_order(input, run);
  wear_per_triangle(input, run);
  belt_loading(input, run);
  find_belt_capacities(in, run);
  find_choke_and_profiles(in, run);
  other_series(input, run);
  add_metrics(input, run);
  return run;
}

void write_run_tables(const RunAnalysis& run, const Model& model, const std::string& report_dir) {
  // ---- files: steady_state.csv, wear_hotspots.csv, metrics.csv --------------------------
  const std::vector<const Quantity*> all = run.all();
  const std::vector<Hotspot>& spots = run.spots;
  const RunMetrics& metrics = run.metrics;
  {
    std::string csv = "series,unit,found,t_start_s,t_end_s,mean,std_dev,std_error,trend_per_s,why\n";
    for (const Quantity* q : all) {
      std::string why = q->own.why;
      std::replace(why.begin(), why.end(), '"', '\'');
      csv += fmt::format("\"{}\",{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},\"{}\"\n", q->name, q->unit, q->own.found ? 1 : 0,
                         q->own.t_start, q->own.t_end, q->own.mean, q->own.std_dev, q->own.std_error, q->own.trend_per_s, why);
    }
    write_file_atomically((fs::path(report_dir) / "steady_state.csv").string(), csv);
    // Loads per mesh and component over the run's interval: what a structural check reads.
    static constexpr const char* kComponentKeys[6] = {"fx", "fy", "fz", "tx", "ty", "tz"};
    std::string loads = "mesh,component,unit,mean,std_error,std_dev,samples,t_start_s,t_end_s\n";
    for (std::size_t m = 0; m < model.meshes.size() && 6 * m + 5 < run.mesh_load.size(); ++m)
      for (int c = 0; c < 6; ++c) {
        const IntervalStats& s = run.mesh_load[6 * m + c].at_run;
        loads += fmt::format("{},{},{},{:.6g},{:.6g},{:.6g},{},{:.6g},{:.6g}\n", model.meshes[m].name, kComponentKeys[c],
                             c < 3 ? "N" : "N m", s.mean, s.std_error, s.std_dev, s.samples, run.run_t0, run.run_t1);
      }
    if (!model.meshes.empty()) write_file_atomically((fs::path(report_dir) / "mesh_loads.csv").string(), loads);
    std::string hot = "rank,mesh,triangle,x_m,y_m,z_m,area_m2,shear_power_W_m2,impact_power_W_m2,impacts_per_s_m2,wear_rate_mm_yr\n";
    for (std::size_t r = 0; r < spots.size(); ++r) {
      const Hotspot& h = spots[r];
      hot += fmt::format("{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n", r + 1, model.meshes[h.mesh].name, h.triangle,
                         h.centroid.x(), h.centroid.y(), h.centroid.z(), h.area, h.shear_rate, h.impact_rate, h.impacts_rate, h.wear_mm_per_year);
    }
    write_file_atomically((fs::path(report_dir) / "wear_hotspots.csv").string(), hot);
    write_metrics(metrics, (fs::path(report_dir) / "metrics.csv").string());
  }
  write_drives_csv(run, report_dir);
  write_wear_life_csv(run, model, report_dir);
  write_belt_capacity_csv(run, report_dir);
  write_choke_csv(run, report_dir);

}

}  // namespace dem::report
