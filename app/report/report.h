// The engineering report of a run (throughput, spillage, blockage, power, wear, belt loading,
// all at a steady state found from the data) and of a design sweep (variants ranked by
// weighted criteria). Each report is one self-contained HTML file (images as base64 data URIs,
// inline CSS, no links; the run report's only scripts are the inlined 3D view, app/pages/viewer3d.h)
// beside the CSV files and plot scripts it was made from.
#pragma once

#include <cstddef>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "case/spec.h"
#include "core/model.h"
#include "core/state.h"
#include "statistics/diagnostics.h"
#include "statistics/events.h"
#include "pages/viewer3d.h"

namespace dem::report {

/// An image made by the caller (flow render, wear map), embedded in the report.
struct ImageRef {
  std::string title, path, caption;
};

/// A liner's own pressure map, the caller's render of one mesh (app/pages/flow_images.h,
/// render_mesh_field), shown in the Liner pressure section with the mesh's peak pressure.
struct LinerMap {
  std::string mesh;  ///< the mesh's name, as in the liner pressure table
  std::string path;  ///< the PNG
};

/// The liner of a mesh as the wear analysis reads it: what it is, how thick, and the volume it
/// loses per joule by sliding and by impact (case/liner_materials.cpp has the laws and sources).
struct Liner {
  std::string material;  ///< key of the liner-material table; "" when only a coefficient is given
  std::string origin;    ///< the case key it came from: "wear.liners.spoon", "wear_coefficients.default"
  double thickness = 0;  ///< [m] wearable thickness; 0 when not given (no life)
  double sliding_coefficient = std::numeric_limits<double>::quiet_NaN();  ///< [m^3/J] per friction work; NaN: none
  double impact_coefficient = std::numeric_limits<double>::quiet_NaN();   ///< [m^3/J] per normal impact energy; NaN: none
};

struct RunReportInput {
  const Model* model = nullptr;
  const State* state = nullptr;  ///< final state; state->records give the wear inputs
  std::vector<Scalars> scalars;  ///< rows over the run, time ascending
  std::string case_path, case_text, version;
  double wall_seconds = 0;  // [s] run wall time
  std::vector<ImageRef> images;
  /// Per liner its own pressure map: a gallery under the liner pressure table (rejected: among
  /// `images`, whose section comes last, far from the table the maps explain).
  std::vector<LinerMap> liner_maps;
  /// Per mesh name: its liner (report/report_wear.h, liners_for, resolves them from a case).
  std::map<std::string, Liner> liners;
  /// Per mesh name not in `liners`: a sliding wear coefficient [m^3/J] (wear volume per friction
  /// work) alone, as a liner with no material, thickness or impact wear.
  std::map<std::string, double> wear_coefficient;
  double operating_hours_per_year = kDefaultOperatingHoursPerYear;  ///< [h] the wear rates and lives are at
  bool operating_hours_given = false;  ///< false: the default, stated in the report as an assumption
  double records_from = 0;  // [s] when the wall records started accumulating
  /// Names of the outlets material is meant to leave by; empty: all outlets. Mass into any other
  /// outlet counts as spillage.
  std::vector<std::string> outlet_intended;
  /// The case's sensors (in the order of Scalars::sensors) and design values (name with unit ->
  /// value, e.g. "receiving_belt_speed_m_s", "design_capacity_t_h"): model.sensors and
  /// model.design, or edited copies.
  std::vector<SensorSpec> sensors;
  std::vector<std::pair<std::string, double>> design;
  viewer3d::Options viewer;  ///< the interactive 3D view (three.js to inline, particle limit)
  std::vector<RunEvent> events;  ///< the run's first arrivals (RunSummary::events)
  std::string stopped;  ///< why the run stopped before its end (RunSummary::stopped); "" when it reached it
};

/// Key numbers of a run, to rank sweep variants. Names carry their unit ("throughput_t_h").
struct RunMetrics {
  std::vector<std::pair<std::string, double>> values;
  /// Metric -> the standard error of its value, for the metrics that are a mean over the run's
  /// records (batch means: statistics/steady_state.h average_over, and report_analysis.cpp
  /// weighted_over for a sensor's mass-weighted figures): the noise a check of the same case at
  /// another modelling choice measures a shift against (app/campaign/bias_check.h). Totals,
  /// peaks and derived figures have none.
  std::map<std::string, double> std_errors;
  bool steady = false;
  std::string steady_text;  ///< "steady from 1.2 s to 4 s (outflow)" or why not
  /// The value named `name`; NaN when absent.
  double get(const std::string& name) const;
  /// The standard error of `metric`'s value [its unit]; NaN when it has none.
  double std_error(const std::string& metric) const;
  /// The run's own standard deviation of `metric` ("throughput_t_h" -> "throughput_std_t_h",
  /// otherwise METRIC_std); NaN when the report gives none.
  double noise(const std::string& metric) const;
};

/// Writes report.html, plots (PNG + TSV + gnuplot script), steady_state.csv, wear_hotspots.csv
/// and metrics.csv into report_dir (created). A missing gnuplot is reported in the HTML in
/// place of each plot. Throws std::invalid_argument without a model or state, std::runtime_error
/// when a file cannot be written.
RunMetrics write_run_report(const RunReportInput& input, const std::string& report_dir);

/// metrics.csv: `name,value,std_error` rows (std_error empty where the metric has none), a
/// `steady` row (1/0) and a `# steady_text: ...` line. Read back, files of `name,value` rows are
/// accepted too.
void write_metrics(const RunMetrics& metrics, const std::string& path);
/// Reads metrics.csv; throws std::runtime_error naming the file when it cannot be read.
RunMetrics read_metrics(const std::string& path);
/// The same from the text of a metrics.csv; `source` names it in errors (source:line: ...).
RunMetrics parse_metrics(const std::string& text, const std::string& source);

/// One design variant of a sweep.
struct SweepVariant {
  std::string name;
  std::vector<std::pair<std::string, std::string>> parameters;  ///< parameter -> value as written
  RunMetrics metrics;
  std::string image_path;   ///< one image, the same camera for every variant ("" when none)
  std::string report_path;  ///< the variant's report.html, shown as a relative path (not a link)
  bool ok = true;
  std::string message;      ///< why it failed
};

/// A criterion for ranking: a metric to minimise or maximise, with a weight.
struct Criterion {
  std::string metric;
  bool maximise = false;
  double weight = 1.0;
};

struct SweepReportInput {
  std::string title, case_path, version;
  std::vector<SweepVariant> variants;
  std::vector<Criterion> criteria;
  std::string extra_html;  ///< a further section after the ranking (the calibration uncertainty)
};

/// Ranking rule (normalised weighted score): for each criterion, over the variants that ran,
/// s = (v - worst) / (best - worst) in [0, 1] (1 for all when every value is equal); a variant
/// without the metric, or with a non-finite value, scores 0 on it. score = sum(w s) / sum(w).
/// Rank by score, highest first (ties keep the sweep order); failed variants come last with
/// score NaN. Non-steady variants are ranked too, and marked.
struct Ranked {
  std::size_t variant = 0;  ///< index into SweepReportInput::variants
  double score = 0;
  std::vector<double> criterion_scores;  ///< s per criterion
};
std::vector<Ranked> rank_variants(const SweepReportInput& input);

/// Writes sweep.html (self-contained: comparison table, ranking, images side by side) and
/// ranking.csv into dir.
void write_sweep_report(const SweepReportInput& input, const std::string& dir);

}  // namespace dem::report
