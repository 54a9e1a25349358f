// Which experiment would separate two models that explain the measurements equally well (the
// source paper's Fig. 5 problem): the two fitted models are simulated on variants of the file's
// experiments (the quantity each varies, moved beyond its range) and on a standard set-up of each
// test the file lacks, and the experiments are ranked by how far apart the two predictions lie
// in units of a lab's repeatability and the simulations' own noise.
#pragma once

#include <string>
#include <vector>

#include "calibration.h"

namespace dem::materials {


/// Candidate experiments that could separate model a from model b: variants of `measured`'s
/// experiments and standard set-ups of the tests it lacks (sized from the particles' diameter).
std::vector<Experiment> separating_candidates(const MaterialModel& model, const MeasurementSet& measured);

/// The candidates simulated with both models (options.signature_replicas packings each), ranked
/// by separation, largest first.
std::vector<Separator> separating_experiments(const MaterialModel& a, const std::string& name_a, const MaterialModel& b,
                                              const std::string& name_b, const MeasurementSet& measured, const CalibrationOptions& options);

}  // namespace dem::materials
