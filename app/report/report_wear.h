// Liner life from the wall records (internal to app/): the wear depth rate of a liner by sliding
// (friction work x its sliding coefficient) and by impact (normal impact energy x its impact
// coefficient), the months until its thickness is worn through at the stated operating hours,
// and the depth worn per million tonnes conveyed; the liners of a case's meshes; wear_life.csv
// and the liner metrics. The laws, the coefficients and their sources are in
// src/case/liner_materials.cpp; report_analysis.cpp applies this per triangle and per mesh.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "case/spec.h"
#include "core/model.h"
#include "report/report.h"
#include "report/report_internal.h"

namespace dem::report {

struct RunAnalysis;

/// [s] in an hour.
constexpr double kSecondsPerHour = 3600.0;

/// [m/s] Depth rate of a liner that received `energy` [J] (friction work or normal impact
/// energy) on `area` [m^2] over `interval` [s]: coefficient [m^3/J] x energy / (area x interval).
/// NaN when the coefficient is NaN (not given) or the area or interval is not positive.
double depth_rate(double coefficient, double energy, double area, double interval);
/// [m/s] The sliding and impact depth rates [m/s] together, leaving out a NaN one; NaN when both are.
double total_rate(double sliding, double impact);
/// [mm/year] What a depth rate [m/s] wears in a year of hours_per_year [h] of operation.
double mm_per_year(double rate, double hours_per_year);
/// [months] Calendar months until thickness [m] is worn through at rate [m/s] when the plant
/// runs hours_per_year [h] a year: 12 thickness / (rate x 3600 hours_per_year). Infinite at no
/// wear; NaN without a thickness or a rate.
double life_months(double thickness, double rate, double hours_per_year);
/// [mm/Mt] Depth worn per million tonnes conveyed at throughput [t/h]: the rate [m/s] over the
/// tonnes a second, times 1e3 mm/m and 1e6 t/Mt. Independent of the operating hours; NaN
/// without a positive throughput.
double mm_per_megatonne(double rate, double throughput_t_h);

/// A zone of a liner, its worst triangle or the mesh as a whole, and its life.
struct WearZone {
  std::size_t triangle = 0;           ///< the worst triangle; unused for the mesh's mean
  Eigen::Vector3d centroid{0, 0, 0};  ///< [m] the worst triangle's centroid, pose at t = 0
  double sliding = kNaN;              ///< [m/s] depth rate by sliding (Archard); NaN without a coefficient
  double impact = kNaN;               ///< [m/s] depth rate by impact (Bitter); NaN without a coefficient
  double life_months = kNaN;          ///< [months] at the operating hours; NaN without a thickness
  double mm_per_megatonne = kNaN;     ///< [mm/Mt] depth per million tonnes conveyed
};

/// The zone of `liner` that received friction_work and impact_energy [J] on area [m^2] over
/// interval [s], at hours_per_year [h] and throughput [t/h].
WearZone wear_zone(const Liner& liner, double friction_work, double impact_energy, double area, double interval,
                   double hours_per_year, double throughput_t_h);

/// Whether a mesh's surface moves (a belt, a pulley): it takes no `default` liner.
bool has_surface_velocity(const MeshWall& mesh);

/// The liner of each mesh of `model` from the case: its own entry in `wear.liners` or in
/// `wear_coefficients`, else the `default` of either for a mesh without a surface velocity
/// (belts and pulleys take no default: only a liner given by their name). A mesh with neither
/// has no liner and no wear depth.
std::map<std::string, Liner> liners_for(const CaseSpec& spec, const Model& model);
/// The liner the report uses for mesh `name`: input.liners, else a sliding coefficient alone
/// from input.wear_coefficient; none when neither names it.
std::optional<Liner> liner_of(const RunReportInput& input, const std::string& name);

/// [months] Per mesh, per triangle: the life of the mesh's liner there (wear_zone of the
/// triangle's friction work and impact energy over the records' interval, at the operating hours
/// of `input`), for the 3D view's life field. NaN on a mesh without a liner or a thickness, on a
/// triangle of no area and everywhere without records; infinite where a liner does not wear.
std::vector<std::vector<double>> triangle_life_months(const RunReportInput& input);

/// Appends to run.metrics, per mesh with a liner: wear_sliding_MESH_mm_yr and
/// wear_impact_MESH_mm_yr (at the worst triangle), liner_life_MESH_months (worst triangle),
/// liner_life_mean_MESH_months, wear_MESH_mm_per_Mt (worst triangle); and
/// liner_life_min_months over the meshes. Values that are not finite are left out.
void add_liner_metrics(RunAnalysis& run, const Model& model);
/// wear_life.csv into report_dir: per mesh with a liner, a row for its worst triangle and one
/// for its mean. Nothing without meshes.
void write_wear_life_csv(const RunAnalysis& run, const Model& model, const std::string& report_dir);

}  // namespace dem::report
