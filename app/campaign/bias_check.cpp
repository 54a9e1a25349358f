#include "campaign/bias_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "case/spec.h"
#include "case/yaml_check.h"
#include "model/library.h"
#include "pages/html.h"
#include "output/run.h"

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

}  // namespace

void add_bias_check(SweepPlan& plan, const YAML::Node& root, const std::string& file) {
  MapReader map(root["bias_check"], file, "bias_check");
  if (root["uncertainty"])
    map.fail("stiffness_factor", "a case runs either `uncertainty:` or `bias_check:`; check the scalings first, then draw the samples");
  const double stiffness_factor = map.number("stiffness_factor", 4.0, 1.01, 1e4, "-");
  const double mass_factor = map.number("mass_factor", 4.0, 1.01, 1e6, "-");
  const double duration = map.has("duration") ? map.required_number("duration", 1e-9, 1e6, "s") : -1.0;
  plan.bias_tolerance_pct = map.number("tolerance_pct", 5.0, 0.01, 100.0, "%");
  map.finish();
  YAML::Node plain = YAML::Clone(root);
  plain.remove("sweep");
  plain.remove("bias_check");
  const CaseSpec spec = parse_case_node(plain, file, materials::library_lookup());
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
  const std::vector<std::vector<YAML::Node>> designs = plan.variants.empty() ? std::vector<std::vector<YAML::Node>>{{}} : plan.variants;
  plan.variants.clear();
  for (const auto& design : designs)
    for (const Run& r : runs) {
      std::vector<YAML::Node> row = design;
      row.push_back(YAML::Node(r.stiffness));
      row.push_back(YAML::Node(r.mass));
      if (duration > 0) row.push_back(YAML::Node(duration));
      plan.variants.push_back(std::move(row));
    }
  plan.paths.push_back("simulation.stiffness_scaling");
  plan.paths.push_back("simulation.mass_scaling");
  if (duration > 0) plan.paths.push_back("simulation.duration");
  plan.bias_runs.clear();
  for (const Run& r : runs) plan.bias_runs.push_back(r.label);
  if (plan.variants.size() > 1000)
    map.fail("stiffness_factor", fmt::format("makes {} runs ({} design variants x {} runs); at most 1000", plan.variants.size(), designs.size(), runs.size()));
}

BiasSummary summarise_bias_check(const SweepPlan& plan, const std::vector<report::SweepVariant>& variants, const std::string& dir) {
  BiasSummary out;
  const size_t runs = std::max<size_t>(1, plan.bias_runs.size());
  const size_t designs = variants.size() / runs;
  const double tolerance = plan.bias_tolerance_pct;
  std::string csv = "design,check,metric,as_case,checked,shift_pct,noise_pct,sensitive\n";
  for (size_t d = 0; d < designs; ++d) {
    const report::SweepVariant& base = variants[d * runs];
    if (!base.ok) continue;
    for (size_t r = 1; r < runs; ++r) {
      const report::SweepVariant& other = variants[d * runs + r];
      if (!other.ok) continue;
      for (const auto& [metric, value] : base.metrics.values) {
        if (is_noise(metric)) continue;
        const double checked = other.metrics.get(metric);
        if (!std::isfinite(value) || !std::isfinite(checked)) continue;
        KpiShift s{plan.design_label(d * runs), plan.bias_runs[r], metric, value, checked, kNaN, kNaN, false, ""};
        const double scale = std::abs(value);
        const double na = base.metrics.noise(metric), nb = other.metrics.noise(metric);
        const double noise = std::isfinite(na) && std::isfinite(nb) ? std::hypot(na, nb) : kNaN;
        if (scale > 0) {
          s.shift_pct = 100 * (checked - value) / scale;
          s.noise_pct = std::isfinite(noise) ? 100 * noise / scale : kNaN;
        }
        // Sensitive: beyond the tolerance and beyond twice the noise (where the noise is known).
        const double shift = std::abs(checked - value);
        s.sensitive = shift > tolerance / 100 * std::max(scale, std::abs(checked)) && shift > absolute_floor(metric, tolerance) &&
                      !(std::isfinite(noise) && shift <= 2 * noise);
        const double floor = absolute_floor(metric, tolerance);
        const std::string by = fmt::format("{:.4g} -> {:.4g}{}", value, checked,
                                           std::isfinite(s.shift_pct) && floor == 0 ? fmt::format(" ({:+.3g} %)", s.shift_pct) : "");
        const std::string noise_words = std::isfinite(s.noise_pct) ? fmt::format(" (noise {:.2g} %)", s.noise_pct) : "";
        const std::string within = floor > 0 ? fmt::format("{:g} {}", floor, ends_with(metric, "_pct") ? "percentage points" : "m/s")
                                   : std::isfinite(noise) ? fmt::format("{:g} % or twice its noise", tolerance)
                                                          : fmt::format("{:g} %", tolerance);
        if (s.sensitive)
          s.words = fmt::format("{} depends on the scaling: it moves {}{} with {}; the case's value carries that bias, so use a stiffer "
                                "(less scaled) model for it, or calibrate at the scaling the case runs",
                                metric, by, noise_words, s.check);
        else
          s.words = fmt::format("{}: the scaling is good enough; it moves {}{} with {}, within {}", metric, by, noise_words, s.check, within);
        csv += fmt::format("\"{}\",\"{}\",{},{:.9g},{:.9g},{:.6g},{:.6g},{}\n", s.design, s.check, s.metric, s.as_case, s.checked, s.shift_pct,
                           s.noise_pct, s.sensitive ? 1 : 0);
        out.shifts.push_back(std::move(s));
      }
    }
  }
  std::filesystem::create_directories(dir);
  write_file_atomically((std::filesystem::path(dir) / "bias_check.csv").string(), csv);

  using html::esc;
  using html::num;
  std::string& h = out.html;
  h += fmt::format("<h2>What the scalings cost</h2>\n<p>Each design ran as the case is and again with {}. A KPI is <b>sensitive</b> when it "
                   "moves by more than {:g} % of its value and by more than twice the shift's noise (from the runs' own standard deviations, "
                   "where the report gives one): its value then depends on the modelling choice.</p>\n",
                   esc(fmt::format("{}", fmt::join(std::vector<std::string>(plan.bias_runs.begin() + 1, plan.bias_runs.end()), "; "))), tolerance);
  h += "<table>\n<tr><th>design</th><th>check</th><th>KPI</th><th>as the case</th><th>checked</th><th>shift [%]</th><th>noise [%]</th><th>verdict</th></tr>\n";
  for (const KpiShift& s : out.shifts)
    h += fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td>"
                     "<td>{}</td></tr>\n",
                     esc(s.design.empty() ? "(the case)" : s.design), esc(s.check), esc(s.metric), num(s.as_case), num(s.checked), num(s.shift_pct, 3),
                     num(s.noise_pct, 2), s.sensitive ? "<b>sensitive</b>" : "good enough");
  h += "</table>\n<p class=\"note\">Also in bias_check.csv.</p>\n";
  return out;
}

}  // namespace dem::app
