// Design numbers with the calibration's uncertainty: a case with an `uncertainty:` section runs
// at parameter sets drawn from the calibration of each calibrated library material it uses (the
// `calibration:` block that `demdesign calibrate` / `diagnose` write,
// src/case/calibration_record.h), as a sweep runs its variants, and reports every KPI of
// metrics.csv as a median with a 90 % band over the samples. With a `sweep:` too, every design
// variant runs at the same parameter sets, and the variants are compared sample by sample: the
// probability that one beats another.
//
//   uncertainty:
//     samples: 16     # parameter sets per design variant (space-filling: a Latin hypercube)
//     seed: 1         # of the draw; the same seed gives the same parameter sets
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "report/report.h"
#include "campaign/sweep.h"

namespace dem::app {

/// Adds the `uncertainty:` section of `root` to `plan` (after read_sweep has read `sweep:`): every
/// design variant is repeated once per parameter set, and the calibrated parameters become key
/// paths `materials.NAME.KEY`. Throws CaseError naming file, line and key when the section is
/// wrong or no material of the case carries a calibration.
void add_uncertainty(SweepPlan& plan, const YAML::Node& root, const std::string& file);

/// A KPI over the parameter sets of one design variant.
struct KpiBand {
  std::string design;  ///< the design variant's label ("" without a sweep)
  std::string metric;
  double median = 0, p05 = 0, p95 = 0;
  double run_noise = 0;  ///< median over the samples of the run's own standard deviation (METRIC_std), NaN when none
  int samples = 0;       ///< samples that ran
};

/// P(design a beats design b on a criterion), paired by parameter set.
struct Beats {
  std::string metric;
  std::string a, b;
  double probability = 0;  ///< of the samples both ran; ties count one half
  int pairs = 0;
};

struct UncertaintySummary {
  std::vector<KpiBand> bands;
  std::vector<Beats> beats;
  std::string html;  ///< a section for the sweep report
};

/// The bands and, with design variants and criteria, the pairwise probabilities; writes
/// uncertainty.csv (and beats.csv) into `dir`.
UncertaintySummary summarise_uncertainty(const SweepPlan& plan, const std::vector<report::SweepVariant>& variants,
                                         const std::vector<report::Criterion>& criteria, const std::string& dir);

}  // namespace dem::app
