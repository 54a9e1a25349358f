// Which experiment would separate two models that explain the measurements equally well (the
// source paper's Fig. 5 problem): the two fitted models are simulated on variants of the file's
// experiments (the quantity each varies, moved beyond its range) and on a standard set-up of each
// test the file lacks, and the experiments are ranked by how far apart the two predictions lie
// in units of a lab's repeatability and the simulations' own noise. Within a budget the most
// promising candidates are simulated first: the standard set-ups, then the variants of the
// experiments on which the two fitted models already disagree most.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "calibration/calibration.h"

namespace dem::materials {


/// Candidate experiments that could separate model a from model b: variants of `measured`'s
/// experiments and standard set-ups of the tests it lacks (sized from the particles' diameter).
/// The standard set-ups come first, then the variants of the experiments on which the two models
/// lie furthest apart (`apart`, experiment id -> sigma; see apart_by_experiment).
std::vector<Experiment> separating_candidates(const MaterialModel& model, const MeasurementSet& measured,
                                              const std::map<std::string, double>& apart = {});

/// Which candidates to simulate first, and how many at most.
struct SeparationPlan {
  /// How far apart the two fitted models already lie on each of the file's experiments [sigma]
  /// (experiment id -> separation): the variants of the experiment they already disagree on most
  /// are simulated first, after the standard set-ups of the tests the file lacks.
  std::map<std::string, double> apart;
  int most = -1;  ///< candidates simulated at most; all when negative
};

/// What the search found and what it left untried.
struct SeparationSearch {
  std::vector<Separator> found;   ///< ranked by separation, largest first
  int candidates = 0;             ///< candidates there were
  std::vector<std::string> untried;  ///< their ids, beyond plan.most
};

/// How far apart two fitted models lie on each experiment of their comparisons [sigma]: the
/// largest |a - b| / sqrt(sigma_a^2 + sigma_b^2 + sigma_measured^2) over its terms.
std::map<std::string, double> apart_by_experiment(const Comparison& a, const Comparison& b);

/// The candidates simulated with both models (options.signature_replicas packings each), in the
/// plan's order and as many as it allows.
SeparationSearch separating_experiments(const MaterialModel& a, const std::string& name_a, const MaterialModel& b, const std::string& name_b,
                                        const MeasurementSet& measured, const CalibrationOptions& options, const SeparationPlan& plan = {});

}  // namespace dem::materials
