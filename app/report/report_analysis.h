// The numbers of a run report before they are written (internal to app/): every series of the
// run with its own steady state and its average over the run's interval, the mass balance,
// spillage and blockage, the drives of the moving parts and the loads on every mesh, wear per
// triangle and the liners' life (report_wear.h), belt loading and the receiving belts against
// their CEMA capacity (belt_capacity.h), the chute's narrowest section against the stream's fill
// and the stream profiles (choke.h), and the metrics. report_analysis.cpp computes them and
// writes the report's tables (steady_state.csv, wear_hotspots.csv, wear_life.csv,
// belt_capacity.csv, choke.csv, metrics.csv); report.cpp draws the plots and writes report.html.
#pragma once

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

#include "report/belt_capacity.h"
#include "report/choke.h"
#include "report/report.h"
#include "report/report_internal.h"
#include "report/report_wear.h"
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

/// A triangle of a mesh with its wear inputs over the recording interval: area [m^2], shear and
/// impact power per area [W/m^2], impacts per area and second [1/(s m^2)]; with a liner, its
/// depth rate by sliding and impact together [m/s] and that in mm/year at the operating hours.
struct Hotspot {
  std::size_t mesh = 0, triangle = 0;
  Eigen::Vector3d centroid{0, 0, 0};
  double area = 0, shear_rate = 0, impact_rate = 0, impacts_rate = 0, wear_rate = kNaN, wear_mm_per_year = kNaN;
};

/// A mesh's wear totals: powers [W], area [m^2], peaks per area [W/m^2], the worst triangle's
/// wear rate [mm/yr] at the operating hours, the sliding coefficient [m^3/J]; and with a liner,
/// the liner, its worst triangle and its mean (report_wear.h).
struct MeshWear {
  double shear_power = 0, impact_power = 0, area = 0, max_shear = 0, max_impact = 0, max_wear = kNaN, k = kNaN;
  bool has_liner = false;
  Liner liner;
  WearZone worst, mean;
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

// ---- drives: how each mesh is moved and what its drive supplies ---------------------------

/// How a mesh is moved, read from its motion and its surface velocity (the motion first: a mesh
/// that moves and also has a surface velocity is classed by its motion).
enum class DriveKind {
  fixed,     ///< neither moves nor has a surface velocity: it carries loads and does no work
  belt,      ///< a surface moving along a direction (`surface_velocity: {linear}`): a conveyor belt
  rotating,  ///< turning about an axis: a rotation motion part (screw, drum) or a rotating surface (pulley)
  path,      ///< carried along a prescribed path: a belt_loop part (buckets), a translation, oscillation or table
};

/// "belt", "rotating part", "carried on a path", "static".
const char* drive_kind_name(DriveKind kind);

/// A mesh's drive at one time: what the drives table resolves the recorded loads against.
struct DriveGeometry {
  DriveKind kind = DriveKind::fixed;
  /// Belt and path: unit direction of travel. Rotating: unit axis, oriented so that the part
  /// turns anticlockwise about it (right-hand rule) as specified, so that `speed` >= 0 then.
  Eigen::Vector3d direction{0, 0, 0};
  Eigen::Vector3d axis_point{0, 0, 0};  ///< [m] rotating: a point on the axis
  /// [m] The point the recorded torque (Scalars::mesh_load) is taken about, the motion's
  /// reference point Motion::velocity(t).origin: the `point` of the first rotation part placed by
  /// the pose (on a screw's or drum's axis), the carried frame's origin on a belt_loop path (the
  /// bucket's attachment), the world origin for a mesh that does not move (a belt, a pulley's
  /// turning surface).
  Eigen::Vector3d origin{0, 0, 0};
  double speed = 0;  ///< belt, path: [m/s] along `direction`; rotating: [rad/s] about `direction`
};

/// The kind of drive that moves `mesh`.
DriveKind drive_kind(const MeshWall& mesh);
/// The drive of `mesh` at time [s]: its direction or axis, its speed and its motion origin.
DriveGeometry drive_geometry(const MeshWall& mesh, double time);

/// [N] Belt pull: the particles' force on the belt [N] resolved against its unit direction of
/// travel, F_t = -F . d, positive when the material resists the belt (the drive must pull it).
double belt_pull(const Eigen::Vector3d& force_on_belt, const Eigen::Vector3d& direction);

/// [N m] The torque about an axis (through axis_point [m], unit direction `axis`) of loads
/// recorded as a force F [N] and a torque T_origin [N m] about `origin` [m]:
/// T_axis = (T_origin - (axis_point - origin) x F) . axis.
double torque_about_axis(const Eigen::Vector3d& torque_about_origin, const Eigen::Vector3d& force, const Eigen::Vector3d& origin,
                         const Eigen::Vector3d& axis_point, const Eigen::Vector3d& axis);

/// What a drive supplies at one instant, from the particles' load on the mesh.
struct DriveReading {
  /// Belt and path: pull along the direction of travel [N]; rotating: shaft torque about the
  /// part's own axis [N m]; positive = the material resists the motion.
  double effort = 0;
  double check_power = 0;  ///< [W] effort x speed (F_t v, T omega)
};
/// `load`: the particles' force (x, y, z) [N] on the mesh and its torque (x, y, z) [N m] about
/// drive.origin, as in Scalars::mesh_load.
DriveReading drive_reading(const DriveGeometry& drive, const std::array<double, 6>& load);

/// A moving part as its drive sees it: the meshes it is made of, how it moves, and its series
/// over the run. A belt and a rotating part are one mesh each; the meshes carried round one
/// belt loop (an elevator's buckets) are one drive, the chain's.
struct Drive {
  std::string name;                 ///< the mesh's name, or "first to last" of the meshes on one loop
  std::string note;                 ///< "12 meshes carried round one belt loop", or ""
  DriveKind kind = DriveKind::fixed;
  std::vector<std::size_t> meshes;  ///< into Model::meshes
  DriveGeometry at_end;             ///< of the first mesh, at the run's end
  double speed = 0;                 ///< [m/s] or [rad/s] mean over the run's interval
  Quantity effort;  ///< pull [N] (belt, path) or shaft torque about the own axis [N m] (rotating); + = the material resists
  Quantity power;   ///< [W] rate of work the part does on the material (the meshes' recorded power, summed)
  Quantity check;   ///< [W] effort x speed row by row: equals `power` for a belt and a rotating part
};

struct RunAnalysis {
  const std::vector<Scalars>* rows = nullptr;  ///< the input's rows
  std::vector<double> t;                       ///< [s] time of each row
  double t_end = 0;                            ///< [s]
  Scalars last;                                ///< the last row
  std::vector<bool> intended;                  ///< per outlet
  std::vector<Quantity> outlets, plane_sensors;
  /// Per mesh: the rate of work it does on the material [W] (metrics.csv's power_MESH_W).
  std::vector<Quantity> power;
  std::vector<DriveKind> mesh_kind;  ///< per mesh
  std::vector<Drive> drives;         ///< the moving parts, in the order of their first mesh
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
  double operating_hours = kDefaultOperatingHoursPerYear;  ///< [h] a year the wear rates and lives are at
  bool operating_hours_given = false;          ///< false: the default, an assumption the report states
  double wear_throughput = kNaN;               ///< [t/h] the wear per million tonnes is taken against
  std::string wear_throughput_text;            ///< where that throughput comes from
  std::vector<BoxResult> boxes;
  /// Per receiving belt with a load box and a speed: its CEMA capacity and the run's loading of it.
  std::vector<BeltCapacity> belts;
  /// The chute's narrowest section against the stream's fill (a box sensor stream_chute with the
  /// generator's choke_section_* design values), and the profiles of the box sensors with bins.
  ChokeResult choke;
  std::vector<StreamProfile> profiles;
  std::vector<RunEvent> events;                ///< first arrivals, in the order they happened
  Quantity kinetic, particles, holdup_q, contacts;
  RunMetrics metrics;
  /// Every series, in the order of steady_state.csv.
  std::vector<const Quantity*> all() const;
};

/// The numbers of the run report (input.model and input.state are required).
RunAnalysis analyse_run(const RunReportInput& in);
/// steady_state.csv, mesh_loads.csv (with meshes), drives.csv (with moving parts),
/// wear_hotspots.csv, wear_life.csv (with meshes), belt_capacity.csv (with a belt's capacity),
/// choke.csv (with a chute's narrowest section) and metrics.csv into report_dir.
void write_run_tables(const RunAnalysis& run, const Model& model, const std::string& report_dir);

}  // namespace dem::report
