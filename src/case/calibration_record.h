// The `calibration:` block of a calibrated library material (written by `demdesign calibrate` and
// `diagnose`): read with every key checked, and turned into parameter sets drawn from the fit.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>
#include <vector>

#include "case/spec.h"

namespace dem {

class MapReader;

/// Reads `node` (the value of `calibration:` in `file`). Throws CaseError naming file, line and
/// key when a list's length does not match `parameters`, a sigma is negative, or the correlation
/// is not symmetric with a unit diagonal, entries in [-1, 1] and positive semi-definite.
CalibrationRecord read_calibration_record(const YAML::Node& node, const std::string& file);

/// `count` parameter sets drawn from the record's normal posterior (value, sigma, correlation),
/// space-filling: a Latin hypercube in the standard normal space (one draw per stratum of each
/// parameter, strata paired at random with `seed`) mapped through the correlation's Cholesky
/// factor. Each set is clipped to `ranges` (min, max per parameter; empty: no clipping).
/// [k][j] = parameter j of set k.
std::vector<std::vector<double>> posterior_samples(const CalibrationRecord& record, int count, std::uint64_t seed,
                                                   const std::vector<std::pair<double, double>>& ranges = {});

}  // namespace dem
