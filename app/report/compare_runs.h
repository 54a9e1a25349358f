// Two finished runs side by side: `demdesign compare-runs A B [--out DIR]`. Each run's report
// tables are read back (report/steady_state.csv, drives.csv, mesh_loads.csv: a mean and its
// standard error; metrics.csv: a mean only), the figures are matched by name, and each is given
// as A ± se, B ± se, the difference B - A with its standard error sqrt(se_A^2 + se_B^2) and the
// difference in standard errors z. What the runs were run from (run_info.yaml, case.yaml) is
// compared too, so a page says what changed between them. Writes DIR/compare.html (one table
// per group, a bar plot of z) and DIR/compare.csv.
// Rejected alternative: re-reading scalars.csv and recomputing every statistic. The report's
// tables are what a user saw and ranked by; recomputing would need the case and the models of
// both runs, and could disagree with the reports it compares.
#pragma once

#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

namespace dem::report {

/// The groups of the comparison page, in the order they are shown.
enum class FigureGroup { throughput, drives, loads, wear, other };

/// "Throughput and outlets", "Drives", "Loads on the meshes", "Wear and liner life", "Other figures".
const char* figure_group_title(FigureGroup group);

/// One figure of a run's report: a steady-state mean with its standard error (steady_state.csv,
/// drives.csv, mesh_loads.csv) or a mean only (metrics.csv: std_error NaN).
struct RunFigure {
  std::string name;    ///< "outlet bin", "drive pull belt", "force z on chute", "power_total_W"
  std::string unit;    ///< "t/h", "N", "N m", "W", "-"
  std::string source;  ///< the table it came from: "steady_state.csv"
  FigureGroup group = FigureGroup::other;
  double mean = std::numeric_limits<double>::quiet_NaN();       ///< [unit]
  double std_error = std::numeric_limits<double>::quiet_NaN();  ///< [unit] of the mean; NaN: a mean only
  bool steady = true;  ///< false: its series (or the run) reached no steady state
};

/// What a run was run from, read from its folder (run_info.yaml, case.yaml, metrics.csv).
struct RunInputs {
  std::string case_path;    ///< run_info.yaml `case:`; "" when the file is missing
  std::string model_hash;   ///< run_info.yaml `model_hash:` (hex); "" when missing
  std::string software;     ///< run_info.yaml `software:`
  std::string end_text;     ///< "t = 4 s, completed", "t = 1.2 s, did not reach its end", or ""
  std::string case_record;  ///< path of OUT/case.yaml, the case as run; "" when missing
  std::string case_header;  ///< its first line when a comment ("# v03 of cases/chute.yaml: ..."), else ""
  bool steady = false;      ///< metrics.csv `steady`
  std::string steady_text;  ///< metrics.csv `# steady_text:`
};

/// A run's report tables, read back.
struct RunTables {
  std::string folder;         ///< the run folder as given
  std::string report_folder;  ///< FOLDER/report (or FOLDER itself when it is a report folder)
  RunInputs inputs;
  std::vector<RunFigure> figures;  ///< in the order of the tables, each name once
};

/// Reads a run folder's report tables (report/steady_state.csv and report/metrics.csv required;
/// report/drives.csv and report/mesh_loads.csv when written) and what the run was run from.
/// A report folder itself (holding steady_state.csv) is accepted too. Throws CaseError naming
/// the folder or file that is missing, what a run folder must hold, and how to make one.
RunTables read_run_tables(const std::string& folder);

/// One figure of both runs compared.
struct FigureComparison {
  std::string name, unit, source;
  FigureGroup group = FigureGroup::other;
  double a = 0, a_std_error = 0, b = 0, b_std_error = 0;  ///< [unit]; std errors NaN for a mean only
  double difference = 0;  ///< [unit] B - A
  double difference_std_error = std::numeric_limits<double>::quiet_NaN();  ///< [unit] sqrt(se_A^2 + se_B^2); NaN: a mean only
  double z = std::numeric_limits<double>::quiet_NaN();  ///< difference / its std error [-]; NaN: a mean only
  double change_pct = std::numeric_limits<double>::quiet_NaN();  ///< [%] 100 (B - A) / |A|; NaN when A is 0
  std::string verdict;  ///< "B higher", "B lower", "no difference the runs can show", or why there is no z
  std::string note;     ///< "A not steady", ... ("" when nothing to add)
};

/// |z| below this is a difference the runs' noise can make: about 95 % of differences between
/// two runs of one design fall inside it.
constexpr double kSignificantZ = 2.0;

/// Compares one figure of both runs: B - A, its standard error, z and the verdict.
FigureComparison compare_figure(const RunFigure& a, const RunFigure& b);

/// Two runs compared figure by figure.
struct RunComparison {
  RunTables a, b;
  std::vector<FigureComparison> figures;  ///< the figures of both runs, in A's order
  std::vector<RunFigure> only_a, only_b;  ///< figures one run has and the other lacks
  /// What differs between the runs' inputs, in words ("the models differ: model_hash ... and ...").
  std::vector<std::string> input_notes;
  /// Keys of the cases as run (case.yaml) whose values differ, as paths:
  /// "simulation.duration", "equipment.transfer_chute.spoon.radius", "inlets[0].mass_rate_tph".
  std::vector<std::string> differing_keys;
};

/// Matches the figures of two runs by name and compares them and their inputs.
RunComparison compare_runs(RunTables a, RunTables b);

/// The default output folder: beside A, named compare_NAMEA_NAMEB (out/chute and out/chute_v2
/// give out/compare_chute_chute_v2).
std::string default_compare_folder(const std::string& a, const std::string& b);

/// Writes DIR/compare.html (self-contained: the runs' inputs, a bar plot of z when gnuplot is
/// installed, one table per group, the figures of one run only) and DIR/compare.csv, each
/// atomically; the plot's PNG, data and script as DIR/compare_z.*.
void write_compare_report(const RunComparison& comparison, const std::string& dir);

/// `demdesign compare-runs A B [--out DIR]`: reads, compares, writes and prints a summary to
/// `log`; returns the exit status. Throws CaseError for a missing run folder or table.
int compare_runs_command(const std::string& a, const std::string& b, const std::string& out, std::ostream& log);

}  // namespace dem::report
