// The sweep report: every variant's metrics side by side, ranked by weighted normalised
// criteria, with the same view of each variant (one self-contained HTML file and ranking.csv).
#include "report/report.h"

#include "pages/html.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>

#include "output/run.h"

namespace dem::report {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using html::embed_image;
using html::esc;
using html::now_text;
using html::num;

std::string table_row(std::initializer_list<std::string> cells, bool header = false) { return html::row(cells, header); }

/// A metric name as an identifier (anchors, CSV-safe keys).
std::string key(const std::string& text) {
  std::string out;
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

}  // namespace

std::vector<Ranked> rank_variants(const SweepReportInput& input) {
  const std::size_t n = input.variants.size(), nc = input.criteria.size();
  std::vector<Ranked> ranked(n);
  double weight_sum = 0;
  for (const Criterion& c : input.criteria) weight_sum += std::max(c.weight, 0.0);
  for (std::size_t v = 0; v < n; ++v) ranked[v].variant = v, ranked[v].criterion_scores.assign(nc, 0.0);
  for (std::size_t c = 0; c < nc; ++c) {
    const Criterion& crit = input.criteria[c];
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const SweepVariant& var : input.variants) {
      const double v = var.metrics.get(crit.metric);
      if (var.ok && std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    }
    for (std::size_t v = 0; v < n; ++v) {
      const double x = input.variants[v].metrics.get(crit.metric);
      if (!input.variants[v].ok || !std::isfinite(x)) continue;
      double s = hi > lo ? (x - lo) / (hi - lo) : 1.0;
      if (!crit.maximise) s = hi > lo ? 1.0 - s : 1.0;
      ranked[v].criterion_scores[c] = s;
    }
  }
  for (Ranked& r : ranked) {
    if (!input.variants[r.variant].ok) {
      r.score = kNaN;
      continue;
    }
    double s = 0;
    for (std::size_t c = 0; c < nc; ++c) s += std::max(input.criteria[c].weight, 0.0) * r.criterion_scores[c];
    r.score = weight_sum > 0 ? s / weight_sum : 0.0;
  }
  std::stable_sort(ranked.begin(), ranked.end(), [](const Ranked& a, const Ranked& b) {
    const bool fa = std::isnan(a.score), fb = std::isnan(b.score);
    if (fa != fb) return fb;
    return !fa && a.score > b.score;
  });
  return ranked;
}

void write_sweep_report(const SweepReportInput& input, const std::string& dir) {
  fs::create_directories(dir);
  const std::vector<Ranked> ranked = rank_variants(input);

  // Every metric any variant has, in first-seen order.
  std::vector<std::string> names;
  for (const SweepVariant& v : input.variants)
    for (const auto& [name, value] : v.metrics.values)
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  std::vector<std::string> parameters;
  for (const SweepVariant& v : input.variants)
    for (const auto& [name, value] : v.parameters)
      if (std::find(parameters.begin(), parameters.end(), name) == parameters.end()) parameters.push_back(name);
  auto parameter = [](const SweepVariant& v, const std::string& name) {
    for (const auto& [n, value] : v.parameters)
      if (n == name) return value;
    return std::string();
  };

  std::string csv = "rank,variant,status,steady,score";
  for (const std::string& p : parameters) csv += "," + key(p);
  for (const std::string& m : names) csv += "," + m;
  csv += "\n";
  for (std::size_t r = 0; r < ranked.size(); ++r) {
    const SweepVariant& v = input.variants[ranked[r].variant];
    csv += fmt::format("{},\"{}\",{},{},{:.6g}", r + 1, v.name, v.ok ? "ok" : "failed", v.metrics.steady ? 1 : 0, ranked[r].score);
    for (const std::string& p : parameters) csv += ",\"" + parameter(v, p) + "\"";
    for (const std::string& m : names) csv += fmt::format(",{:.9g}", v.metrics.get(m));
    csv += "\n";
  }
  write_file_atomically((fs::path(dir) / "ranking.csv").string(), csv);

  const std::string title = input.title.empty() ? "Design sweep" : input.title;
  std::string h = html::head(title + " - demdesign sweep report");
  h += fmt::format("<h1>{}</h1>\n<p class=\"meta\">Sweep report &middot; {} &middot; demdesign {} &middot; case <code>{}</code> &middot; {} "
                   "variants</p>\n",
                   esc(title), esc(now_text()), esc(input.version), esc(input.case_path), input.variants.size());
  std::size_t failed = 0, unsteady = 0;
  for (const SweepVariant& v : input.variants) failed += !v.ok, unsteady += v.ok && !v.metrics.steady;
  if (failed) h += fmt::format("<div class=\"banner bad\">{} variant(s) failed; they are ranked last.</div>\n", failed);
  if (unsteady)
    h += fmt::format("<div class=\"banner warn\">{} variant(s) reached no steady state; their values are last-third averages.</div>\n", unsteady);

  h += "<h2>Ranking</h2>\n";
  if (input.criteria.empty()) {
    h += "<p>No criteria given: variants are listed in sweep order.</p>\n";
  } else {
    h += "<p>Rule: normalised weighted score. For each criterion, s = (value &minus; worst) / (best &minus; worst) over the variants that "
         "ran (1 when all are equal, 0 when a variant lacks the value); score = &Sigma; w&middot;s / &Sigma; w, highest first. "
         "Criteria:</p>\n<table>\n" +
         table_row({"metric", "goal", "weight"}, true);
    for (const Criterion& c : input.criteria) h += table_row({esc(c.metric), c.maximise ? "maximise" : "minimise", num(c.weight, 3)});
    h += "</table>\n";
  }
  h += "<table>\n<tr><th>rank</th><th>variant</th><th>status</th><th>score</th>";
  for (const std::string& p : parameters) h += "<th>" + esc(p) + "</th>";
  for (const Criterion& c : input.criteria) h += "<th>" + esc(c.metric) + "</th>";
  h += "</tr>\n";
  for (std::size_t r = 0; r < ranked.size(); ++r) {
    const SweepVariant& v = input.variants[ranked[r].variant];
    std::string status = v.ok ? (v.metrics.steady ? "ok" : "ok, not steady") : "failed: " + esc(v.message);
    h += fmt::format("<tr><td class=\"n\">{}</td><td>{}</td><td>{}</td><td class=\"n\">{}</td>", r + 1, esc(v.name), status,
                     num(ranked[r].score, 3));
    for (const std::string& p : parameters) h += "<td>" + esc(parameter(v, p)) + "</td>";
    for (const Criterion& c : input.criteria) h += "<td class=\"n\">" + num(v.metrics.get(c.metric)) + "</td>";
    h += "</tr>\n";
  }
  h += "</table>\n";
  h += input.extra_html;

  h += "<h2>All metrics</h2>\n<table>\n<tr><th>metric</th>";
  for (const Ranked& r : ranked) h += "<th>" + esc(input.variants[r.variant].name) + "</th>";
  h += "</tr>\n";
  for (const std::string& m : names) {
    h += "<tr><td>" + esc(m) + "</td>";
    for (const Ranked& r : ranked) h += "<td class=\"n\">" + num(input.variants[r.variant].metrics.get(m)) + "</td>";
    h += "</tr>\n";
  }
  h += "<tr><td>steady state</td>";
  for (const Ranked& r : ranked) h += "<td>" + esc(input.variants[r.variant].metrics.steady_text) + "</td>";
  h += "</tr>\n</table>\n";

  h += "<h2>Images (same camera for every variant)</h2>\n<div class=\"grid\">\n";
  for (std::size_t r = 0; r < ranked.size(); ++r) {
    const SweepVariant& v = input.variants[ranked[r].variant];
    const std::string image = v.image_path.empty() ? "<p class=\"missing\">no image</p>" : embed_image(v.image_path, v.name);
    h += fmt::format("<figure>{}<figcaption>#{} {}{}</figcaption></figure>\n", image, r + 1, esc(v.name),
                     v.report_path.empty() ? "" : " &middot; report: <code>" + esc(v.report_path) + "</code>");
  }
  h += "</div>\n<p class=\"note\">Also in ranking.csv.</p>\n</body></html>\n";
  write_file_atomically((fs::path(dir) / "sweep.html").string(), h);
}

}  // namespace dem::report
