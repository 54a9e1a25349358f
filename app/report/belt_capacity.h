// Belt loading against CEMA capacity (internal to app/): the load cross-section of a belt on
// three equal-roll troughing idlers (CEMA, Belt Conveyors for Bulk Materials, 6th/7th ed., ch. 4),
// the capacity it gives at a belt speed and bulk density, and how full a run's receiving belt runs
// against it. report_analysis.cpp finds one BeltCapacity per load box on a belt with a speed
// (find_belt_capacities), adds the metrics and writes belt_capacity.csv; report.cpp draws the table.
//
// The cross-section is a design calculation a report checks a run against, so it lives beside the
// report rather than in equipment/: a generator states the belt (width, speed, troughing) and the
// report, which alone knows the material and the run's throughput, sizes the load.
#pragma once

#include <string>
#include <vector>

#include "report/report.h"
#include "report/report_internal.h"

namespace dem::report {

struct RunAnalysis;

/// [m] CEMA standard edge distance: the belt left clear on each side of the load,
/// c = 0.055 b + 0.9 in (0.0229 m), for a belt width b [m].
double cema_edge_distance(double belt_width);
/// [m] Length of the centre roll of three equal-length rolls (the belt lying on it), as CEMA's
/// cross-section takes it: l = 0.371 b + 0.25 in (0.00635 m), for a belt width b [m].
double cema_centre_roll(double belt_width);

/// The CEMA load cross-section of a troughed belt and its parts; lengths along the belt
/// surface unless said otherwise.
struct BeltCrossSection {
  double edge_distance = 0;  ///< [m] c, clear belt on each side
  double usable_width = 0;   ///< [m] b - 2c, the belt under the load
  double centre_roll = 0;    ///< [m] l, the belt on the centre roll
  double wing_load = 0;      ///< [m] loaded belt on each wing roll, (b - 2c - l) / 2 (0 when l takes it all)
  double chord = 0;          ///< [m] horizontal width of the load between its edges: l + 2 wing_load cos(beta)
  double trapezoid = 0;      ///< [m^2] below the chord: (l + wing_load cos(beta)) wing_load sin(beta)
  double surcharge = 0;      ///< [m^2] circular segment above it: chord^2 (theta - sin theta cos theta) / (4 sin^2 theta)
  double area = 0;           ///< [m^2] trapezoid + surcharge
};

/// The CEMA cross-section of a belt of width b [m] on three equal-length rolls troughed at beta
/// [deg] (0: a flat belt, whose load is the surcharge segment alone over b - 2c), carrying a
/// material at surcharge angle theta [deg] (its top a circular arc meeting the load's edges at
/// theta). CEMA, Belt Conveyors for Bulk Materials, 7th ed., ch. 4 (cross-section of the load);
/// the 6th ed. has the same geometry. Non-positive or NaN inputs give NaN areas. Checked
/// (tests/test_belt_capacity.cpp) against a published capacity table of three equal-roll idlers
/// in m^3/h at 1 m/s: a 48 in belt at 35 deg with a 20 deg surcharge carries 603 m^3/h, A =
/// 0.1675 m^2 (1.803 ft^2), and this cross-section gives 0.1676 m^2; six more rows within 0.7 %.
BeltCrossSection cema_cross_section(double belt_width, double troughing_deg, double surcharge_deg);

/// [t/h] Capacity of a load cross-section area [m^2] moving at speed [m/s] with bulk density
/// [kg/m^3]: A v rho is kg/s, and 1 kg/s = 3600 kg/h = 3.6 t/h.
double belt_capacity_t_h(double area, double speed, double bulk_density);

/// [kg/m^3] The bulk density a material file's source text states ("bulk density then ~1.5-1.6
/// t/m^3": the middle of a range, 1550; t/m^3, g/cm^3 or kg/m^3); NaN when it states none.
double stated_bulk_density(const std::string& text);

/// How full a belt runs against its capacity.
enum class LoadingVerdict {
  fine,        ///< <= 80 %: CEMA's usual margin for surges and mistracking
  near_full,   ///< > 80 % to 100 %
  overloaded,  ///< > 100 %: the load's surface exceeds the surcharge profile, spillage expected
  unknown,     ///< no loading (NaN)
};
/// The verdict on a loading [%] of capacity: <= 80 fine, <= 100 near full, above overloaded.
LoadingVerdict loading_verdict(double loading_percent);
/// "fine", "near full", "overloaded: spillage expected", "unknown".
const char* loading_verdict_text(LoadingVerdict verdict);

/// A CEMA flowability class: the materials whose angle of repose lies in [repose_min, repose_max)
/// [deg] take the surcharge angle surcharge [deg].
struct FlowabilityClass {
  const char* name;
  double repose_min, repose_max;  // [deg]
  double surcharge;               // [deg]
};
/// CEMA's flowability classes (Belt Conveyors for Bulk Materials, 7th ed., ch. 3, flowability,
/// angle of surcharge and angle of repose), from very free flowing to sluggish.
const std::vector<FlowabilityClass>& cema_flowability_classes();
/// The class of a material with angle of repose [deg]; the average-flowing class (surcharge 20
/// deg, the default the report assumes without a measured angle) when the angle is NaN.
const FlowabilityClass& cema_flowability(double repose_deg);

/// What the report knows of the material the inlets feed (the inlet of the largest mass rate,
/// else the first particle set's): its name, bulk density [kg/m^3] of the real material (not
/// mass-scaled) and where it comes from, and a measured angle of repose [deg] (NaN without one).
struct MaterialFacts {
  std::string name;
  double bulk_density = kNaN;
  std::string bulk_source;
  bool bulk_assumed = false;
  double repose = kNaN;
  std::string repose_source;
};
/// The fed material's facts: its bulk density from a design value bulk_density_kg_m3, else
/// measured (the poured bulk density tests of a calibrated material's measurement file), else
/// stated in its library file's source of `density`, else 0.6 x its solid density, assumed; and
/// its measured angle of repose. Needs in.model; reads in.case_text and in.design.
MaterialFacts material_facts(const RunReportInput& in);

/// One receiving belt with a load box: its CEMA capacity, where each input came from, and the
/// run's throughput onto it against that capacity. `missing` says why there is no capacity
/// (no belt width, no speed); the other numbers are then NaN.
struct BeltCapacity {
  std::string belt;    ///< the belt's name as its design values give it ("receiving_belt"), metrics key
  std::string sensor;  ///< the load box on it
  std::string missing;
  double width = kNaN;      ///< [m] b
  double troughing = kNaN;  ///< [deg] beta
  double surcharge = kNaN;  ///< [deg] theta
  double speed = kNaN;      ///< [m/s] belt speed
  std::string width_source, troughing_source, surcharge_source, speed_source;
  bool surcharge_assumed = false;
  std::string material;      ///< the case material the inlets feed
  double bulk_density = kNaN;  ///< [kg/m^3] of the real material (not mass-scaled)
  std::string bulk_density_source;
  bool bulk_density_assumed = false;
  BeltCrossSection section;
  double capacity = kNaN;  ///< [t/h] at `speed` and `bulk_density`
  /// [t/h] The run's steady throughput onto the belt, divided by the mass scaling (the real
  /// material's tonnes), and the standard error of that mean.
  double throughput = kNaN, throughput_error = kNaN;
  std::string throughput_source;
  double loading = kNaN, loading_error = kNaN;  ///< [%] 100 throughput / capacity
  LoadingVerdict verdict = LoadingVerdict::unknown;
};

/// Per box sensor of run.boxes with a belt speed: the belt's CEMA capacity and its loading, into
/// run.belts. Needs run.boxes, run.plane_sensors and run.primary finished.
void find_belt_capacities(const RunReportInput& in, RunAnalysis& run);
/// Appends belt_capacity_BELT_t_h and belt_loading_BELT_percent per belt with a capacity.
void add_belt_capacity_metrics(RunAnalysis& run);
/// belt_capacity.csv into report_dir: one row per belt with a capacity; nothing without one.
void write_belt_capacity_csv(const RunAnalysis& run, const std::string& report_dir);

}  // namespace dem::report
