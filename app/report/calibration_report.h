// The calibration report: OUT/calibration_report.html, self-contained (images as data URIs,
// inline CSS), with the comparison tables and plots, residual patterns, the fit with its
// uncertainty, correlations and identifiability, the Fig. 5 contour maps, the diagnosis and the
// error ledger. Plots (PNG + TSV + gnuplot script) go to OUT/plots.
#pragma once

#include <string>
#include <vector>

#include "calibration/calibration.h"

namespace dem::report {

struct CalibrationReportInput {
  std::string title;             ///< "compare", "calibrate" or "diagnose" with the material name
  std::string material_path, measurements_path, version;
  const materials::MeasurementSet* measured = nullptr;
  const materials::Comparison* comparison = nullptr;        ///< compare
  const materials::CalibrationResult* calibration = nullptr;  ///< calibrate
  const materials::Diagnosis* diagnosis = nullptr;          ///< diagnose
  std::vector<materials::LedgerEntry> ledger;
  std::vector<std::string> images;  ///< renders of final states (PNG paths)
  double wall_seconds = 0;
  /// [-] The coarse_grain the virtual tests ran at (--coarse-grain; MaterialModel::coarse_grain):
  /// said beside the title, since a fit with parcels holds for cases run at that parcel size.
  double coarse_grain = 1.0;
};

/// Writes dir/calibration_report.html and dir/plots/*; returns the HTML path.
std::string write_calibration_report(const CalibrationReportInput& input, const std::string& dir);

}  // namespace dem::report
