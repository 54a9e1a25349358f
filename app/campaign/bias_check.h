// What reduced stiffness and mass scaling cost: a case with a `bias_check:` section runs each
// design variant as the case is and again with the particles' Young's modulus multiplied by
// `stiffness_factor` (the automatic time step follows), and, when the case uses mass scaling,
// again with the mass scaling divided by `mass_factor` (not below 1). Every KPI of metrics.csv is
// reported with its shift, the shift's noise (the runs' own standard deviations, where the run
// report gives one), and in words whether the case's stiffness (mass scaling) is good enough for
// that KPI. The runs are a sweep's variants (child processes, shared over MPI ranks).
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
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "report/report.h"
#include "campaign/sweep.h"

namespace dem::app {

/// Adds the `bias_check:` section of `root` to `plan` (after read_sweep has read `sweep:`):
/// every design variant is repeated once per run of the check. Throws CaseError naming file,
/// line and key when the section is wrong (or combined with `uncertainty:`).
void add_bias_check(SweepPlan& plan, const YAML::Node& root, const std::string& file);

/// One KPI of one design variant: the case's value against a check run's.
struct KpiShift {
  std::string design;   ///< the design variant's label ("" without a sweep)
  std::string check;    ///< "stiffness x 4", "mass scaling 8 -> 2"
  std::string metric;
  double as_case = 0, checked = 0;
  double shift_pct = 0;  ///< (checked - as_case) / |as_case| [%]; NaN when as_case is 0
  double noise_pct = 0;  ///< the shift's standard deviation from the runs' own noise [%]; NaN when unknown
  bool sensitive = false;
  std::string words;
};

struct BiasSummary {
  std::vector<KpiShift> shifts;
  std::string html;  ///< a section for the sweep report
};

/// The shifts of every KPI; writes bias_check.csv into `dir`.
BiasSummary summarise_bias_check(const SweepPlan& plan, const std::vector<report::SweepVariant>& variants, const std::string& dir);

}  // namespace dem::app
