#include "report/calibration_report.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>

#include "pages/html.h"
#include "pages/plot.h"
#include "pages/plot_contour.h"

namespace dem::report {

namespace {

namespace fs = std::filesystem;
using html::esc;
using html::num;
using html::row;
using materials::Comparison;
using materials::ExperimentRun;
using materials::Term;

std::string figure_html(bool ok, const std::string& png, const std::string& title, const std::string& message, const std::string& caption) {
  const std::string body = ok ? html::embed_image(png, title) : fmt::format("<p class=\"missing\">Plot &ldquo;{}&rdquo; not drawn: {}</p>", esc(title), esc(message));
  return fmt::format("<figure>{}<figcaption>{}</figcaption></figure>\n", body, caption);
}

std::string banner(double chi2n, double within) {
  const char* cls = chi2n <= within ? "good" : chi2n <= 4 ? "warn" : "bad";
  return fmt::format("<div class=\"banner {}\">chi&sup2;/n = {} {}</div>\n", cls, num(chi2n, 3),
                     chi2n <= within ? "&mdash; fits within the noise" : "&mdash; the model misfits");
}

/// Table and plots of one comparison (tag names the plot files).
std::string comparison_section(const Comparison& c, const std::string& heading, const std::string& dir, const std::string& tag) {
  std::string h = fmt::format("<h2>{}</h2>\n", esc(heading)) + banner(c.chi2_per_n(), 1.5);
  h += "<table>" + row({"experiment", "test", "observable", "varied", "measured", "simulated", "residual [&sigma;]"}, true);
  for (const Term& t : c.terms) {
    const std::string varied = t.varied.empty() ? "" : fmt::format("{} = {}", esc(t.varied), num(t.varied_value));
    if (t.is_outcome())
      h += row({esc(t.experiment), esc(t.test), "outcome", varied, esc(t.measured_outcome),
                fmt::format("{} in {:.0f} % of replicas", esc(t.measured_outcome), 100 * t.simulated), num(t.residual, 3)});
    else
      h += row({esc(t.experiment), esc(t.test), esc(t.observable), varied, num(t.measured) + " &plusmn; " + num(t.sigma_measured, 2),
                num(t.simulated) + " &plusmn; " + num(t.sigma_simulated, 2), num(t.residual, 3)});
  }
  h += "</table>\n<p class=\"note\">residual = (simulated &minus; measured) / sqrt(&sigma;<sub>meas</sub>&sup2; + &sigma;<sub>sim</sub>&sup2;); "
       "&sigma;<sub>sim</sub> is the standard error of the mean over the replicas (different packings). A mismatched outcome counts 3 &sigma;.</p>\n";
  for (const std::string& n : c.notes) h += "<p class=\"note\">" + esc(n) + "</p>\n";
  // Per experiment: what drives its misfit, and how its simulations ran (the protocol quantities
  // each virtual test reports: how far a drum's wall layer is carried, how much of a silo
  // discharged when, a shear sample's height and mass scaling, ...). A misfit that comes with an
  // unusual protocol quantity may be a difference of apparatus rather than missing physics.
  if (!c.runs.empty()) {
    h += "<h3>Each experiment: what drives its misfit, and how it ran</h3>\n<table>" +
         row({"experiment", "largest residual", "outcomes in the replicas", "replicas", "particles", "how the simulations ran"}, true);
    for (const ExperimentRun& r : c.runs) {
      const Term* worst = nullptr;
      for (const Term& t : c.terms)
        if (t.experiment == r.id && (!worst || std::abs(t.residual) > std::abs(worst->residual))) worst = &t;
      std::string outcomes;
      for (const auto& [flag, share] : r.flag_fraction)
        if (share > 0) outcomes += (outcomes.empty() ? "" : ", ") + fmt::format("{} in {:.0f} %", flag, 100 * share);
      std::string notes;
      for (const std::string& n : r.notes) notes += (notes.empty() ? "" : "<br>") + esc(n);
      h += row({esc(r.id), worst ? fmt::format("{} {:+.2f} &sigma;", esc(worst->observable), worst->residual) : "",
                outcomes.empty() ? "none" : esc(outcomes), std::to_string(r.replicas), std::to_string(r.particles), notes});
    }
    h += "</table>\n";
  }
  // Residual per term.
  plot::ErrorBarPlot rp;
  rp.title = heading + ": normalised residuals";
  rp.x_label = "observation";
  rp.y_label = "residual [sigma]";
  plot::ErrorSeries s{"residual", {}, {}, {}, false};
  for (size_t k = 0; k < c.terms.size(); ++k) s.x.push_back(k), s.y.push_back(c.terms[k].residual), s.error.push_back(1.0), rp.x_tics.push_back(c.terms[k].name());
  rp.series.push_back(s);
  rp.zero_band = {-2, 0, 2};
  std::string message;
  const std::string png = (fs::path(dir) / "plots" / (tag + "_residuals.png")).string();
  h += figure_html(plot::draw_errorbar_plot(rp, png, &message), png, rp.title, message, "Residual of every observation with its unit error; dashed: 0 and &plusmn;2 &sigma;.");
  // Measured and simulated against the varied quantity, per test and observable (yield locus, angle against speed).
  std::map<std::pair<std::string, std::string>, std::vector<const Term*>> groups;
  for (const Term& t : c.terms)
    if (!t.is_outcome() && !t.varied.empty()) groups[{t.test, t.observable}].push_back(&t);
  std::string grid;
  for (const auto& [key, list] : groups) {
    if (list.size() < 2) continue;
    plot::ErrorBarPlot p;
    p.title = key.first == "direct_shear" && key.second == "peak_shear_stress" ? "yield locus" : key.second + " against " + list.front()->varied;
    p.x_label = list.front()->varied;
    p.y_label = key.second;
    plot::ErrorSeries m{"measured", {}, {}, {}, true}, sim{"simulated", {}, {}, {}, true};
    std::vector<const Term*> sorted = list;
    std::sort(sorted.begin(), sorted.end(), [](const Term* a, const Term* b) { return a->varied_value < b->varied_value; });
    for (const Term* t : sorted) {
      m.x.push_back(t->varied_value), m.y.push_back(t->measured), m.error.push_back(t->sigma_measured);
      sim.x.push_back(t->varied_value), sim.y.push_back(t->simulated), sim.error.push_back(t->sigma_simulated);
    }
    p.series = {m, sim};
    p.width = 640, p.height = 420;
    const std::string name = tag + "_" + key.first + "_" + key.second;
    const std::string ppng = (fs::path(dir) / "plots" / (name + ".png")).string();
    grid += figure_html(plot::draw_errorbar_plot(p, ppng, &message), ppng, p.title, message, esc(key.first) + ": measured and simulated, both with one-sigma bars.");
  }
  if (!grid.empty()) h += "<div class=\"grid\">" + grid + "</div>\n";
  if (!c.patterns.empty()) {
    h += "<h3>Where and how the model fails</h3>\n<ul>";
    for (const auto& p : c.patterns) h += fmt::format("<li><b>{}</b>: {}</li>", esc(p.kind), esc(p.words));
    h += "</ul>\n";
  }
  return h;
}

std::string calibration_section(const materials::CalibrationResult& r, const std::string& dir, const std::string& tag, const std::string& heading) {
  std::string h = fmt::format("<h2>{}</h2>\n", esc(heading));
  for (const std::string& w : r.words) h += "<p>" + esc(w) + "</p>\n";
  h += "<table>" + row({"parameter", "start", "fitted", "&plusmn; 1 &sigma;", "range", "identified"}, true);
  for (size_t i = 0; i < r.parameters.size(); ++i) {
    const bool bad = std::find(r.unidentified.begin(), r.unidentified.end(), r.parameters[i].key) != r.unidentified.end();
    h += row({esc(r.parameters[i].key), num(r.start[i]), num(r.value[i]), num(r.sigma[i], 2),
              fmt::format("[{}, {}]", num(r.parameters[i].min), num(r.parameters[i].max)), bad ? "<b>no</b>" : "yes"});
  }
  h += "</table>\n";
  if (r.parameters.size() > 1) {
    std::vector<std::string> header = {"correlation"};
    for (const auto& p : r.parameters) header.push_back(esc(p.key));
    h += "<table>" + row(header, true);
    for (size_t i = 0; i < r.parameters.size(); ++i) {
      std::vector<std::string> cells = {esc(r.parameters[i].key)};
      for (size_t j = 0; j < r.parameters.size(); ++j) cells.push_back(num(r.correlation[i][j], 2));
      h += row(cells);
    }
    h += "</table>\n";
  }
  std::string eig;
  for (double l : r.eigenvalues) eig += (eig.empty() ? "" : ", ") + num(l, 3);
  h += fmt::format("<p class=\"note\">Eigenvalues of J<sup>T</sup>WJ in half-range units: {}; condition number {}. A direction whose 1/&radic;&lambda; exceeds 0.5 "
                   "(a quarter of the range) is not pinned down by the data. {} simulations, {:.0f} s.</p>\n",
                   eig, num(r.condition, 3), r.simulations, r.wall_seconds);
  for (size_t k = 0; k < r.contours.size(); ++k) {
    const materials::ContourMap& c = r.contours[k];
    plot::ContourPlot p;
    p.title = fmt::format("Fig. 5 map: {} and {} over {} and {}", c.fields.front().label, c.fields.back().label, c.x_key, c.y_key);
    p.x_label = c.x_key, p.y_label = c.y_key, p.background_label = "log10 surrogate chi^2";
    p.x = c.x, p.y = c.y, p.background = c.chi2;
    for (const auto& f : c.fields)
      p.fields.push_back({fmt::format("{} = {:.4g} +- {:.2g}", f.label, f.measured, f.sigma), f.value, {f.measured - f.sigma, f.measured, f.measured + f.sigma}});
    p.marker_x = c.fit_x, p.marker_y = c.fit_y;
    std::string message;
    const std::string png = (fs::path(dir) / "plots" / fmt::format("{}_contour{}.png", tag, k)).string();
    h += figure_html(plot::draw_contour_plot(p, png, &message), png, p.title, message,
                     "Each observation's measured value (&plusmn; &sigma;) as contour lines of the surrogate over two parameters (others at the fit); "
                     "one test alone leaves a line of equally good pairs, two tests cross at the answer. Background: surrogate chi&sup2;.");
  }
  return h + comparison_section(r.after, heading + ": at the fit (real simulations)", dir, tag + "_after");
}

/// One comparison whose simulated yield loci the report shows beside the measured ones.
struct LociStage {
  std::string label;  ///< "simulated", "before calibration", ...
  const Comparison* comparison = nullptr;
};

/// The locus comparison among `loci` that belongs to the measured locus `m`; nullptr when none.
const materials::LocusComparison* matching_locus(const std::vector<materials::LocusComparison>& loci, const materials::YieldLocus& m) {
  for (const materials::LocusComparison& l : loci)
    if (l.measured.observable == m.observable && l.measured.preshear_stress == m.preshear_stress) return &l;
  return nullptr;
}

/// A locus's points in kPa with their one-sigma bars, and its fitted line from sigma = 0 to `x_end` [kPa].
void add_locus(plot::ErrorBarPlot& p, const materials::YieldLocus& locus, const std::string& label, double x_end) {
  plot::ErrorSeries s{label, {}, {}, {}, false};
  for (const materials::LocusPoint& q : locus.points)
    s.x.push_back(q.normal_stress / 1000), s.y.push_back(q.shear_stress / 1000), s.error.push_back(q.error / 1000);
  p.series.push_back(s);
  if (!locus.fit.fitted) return;
  const double slope = std::tan(locus.fit.friction_angle * std::numbers::pi / 180), intercept = locus.fit.cohesion / 1000;
  p.straight_lines.push_back({label + ": fitted line", 0, intercept, x_end, intercept + slope * x_end, static_cast<int>(p.series.size()) - 1});
}

/// One row of the loci table: phi and c with their standard errors, or why there is no fit.
std::string locus_row(const std::string& label, const materials::YieldLocusFit& f) {
  if (!f.fitted) return row({esc(label), "no fit: " + esc(f.reason), "", "", "", std::to_string(f.points), ""});
  return row({esc(label), num(f.friction_angle, 3) + " &plusmn; " + num(f.friction_angle_sigma, 2),
              num(f.cohesion / 1000, 3) + " &plusmn; " + num(f.cohesion_sigma / 1000, 2), num(f.correlation, 2), num(f.chi2_per_dof, 3),
              std::to_string(f.points), f.cohesion_zero ? "yes" : "no"});
}

/// One measured locus with the simulated loci of every stage: plot, table of phi and c, words.
std::string locus_html(const materials::YieldLocus& m, const std::vector<LociStage>& stages,
                       const std::vector<std::vector<materials::LocusComparison>>& per_stage, const std::string& png) {
  double x_end = 0;  // [kPa]
  for (const materials::LocusPoint& q : m.points) x_end = std::max(x_end, 1.1 * q.normal_stress / 1000);
  plot::ErrorBarPlot p;
  p.title = "yield locus: " + m.label();
  p.x_label = "normal stress [kPa]";
  p.y_label = "shear stress [kPa]";
  p.width = 720, p.height = 480;
  add_locus(p, m, "measured", x_end);
  std::string table = "<table>" + row({"locus", "&phi; [&deg;]", "c [kPa]", "correlation of &phi; and c", "&chi;&sup2;/dof", "points",
                                       "c within 2 &sigma; of 0"}, true) + locus_row("measured", m.fit);
  std::string words;
  for (size_t k = 0; k < stages.size(); ++k) {
    const materials::LocusComparison* l = matching_locus(per_stage[k], m);
    if (!l) continue;
    add_locus(p, l->simulated, "simulated: " + stages[k].label, x_end);
    table += locus_row("simulated: " + stages[k].label, l->simulated.fit);
    words += fmt::format("<li><b>{}</b>: {}</li>", esc(stages[k].label), esc(l->words));
  }
  std::string message;
  std::string h = fmt::format("<h3>{}</h3>\n", esc(m.label()));
  h += figure_html(plot::draw_errorbar_plot(p, png, &message), png, p.title, message,
                   "Shear stress against normal stress: points with one-sigma bars, lines the weighted Mohr-Coulomb fits.");
  return h + table + "</table>\n" + (words.empty() ? "" : "<ul>" + words + "</ul>\n");
}

/// The yield loci of the direct shear experiments, for every measured locus with two or more
/// normal stresses; "" when there is none.
std::string yield_loci_section(const materials::MeasurementSet& measured, const std::vector<LociStage>& stages, const std::string& dir) {
  std::vector<std::vector<materials::LocusComparison>> per_stage;
  for (const LociStage& s : stages) per_stage.push_back(materials::yield_loci(measured, *s.comparison));
  const std::vector<materials::YieldLocus> loci = materials::measured_yield_loci(measured);
  std::string body;
  for (size_t k = 0; k < loci.size(); ++k)
    if (loci[k].fit.fitted)
      body += locus_html(loci[k], stages, per_stage, (fs::path(dir) / "plots" / fmt::format("yield_locus{}.png", k)).string());
  if (body.empty()) return "";
  return "<h2>Yield loci</h2>\n<p>Shear tests at several normal stresses after one pre-shear, as materials are compared by Gr&ouml;ger &amp; "
         "Katterfeld: the Mohr-Coulomb line &tau; = c + &sigma; tan &phi; fitted by weighted least squares (weights 1/&sigma;&sup2;), the "
         "angle of internal friction &phi; from the slope and the cohesion c from the intercept, with standard errors from the fit's "
         "covariance. Peaks are sheared at <code>normal_stress</code> after pre-shear at <code>preshear_stress</code>; steady states "
         "at <code>preshear_stress</code>. A difference is named when it exceeds 2 &sigma; of both fits combined.</p>\n" + body;
}

/// The comparisons of a report whose yield loci are shown, labelled.
std::vector<LociStage> loci_stages(const CalibrationReportInput& in) {
  if (in.diagnosis) {
    std::vector<LociStage> stages = {{"starting model", &in.diagnosis->base.before}, {"calibrated as it is", &in.diagnosis->base.after}};
    for (const materials::CandidateResult& c : in.diagnosis->candidates)
      if (c.confirmed) stages.push_back({"with " + c.name + ", recalibrated", &c.fit.after});
    return stages;
  }
  if (in.calibration) return {{"before calibration", &in.calibration->before}, {"after calibration", &in.calibration->after}};
  if (in.comparison) return {{"simulated", in.comparison}};
  return {};
}

std::string ledger_section(const std::vector<materials::LedgerEntry>& ledger, const std::string& dir) {
  if (ledger.empty()) return "";
  std::string h = "<h2>Error ledger</h2>\n<p>Every model version of this material (ledger.yaml), its effects and parameters, and its error.</p>\n";
  std::set<std::string> terms;
  for (const auto& e : ledger)
    for (const auto& kv : e.residuals) terms.insert(kv.first);
  std::vector<std::string> header = {"version", "label", "effects", "parameters", "chi&sup2;/n"};
  for (const auto& t : terms) header.push_back(esc(t));
  h += "<table>" + row(header, true);
  for (const auto& e : ledger) {
    std::string effects, params;
    for (const auto& x : e.effects) effects += (effects.empty() ? "" : ", ") + esc(x);
    for (const auto& [k, v] : e.parameters) params += (params.empty() ? "" : "<br>") + esc(k) + " = " + num(v);
    const std::string label = esc(e.label) + (e.coarse_grain != 1.0 ? fmt::format("<br><small>coarse_grain {:g}</small>", e.coarse_grain) : "");
    std::vector<std::string> cells = {std::to_string(e.version), label, effects, params, num(e.chi2_per_n(), 3)};
    for (const auto& t : terms) cells.push_back(e.residuals.count(t) ? num(e.residuals.at(t), 2) : "&ndash;");
    h += row(cells);
  }
  h += "</table>\n";
  plot::ErrorBarPlot p;
  p.title = "error per model version";
  p.x_label = "model version";
  p.y_label = "chi^2/n";
  plot::ErrorSeries s{"chi^2/n", {}, {}, {}, true};
  for (size_t k = 0; k < ledger.size(); ++k) s.x.push_back(k), s.y.push_back(ledger[k].chi2_per_n()), s.error.push_back(0), p.x_tics.push_back(fmt::format("v{} {}", ledger[k].version, ledger[k].label));
  p.series.push_back(s);
  p.zero_band = {1.0};
  std::string message;
  const std::string png = (fs::path(dir) / "plots" / "ledger.png").string();
  return h + figure_html(plot::draw_errorbar_plot(p, png, &message), png, p.title, message, "chi&sup2;/n of every version; dashed: 1 (the noise level).");
}

}  // namespace

std::string write_calibration_report(const CalibrationReportInput& in, const std::string& dir) {
  fs::create_directories(fs::path(dir) / "plots");
  std::string h = html::head(in.title);
  h += fmt::format("<h1>{}</h1>\n<p class=\"meta\">material {} &middot; measurements {} &middot; {} &middot; demdesign {} &middot; {:.0f} s</p>\n", esc(in.title),
                   esc(in.material_path), esc(in.measurements_path), esc(html::now_text()), esc(in.version), in.wall_seconds);
  if (in.coarse_grain != 1.0) {
    const double f = in.coarse_grain;
    h += fmt::format("<div class=\"banner warn\">COARSE GRAINING: the virtual tests ran with parcels of coarse_grain {0:g} &mdash; the "
                     "real apparatus filled with parcels {0:g} &times; the diameter, each standing for {1:.4g} real particles, their "
                     "contact parameters scaled by stress similarity. What is fitted here is the material at that parcel size: it "
                     "holds for cases run at coarse_grain {0:g}.</div>\n",
                     f, f * f * f);
  }
  if (in.measured && !in.measured->warnings.empty()) {
    h += "<h2>Warnings on the measurement file</h2>\n<ul>";
    for (const std::string& w : in.measured->warnings) h += "<li>" + esc(w) + "</li>";
    h += "</ul>\n";
  }
  if (in.measured && !in.measured->known.empty()) {
    h += "<h2>Known inputs</h2>\n<p>Measured directly (the measurement file): inputs of every simulation, never fitted.</p>\n<table>" +
         row({"parameter", "value", "unit", "where"}, true);
    for (const materials::KnownValue& k : in.measured->known) h += row({esc(k.key), num(k.value, 4), esc(k.unit), esc(k.location.str())});
    h += "</table>\n";
  }
  if (in.diagnosis) {
    const materials::Diagnosis& d = *in.diagnosis;
    h += "<h2>Diagnosis</h2>\n";
    const bool sure = d.grade == materials::Verdict::missing || d.grade == materials::Verdict::nothing_missing || d.grade == materials::Verdict::parameter;
    h += fmt::format("<div class=\"banner {}\">Verdict: <b>{}</b>{}</div>\n", sure ? "good" : "warn", esc(materials::verdict_words(d.grade)),
                     d.best.empty() ? "" : " &mdash; best candidate " + esc(d.best));
    for (const auto& w : d.words) h += "<p><b>" + esc(w) + "</b></p>\n";
    h += "<table>" + row({"candidate", "adds", "explains", "ranked by", "confirmed chi&sup2;/n", "BIC", "&Delta;BIC", "what it adds"}, true);
    h += row({"(model as it is)", "", "", "", num(d.base.after.chi2_per_n(), 3), num(d.base_bic, 4), "0", ""});
    for (const auto& c : d.candidates) {
      std::string adds;
      for (const auto& a : c.adds) adds += (adds.empty() ? "" : ", ") + esc(a.key);
      h += row({esc(c.name) + "<br><small>" + esc(c.title) + "</small>", adds, fmt::format("{:.0f} %", 100 * c.explained), esc(c.ranked_why),
                c.confirmed ? num(c.fit.after.chi2_per_n(), 3) : "&ndash;", c.confirmed ? num(c.bic, 4) : "&ndash;",
                c.confirmed ? num(c.delta_bic, 3) : "&ndash;", esc(c.description)});
    }
    h += "</table>\n<p class=\"note\">explains: fraction of the calibrated model's chi&sup2; the screen expects the effect to remove after a "
         "short recalibration: a least-squares multiple of its signature (made orthogonal to what the fitted parameters can do) where its two "
         "strengths agree, else its own runs' chi&sup2;. BIC = chi&sup2; + k ln n. An effect is named as missing when, added and recalibrated, "
         "it lowers BIC by more than the margin, fits within the noise (chi&sup2;/n at most 1.5, or the 95 % point of chi&sup2; for few "
         "terms) and beats every other confirmed candidate by the margin; one that lowers BIC but still misfits improves the fit without "
         "explaining it and is not named.</p>\n";
    for (const auto& [rival, found] : d.separators) {
      if (found.empty()) continue;
      h += fmt::format("<h3>Experiments that would tell {} from {}</h3>\n<table>", esc(d.best), esc(rival)) +
           row({"experiment", "observable", esc(d.best) + " predicts", esc(rival) + " predicts", "&sigma;", "apart [&sigma;]"}, true);
      for (const auto& x : found)
        h += row({esc(x.id), esc(x.observable), num(x.predicted_a), num(x.predicted_b), num(x.sigma, 2), fmt::format("{:.1f}", x.separation)});
      h += "</table>\n<p class=\"note\">Both fitted models simulated on variants of the file's experiments and on standard set-ups of the tests "
           "it lacks; &sigma; is a lab's repeatability with both simulations' standard errors.</p>\n";
    }
    h += comparison_section(in.diagnosis->base.before, "The starting model", dir, "start");
    h += calibration_section(in.diagnosis->base, dir, "base", "The model as it is, calibrated");
    for (const auto& c : in.diagnosis->candidates)
      if (c.confirmed) h += calibration_section(c.fit, dir, "cand_" + c.name, "With " + c.title + " (" + c.name + "), recalibrated");
  } else if (in.calibration) {
    h += comparison_section(in.calibration->before, "Before calibration", dir, "before");
    h += calibration_section(*in.calibration, dir, "fit", "Calibration");
  } else if (in.comparison) {
    h += comparison_section(*in.comparison, "Measured against simulated", dir, "compare");
  }
  if (in.measured) h += yield_loci_section(*in.measured, loci_stages(in), dir);
  h += ledger_section(in.ledger, dir);
  if (!in.images.empty()) {
    h += "<h2>Final states</h2><div class=\"grid\">";
    for (const auto& img : in.images) h += "<figure>" + html::embed_image(img, fs::path(img).stem().string()) + "<figcaption>" + esc(fs::path(img).stem().string()) + "</figcaption></figure>";
    h += "</div>\n";
  }
  h += "</body></html>\n";
  const std::string path = (fs::path(dir) / "calibration_report.html").string();
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write the report");
  out << h;
  return path;
}

}  // namespace dem::report
