// A calibrated material as a library file: what `calibrate` and `diagnose` write into their
// output folder, so that measurement -> material -> design is one chain of files. The file is a
// materials/NAME.yaml like the shipped ones (a case names it with `{library: NAME}`) plus a
// `calibration:` block with the fit it came from (src/case/calibration_record.h): the fitted
// parameters, their standard deviations and correlation, chi^2/n, the effects and the command,
// and the stiffness scaling and coarse_grain the virtual tests ran at.
#pragma once

#include <string>

#include "calibration/calibration.h"

namespace dem::materials {

struct CalibratedMaterialSource {
  std::string command;       ///< "calibrate" or "diagnose"
  std::string measurements;  ///< the measurement file
  std::string date;          ///< YYYY-MM-DD
  std::string note;          ///< one line for the header: "diagnose recommended epsd"
};

/// The library file of `fit.fitted` with its calibration. Throws std::invalid_argument for a
/// model a library file cannot hold (particle shape as clumps).
std::string calibrated_material_text(const CalibrationResult& fit, const CalibratedMaterialSource& source);

/// Writes it atomically (a temporary file, then a rename) to `path`.
void write_calibrated_material(const std::string& path, const CalibrationResult& fit, const CalibratedMaterialSource& source);

}  // namespace dem::materials
