// What a case's modelling shortcuts cost: a check rides with a case and runs it again with the
// shortcut reduced, as a sweep's variants (child processes, shared over MPI ranks), and reports
// for every KPI of metrics.csv how far it moved and whether that matters. Two checks share the
// machinery (the variant list, the per-KPI shifts, the report section, the CSV):
//
// `bias_check:` (reduced stiffness, mass scaling) runs each design variant as the case is and
// again with the particles' Young's modulus multiplied by `stiffness_factor` (the automatic time
// step follows), and, when the case uses mass scaling, again with the mass scaling divided by
// `mass_factor` (not below 1). Every KPI is reported with its shift, the shift's noise (the runs'
// own standard deviations, where the run report gives one), and in words whether the case's
// stiffness (mass scaling) is good enough for that KPI.
//
//   bias_check:
//     stiffness_factor: 4   # > 1: the particles this much stiffer in the check run
//     mass_factor: 4        # > 1: with simulation.mass_scaling > 1, a run at mass_scaling / factor
//     duration: 0.5         # [s] optional: every run of the check this long (a window of the case)
//     tolerance_pct: 5      # a KPI is sensitive when it shifts by more than this share of its
//                           # value and by more than twice the shift's noise
//
// A KPI is "sensitive" to a scaling when both hold (and a share in per cent moves by more than
// `tolerance_pct` points, a speed by more than 1 cm/s); the words then say that the value depends
// on the modelling choice and by how much. The run's kinetic energy and steady-state start are not
// checked. Scalings are named in every run's run_info.yaml.
//
// `coarse_grain_check:` (parcels, core/coarse_grain.h) runs each design variant at the case's
// coarse_grain F and again with every inlet's and particle set's coarse_grain replaced by a finer
// F' (1 <= F' < F; 1 runs the real particles). Each KPI is given at F and at F' with the standard
// errors of both (batch means, report::RunMetrics::std_errors) and the difference in standard
// errors z = (value at F' - value at F) / sqrt(se_F^2 + se_F'^2):
//
//   coarse_grain_check:
//     finer: 1              # F': every coarse_grain of the check run; at least 1, below the case's F
//     kpis: [throughput_t_h, power_total_W]   # optional: the KPIs to report (metrics.csv names);
//                                             # default: every KPI of the runs
//     duration: 2.0         # [s] optional: every run of the check this long (a window of the case)
//     tolerance_pct: 5      # a shift smaller than this share of the value is not a bias
//
// Verdicts: "within noise" when |z| <= 2 (report::kSignificantZ: the runs cannot tell F from F');
// "moved by z sigma: coarse graining biases this KPI" when |z| > 2 and the shift exceeds
// `tolerance_pct` of the value (a share in per cent: that many points, a speed: 1 cm/s); moved
// by more than the noise but less than the tolerance is said so and not flagged. A KPI without a
// standard error (a total such as spillage, a peak, a wear figure) is judged by the tolerance
// alone. Rejected: the runs' standard deviations as bias_check's noise: a shift of a mean is
// measured against the mean's standard error, and a standard deviation would hide every bias
// smaller than the scatter of the rows. The case's F and the check's F' are named in every
// run's run_info.yaml (`coarse_grain`) and in the table's header.
//
// A case runs one of bias_check, coarse_grain_check and uncertainty.
#pragma once

#include <yaml-cpp/yaml.h>

#include <limits>
#include <string>
#include <vector>

#include "report/report.h"
#include "campaign/sweep.h"

namespace dem::app {

/// Adds the `bias_check:` section of `root` to `plan` (after read_sweep has read `sweep:`):
/// every design variant is repeated once per run of the check. Throws CaseError naming file,
/// line and key when the section is wrong (or combined with `uncertainty:` or
/// `coarse_grain_check:`).
void add_bias_check(SweepPlan& plan, const YAML::Node& root, const std::string& file);

/// Adds the `coarse_grain_check:` section of `root` to `plan` the same way: the runs at the
/// case's coarse_grain and at `finer`. Throws CaseError naming file, line and key for a finer
/// factor below 1 or not below the case's, a case without coarse_grain, a design sweep that
/// varies a coarse_grain, an unknown key, or the section combined with `uncertainty:`.
void add_coarse_grain_check(SweepPlan& plan, const YAML::Node& root, const std::string& file);

/// One KPI of one design variant: the case's value against a check run's.
struct KpiShift {
  std::string design;   ///< the design variant's label ("" without a sweep)
  std::string check;    ///< "stiffness x 4", "mass scaling 8 -> 2", "coarse_grain 1"
  std::string metric;
  double as_case = 0, checked = 0;
  double shift_pct = 0;  ///< (checked - as_case) / |as_case| [%]; NaN when as_case is 0
  double noise_pct = 0;  ///< the shift's standard deviation from the runs' own noise [%]; NaN when unknown
  double noise = std::numeric_limits<double>::quiet_NaN();  ///< [the KPI's unit] the same, absolute
  /// [the KPI's unit] batch-means standard errors of the two values; NaN where a run gives none.
  double std_error_case = std::numeric_limits<double>::quiet_NaN(), std_error_checked = std::numeric_limits<double>::quiet_NaN();
  /// (checked - as_case) / sqrt(se_case^2 + se_checked^2) [-]: the shift in standard errors; NaN
  /// unless both runs give one.
  double z = std::numeric_limits<double>::quiet_NaN();
  bool sensitive = false;  ///< bias_check: sensitive to the scaling; coarse_grain_check: biased by the parcels
  std::string words;
};

struct BiasSummary {
  std::vector<KpiShift> shifts;
  std::string html;         ///< a section for the sweep report
  std::string title;        ///< of the sweep report: "What the scalings cost", "What coarse graining costs"
  std::string log_heading;  ///< the log's line above the verdicts
  std::string flag_word;    ///< before a flagged KPI's words in the log: "SENSITIVE", "BIASED"
  std::vector<std::string> log_lines;  ///< said before the verdicts: KPIs named that no run reports
};

/// The shifts of every KPI; writes bias_check.csv (coarse_grain_check.csv for a coarse_grain_check)
/// into `dir`.
BiasSummary summarise_bias_check(const SweepPlan& plan, const std::vector<report::SweepVariant>& variants, const std::string& dir);

}  // namespace dem::app
