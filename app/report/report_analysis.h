// The numbers of a run report before they are written (internal to app/): every series of the
// run with its own steady state and its average over the run's interval, the mass balance,
// spillage and blockage, power and torque per mesh, wear per triangle, belt loading, and the
// metrics. report_analysis.cpp computes them and writes the report's tables (steady_state.csv,
// wear_hotspots.csv, metrics.csv); report.cpp draws the plots and writes report.html.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

#include "report/report.h"
#include "report/report_internal.h"
#include "statistics/steady_state.h"

namespace dem::report {

/// A time series of the run with its own steady-state detection and its average over the
/// run's steady interval.
struct Quantity {
  std::string name;  ///< "outlet bin"
  std::string unit;  ///< "t/h"
  std::vector<double> y;
  SteadyState own;
  IntervalStats at_run;
};

/// A triangle of a mesh with its wear inputs over the recording interval.
struct Hotspot {
  std::size_t mesh = 0, triangle = 0;
  Eigen::Vector3d centroid{0, 0, 0};
  double area = 0, shear_rate = 0, impact_rate = 0, impacts_rate = 0, wear_mm_per_year = kNaN;
};

/// A mesh's wear totals: powers [W], area [m^2], peaks per area [W/m^2], wear [mm/yr], k_A [m^3/J].
struct MeshWear {
  double shear_power = 0, impact_power = 0, area = 0, max_shear = 0, max_impact = 0, max_wear = kNaN, k = kNaN;
};

/// A box sensor's belt loading.
struct BoxResult {
  std::string name;
  Quantity offset, mass;
  double width = 0;                   // [m] extent of the box along `across`
  Eigen::Vector3d velocity{0, 0, 0};  // [m/s] mean over the run interval
  double along = 0, lateral = 0, vertical = 0;  // [m/s]
  std::string belt_name;
  double belt_speed = kNaN;
};

struct RunAnalysis {
  const std::vector<Scalars>* rows = nullptr;  ///< the input's rows
  std::vector<double> t;                       ///< [s] time of each row
  double t_end = 0;                            ///< [s]
  Scalars last;                                ///< the last row
  std::vector<bool> intended;                  ///< per outlet
  std::vector<Quantity> outlets, plane_sensors, power, torque;
  /// Per mesh, six series: the particles' force on it (x, y, z) [N] and its torque about the
  /// mesh's motion origin (x, y, z) [N m], each averaged over the run's interval with its
  /// standard error (mesh_loads.csv).
  std::vector<Quantity> mesh_load;
  /// Per plane sensor (in the order of plane_sensors), four series: particles through it [1/s]
  /// and the mean velocity of what crosses it (x, y, z) [m/s].
  std::vector<Quantity> plane_detail;
  Quantity primary;                            ///< the series that defines the run's steady state
  std::vector<double> inserted, removed, lost, holdup;  ///< [kg] cumulative masses per row
  bool steady = false;
  double run_t0 = 0, run_t1 = 0;               ///< [s] the interval the averages are taken over
  std::string interval_text;                   ///< "1.2 s to 4 s"
  Blockage blockage;
  double spill_outlets = 0, spillage = 0, spillage_pct = 0;  ///< [kg], [kg], [%]
  double capacity = kNaN;                      ///< [t/h]
  std::string capacity_label, capacity_source;
  double record_time = 0;                      ///< [s] of wall records
  std::vector<Hotspot> spots;                  ///< the 10 triangles with the highest shear power per area
  std::vector<MeshWear> mesh_wear;             ///< per mesh
  std::vector<BoxResult> boxes;
  std::vector<RunEvent> events;                ///< first arrivals, in the order they happened
  Quantity kinetic, particles, holdup_q, contacts;
  RunMetrics metrics;
  /// Every series, in the order of steady_state.csv.
  std::vector<const Quantity*> all() const;
};

/// The numbers of the run report (input.model and input.state are required).
RunAnalysis analyse_run(const RunReportInput& in);
/// steady_state.csv, wear_hotspots.csv and metrics.csv into report_dir.
void write_run_tables(const RunAnalysis& run, const Model& model, const std::string& report_dir);

}  // namespace dem::report
