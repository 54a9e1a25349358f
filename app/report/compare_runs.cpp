// Two finished runs compared figure by figure from their report tables (compare_runs.h).
#include "report/compare_runs.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <set>
#include <utility>

#include "case/spec.h"
#include "case/yaml_check.h"
#include "output/run.h"
#include "pages/html.h"
#include "pages/plot.h"
#include "report/report.h"

namespace dem::report {
namespace {

namespace fs = std::filesystem;
constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

using html::esc;
using html::num;

/// What a user is told when a folder is not a finished run's.
constexpr const char* kWhatARunHolds =
    "A run folder is the --out folder of a finished run (its case's output.directory): run_info.yaml, case.yaml and report/ with "
    "steady_state.csv and metrics.csv (and drives.csv, mesh_loads.csv for a case with meshes). Run the case first "
    "(demdesign CASE.yaml --out FOLDER), then compare the two folders";

bool starts(const std::string& text, const char* prefix) { return text.rfind(prefix, 0) == 0; }

// ---- CSV tables ----------------------------------------------------------------------------

/// The fields of one CSV line; a field in double quotes may hold commas ("" is a quote).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') fields.back() += '"', ++i;
    else if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) fields.emplace_back();
    else if (c != '\r') fields.back() += c;
  }
  return fields;
}

/// A CSV file read back: its header and its rows (comment lines and empty lines skipped).
struct CsvTable {
  std::string path;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<int> lines;  ///< each row's line number in the file, for errors

  /// Row r's cell in column `name` ("" beyond the row's end); throws CaseError naming the file
  /// when it has no such column.
  std::string text(std::size_t r, const std::string& name) const {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw CaseError(fmt::format("{}: no column '{}' (a report table of another version?)", path, name));
    const std::size_t c = static_cast<std::size_t>(it - header.begin());
    return c < rows[r].size() ? rows[r][c] : std::string();
  }
  /// Row r's cell `name` as a number ("" reads as NaN, as do "nan" and "inf" their values);
  /// throws CaseError naming file and line when it is not one.
  double number(std::size_t r, const std::string& name) const {
    const std::string cell = text(r, name);
    if (cell.empty()) return kNoValue;
    char* end = nullptr;
    const double value = std::strtod(cell.c_str(), &end);
    if (end != cell.c_str() + cell.size()) throw CaseError(fmt::format("{}:{}: {} '{}' is not a number", path, lines[r], name, cell));
    return value;
  }
};

CsvTable read_csv(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw CaseError(fmt::format("{}: cannot be read", path.string()));
  CsvTable table{path.string(), {}, {}, {}};
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    if (table.header.empty()) {
      table.header = csv_fields(line);
    } else {
      table.rows.push_back(csv_fields(line));
      table.lines.push_back(number);
    }
  }
  if (table.header.empty()) throw CaseError(fmt::format("{}: empty; a report table starts with a header line", path.string()));
  return table;
}

// ---- groups and units ----------------------------------------------------------------------

struct GroupName {
  FigureGroup group;
  const char* key;    ///< compare.csv's `group`
  const char* title;  ///< the page's heading
};
constexpr GroupName kGroups[] = {{FigureGroup::throughput, "throughput", "Throughput and outlets"},
                                 {FigureGroup::drives, "drives", "Drives"},
                                 {FigureGroup::loads, "loads", "Loads on the meshes"},
                                 {FigureGroup::wear, "wear", "Wear and liner life"},
                                 {FigureGroup::other, "other", "Other figures"}};

const char* group_key(FigureGroup group) {
  for (const GroupName& g : kGroups)
    if (g.group == group) return g.key;
  return "other";
}

/// A steady_state.csv series that mesh_loads.csv also holds ("force z on chute").
bool is_load_series(const std::string& name) {
  return (starts(name, "force ") || starts(name, "torque ")) && name.find(" on ") != std::string::npos;
}

/// The group of a steady_state.csv series, by the names report_analysis.cpp gives them.
FigureGroup series_group(const std::string& name) {
  for (const char* prefix : {"throughput", "outlet ", "flow through", "sensor ", "hold-up"})
    if (starts(name, prefix)) return FigureGroup::throughput;
  if (starts(name, "drive ")) return FigureGroup::drives;
  if (is_load_series(name)) return FigureGroup::loads;
  return FigureGroup::other;
}

/// The group of a metrics.csv name (docs/results.md lists them).
FigureGroup metric_group(const std::string& name) {
  for (const char* prefix :
       {"throughput", "outlet_", "sensor_", "spillage", "holdup", "blockage", "steady_from", "belt_capacity_", "belt_loading_"})
    if (starts(name, prefix)) return FigureGroup::throughput;
  for (const char* prefix : {"drive_", "power_"})
    if (starts(name, prefix)) return FigureGroup::drives;
  for (const char* prefix : {"force_", "liner_pressure_"})
    if (starts(name, prefix)) return FigureGroup::loads;
  for (const char* prefix : {"wear_", "liner_life_", "shear_power_max", "impact_power_max"})
    if (starts(name, prefix)) return FigureGroup::wear;
  return FigureGroup::other;
}

/// A metrics.csv name's unit, read from its ending (the unit ends every metric's name); longer
/// endings first, so "_m_s" is not read as seconds.
std::string metric_unit(const std::string& name) {
  static constexpr std::pair<const char*, const char*> kEndings[] = {
      {"_mm_per_Mt", "mm/Mt"}, {"_W_m2", "W/m²"}, {"_mm_yr", "mm/yr"}, {"_months", "months"}, {"_percent", "%"}, {"_kPa", "kPa"},
      {"_N_m", "N m"},         {"_t_h", "t/h"},   {"_m_s", "m/s"},     {"_pct", "%"},          {"_kg", "kg"},
      {"_W", "W"},             {"_N", "N"},       {"_J", "J"},         {"_s", "s"}};
  for (const auto& [ending, unit] : kEndings)
    if (name.ends_with(ending)) return unit;
  return "-";
}

// ---- reading a run folder ------------------------------------------------------------------

/// `folder` without "." segments and a trailing separator; made absolute when it names no
/// folder by itself ("." or "..").
fs::path clean(const std::string& folder) {
  fs::path p = fs::path(folder.empty() ? "." : folder).lexically_normal();
  if (!p.has_filename() && p.has_parent_path()) p = p.parent_path();
  if (p.empty() || p.filename() == "." || p.filename() == "..") p = fs::absolute(p).lexically_normal();
  if (!p.has_filename() && p.has_parent_path()) p = p.parent_path();
  return p;
}

/// Where a run's report tables and its inputs lie.
struct RunPlaces {
  fs::path run, report;
};

/// FOLDER/report of a run folder, or FOLDER when it is a report folder itself; throws CaseError
/// naming what is missing and what a run folder holds.
RunPlaces locate_run(const std::string& folder) {
  if (folder.empty()) throw CaseError(fmt::format("an empty name for a run folder. {}", kWhatARunHolds));
  const fs::path given = clean(folder);
  if (!fs::is_directory(given)) throw CaseError(fmt::format("{}: no such folder. {}", folder, kWhatARunHolds));
  const bool is_report = !fs::exists(given / "report") && fs::exists(given / "steady_state.csv");
  const RunPlaces places{is_report ? given.parent_path() : given, is_report ? given : given / "report"};
  for (const char* table : {"steady_state.csv", "metrics.csv"}) {
    if (fs::exists(places.report / table)) continue;
    const bool ran = fs::exists(places.run / "run_info.yaml") && !fs::exists(places.report);
    throw CaseError(fmt::format("{}: missing{}. {}", (places.report / table).string(),
                                ran ? fmt::format(" ({} holds a run without its report: run with --no-report, or stopped before its end?)", folder)
                                    : std::string(),
                                kWhatARunHolds));
  }
  return places;
}

/// Adds `figure` unless the run has a figure of that name already (the primary series may repeat
/// another: "kinetic energy" of a run with neither outlets nor sensors).
void add_figure(RunTables& run, RunFigure figure) {
  for (const RunFigure& f : run.figures)
    if (f.name == figure.name) return;
  run.figures.push_back(std::move(figure));
}

/// steady_state.csv: each series' mean over its own steady state with its standard error. The
/// drives' and loads' series are left to drives.csv and mesh_loads.csv where the run has them
/// (those are over the run's interval, as the report's tables give them).
void read_steady_state(RunTables& run, bool has_drives, bool has_loads) {
  const CsvTable t = read_csv(fs::path(run.report_folder) / "steady_state.csv");
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const std::string name = t.text(r, "series");
    if ((has_drives && starts(name, "drive ")) || (has_loads && is_load_series(name))) continue;
    add_figure(run, {name, t.text(r, "unit"), "steady_state.csv", series_group(name), t.number(r, "mean"), t.number(r, "std_error"),
                     t.number(r, "found") != 0});
  }
}

/// The steady_state.csv name of a drives.csv row (report_analysis.cpp, drive_series), so that a
/// run without drives.csv still matches by name.
std::string drive_figure_name(const std::string& drive, const std::string& kind, const std::string& quantity) {
  if (quantity == "pull") return "drive pull " + drive;
  if (quantity == "shaft_torque") return "drive torque " + drive;
  if (quantity == "power") return "drive power " + drive;
  if (quantity == "check_power") return (kind == "rotating_part" ? "drive T omega " : "drive F v ") + drive;
  return "drive " + quantity + " " + drive;
}

/// drives.csv: each drive's pull or shaft torque, power and check power over the run's interval.
void read_drives(RunTables& run) {
  const CsvTable t = read_csv(fs::path(run.report_folder) / "drives.csv");
  for (std::size_t r = 0; r < t.rows.size(); ++r)
    add_figure(run, {drive_figure_name(t.text(r, "drive"), t.text(r, "kind"), t.text(r, "quantity")), t.text(r, "unit"), "drives.csv",
                     FigureGroup::drives, t.number(r, "mean"), t.number(r, "std_error"), run.inputs.steady});
}

/// The steady_state.csv name of a mesh_loads.csv row: "force z on chute", "torque x on screw
/// about its motion origin".
std::string load_figure_name(const std::string& mesh, const std::string& component) {
  if (component.size() != 2 || (component[0] != 'f' && component[0] != 't')) return component + " on " + mesh;
  const bool force = component[0] == 'f';
  return fmt::format("{} {} on {}{}", force ? "force" : "torque", component[1], mesh, force ? "" : " about its motion origin");
}

/// mesh_loads.csv: each mesh's force and torque by component over the run's interval.
void read_mesh_loads(RunTables& run) {
  const CsvTable t = read_csv(fs::path(run.report_folder) / "mesh_loads.csv");
  for (std::size_t r = 0; r < t.rows.size(); ++r)
    add_figure(run, {load_figure_name(t.text(r, "mesh"), t.text(r, "component")), t.text(r, "unit"), "mesh_loads.csv", FigureGroup::loads,
                     t.number(r, "mean"), t.number(r, "std_error"), run.inputs.steady});
}

/// metrics.csv: means only (no standard errors); the run's steady flag and its words go to the
/// run's inputs.
std::vector<RunFigure> read_metric_figures(RunTables& run) {
  const RunMetrics metrics = read_metrics((fs::path(run.report_folder) / "metrics.csv").string());
  run.inputs.steady = metrics.steady, run.inputs.steady_text = metrics.steady_text;
  std::vector<RunFigure> figures;
  for (const auto& [name, value] : metrics.values)
    figures.push_back({name, metric_unit(name), "metrics.csv", metric_group(name), value, kNoValue, metrics.steady});
  return figures;
}

/// What the run was run from: run_info.yaml's set-up lines and the case as run (case.yaml).
void read_inputs(const fs::path& run_folder, RunInputs& in) {
  std::ifstream info(run_folder / "run_info.yaml");
  std::string line, completed, end_time;
  while (std::getline(info, line)) {
    if (starts(line, "case: ")) in.case_path = line.substr(6);
    else if (starts(line, "model_hash: ")) in.model_hash = line.substr(12);
    else if (starts(line, "software: ")) in.software = line.substr(10);
    else if (starts(line, "  completed: ")) completed = line.substr(13);
    else if (starts(line, "  time_s: ")) end_time = line.substr(10);
  }
  if (!end_time.empty())
    in.end_text = fmt::format("t = {:.6g} s, {}", std::strtod(end_time.c_str(), nullptr), completed == "true" ? "completed" : "did not reach its end");
  const fs::path record = run_folder / "case.yaml";
  if (!fs::exists(record)) return;
  in.case_record = record.string();
  std::ifstream text(record);
  if (std::getline(text, line) && starts(line, "# ")) in.case_header = line.substr(2);
}

// ---- what differs between the runs' inputs ---------------------------------------------------

/// "A", "B" or "A and B": the runs for which a statement holds.
std::string runs_where(bool a, bool b) { return a && b ? "A and B" : a ? "A" : "B"; }

/// Whether two YAML values are the same; scalars that read as numbers compare as numbers
/// (0.10 and 0.1 are one value).
bool same_value(const YAML::Node& a, const YAML::Node& b) {
  if (a.IsScalar() && b.IsScalar()) {
    const std::string& x = a.Scalar();
    const std::string& y = b.Scalar();
    char *end_x = nullptr, *end_y = nullptr;
    const double vx = std::strtod(x.c_str(), &end_x), vy = std::strtod(y.c_str(), &end_y);
    if (!x.empty() && !y.empty() && end_x == x.c_str() + x.size() && end_y == y.c_str() + y.size()) return vx == vy;
    return x == y;
  }
  return YAML::Dump(a) == YAML::Dump(b);
}

/// Appends the paths of the keys whose values differ between two YAML nodes: maps, and lists of
/// one length, are walked into (`depth` levels at most), with the paths a sweep uses
/// ("equipment.transfer_chute.spoon.radius", "inlets[0].mass_rate_tph").
void differing_keys(const YAML::Node& a, const YAML::Node& b, const std::string& path, int depth, std::vector<std::string>& out) {
  if (depth > 0 && a.IsMap() && b.IsMap()) {
    std::vector<std::string> keys;
    for (const auto& kv : a) keys.push_back(kv.first.Scalar());
    for (const auto& kv : b)
      if (std::find(keys.begin(), keys.end(), kv.first.Scalar()) == keys.end()) keys.push_back(kv.first.Scalar());
    for (const std::string& key : keys) {
      const std::string child = path.empty() ? key : path + "." + key;
      const YAML::Node x = a[key], y = b[key];
      if (!x || !y) out.push_back(child + (!x ? " (only in B)" : " (only in A)"));
      else differing_keys(x, y, child, depth - 1, out);
    }
    return;
  }
  if (depth > 0 && a.IsSequence() && b.IsSequence() && a.size() == b.size()) {
    for (std::size_t i = 0; i < a.size(); ++i) differing_keys(a[i], b[i], fmt::format("{}[{}]", path, i), depth - 1, out);
    return;
  }
  if (!same_value(a, b)) out.push_back(path.empty() ? "the whole case" : path);
}

/// The keys in which the cases as run (case.yaml) differ; a note when they cannot be compared
/// or are identical.
std::vector<std::string> differing_case_keys(const RunInputs& a, const RunInputs& b, std::vector<std::string>& notes) {
  if (a.case_record.empty() || b.case_record.empty()) {
    notes.push_back(fmt::format("{} no case.yaml (the case as run): the cases cannot be compared key by key",
                                runs_where(a.case_record.empty(), b.case_record.empty()) +
                                    (a.case_record.empty() && b.case_record.empty() ? " have" : " has")));
    return {};
  }
  std::vector<std::string> keys;
  try {
    differing_keys(read_yaml_file(a.case_record, "the case as run"), read_yaml_file(b.case_record, "the case as run"), "", 8, keys);
  } catch (const std::exception& e) {
    notes.push_back(fmt::format("the cases as run could not be compared: {}", e.what()));
    return {};
  }
  if (keys.empty())
    notes.push_back("the cases as run (case.yaml) are identical: the differences below are those of two runs of one design (mesh "
                    "files a case names are compared by their names, not their contents)");
  else
    notes.push_back(fmt::format("the cases as run (case.yaml) differ in {} key{}, listed below", keys.size(), keys.size() == 1 ? "" : "s"));
  return keys;
}

/// What differs between the runs' inputs besides their cases' keys: the model hash (which covers
/// the contact law, time step, gravity and plane walls; src/core/compile.cpp, physics_hash), the
/// case file, the software and whether each run reached a steady state.
std::vector<std::string> input_notes(const RunInputs& a, const RunInputs& b) {
  std::vector<std::string> notes;
  if (a.model_hash.empty() || b.model_hash.empty())
    notes.push_back(fmt::format("{}: no run_info.yaml with a model hash", runs_where(a.model_hash.empty(), b.model_hash.empty())));
  else if (a.model_hash != b.model_hash)
    notes.push_back(fmt::format("the contact law, time step, gravity or plane walls differ (model_hash {} in A, {} in B)", a.model_hash, b.model_hash));
  else
    notes.push_back(fmt::format("the same contact law, time step, gravity and plane walls (model_hash {}; meshes, inlets and equipment "
                                "are compared by the cases' keys)", a.model_hash));
  if (!a.case_path.empty() && !b.case_path.empty() && a.case_path != b.case_path)
    notes.push_back(fmt::format("A ran {}, B ran {}", a.case_path, b.case_path));
  if (!a.software.empty() && !b.software.empty() && a.software != b.software)
    notes.push_back(fmt::format("the software differs: A {}, B {}", a.software, b.software));
  if (!a.steady || !b.steady)
    notes.push_back(fmt::format("{} reached no steady state: its means are over the last third of the run and may still drift, so a z "
                                "there overstates what the runs can show",
                                runs_where(!a.steady, !b.steady)));
  return notes;
}

// ---- compare.csv ---------------------------------------------------------------------------

/// A CSV field: quoted when it holds a comma or a quote.
std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string comparison_csv(const RunComparison& c) {
  std::string csv = "group,figure,unit,source,a_mean,a_std_error,b_mean,b_std_error,difference,difference_std_error,z,change_pct,verdict,note\n";
  for (const FigureComparison& f : c.figures)
    csv += fmt::format("{},{},{},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.6g},{},{}\n", group_key(f.group), csv_cell(f.name),
                       csv_cell(f.unit), f.source, f.a, f.a_std_error, f.b, f.b_std_error, f.difference, f.difference_std_error, f.z,
                       f.change_pct, csv_cell(f.verdict), csv_cell(f.note));
  // Figures of one run only: that run's value, the other's cells empty.
  for (const auto& [figures, run] : {std::pair{&c.only_a, "A"}, std::pair{&c.only_b, "B"}})
    for (const RunFigure& f : *figures) {
      // a_mean,a_std_error or b_mean,b_std_error; difference to change_pct empty; the verdict.
      const std::string value = fmt::format("{:.9g},{:.9g}", f.mean, f.std_error), none = ",";
      const bool in_a = run[0] == 'A';
      csv += fmt::format("{},{},{},{},{},{},,,,,only in {},\n", group_key(f.group), csv_cell(f.name), csv_cell(f.unit), f.source,
                         in_a ? value : none, in_a ? none : value, run);
    }
  return csv;
}

// ---- the bar plot of z ---------------------------------------------------------------------

constexpr double kZClamp = 10;       ///< bars beyond this |z| are drawn to it and labelled so
constexpr std::size_t kPlotRows = 60;  ///< at most this many bars: the largest |z|

/// The figures in the page's order: by group, each group in A's order.
std::vector<const FigureComparison*> in_page_order(const RunComparison& c) {
  std::vector<const FigureComparison*> out;
  for (const GroupName& g : kGroups)
    for (const FigureComparison& f : c.figures)
      if (f.group == g.group) out.push_back(&f);
  return out;
}

/// The figures with a z, in page order; with more than kPlotRows, those with the largest |z|.
std::vector<const FigureComparison*> plotted(const RunComparison& c) {
  std::vector<const FigureComparison*> rows;
  for (const FigureComparison* f : in_page_order(c))
    if (!std::isnan(f->z)) rows.push_back(f);
  if (rows.size() <= kPlotRows) return rows;
  std::vector<const FigureComparison*> largest = rows;
  std::stable_sort(largest.begin(), largest.end(), [](auto* x, auto* y) { return std::abs(x->z) > std::abs(y->z); });
  largest.resize(kPlotRows);
  std::erase_if(rows, [&](auto* f) { return std::find(largest.begin(), largest.end(), f) == largest.end(); });
  return rows;
}

/// One bar per row k (from 1): k, its extent (from 0 to z, clamped) and 1 when |z| >= 2.
std::string z_plot_data(const std::vector<const FigureComparison*>& rows) {
  std::string data = "# row\tfrom\tto\tsignificant\n";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double z = std::clamp(rows[k]->z, -kZClamp, kZClamp);
    data += fmt::format("{}\t{:.6g}\t{:.6g}\t{}\n", k + 1, std::min(0.0, z), std::max(0.0, z), std::abs(rows[k]->z) >= kSignificantZ ? 1 : 0);
  }
  return data;
}

/// The y tic labels: each figure's name and unit at its row.
std::string z_plot_tics(const std::vector<const FigureComparison*>& rows) {
  std::string tics;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    std::string label = rows[k]->name.size() > 48 ? rows[k]->name.substr(0, 45) + "..." : rows[k]->name;
    label += fmt::format(" [{}]{}", rows[k]->unit, std::abs(rows[k]->z) > kZClamp ? fmt::format(" (|z| > {:g})", kZClamp) : "");
    tics += fmt::format("{}{} {}", k ? ", " : "", plot::gnuplot_string(label), k + 1);
  }
  return tics;
}

/// The gnuplot script of the bars: grey within two standard errors, blue beyond, with the
/// z = -2 and z = 2 lines dashed.
std::string z_plot_script(const std::vector<const FigureComparison*>& rows, const std::string& data, const std::string& png) {
  double reach = 3;
  for (const FigureComparison* f : rows) reach = std::max(reach, std::min(std::abs(f->z), kZClamp));
  const int width = 960, height = 140 + 20 * static_cast<int>(rows.size());  // [px]
  std::string s = fmt::format(
      "# demdesign plot: the difference B - A of each figure in standard errors\n# Redraw: cd into this folder and run `gnuplot {}`.\n"
      "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {{\n  set terminal pngcairo size {},{} noenhanced font 'DejaVu Sans,10'\n"
      "}} else {{\n  set terminal png size {},{} noenhanced\n}}\nset output {}\n"
      "set datafile separator tab\nset title 'B - A in standard errors of the difference' noenhanced\n"
      "set xlabel 'z = (B - A) / sqrt(se_A^2 + se_B^2)' noenhanced\nset ytics ({})\nset yrange [{:.1f}:0.3]\n"
      "set xrange [{:.3g}:{:.3g}]\nset grid xtics lc rgb '#dddddd'\nset key below noenhanced\nset border 3\nset tics nomirror\n"
      "set arrow from -2, graph 0 to -2, graph 1 nohead dashtype 2 lc rgb '#b2182b'\n"
      "set arrow from 2, graph 0 to 2, graph 1 nohead dashtype 2 lc rgb '#b2182b'\n",
      fs::path(png).replace_extension(".gp").string(), width, height, width, height, plot::gnuplot_string(png), z_plot_tics(rows),
      rows.size() + 0.7, -1.1 * reach, 1.1 * reach);
  // Only the kinds of bar the data has: gnuplot warns of a plot item with no points.
  const bool any_within = std::any_of(rows.begin(), rows.end(), [](auto* f) { return std::abs(f->z) < kSignificantZ; });
  const bool any_beyond = std::any_of(rows.begin(), rows.end(), [](auto* f) { return std::abs(f->z) >= kSignificantZ; });
  std::vector<std::string> items;
  const auto item = [&](int significant, const char* colour, const char* title) {
    items.push_back(fmt::format("{} using (($2+$3)/2):($4 == {} ? $1 : NaN):2:3:($1-0.35):($1+0.35) with boxxyerror "
                                "fillstyle solid 0.8 noborder lc rgb '{}' title '{}'",
                                plot::gnuplot_string(data), significant, colour, title));
  };
  if (any_within) item(0, "#9e9e9e", "|z| < 2: no difference the runs can show");
  if (any_beyond) item(1, "#2166ac", "|z| >= 2: B higher (z > 0) or lower (z < 0)");
  s += "plot " + items[0] + (items.size() > 1 ? ", \\\n     " + items[1] : std::string()) + "\n";
  return s;
}

/// Draws DIR/compare_z.png (data and script beside it); returns its <figure>, or a note why
/// there is none.
std::string z_plot_html(const RunComparison& c, const std::string& dir) {
  const std::vector<const FigureComparison*> rows = plotted(c);
  if (rows.empty()) return "<p class=\"missing\">No figure has a standard error in both runs: nothing to plot.</p>\n";
  const fs::path png = fs::absolute(fs::path(dir) / "compare_z.png");
  write_file_atomically(fs::path(png).replace_extension(".tsv").string(), z_plot_data(rows));
  write_file_atomically(fs::path(png).replace_extension(".gp").string(), z_plot_script(rows, "compare_z.tsv", "compare_z.png"));
  std::string message;
  if (!plot::run_gnuplot_script(fs::path(png).replace_extension(".gp").string(), png.string(), &message))
    return fmt::format("<p class=\"missing\">Plot not drawn: {}</p>\n", esc(message));
  const std::size_t with_z = std::count_if(c.figures.begin(), c.figures.end(), [](const FigureComparison& f) { return !std::isnan(f.z); });
  const std::string shown = rows.size() < with_z ? fmt::format(" The {} bars of the largest |z| of {} are shown.", rows.size(), with_z) : "";
  return fmt::format("<figure>{}<figcaption>The difference B &minus; A of each figure in standard errors of the difference (z); "
                     "the dashed lines are z = &plusmn;2.{} Figures from metrics.csv have no standard error and no bar. Data and "
                     "script: compare_z.tsv, compare_z.gp.</figcaption></figure>\n",
                     html::embed_image(png.string(), "z per figure"), shown);
}

// ---- compare.html --------------------------------------------------------------------------

/// "100.0 &plusmn; 3.0", or the value alone without a standard error.
std::string value_cell(double mean, double std_error) {
  return std::isnan(std_error) ? num(mean) : num(mean) + " &plusmn; " + num(std_error, 2);
}

/// The two runs side by side: folder, case, model, software, end and steady state.
std::string runs_table(const RunComparison& c) {
  const RunInputs &a = c.a.inputs, &b = c.b.inputs;
  const auto line = [](const char* what, const std::string& x, const std::string& y) {
    return html::row({what, x.empty() ? "&ndash;" : esc(x), y.empty() ? "&ndash;" : esc(y)});
  };
  std::string h = "<table>\n" + html::row({"", "A", "B"}, true);
  h += line("run folder", c.a.folder, c.b.folder);
  h += line("case", a.case_path, b.case_path);
  if (!a.case_header.empty() || !b.case_header.empty()) h += line("case as run", a.case_header, b.case_header);
  h += line("model hash", a.model_hash, b.model_hash);
  h += line("software", a.software, b.software);
  h += line("end", a.end_text, b.end_text);
  h += line("steady state", a.steady_text, b.steady_text);
  return h + "</table>\n";
}

/// What differs between the runs' inputs: the notes and the differing keys of their cases.
std::string inputs_section(const RunComparison& c) {
  std::string h = "<h2>The two runs</h2>\n" + runs_table(c) + "<ul>\n";
  for (const std::string& note : c.input_notes) h += "<li>" + esc(note) + "</li>\n";
  h += "</ul>\n";
  if (c.differing_keys.empty()) return h;
  h += "<h3>Keys of the cases that differ</h3>\n<p>";
  for (std::size_t k = 0; k < c.differing_keys.size(); ++k) h += (k ? ", " : "") + fmt::format("<code>{}</code>", esc(c.differing_keys[k]));
  return h + "</p>\n";
}

std::string reading_note() {
  return "<p class=\"note\">Each figure is a mean &plusmn; the standard error of that mean (batch means, so correlated samples do not "
         "shrink it): steady_state.csv over each series' own steady state, drives.csv and mesh_loads.csv over the run's interval. "
         "B &minus; A has the standard error &radic;(se<sub>A</sub>&sup2; + se<sub>B</sub>&sup2;), and z = (B &minus; A) / that "
         "error. With |z| &lt; 2 the runs cannot tell the two values apart (two runs of one design differ by that much about one "
         "time in twenty); beyond, B is higher or lower. Figures from metrics.csv carry a mean only: their difference is shown "
         "without a z, and whether it exceeds the runs' noise is not known.</p>\n";
}

/// One table of a group's figures; "" when the group has none.
std::string group_section(const RunComparison& c, const GroupName& g) {
  std::string rows;
  for (const FigureComparison& f : c.figures) {
    if (f.group != g.group) continue;
    const bool significant = !std::isnan(f.z) && std::abs(f.z) >= kSignificantZ;
    const std::string verdict = (significant ? "<b>" + esc(f.verdict) + "</b>" : esc(f.verdict)) +
                                (f.note.empty() ? "" : " <span class=\"note\">(" + esc(f.note) + ")</span>");
    rows += html::row({esc(f.name), esc(f.unit), value_cell(f.a, f.a_std_error), value_cell(f.b, f.b_std_error),
                       value_cell(f.difference, f.difference_std_error), std::isnan(f.change_pct) ? num(f.change_pct) : num(f.change_pct, 3) + " %",
                       num(f.z, 3), verdict});
  }
  if (rows.empty()) return "";
  return fmt::format("<h2>{}</h2>\n<table>\n", g.title) +
         html::row({"figure", "unit", "A", "B", "B &minus; A", "change", "z", "verdict"}, true) + rows + "</table>\n";
}

/// The figures one run has and the other lacks.
std::string only_section(const std::vector<RunFigure>& figures, const char* run, const char* other) {
  if (figures.empty()) return "";
  std::string h = fmt::format("<h3>Only in {} ({} figure{}; {} has none of these names)</h3>\n<table>\n", run, figures.size(),
                              figures.size() == 1 ? "" : "s", other);
  h += html::row({"figure", "unit", run, "table"}, true);
  for (const RunFigure& f : figures) h += html::row({esc(f.name), esc(f.unit), value_cell(f.mean, f.std_error), esc(f.source)});
  return h + "</table>\n";
}

std::string comparison_html(const RunComparison& c, const std::string& dir) {
  std::string h = html::head("Two runs compared - demdesign");
  h += fmt::format("<h1>Two runs compared</h1>\n<p class=\"meta\">A <code>{}</code> &middot; B <code>{}</code> &middot; {} &middot; "
                   "demdesign {}</p>\n",
                   esc(c.a.folder), esc(c.b.folder), esc(html::now_text()), esc(DEMDESIGN_VERSION));
  std::size_t differ = 0, with_z = 0;
  for (const FigureComparison& f : c.figures) with_z += !std::isnan(f.z), differ += !std::isnan(f.z) && std::abs(f.z) >= kSignificantZ;
  h += fmt::format("<div class=\"banner {}\">{} of {} figures with standard errors differ by 2 or more standard errors; {} more "
                   "figures carry a mean only.</div>\n",
                   differ ? "warn" : "good", differ, with_z, c.figures.size() - with_z);
  h += inputs_section(c) + "<h2>Differences in standard errors</h2>\n" + reading_note() + z_plot_html(c, dir);
  for (const GroupName& g : kGroups) h += group_section(c, g);
  if (!c.only_a.empty() || !c.only_b.empty())
    h += "<h2>Figures of one run only</h2>\n" + only_section(c.only_a, "A", "B") + only_section(c.only_b, "B", "A");
  return h + "<p class=\"note\">The same numbers: compare.csv.</p>\n</body></html>\n";
}

/// The summary a command prints: counts, the figures that differ most, the changed keys.
void print_summary(const RunComparison& c, const std::string& dir, std::ostream& log) {
  std::vector<const FigureComparison*> differ;
  for (const FigureComparison& f : c.figures)
    if (!std::isnan(f.z) && std::abs(f.z) >= kSignificantZ) differ.push_back(&f);
  std::stable_sort(differ.begin(), differ.end(), [](auto* x, auto* y) { return std::abs(x->z) > std::abs(y->z); });
  log << fmt::format("compared {} figures: {} differ by 2 standard errors or more; {} only in A, {} only in B\n", c.figures.size(),
                     differ.size(), c.only_a.size(), c.only_b.size());
  for (std::size_t k = 0; k < differ.size() && k < 10; ++k) {
    const FigureComparison& f = *differ[k];
    log << fmt::format("  {}: {:.4g} ± {:.2g} -> {:.4g} ± {:.2g} {} (z = {:.3g}, {})\n", f.name, f.a, f.a_std_error, f.b, f.b_std_error,
                       f.unit, f.z, f.verdict);
  }
  for (const std::string& note : c.input_notes) log << "  note: " << note << "\n";
  for (std::size_t k = 0; k < c.differing_keys.size() && k < 10; ++k) log << "  case key differs: " << c.differing_keys[k] << "\n";
  if (c.differing_keys.size() > 10) log << fmt::format("  ... and {} more keys (compare.html)\n", c.differing_keys.size() - 10);
  log << fmt::format("wrote {0}/compare.html, {0}/compare.csv\n", dir);
}

}  // namespace

const char* figure_group_title(FigureGroup group) {
  for (const GroupName& g : kGroups)
    if (g.group == group) return g.title;
  return "Other figures";
}

RunTables read_run_tables(const std::string& folder) {
  const RunPlaces places = locate_run(folder);
  RunTables run;
  run.folder = folder, run.report_folder = places.report.string();
  read_inputs(places.run, run.inputs);
  std::vector<RunFigure> metrics = read_metric_figures(run);
  const bool has_drives = fs::exists(places.report / "drives.csv"), has_loads = fs::exists(places.report / "mesh_loads.csv");
  read_steady_state(run, has_drives, has_loads);
  if (has_drives) read_drives(run);
  if (has_loads) read_mesh_loads(run);
  for (RunFigure& f : metrics) add_figure(run, std::move(f));
  return run;
}

FigureComparison compare_figure(const RunFigure& a, const RunFigure& b) {
  FigureComparison c;
  c.name = a.name, c.unit = a.unit, c.source = a.source, c.group = a.group;
  c.a = a.mean, c.a_std_error = a.std_error, c.b = b.mean, c.b_std_error = b.std_error;
  c.difference = b.mean - a.mean;
  if (std::isfinite(a.mean) && a.mean != 0) c.change_pct = 100 * c.difference / std::abs(a.mean);
  if (!a.steady || !b.steady) c.note = runs_where(!a.steady, !b.steady) + " not steady";
  if (a.unit != b.unit) {
    c.verdict = fmt::format("not compared: A in {}, B in {}", a.unit, b.unit);
  } else if (!std::isfinite(a.mean) || !std::isfinite(b.mean)) {
    c.verdict = "no finite value in " + runs_where(!std::isfinite(a.mean), !std::isfinite(b.mean));
  } else if (std::isnan(a.std_error) || std::isnan(b.std_error)) {
    c.verdict = "mean only (no standard error): the difference alone";
  } else {
    c.difference_std_error = std::sqrt(a.std_error * a.std_error + b.std_error * b.std_error);
    // Two exact figures (no spread in either run) differ with certainty when they differ at all.
    c.z = c.difference_std_error > 0 ? c.difference / c.difference_std_error
          : c.difference == 0        ? 0.0
                                     : std::copysign(std::numeric_limits<double>::infinity(), c.difference);
    c.verdict = std::abs(c.z) < kSignificantZ ? "no difference the runs can show" : c.z > 0 ? "B higher" : "B lower";
  }
  return c;
}

RunComparison compare_runs(RunTables a, RunTables b) {
  RunComparison out;
  std::map<std::string, const RunFigure*> in_b;
  for (const RunFigure& f : b.figures) in_b.emplace(f.name, &f);
  std::set<std::string> in_a;
  for (const RunFigure& f : a.figures) {
    in_a.insert(f.name);
    const auto match = in_b.find(f.name);
    if (match == in_b.end()) out.only_a.push_back(f);
    else out.figures.push_back(compare_figure(f, *match->second));
  }
  for (const RunFigure& f : b.figures)
    if (!in_a.count(f.name)) out.only_b.push_back(f);
  out.input_notes = input_notes(a.inputs, b.inputs);
  out.differing_keys = differing_case_keys(a.inputs, b.inputs, out.input_notes);
  out.a = std::move(a), out.b = std::move(b);
  return out;
}

std::string default_compare_folder(const std::string& a, const std::string& b) {
  const fs::path pa = clean(a), pb = clean(b);
  const std::string name = fmt::format("compare_{}_{}", pa.filename().string(), pb.filename().string());
  return pa.has_parent_path() ? (pa.parent_path() / name).string() : name;
}

void write_compare_report(const RunComparison& comparison, const std::string& dir) {
  fs::create_directories(dir);
  write_file_atomically((fs::path(dir) / "compare.csv").string(), comparison_csv(comparison));
  write_file_atomically((fs::path(dir) / "compare.html").string(), comparison_html(comparison, dir));
}

int compare_runs_command(const std::string& a, const std::string& b, const std::string& out, std::ostream& log) {
  RunTables run_a = read_run_tables(a);
  RunTables run_b = read_run_tables(b);
  const std::string dir = out.empty() ? default_compare_folder(a, b) : out;
  const RunComparison comparison = compare_runs(std::move(run_a), std::move(run_b));
  write_compare_report(comparison, dir);
  print_summary(comparison, dir, log);
  return 0;
}

}  // namespace dem::report
