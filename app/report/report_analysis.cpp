// The numbers of the run report: each series with its steady state and its average over the
// run's interval, the mass balance, spillage and blockage, power and torque, wear per triangle,
// belt loading and the metrics; and the report's tables (steady_state.csv, wear_hotspots.csv,
// metrics.csv). report.cpp draws the plots and writes report.html.
#include "report/report_analysis.h"

#include <fmt/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "pages/html.h"
#include "output/run.h"

namespace dem::report {
namespace {

namespace fs = std::filesystem;
using html::num;
constexpr double kSecondsPerYear = 8760.0 * 3600.0;  // 8760 h
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

// ---- power and torque per mesh --------------------------------------------------------

/// Per mesh: its power, torque and the six components of its load, each a finished series.
void power_and_torque(const AnalysisInput& input, RunAnalysis& run) {
  const Model& model = input.model;
  const std::vector<Scalars>& rows = input.rows;
  std::vector<Quantity>& power = run.power;
  std::vector<Quantity>& torque = run.torque;
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    power.push_back({"power " + model.meshes[m].name, "W", column(rows, [m](const Scalars& r) { return at(r.mesh_power, m); }), {}, {}});
    torque.push_back({"torque " + model.meshes[m].name, "N m", column(rows, [m](const Scalars& r) { return at(r.mesh_torque, m); }), {}, {}});
    finish_series(run, power.back());
    finish_series(run, torque.back());
    static constexpr const char* kComponents[6] = {"force x", "force y", "force z", "torque x", "torque y", "torque z"};
    for (int c = 0; c < 6; ++c) {
      run.mesh_load.push_back({fmt::format("{} {}", kComponents[c], model.meshes[m].name), c < 3 ? "N" : "N m",
                               column(rows, [m, c](const Scalars& r) { return m < r.mesh_load.size() ? r.mesh_load[m][c] : 0.0; }), {}, {}});
      finish_series(run, run.mesh_load.back());
    }
  }
}

/// The run's first arrivals, in the order they happened.
void events_in_order(const AnalysisInput& input, RunAnalysis& run) {
  run.events = input.in.events;
  std::stable_sort(run.events.begin(), run.events.end(), [](const RunEvent& a, const RunEvent& b) { return a.step < b.step; });
}

// ---- wear per triangle ----------------------------------------------------------------

/// Per mesh its wear totals, and the 10 triangles with the highest shear power per area.
void wear_per_triangle(const AnalysisInput& input, RunAnalysis& run) {
  const RunReportInput& in = input.in;
  const Model& model = input.model;
  const State& state = input.state;
  const double record_time = run.record_time = state.time - in.records_from;  // [s]
  std::vector<Hotspot>& spots = run.spots;

  std::vector<MeshWear>& mesh_wear = run.mesh_wear;
  mesh_wear.resize(model.meshes.size());
  if (record_time > 0) {
    for (std::size_t m = 0; m < model.meshes.size() && m < state.records.size(); ++m) {
      const MeshWall& mesh = model.meshes[m];
      const TriangleSurface& surface = *mesh.surface;
      const TriangleRecords& rec = state.records[m];
      const Pose pose = mesh.motion.pose(0.0);
      const auto k_it = in.wear_coefficient.find(mesh.name);
      MeshWear& w = mesh_wear[m];
      if (k_it != in.wear_coefficient.end()) w.k = k_it->second;
      for (std::size_t tri = 0; tri < surface.size() && tri < rec.shear_work.size(); ++tri) {
        const double area = surface.areas[tri];
        if (area <= 0) continue;
        Hotspot h;
        h.mesh = m, h.triangle = tri, h.area = area;
        Eigen::Vector3d c(0, 0, 0);
        for (int v = 0; v < 3; ++v) {
          const auto& p = surface.vertices[surface.triangles[tri][v]];
          c += Eigen::Vector3d(p[0], p[1], p[2]) / 3.0;
        }
        h.centroid = pose.rotation * c + pose.translation;
        h.shear_rate = rec.shear_work[tri] / (area * record_time);
        h.impact_rate = at(rec.impact_energy, tri) / (area * record_time);
        h.impacts_rate = at(rec.impacts, tri) / (area * record_time);
        // Archard: wear depth rate = k_A q, k_A [m^3/J] = [m/Pa m], q [W/m^2] -> [m/s].
        if (!std::isnan(w.k)) h.wear_mm_per_year = w.k * h.shear_rate * 1000.0 * kSecondsPerYear;
        w.shear_power += rec.shear_work[tri] / record_time;
        w.impact_power += at(rec.impact_energy, tri) / record_time;
        w.area += area;
        w.max_shear = std::max(w.max_shear, h.shear_rate);
        w.max_impact = std::max(w.max_impact, h.impact_rate);
        if (!std::isnan(h.wear_mm_per_year)) w.max_wear = std::isnan(w.max_wear) ? h.wear_mm_per_year : std::max(w.max_wear, h.wear_mm_per_year);
        spots.push_back(h);
      }
    }
  }
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
    std::tie(b.belt_name, b.belt_speed) = belt_speed_for(in.design, s.name);
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
  const auto metric = [&metrics](const std::string& name, double value) { metrics.values.emplace_back(key(name), value); };
  const Quantity& primary = run.primary;
  const std::vector<Quantity>& plane_sensors = run.plane_sensors;
  const std::vector<Quantity>& power = run.power;
  const std::vector<Quantity>& torque = run.torque;
  const double capacity = run.capacity;
  const double record_time = run.record_time;

  metric("steady_from_s", run.steady ? run.run_t0 : kNaN);
  if (!model.outlets.empty()) {
    metric("throughput_t_h", primary.at_run.mean);
    metric("throughput_std_t_h", primary.at_run.std_dev);
    for (const Quantity& q : run.outlets) metric(key(q.name) + "_t_h", q.at_run.mean);
  }
  for (const Quantity& q : plane_sensors) metric(key(q.name) + "_t_h", q.at_run.mean);
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
    metric("power_" + model.meshes[m].name + "_W", power[m].at_run.mean);
    metric("torque_" + model.meshes[m].name + "_N_m", torque[m].at_run.mean);
    total_power += power[m].at_run.mean;
    // The magnitude of the mean force, not the mean of the magnitude (which noise inflates).
    const double fx = run.mesh_load[6 * m].at_run.mean, fy = run.mesh_load[6 * m + 1].at_run.mean, fz = run.mesh_load[6 * m + 2].at_run.mean;
    metric("force_" + model.meshes[m].name + "_N", std::sqrt(fx * fx + fy * fy + fz * fz));
  }
  if (!power.empty()) metric("power_total_W", total_power);
  if (!model.meshes.empty() && record_time > 0) {
    double max_shear = 0, max_impact = 0, max_wear = kNaN;
    for (const MeshWear& w : run.mesh_wear) {
      max_shear = std::max(max_shear, w.max_shear), max_impact = std::max(max_impact, w.max_impact);
      if (!std::isnan(w.max_wear)) max_wear = std::isnan(max_wear) ? w.max_wear : std::max(max_wear, w.max_wear);
    }
    metric("shear_power_max_W_m2", max_shear);
    metric("impact_power_max_W_m2", max_impact);
    if (!std::isnan(max_wear)) metric("wear_rate_max_mm_yr", max_wear);
  }
  for (const BoxResult& b : run.boxes) {
    metric("centring_offset_" + b.name + "_pct", b.width > 0 ? 100 * b.offset.at_run.mean / (1000 * b.width) : kNaN);
    metric("vertical_speed_" + b.name + "_m_s", b.vertical);
    metric("mass_in_" + b.name + "_kg", b.mass.at_run.mean);  // a packing's bulk density times the box's volume
    if (!std::isnan(b.belt_speed) && b.belt_speed != 0) {
      metric("speed_ratio_" + b.name, b.along / b.belt_speed);
      // For ranking: how far the load's speed along the belt is from the belt's (0 is best).
      metric("speed_mismatch_" + b.name + "_pct", 100 * std::abs(1 - b.along / b.belt_speed));
    }
  }
  metric("kinetic_energy_J", run.kinetic.at_run.mean);
}

}  // namespace

std::vector<const Quantity*> RunAnalysis::all() const {
  std::vector<const Quantity*> out{&primary};
  for (const auto* group : {&outlets, &plane_sensors, &power, &torque, &mesh_load})
    for (const Quantity& q : *group) out.push_back(&q);
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
  power_and_torque(input, run);
  events_in_order(input, run);
  wear_per_triangle(input, run);
  belt_loading(input, run);
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

}

}  // namespace dem::report
