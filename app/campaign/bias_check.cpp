// The checks of a case's modelling shortcuts (bias_check.h): reading `bias_check:` and
// `coarse_grain_check:` into the runs of a sweep plan, and judging every KPI of those runs.
#include "campaign/bias_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "case/spec.h"
#include "case/yaml_check.h"
#include "core/coarse_grain.h"
#include "model/library.h"
#include "pages/html.h"
#include "output/run.h"
#include "report/compare_runs.h"

namespace dem::app {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Not a design KPI: a run's own noise, when its steady state began, its kinetic energy (the
/// steady-state detector's series, near zero in a bed at rest).
bool is_noise(const std::string& metric) {
  return metric.find("_std") != std::string::npos || metric == "steady_from_s" || metric == "kinetic_energy_J";
}

bool ends_with(const std::string& s, const std::string& end) {
  return s.size() >= end.size() && s.compare(s.size() - end.size(), end.size(), end) == 0;
}

/// The smallest shift that can matter for a KPI whose value may sit near zero: a share already in
/// per cent moves by `tolerance` percentage points; a speed by 1 cm/s. 0: relative only.
double absolute_floor(const std::string& metric, double tolerance_pct) {
  if (ends_with(metric, "_pct")) return tolerance_pct;
  if (ends_with(metric, "_m_s")) return 0.01;
  return 0.0;
}

/// The case as it runs without its sweep and checks, parsed (its scalings, its coarse_grain).
CaseSpec plain_case(const YAML::Node& root, const std::string& file) {
  YAML::Node plain = YAML::Clone(root);
  for (const char* section : {"sweep", "bias_check", "coarse_grain_check"}) plain.remove(std::string(section));
  return parse_case_node(plain, file, materials::library_lookup());
}

/// Every design variant of `plan` repeated once per run of a check: run r appends `runs[r]`, one
/// value per path the caller appended to plan.paths. `key` names the section's key a plan of
/// more than kMostSweepVariants runs is refused at.
void repeat_designs(SweepPlan& plan, const std::vector<std::vector<YAML::Node>>& runs, const MapReader& map, const std::string& key) {
  const std::vector<std::vector<YAML::Node>> designs = plan.variants.empty() ? std::vector<std::vector<YAML::Node>>{{}} : plan.variants;
  plan.variants.clear();
  for (const auto& design : designs)
    for (const auto& values : runs) {
      std::vector<YAML::Node> row = design;
      row.insert(row.end(), values.begin(), values.end());
      plan.variants.push_back(std::move(row));
    }
  if (plan.variants.size() > kMostSweepVariants)
    map.fail(key, fmt::format("makes {} runs ({} design variants x {} runs); at most {}", plan.variants.size(), designs.size(), runs.size(),
                              kMostSweepVariants));
}

/// coarse_grain_check.kpis: a non-empty list of metric names; empty when the key is absent.
std::vector<std::string> read_kpis(MapReader& map) {
  std::vector<std::string> kpis;
  const YAML::Node list = map.node("kpis");
  if (!list) return kpis;
  const std::string valid = "must be a non-empty list of KPI names of the run report's metrics.csv (docs/results.md), e.g. "
                            "[throughput_t_h, power_total_W]; leave it out to check every KPI";
  if (!list.IsSequence() || list.size() == 0) map.fail("kpis", valid);
  for (const YAML::Node& k : list) {
    if (!k.IsScalar() || k.Scalar().empty()) map.fail("kpis", valid);
    kpis.push_back(k.Scalar());
  }
  return kpis;
}

/// "particles[0] (case.yaml:12:5)": the first inlet or particle set, whose coarse_grain is the case's.
std::string first_source(const CaseSpec& spec) {
  if (!spec.particles.empty()) return fmt::format("particles[0] ({})", spec.particles[0].location.str());
  if (!spec.inlets.empty()) return fmt::format("inlets[0] ({})", spec.inlets[0].location.str());
  return "no inlet or particle set";
}

}  // namespace

void add_bias_check(SweepPlan& plan, const YAML::Node& root, const std::string& file) {
  MapReader map(root["bias_check"], file, "bias_check");
  if (root["uncertainty"])
    map.fail("stiffness_factor", "a case runs either `uncertainty:` or `bias_check:`; check the scalings first, then draw the samples");
  if (root["coarse_grain_check"])
    map.fail("stiffness_factor", "a case runs one check at a time, `bias_check:` or `coarse_grain_check:`; check the parcel size in a "
                                 "copy of the case");
  const double stiffness_factor = map.number("stiffness_factor", 4.0, 1.01, 1e4, "-");
  const double mass_factor = map.number("mass_factor", 4.0, 1.01, 1e6, "-");
  const double duration = map.has("duration") ? map.required_number("duration", 1e-9, 1e6, "s") : -1.0;
  plan.bias_tolerance_pct = map.number("tolerance_pct", 5.0, 0.01, 100.0, "%");
  map.finish();
  const CaseSpec spec = plain_case(root, file);
  const double stiffness = spec.simulation.stiffness_scaling, mass = spec.simulation.mass_scaling;
  // The runs of the check: the case as it is, stiffer particles, and lighter ones when scaled.
  struct Run {
    std::string label;
    double stiffness, mass;
  };
  std::vector<Run> runs = {{"as the case", stiffness, mass}, {fmt::format("stiffness x {:g}", stiffness_factor), stiffness * stiffness_factor, mass}};
  if (mass > 1.0) {
    const double lighter = std::max(1.0, mass / mass_factor);
    runs.push_back({fmt::format("mass scaling {:g} -> {:g}", mass, lighter), stiffness, lighter});
  }
  std::vector<std::vector<YAML::Node>> values;
  for (const Run& r : runs) {
    values.push_back({YAML::Node(r.stiffness), YAML::Node(r.mass)});
    if (duration > 0) values.back().push_back(YAML::Node(duration));
  }
  repeat_designs(plan, values, map, "stiffness_factor");
  plan.paths.push_back("simulation.stiffness_scaling");
  plan.paths.push_back("simulation.mass_scaling");
  if (duration > 0) plan.paths.push_back("simulation.duration");
  plan.check = SweepPlan::Check::scalings;
  plan.bias_runs.clear();
  for (const Run& r : runs) plan.bias_runs.push_back(r.label);
}

void add_coarse_grain_check(SweepPlan& plan, const YAML::Node& root, const std::string& file) {
  MapReader map(root["coarse_grain_check"], file, "coarse_grain_check");
  if (root["uncertainty"])
    map.fail("finer", "a case runs either `uncertainty:` or `coarse_grain_check:`; check the parcel size first, then draw the samples");
  const double finer = map.required_number("finer", 1.0, kMostCoarseGrain, "-");
  const std::vector<std::string> kpis = read_kpis(map);
  const double duration = map.number("duration", 0.0, 1e-9, 1e6, "s");  // 0 (absent): the case's own duration
  plan.bias_tolerance_pct = map.number("tolerance_pct", 5.0, 0.01, 100.0, "%");
  map.finish();
  const CaseSpec spec = plain_case(root, file);
  const double coarse = case_coarse_grain(spec);  // throws for mixed factors
  if (coarse == 1.0)
    throw CaseError(fmt::format("{}: coarse_grain_check: the case has no coarse_grain (its inlets and particle sets are real particles): "
                                "nothing to check; give `coarse_grain: F` (F > 1) on every inlet and particle set, or remove the section",
                                map.location().str()));
  if (!(finer < coarse))
    map.fail("finer", fmt::format("{:g} is not finer than the case's coarse_grain {:g} (of {}); valid: at least 1 and below {:g} "
                                  "(1: the real particles)",
                                  finer, coarse, first_source(spec), coarse));
  for (const std::string& path : plan.paths)
    if (ends_with(path, ".coarse_grain"))
      map.fail("finer", fmt::format("sweep.parameters varies {}; the check sets every coarse_grain itself: sweep other keys, or check "
                                    "each parcel size in a case of its own",
                                    path));
  // Every inlet and particle set at F, then at F' (one factor per case: core/coarse_grain.h).
  std::vector<std::string> paths;
  for (size_t k = 0; k < spec.particles.size(); ++k) paths.push_back(fmt::format("particles[{}].coarse_grain", k));
  for (size_t k = 0; k < spec.inlets.size(); ++k) paths.push_back(fmt::format("inlets[{}].coarse_grain", k));
  std::vector<std::vector<YAML::Node>> values;
  for (const double f : {coarse, finer}) {
    // A node of its own per path: one node at two places of a case is written as a YAML alias.
    values.emplace_back();
    for (size_t p = 0; p < paths.size(); ++p) values.back().push_back(YAML::Node(f));
    if (duration > 0) values.back().push_back(YAML::Node(duration));
  }
  repeat_designs(plan, values, map, "finer");
  plan.paths.insert(plan.paths.end(), paths.begin(), paths.end());
  if (duration > 0) plan.paths.push_back("simulation.duration");
  plan.check = SweepPlan::Check::coarse_grain;
  plan.coarse_grain = coarse, plan.finer_coarse_grain = finer;
  plan.check_kpis = kpis;
  plan.bias_runs = {fmt::format("coarse_grain {:g} (as the case)", coarse), fmt::format("coarse_grain {:g}", finer)};
}

namespace {

// ---- judging each KPI ---------------------------------------------------------------------

/// bias_check: sensitive beyond the tolerance and beyond twice the noise (where the noise is known).
void judge_scaling(KpiShift& s, double tolerance) {
  const double scale = std::abs(s.as_case), shift = std::abs(s.checked - s.as_case), noise = s.noise;
  const double floor = absolute_floor(s.metric, tolerance);
  s.sensitive = shift > tolerance / 100 * std::max(scale, std::abs(s.checked)) && shift > floor && !(std::isfinite(noise) && shift <= 2 * noise);
  const std::string by = fmt::format("{:.4g} -> {:.4g}{}", s.as_case, s.checked,
                                     std::isfinite(s.shift_pct) && floor == 0 ? fmt::format(" ({:+.3g} %)", s.shift_pct) : "");
  const std::string noise_words = std::isfinite(s.noise_pct) ? fmt::format(" (noise {:.2g} %)", s.noise_pct) : "";
  const std::string within = floor > 0 ? fmt::format("{:g} {}", floor, ends_with(s.metric, "_pct") ? "percentage points" : "m/s")
                             : std::isfinite(noise) ? fmt::format("{:g} % or twice its noise", tolerance)
                                                    : fmt::format("{:g} %", tolerance);
  if (s.sensitive)
    s.words = fmt::format("{} depends on the scaling: it moves {}{} with {}; the case's value carries that bias, so use a stiffer "
                          "(less scaled) model for it, or calibrate at the scaling the case runs",
                          s.metric, by, noise_words, s.check);
  else
    s.words = fmt::format("{}: the scaling is good enough; it moves {}{} with {}, within {}", s.metric, by, noise_words, s.check, within);
}

/// coarse_grain_check: biased when it moves by more than kSignificantZ standard errors and by more
/// than the tolerance; without standard errors, by the tolerance alone.
void judge_coarse_grain(KpiShift& s, const SweepPlan& plan) {
  const double tolerance = plan.bias_tolerance_pct, floor = absolute_floor(s.metric, tolerance);
  const double shift = std::abs(s.checked - s.as_case);
  const bool beyond = shift > tolerance / 100 * std::max(std::abs(s.as_case), std::abs(s.checked)) && shift > floor;
  const std::string values =
      fmt::format("{:.4g} at coarse_grain {:g}, {:.4g} at {:g}{}", s.as_case, plan.coarse_grain, s.checked, plan.finer_coarse_grain,
                  std::isfinite(s.shift_pct) && floor == 0 ? fmt::format(" ({:+.3g} %)", s.shift_pct) : "");
  const std::string tolerance_words =
      floor > 0 ? fmt::format("{:g} {}", floor, ends_with(s.metric, "_pct") ? "percentage points" : "m/s") : fmt::format("{:g} %", tolerance);
  const std::string remedy = fmt::format("take it from a run at coarse_grain {:g} or finer, or calibrate the material at the parcel size "
                                         "(demdesign compare/calibrate --coarse-grain {:g})",
                                         plan.finer_coarse_grain, plan.coarse_grain);
  if (!std::isfinite(s.z)) {
    s.sensitive = beyond;
    s.words = fmt::format("{}: no standard error (not a mean over the run's records), judged by the tolerance: {}; {}", s.metric, values,
                          beyond ? fmt::format("moved by more than {}: coarse graining biases this KPI; {}", tolerance_words, remedy)
                                 : fmt::format("within {}", tolerance_words));
    return;
  }
  const bool moved = std::abs(s.z) > report::kSignificantZ;
  s.sensitive = moved && beyond;
  if (!moved)
    s.words = fmt::format("{}: within noise: {}, {:+.2f} standard errors apart", s.metric, values, s.z);
  else if (!beyond)
    s.words = fmt::format("{}: moved by {:+.1f} sigma but by less than {}: {}", s.metric, s.z, tolerance_words, values);
  else
    s.words = fmt::format("{}: moved by {:+.1f} sigma: coarse graining biases this KPI: {}; {}", s.metric, s.z, values, remedy);
}

/// The KPIs a check reports for one design: coarse_grain_check.kpis in their order, else every
/// metric of the case's run that is not a run's own noise.
std::vector<std::string> checked_metrics(const SweepPlan& plan, const report::SweepVariant& base) {
  if (plan.check == SweepPlan::Check::coarse_grain && !plan.check_kpis.empty()) return plan.check_kpis;
  std::vector<std::string> metrics;
  for (const auto& [metric, value] : base.metrics.values)
    if (!is_noise(metric)) metrics.push_back(metric);
  return metrics;
}

/// One KPI of design run `base` against check run `other`, with both noises; not yet judged.
KpiShift measure_shift(const std::string& metric, const report::SweepVariant& base, const report::SweepVariant& other) {
  KpiShift s;
  s.metric = metric;
  s.as_case = base.metrics.get(metric), s.checked = other.metrics.get(metric);
  s.shift_pct = s.noise_pct = kNaN;
  const double scale = std::abs(s.as_case);
  const double na = base.metrics.noise(metric), nb = other.metrics.noise(metric);
  s.noise = std::isfinite(na) && std::isfinite(nb) ? std::hypot(na, nb) : kNaN;
  if (scale > 0) {
    s.shift_pct = 100 * (s.checked - s.as_case) / scale;
    s.noise_pct = std::isfinite(s.noise) ? 100 * s.noise / scale : kNaN;
  }
  s.std_error_case = base.metrics.std_error(metric), s.std_error_checked = other.metrics.std_error(metric);
  const double error = std::hypot(s.std_error_case, s.std_error_checked);  // NaN unless both are known
  if (error > 0) s.z = (s.checked - s.as_case) / error;
  return s;
}

/// Every KPI of every design, each check run against the run as the case, judged.
std::vector<KpiShift> judged_shifts(const SweepPlan& plan, const std::vector<report::SweepVariant>& variants) {
  std::vector<KpiShift> shifts;
  const size_t runs = std::max<size_t>(1, plan.bias_runs.size());
  const size_t designs = variants.size() / runs;
  for (size_t d = 0; d < designs; ++d) {
    const report::SweepVariant& base = variants[d * runs];
    if (!base.ok) continue;
    for (size_t r = 1; r < runs; ++r) {
      const report::SweepVariant& other = variants[d * runs + r];
      if (!other.ok) continue;
      for (const std::string& metric : checked_metrics(plan, base)) {
        KpiShift s = measure_shift(metric, base, other);
        if (!std::isfinite(s.as_case) || !std::isfinite(s.checked)) continue;
        s.design = plan.design_label(d * runs), s.check = plan.bias_runs[r];
        if (plan.check == SweepPlan::Check::coarse_grain) judge_coarse_grain(s, plan);
        else judge_scaling(s, plan.bias_tolerance_pct);
        shifts.push_back(std::move(s));
      }
    }
  }
  return shifts;
}

/// coarse_grain_check.kpis that no run that finished reports: said in the log and on the page.
std::vector<std::string> missing_kpis(const SweepPlan& plan, const std::vector<report::SweepVariant>& variants) {
  std::vector<std::string> lines;
  if (plan.check != SweepPlan::Check::coarse_grain) return lines;
  for (const std::string& kpi : plan.check_kpis) {
    const bool reported = std::any_of(variants.begin(), variants.end(), [&](const report::SweepVariant& v) {
      return v.ok && std::isfinite(v.metrics.get(kpi));
    });
    if (reported) continue;
    std::string names;
    for (const report::SweepVariant& v : variants)
      if (v.ok) {
        for (const auto& kv : v.metrics.values) names += (names.empty() ? "" : ", ") + kv.first;
        break;
      }
    lines.push_back(fmt::format("warning: coarse_grain_check.kpis names '{}', which no run's metrics.csv reports (or not as a number); "
                                "metrics: {}", kpi, names.empty() ? "none (no run finished)" : names));
  }
  return lines;
}

// ---- the page and the CSV -----------------------------------------------------------------

/// bias_check: the section of the sweep report and bias_check.csv.
void write_scaling_check(const SweepPlan& plan, BiasSummary& out, const std::string& dir) {
  std::string csv = "design,check,metric,as_case,checked,shift_pct,noise_pct,sensitive\n";
  for (const KpiShift& s : out.shifts)
    csv += fmt::format("\"{}\",\"{}\",{},{:.9g},{:.9g},{:.6g},{:.6g},{}\n", s.design, s.check, s.metric, s.as_case, s.checked, s.shift_pct,
                       s.noise_pct, s.sensitive ? 1 : 0);
  write_file_atomically((std::filesystem::path(dir) / "bias_check.csv").string(), csv);
  using html::esc;
  using html::num;
  std::string& h = out.html;
  h += fmt::format("<h2>What the scalings cost</h2>\n<p>Each design ran as the case is and again with {}. A KPI is <b>sensitive</b> when it "
                   "moves by more than {:g} % of its value and by more than twice the shift's noise (from the runs' own standard deviations, "
                   "where the report gives one): its value then depends on the modelling choice.</p>\n",
                   esc(fmt::format("{}", fmt::join(std::vector<std::string>(plan.bias_runs.begin() + 1, plan.bias_runs.end()), "; "))),
                   plan.bias_tolerance_pct);
  h += "<table>\n<tr><th>design</th><th>check</th><th>KPI</th><th>as the case</th><th>checked</th><th>shift [%]</th><th>noise [%]</th><th>verdict</th></tr>\n";
  for (const KpiShift& s : out.shifts)
    h += fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td>"
                     "<td>{}</td></tr>\n",
                     esc(s.design.empty() ? "(the case)" : s.design), esc(s.check), esc(s.metric), num(s.as_case), num(s.checked), num(s.shift_pct, 3),
                     num(s.noise_pct, 2), s.sensitive ? "<b>sensitive</b>" : "good enough");
  h += "</table>\n<p class=\"note\">Also in bias_check.csv.</p>\n";
  out.title = "What the scalings cost";
  out.log_heading = "bias check: each KPI as the case runs against the checks";
  out.flag_word = "SENSITIVE";
}

/// A CSV cell of words: quoted, inner quotes doubled.
std::string quoted(const std::string& words) {
  std::string out = "\"";
  for (const char c : words) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

/// The verdict column: "within noise", "moved, within tolerance", "biased".
std::string verdict_word(const KpiShift& s) {
  if (s.sensitive) return "biased";
  return std::isfinite(s.z) && std::abs(s.z) > report::kSignificantZ ? "moved, within tolerance" : "within noise";
}

/// coarse_grain_check: the section of the sweep report and coarse_grain_check.csv.
void write_coarse_grain_check(const SweepPlan& plan, BiasSummary& out, const std::string& dir) {
  std::string csv = "design,metric,coarse_grain,value,std_error,finer_coarse_grain,finer_value,finer_std_error,difference,z,shift_pct,biased,verdict\n";
  for (const KpiShift& s : out.shifts)
    csv += fmt::format("{},{},{:g},{:.9g},{:.6g},{:g},{:.9g},{:.6g},{:.9g},{:.4g},{:.6g},{},{}\n", quoted(s.design), s.metric, plan.coarse_grain,
                       s.as_case, s.std_error_case, plan.finer_coarse_grain, s.checked, s.std_error_checked, s.checked - s.as_case, s.z,
                       s.shift_pct, s.sensitive ? 1 : 0, quoted(s.words));
  write_file_atomically((std::filesystem::path(dir) / "coarse_grain_check.csv").string(), csv);
  using html::esc;
  using html::num;
  const double f = plan.coarse_grain, finer = plan.finer_coarse_grain;
  std::string& h = out.html;
  h += fmt::format("<h2>What coarse graining costs</h2>\n<p>Each design ran at the case's coarse_grain {0:g} (parcels {0:g} &times; the real "
                   "diameter, {1:.4g} real particles each) and again at coarse_grain {2:g}. z is the difference in standard errors (the runs' "
                   "batch-means standard errors of each mean). A KPI is <b>biased</b> when |z| &gt; {3:g} and it moves by more than {4:g} % "
                   "of its value; a KPI without a standard error (a total, a peak) is judged by the tolerance alone.</p>\n",
                   f, f * f * f, finer, report::kSignificantZ, plan.bias_tolerance_pct);
  for (const std::string& line : out.log_lines) h += "<p class=\"note\">" + esc(line) + "</p>\n";
  h += "<table>" + html::row({"design", "KPI", fmt::format("at {:g}", f), "&plusmn; se", fmt::format("at {:g}", finer), "&plusmn; se", "difference",
                  "z [&sigma;]", "shift [%]", "verdict"},
                 true);
  for (const KpiShift& s : out.shifts)
    h += html::row({esc(s.design.empty() ? "(the case)" : s.design), esc(s.metric), num(s.as_case), num(s.std_error_case, 2), num(s.checked),
                    num(s.std_error_checked, 2), num(s.checked - s.as_case), num(s.z, 3), num(s.shift_pct, 3),
                    s.sensitive ? "<b>biased</b>" : esc(verdict_word(s))});
  h += "</table>\n<p class=\"note\">Also in coarse_grain_check.csv.</p>\n";
  out.title = "What coarse graining costs";
  out.log_heading = fmt::format("coarse-grain check: each KPI at coarse_grain {:g} (the case) against {:g}", f, finer);
  out.flag_word = "BIASED";
}

}  // namespace

BiasSummary summarise_bias_check(const SweepPlan& plan, const std::vector<report::SweepVariant>& variants, const std::string& dir) {
  BiasSummary out;
  out.shifts = judged_shifts(plan, variants);
  out.log_lines = missing_kpis(plan, variants);
  std::filesystem::create_directories(dir);
  if (plan.check == SweepPlan::Check::coarse_grain) write_coarse_grain_check(plan, out, dir);
  else write_scaling_check(plan, out, dir);
  return out;
}

}  // namespace dem::app
