// Design sweeps: a case with a `sweep:` section is run once per variant (a parameter of the case
// replaced by each of its values), the variants in child processes of this program, several at
// once when the cores allow, and ranked by the criteria the case names. Under `mpirun -np N` the
// variants are handed out among the ranks and rank 0 writes the report (app/campaign/mpi_campaign.h).
//
//   sweep:
//     parameters:                                  # key path in the case -> values
//       equipment.transfer_chute.spoon.radius: [0.6, 0.8, 1.0]
//       equipment.transfer_chute.receiving_belt.speed: [2.5, 3.5]
//     combine: grid              # grid (every combination, default) or zip (k-th with k-th)
//     rank_by:                   # metrics of the run report (metrics.csv), lower or higher is better
//       - {metric: spillage_percent, goal: minimize, weight: 2}
//       - {metric: peak_shear_work_rate_W_m2, goal: minimize}
//     parallel: 2                # variants at once (default: cores / threads per variant)
//
// Key paths name maps by key and lists by index: `inlets[0].mass_rate_tph`. A variant's case is
// the sweep case with its values set and the `sweep:` section removed; it is written beside the
// variant's results (case.yaml), so every variant can be rerun alone.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <utility>
#include <vector>

namespace dem::app {

struct SweepCriterion {
  std::string metric;
  bool minimize = true;
  double weight = 1.0;
};

/// The most variants a sweep may make (a grid is sized before it is built).
inline constexpr std::size_t kMostSweepVariants = 1000;

struct SweepPlan {
  std::vector<std::string> paths;                   ///< key paths, in file order
  std::vector<std::vector<YAML::Node>> variants;    ///< per variant, one value per path
  std::vector<SweepCriterion> criteria;
  int parallel = 0;                                 ///< 0: automatic
  std::string file;
  /// With `uncertainty:` (app/campaign/uncertainty.h): parameter sets per design variant; variant k is
  /// design k / samples at parameter set k % samples, and the paths after the first
  /// `design_paths` are the sampled parameters. 0: no uncertainty section.
  int samples = 0;
  size_t design_paths = 0;
  std::vector<std::string> held;  ///< calibrated parameters a case cannot vary, held at their fitted values
  /// With `bias_check:` or `coarse_grain_check:` (app/campaign/bias_check.h): the runs per design
  /// variant ("as the case", then the checks); variant k is design k / runs at run k % runs.
  /// Empty: no check.
  std::vector<std::string> bias_runs;
  double bias_tolerance_pct = 5;  ///< [%] a KPI that moves by less is not sensitive to the scaling
  /// What the check's runs vary: bias_check's stiffness and mass scaling, or coarse_grain_check's
  /// parcel size (every inlet's and particle set's coarse_grain).
  enum class Check { scalings, coarse_grain } check = Check::scalings;
  double coarse_grain = 1, finer_coarse_grain = 1;  ///< coarse_grain_check: the case's F and the check run's F' < F
  std::vector<std::string> check_kpis;  ///< coarse_grain_check.kpis: the KPIs reported (metrics.csv names); empty: all
  /// The design part of variant k's label ("" without a sweep).
  std::string design_label(size_t k) const;
  /// Short name of variant k: "v02".
  std::string name(size_t k) const;
  /// "spoon.radius=0.8, receiving_belt.speed=3.5"
  std::string label(size_t k) const;
};

/// Reads the `sweep:` section of a case and its `uncertainty:`, `bias_check:` or
/// `coarse_grain_check:` section (app/campaign/uncertainty.h, app/campaign/bias_check.h; throws
/// CaseError naming file, line and key); an empty plan (no variants) when the case has none.
SweepPlan read_sweep(const YAML::Node& root, const std::string& file);
/// The `sweep:` section alone.
SweepPlan read_design_sweep(const YAML::Node& root, const std::string& file);

/// The case of variant k: a deep copy of `root` with the sweep's values set and `sweep` removed.
/// Throws CaseError when a path cannot be set (a list index out of range, a scalar in the way).
YAML::Node variant_case(const YAML::Node& root, const SweepPlan& plan, size_t k);

struct SweepOptions {
  std::string case_path;
  std::string out;     ///< sweep folder; variants go to OUT/variants/NAME
  int threads = 0;     ///< per variant; 0: automatic
  double duration = -1;
  long long max_steps = -1;
  bool quiet = false;
};

/// Runs every variant as `demdesign run CASE --variant k --out ...` (posix_spawn, no shell), several
/// at once, with progress and time left; returns 0 when all succeeded (failed variants are
/// reported in the comparison, not fatal). Writes the comparison report into OUT/report.
/// Under MPI (collective): each rank runs the variants rank 0 hands it, rank 0 gathers the
/// results, writes the report and returns the status; the other ranks return 0.
int run_sweep(const SweepPlan& plan, const SweepOptions& options, std::ostream& log);

}  // namespace dem::app
