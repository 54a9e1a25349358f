#include "campaign/uncertainty.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <fstream>
#include <set>
#include <sstream>

#include "case/calibration_record.h"
#include "case/spec.h"
#include "case/yaml_check.h"
#include "model/library.h"
#include "pages/html.h"
#include "output/run.h"
#include "pages/plot.h"

namespace dem::app {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The q-quantile of sorted values (linear interpolation between order statistics).
double quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return kNaN;
  const double at = q * static_cast<double>(sorted.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(at)), hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (at - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

/// One series of a run report's plot data (plots/NAME.tsv): its label and points.
struct Block {
  std::string label;
  std::vector<double> t, y;
};

/// The blocks of a plot's TSV ("# label", then "t<TAB>y" rows; blocks apart by blank lines).
std::vector<Block> read_blocks(const std::filesystem::path& path) {
  std::vector<Block> blocks;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("# ", 0) == 0) {
      blocks.push_back({line.substr(2), {}, {}});
      continue;
    }
    if (line.empty() || blocks.empty()) continue;
    std::istringstream row(line);
    double t = kNaN, y = kNaN;
    row >> t >> y;
    if (row) blocks.back().t.push_back(t), blocks.back().y.push_back(y);
  }
  return blocks;
}

/// y(t) of a block by linear interpolation (held constant beyond its ends).
double at_time(const Block& b, double t) {
  if (b.t.empty()) return kNaN;
  if (t <= b.t.front()) return b.y.front();
  if (t >= b.t.back()) return b.y.back();
  const size_t hi = static_cast<size_t>(std::upper_bound(b.t.begin(), b.t.end(), t) - b.t.begin());
  const double w = (t - b.t[hi - 1]) / (b.t[hi] - b.t[hi - 1]);
  return b.y[hi - 1] + w * (b.y[hi] - b.y[hi - 1]);
}

/// The time series of the run reports as bands over the parameter sets: for each plot of the
/// KPIs over time that the runs drew, per design and series, the median line and the 5-95 %
/// band. Returns the HTML figures (drawn into dir/plots).
std::string time_bands(const SweepPlan& plan, const std::vector<report::SweepVariant>& variants, size_t designs, size_t samples,
                       const std::string& dir) {
  namespace fs = std::filesystem;
  const fs::path runs = fs::path(dir).parent_path() / "variants";
  struct Kind {
    const char* name;
    const char* title;
    const char* y_label;
  };
  const Kind kinds[] = {{"outlet_flow", "Mass flow at the outlets", "mass flow [t/h]"},
                        {"sensor_flow", "Mass flow through the plane sensors", "mass flow [t/h]"},
                        {"mesh_power", "Power per mesh", "power [W]"},
                        {"mesh_torque", "Torque per mesh", "torque [N m]"}};
  std::string h;
  for (const Kind& kind : kinds) {
    plot::Plot p;
    p.title = fmt::format("{}: median and 90 % band over the parameter sets", kind.title);
    p.x_label = "time [s]";
    p.y_label = kind.y_label;
    for (size_t d = 0; d < designs && p.series.size() < 8; ++d) {
      std::vector<std::vector<Block>> per_sample;
      for (size_t s = 0; s < samples; ++s) {
        const size_t k = d * samples + s;
        if (!variants[k].ok) continue;
        std::vector<Block> blocks = read_blocks(runs / plan.name(k) / "report" / "plots" / (std::string(kind.name) + ".tsv"));
        if (!blocks.empty()) per_sample.push_back(std::move(blocks));
      }
      if (per_sample.size() < 2) continue;
      for (const Block& first : per_sample.front()) {
        plot::Series line;
        const std::string design = plan.design_label(d * samples);
        line.label = design.empty() ? first.label : design + ": " + first.label;
        line.band_label = "5-95 %";
        for (double t : first.t) {
          std::vector<double> values;
          for (const auto& blocks : per_sample)
            for (const Block& b : blocks)
              if (b.label == first.label) {
                const double y = at_time(b, t);
                if (std::isfinite(y)) values.push_back(y);
              }
          std::sort(values.begin(), values.end());
          line.x.push_back(t);
          line.y.push_back(quantile(values, 0.5));
          line.lo.push_back(quantile(values, 0.05));
          line.hi.push_back(quantile(values, 0.95));
        }
        if (p.series.size() < 8) p.series.push_back(std::move(line));
      }
    }
    if (p.series.empty()) continue;
    const std::string png = (fs::path(dir) / "plots" / (std::string("band_") + kind.name + ".png")).string();
    std::string message;
    const bool ok = plot::draw_plot(p, png, &message);
    h += fmt::format("<figure>{}<figcaption>{} over time: the median over the parameter sets (line) and the band from 5 % to 95 % "
                     "(shaded), per design; data in plots/band_{}.tsv.</figcaption></figure>\n",
                     ok ? html::embed_image(png, p.title) : fmt::format("<p class=\"missing\">not drawn: {}</p>", html::esc(message)),
                     kind.title, kind.name);
  }
  return h;
}

}  // namespace

void add_uncertainty(SweepPlan& plan, const YAML::Node& root, const std::string& file) {
  MapReader map(root["uncertainty"], file, "uncertainty");
  const int samples = static_cast<int>(map.integer("samples", 16, 2, 1000));
  const auto seed = static_cast<std::uint64_t>(map.integer("seed", 1, 0, std::numeric_limits<std::int32_t>::max()));
  map.finish();
  // The case's materials as the engine reads them: a library material brings its calibration.
  YAML::Node plain = YAML::Clone(root);
  plain.remove("sweep");
  plain.remove("uncertainty");
  const CaseSpec spec = parse_case_node(plain, file, materials::library_lookup());
  std::vector<std::string> paths;
  std::vector<std::vector<double>> columns;  // per path, one value per sample
  for (size_t m = 0; m < spec.materials.size(); ++m) {
    const MaterialSpec& material = spec.materials[m];
    if (!material.calibration) continue;
    const CalibrationRecord& record = *material.calibration;
    std::vector<std::pair<double, double>> ranges;
    for (const std::string& key : record.parameters) {
      const auto t = material.tunable.find(key);
      ranges.push_back(t != material.tunable.end() ? t->second
                                                   : std::pair{-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()});
    }
    const auto drawn = posterior_samples(record, samples, seed + 7919 * m, ranges);
    for (size_t j = 0; j < record.parameters.size(); ++j) {
      const std::string& key = record.parameters[j];
      // A wall pair parameter ("steel.friction") lives in the library file's walls, which a case
      // cannot override: it is held at its fitted value, and the report says so.
      if (key.find('.') != std::string::npos) {
        plan.held.push_back(fmt::format("{}: {} held at its calibrated {:.4g} (a wall pair parameter is not varied)", material.name, key, record.value[j]));
        continue;
      }
      paths.push_back(fmt::format("materials.{}.{}", material.name, key));
      std::vector<double> column;
      for (const auto& set : drawn) column.push_back(set[j]);
      columns.push_back(std::move(column));
    }
  }
  if (paths.empty())
    map.fail("samples", "no material of this case carries a calibration to draw from: name a calibrated material (the *_calibrated.yaml "
                        "that `demdesign calibrate` or `diagnose` writes) with {library: NAME}");
  // Every design variant (one when the case has no sweep) at every parameter set.
  const std::vector<std::vector<YAML::Node>> designs = plan.variants.empty() ? std::vector<std::vector<YAML::Node>>{{}} : plan.variants;
  plan.variants.clear();
  for (const auto& design : designs)
    for (int s = 0; s < samples; ++s) {
      std::vector<YAML::Node> row = design;
      for (const auto& column : columns) row.push_back(YAML::Node(column[static_cast<size_t>(s)]));
      plan.variants.push_back(std::move(row));
    }
  plan.paths.insert(plan.paths.end(), paths.begin(), paths.end());
  plan.samples = samples;
  if (plan.variants.size() > 1000)
    map.fail("samples", fmt::format("makes {} runs ({} design variants x {} samples); at most 1000", plan.variants.size(), designs.size(), samples));
}

UncertaintySummary summarise_uncertainty(const SweepPlan& plan, const std::vector<report::SweepVariant>& variants,
                                         const std::vector<report::Criterion>& criteria, const std::string& dir) {
  UncertaintySummary out;
  const size_t samples = static_cast<size_t>(std::max(1, plan.samples));
  const size_t designs = variants.size() / samples;
  // Metrics in the order the first variant that ran lists them; METRIC_std is a run's own noise.
  std::vector<std::string> metrics;
  for (const auto& v : variants)
    if (v.ok) {
      for (const auto& [name, value] : v.metrics.values)
        if (name.size() < 4 || name.compare(name.size() - 4, 4, "_std") != 0) metrics.push_back(name);
      break;
    }
  std::string csv = "design,metric,median,p05,p95,run_noise,samples\n";
  for (size_t d = 0; d < designs; ++d) {
    const std::string label = plan.design_label(d * samples);
    for (const std::string& metric : metrics) {
      std::vector<double> values, noise;
      for (size_t s = 0; s < samples; ++s) {
        const report::SweepVariant& v = variants[d * samples + s];
        if (!v.ok) continue;
        const double x = v.metrics.get(metric);
        if (std::isfinite(x)) values.push_back(x);
        const double n = v.metrics.noise(metric);  // the run's own noise
        if (std::isfinite(n)) noise.push_back(n);
      }
      std::sort(values.begin(), values.end());
      std::sort(noise.begin(), noise.end());
      KpiBand band{label, metric, quantile(values, 0.5), quantile(values, 0.05), quantile(values, 0.95), quantile(noise, 0.5),
                   static_cast<int>(values.size())};
      csv += fmt::format("\"{}\",{},{:.9g},{:.9g},{:.9g},{:.9g},{}\n", label, metric, band.median, band.p05, band.p95, band.run_noise, band.samples);
      out.bands.push_back(band);
    }
  }
  std::filesystem::create_directories(dir);
  write_file_atomically((std::filesystem::path(dir) / "uncertainty.csv").string(), csv);
  // Paired comparison of the design variants on each criterion.
  std::string beats_csv = "metric,a,b,probability_a_beats_b,pairs\n";
  for (const report::Criterion& c : criteria)
    for (size_t a = 0; a < designs; ++a)
      for (size_t b = 0; b < designs; ++b) {
        if (a == b) continue;
        double wins = 0;
        int pairs = 0;
        for (size_t s = 0; s < samples; ++s) {
          const report::SweepVariant &va = variants[a * samples + s], &vb = variants[b * samples + s];
          if (!va.ok || !vb.ok) continue;
          const double x = va.metrics.get(c.metric), y = vb.metrics.get(c.metric);
          if (!std::isfinite(x) || !std::isfinite(y)) continue;
          ++pairs;
          wins += x == y ? 0.5 : ((c.maximise ? x > y : x < y) ? 1.0 : 0.0);
        }
        Beats beat{c.metric, plan.design_label(a * samples), plan.design_label(b * samples), pairs ? wins / pairs : kNaN, pairs};
        beats_csv += fmt::format("{},\"{}\",\"{}\",{:.6g},{}\n", beat.metric, beat.a, beat.b, beat.probability, beat.pairs);
        out.beats.push_back(beat);
      }
  if (!out.beats.empty()) write_file_atomically((std::filesystem::path(dir) / "beats.csv").string(), beats_csv);

  // The report's section.
  using html::esc;
  using html::num;
  std::string& h = out.html;
  h += fmt::format("<h2>Calibration uncertainty</h2>\n<p>Each design ran at {} parameter sets drawn from the calibration of its material "
                   "(a Latin hypercube over the fitted parameters' normal posterior: values, standard deviations and correlation of the "
                   "<code>calibration:</code> block): {}. Each KPI is given as the median with the 90 % band over those runs; "
                   "<em>run noise</em> is the median of each run's own standard deviation of that KPI (time-series scatter), so a band "
                   "much wider than it comes from the calibration.</p>\n",
                   samples, esc(fmt::format("{}", fmt::join(std::vector<std::string>(plan.paths.begin() + static_cast<long>(plan.design_paths), plan.paths.end()), ", "))));
  for (const std::string& note : plan.held) h += "<p class=\"note\">" + esc(note) + "</p>\n";
  h += "<table>\n<tr><th>design</th><th>KPI</th><th>median</th><th>5 %</th><th>95 %</th><th>run noise</th><th>runs</th></tr>\n";
  for (const KpiBand& b : out.bands)
    h += fmt::format("<tr><td>{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td>"
                     "<td class=\"n\">{}</td></tr>\n",
                     esc(b.design.empty() ? "(the case)" : b.design), esc(b.metric), num(b.median), num(b.p05), num(b.p95), num(b.run_noise), b.samples);
  h += "</table>\n";
  if (!out.beats.empty()) {
    h += "<h3>Which design wins, sample by sample</h3>\n<p>The probability that the row's design beats the column's on a criterion, over "
         "the parameter sets both ran (paired: the same material parameters in both).</p>\n";
    for (const report::Criterion& c : criteria) {
      h += fmt::format("<p><b>{}</b> ({})</p>\n<table>\n<tr><th></th>", esc(c.metric), c.maximise ? "higher is better" : "lower is better");
      for (size_t b = 0; b < designs; ++b) h += "<th>" + esc(plan.design_label(b * samples)) + "</th>";
      h += "</tr>\n";
      for (size_t a = 0; a < designs; ++a) {
        h += "<tr><td>" + esc(plan.design_label(a * samples)) + "</td>";
        for (size_t b = 0; b < designs; ++b) {
          const auto it = std::find_if(out.beats.begin(), out.beats.end(), [&](const Beats& x) {
            return x.metric == c.metric && x.a == plan.design_label(a * samples) && x.b == plan.design_label(b * samples);
          });
          h += "<td class=\"n\">" + (a == b || it == out.beats.end() ? std::string("&ndash;") : num(it->probability, 2)) + "</td>";
        }
        h += "</tr>\n";
      }
      h += "</table>\n";
    }
  }
  if (const std::string over_time = time_bands(plan, variants, designs, samples, dir); !over_time.empty())
    h += "<h3>KPIs over time</h3>\n" + over_time;
  h += "<p class=\"note\">Also in uncertainty.csv" + std::string(out.beats.empty() ? "" : " and beats.csv") + ".</p>\n";
  return out;
}

}  // namespace dem::app
