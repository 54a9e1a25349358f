// Compare: simulated against measured, normalised residuals and the pattern of the misfit per test
// (rules in calibration.h).
#include "calibration/calibration.h"
#include "calibration/calibration_support.h"

#include <Eigen/Dense>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <ranges>
#include <set>

namespace dem::materials {

using detail::kNaN;
using detail::Progress;
using detail::simulate_experiments;

namespace {

/// The set-up number that varies most (relative) over the experiments of one test.
std::map<std::string, std::string> varied_keys(const MeasurementSet& measured) {
  std::map<std::string, std::vector<const Experiment*>> by_test;
  for (const Experiment& e : measured.experiments) by_test[e.setup.test].push_back(&e);
  std::map<std::string, std::string> out;
  for (const auto& [test, list] : by_test) {
    if (list.size() < 2) continue;
    std::set<std::string> keys;
    for (const Experiment* e : list)
      for (const auto& kv : e->setup.numbers) keys.insert(kv.first);
    double best = 0;
    for (const std::string& key : keys) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo, scale = 0;
      bool all = true;
      for (const Experiment* e : list) {
        const auto it = e->setup.numbers.find(key);
        if (it == e->setup.numbers.end()) { all = false; break; }
        lo = std::min(lo, it->second), hi = std::max(hi, it->second), scale = std::max(scale, std::abs(it->second));
      }
      if (!all || scale == 0) continue;
      const double spread = (hi - lo) / scale;
      if (spread > best + 1e-12) best = spread, out[test] = key;
    }
  }
  return out;
}

std::string signed_sigma(double r) { return fmt::format("{:+.1f} sigma", r); }

/// Least squares of y on basis columns; returns coefficients and their standard errors for
/// unit-variance y (normalised residuals).
void regress(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, Eigen::VectorXd& coef, Eigen::VectorXd& se) {
  const Eigen::MatrixXd XtX = X.transpose() * X;
  coef = XtX.ldlt().solve(X.transpose() * y);
  const Eigen::MatrixXd inv = XtX.inverse();
  se = inv.diagonal().cwiseSqrt();
}

}  // namespace

double Comparison::residual(const std::string& experiment, const std::string& observable) const {
  for (const Term& t : terms)
    if (t.experiment == experiment && t.observable == observable) return t.residual;
  return kNaN;
}

// ---- comparison ---------------------------------------------------------------------------

ExperimentRun simulate_experiment(const MaterialModel& model, const Experiment& experiment, const CalibrationOptions& options, int replicas) {
  return simulate_experiments(model, {experiment}, options, replicas, nullptr, "").front();
}

Comparison compare_runs(const MeasurementSet& measured, const std::vector<ExperimentRun>& runs, const CalibrationOptions& options,
                        const std::map<std::string, double>& sigma_floor) {
  Comparison c;
  c.runs = runs;
  const auto varied = varied_keys(measured);
  for (size_t k = 0; k < measured.experiments.size() && k < runs.size(); ++k) {
    const Experiment& e = measured.experiments[k];
    const ExperimentRun& run = runs[k];
    const auto vit = varied.find(e.setup.test);
    const std::string vkey = vit == varied.end() ? "" : vit->second;
    const double vvalue = vkey.empty() ? 0.0 : e.setup.numbers.at(vkey);
    for (const auto& [obs, o] : e.observed) {
      Term t;
      t.experiment = e.id, t.test = e.setup.test, t.observable = obs;
      t.measured = o.value, t.sigma_measured = o.sigma;
      t.varied = vkey, t.varied_value = vvalue;
      const auto m = run.mean.find(obs);
      if (m == run.mean.end() || !std::isfinite(m->second)) {
        c.notes.push_back(fmt::format("{}: {} was not simulated (the test returned no value); left out of chi^2", e.id, obs));
        continue;
      }
      t.simulated = m->second;
      t.sigma_simulated = run.sigma.at(obs);
      // Another model's noise on the same apparatus: the noise of a run of one replica, and the
      // least noise of a few replicas (two that agree by chance must not look sure).
      if (const auto f = sigma_floor.find(t.name()); f != sigma_floor.end()) t.sigma_simulated = std::max(t.sigma_simulated, f->second);
      // A shrunk apparatus' mean carries the shift to full size, measured with its own noise.
      if (const auto s = options.size_shift.find(t.name()); options.size_factor < 1 && s != options.size_shift.end())
        t.sigma_simulated = std::hypot(t.sigma_simulated, s->second.sigma);
      t.residual = (t.simulated - t.measured) / std::sqrt(t.sigma_measured * t.sigma_measured + t.sigma_simulated * t.sigma_simulated);
      c.terms.push_back(t);
    }
    if (!e.outcome.empty()) {
      Term t;
      t.experiment = e.id, t.test = e.setup.test, t.observable = "outcome";
      t.measured_outcome = e.outcome;
      t.measured = 1.0, t.sigma_measured = 1.0 / options.outcome_residual;
      const auto f = run.flag_fraction.find(e.outcome);
      t.simulated = f == run.flag_fraction.end() ? 0.0 : f->second;
      // An outcome the file gave as a number is read from the simulated numbers by the same
      // rule (outcome_read_as_number): a drum bed whose surface stays level shows an angle near 0
      // whether it slides on the shell or rides on it, and the lab's number cannot tell which.
      if (const auto v = run.values.find(e.outcome_read_from); !e.outcome_read_from.empty() && v != run.values.end() && !v->second.empty()) {
        const auto read = std::count_if(v->second.begin(), v->second.end(),
                                        [&](double x) { return outcome_read_as_number(e.setup.test, e.outcome_read_from, x) == e.outcome; });
        t.simulated = std::max(t.simulated, static_cast<double>(read) / static_cast<double>(v->second.size()));
      }
      if (t.simulated > 0) t.simulated_outcome = e.outcome;
      t.residual = options.outcome_residual * (t.simulated - 1.0);
      t.varied = vkey, t.varied_value = vvalue;
      c.terms.push_back(t);
    }
    // A simulated outcome where none was observed shows in the observable (0) and in a note.
    for (const auto& [flag, fraction] : run.flag_fraction)
      if (flag != e.outcome && (flag == "blocked" || flag == "no_heap"))
        c.notes.push_back(fmt::format("{}: simulated {} in {:.0f} % of the replicas, not observed", e.id, flag, 100 * fraction));
  }
  for (const Term& t : c.terms) c.chi2 += t.residual * t.residual;
  c.n = static_cast<int>(c.terms.size());
  c.patterns = analyse_patterns(c.terms);
  return c;
}

Comparison compare(const MaterialModel& model, const MeasurementSet& measured, const CalibrationOptions& given) {
  const CalibrationOptions options = detail::within_command(given);
  const detail::CommandScope command(options.context, "compare", static_cast<int>(measured.experiments.size()) * std::max(1, options.replicas));
  Progress progress{options, "compare"};
  for (const Experiment& e : measured.experiments) progress.plan(e, std::max(1, options.replicas));
  std::vector<ExperimentRun> runs = simulate_experiments(model, measured.experiments, options, options.replicas, &progress, "");
  Comparison c = compare_runs(measured, runs, options);
  // More packings where the verdict depends on them: near the line between fitting within the
  // noise and not, the largest residuals decide, and a mean of few packings may sit far from the
  // model's own mean while they happen to agree. Deterministic tests (one particle) are left, and
  // so is a diagnosis's runner-up too far behind the best candidate to rival it either way.
  const auto undecided = [&](const Comparison& now) {
    std::vector<size_t> out;
    const double per_n = now.chi2_per_n();
    if (per_n <= options.fits_within_noise || per_n > 4 * options.fits_within_noise || now.chi2 > options.no_rival_above_chi2) return out;
    for (size_t k = 0; k < runs.size(); ++k) {
      if (runs[k].replicas >= options.most_replicas) continue;
      bool beyond = false, scatters = false;
      for (const Term& t : now.terms)
        if (t.experiment == runs[k].id && std::abs(t.residual) > 2) beyond = true;
      for (const auto& [key, list] : runs[k].values)
        if (std::any_of(list.begin(), list.end(), [&](double v) { return v != list.front(); })) scatters = true;
      if (beyond && scatters) out.push_back(k);
    }
    return out;
  };
  for (std::vector<size_t> more = undecided(c); !more.empty(); more = undecided(c)) {
    std::vector<const Experiment*> experiments;
    std::vector<ExperimentRun*> extended;
    for (size_t k : more) experiments.push_back(&measured.experiments[k]), extended.push_back(&runs[k]), progress.plan(measured.experiments[k]);
    command.count().plan_more(static_cast<int>(more.size()));
    if (options.progress)
      options.progress(fmt::format("compare: chi^2/n {:.2f} is near the line of {:.2f}; one more packing of {}", c.chi2_per_n(), options.fits_within_noise,
                                   fmt::join(experiments | std::views::transform([](const Experiment* e) { return e->id; }), ", ")));
    detail::add_packing(model, experiments, extended, options, &progress);
    c = compare_runs(measured, runs, options);
  }
  return c;
}

std::vector<Pattern> analyse_patterns(const std::vector<Term>& terms) {
  std::map<std::pair<std::string, std::string>, std::vector<const Term*>> groups;
  std::vector<std::pair<std::string, std::string>> order;
  for (const Term& t : terms) {
    if (t.is_outcome()) continue;
    const auto key = std::make_pair(t.test, t.observable);
    if (!groups.count(key)) order.push_back(key);
    groups[key].push_back(&t);
  }
  std::vector<Pattern> out;
  for (const auto& key : order) {
    const auto& list = groups[key];
    Pattern p;
    p.test = key.first, p.observable = key.second, p.varied = list.front()->varied;
    p.count = static_cast<int>(list.size());
    for (const Term* t : list) p.mean += t->residual / p.count, p.chi2 += t->residual * t->residual;
    const std::string what = fmt::format("{} ({})", p.observable, p.test);
    const std::string sign_word = p.mean > 0 ? "higher" : "lower";
    if (p.count == 1) {
      p.kind = std::abs(p.mean) <= 2 ? "fits" : "single";
      p.words = p.kind == "fits" ? fmt::format("{}: fits within the noise ({}).", what, signed_sigma(p.mean))
                                 : fmt::format("{}: simulated {} than measured by {:.1f} sigma (one experiment: no pattern can be told).", what,
                                               sign_word, std::abs(p.mean));
      out.push_back(p);
      continue;
    }
    // Normalised set-up quantity z in [-1, 1].
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Term* t : list) lo = std::min(lo, t->varied_value), hi = std::max(hi, t->varied_value);
    const bool varies = !p.varied.empty() && hi > lo;
    std::set<double> distinct;
    for (const Term* t : list) distinct.insert(t->varied_value);
    // Weighted least squares on the differences d = simulated - measured in the observable's own
    // unit (d_i = r_i s_i, s_i = sqrt(s_meas^2 + s_sim^2)): rows scaled by 1/s_i, so y = r. A
    // constant offset in stress units (cohesion) is then told apart from a slope (friction) even
    // when the experiments' uncertainties differ, which residuals in sigma would read as a trend.
    Eigen::VectorXd y(p.count), z(p.count), w(p.count);
    double typical = 0;  // rms uncertainty of the group, in the observable's unit
    for (int i = 0; i < p.count; ++i) {
      const Term& t = *list[i];
      const double sigma = std::sqrt(t.sigma_measured * t.sigma_measured + t.sigma_simulated * t.sigma_simulated);
      w[i] = sigma > 0 ? 1.0 / sigma : 1.0;
      y[i] = t.residual;
      z[i] = varies ? 2 * (t.varied_value - lo) / (hi - lo) - 1 : 0;
      typical += 1.0 / (w[i] * w[i]) / p.count;
    }
    typical = std::sqrt(typical);
    bool slope_significant = false, curve_significant = false;
    if (varies && distinct.size() >= 2) {
      Eigen::MatrixXd X(p.count, 2);
      X.col(0) = w, X.col(1) = z.cwiseProduct(w);
      Eigen::VectorXd coef, se;
      regress(X, y, coef, se);
      p.slope = 2 * coef[1];  // change over the whole range
      p.at_low = coef[0] - coef[1], p.at_high = coef[0] + coef[1];
      slope_significant = std::abs(coef[1]) > 2 * se[1] && std::abs(p.slope) > 1.5 * typical;
      if (distinct.size() >= 4) {
        Eigen::MatrixXd Q(p.count, 3);
        Q.col(0) = w, Q.col(1) = z.cwiseProduct(w), Q.col(2) = z.cwiseProduct(z).cwiseProduct(w);
        regress(Q, y, coef, se);
        p.curvature = coef[2];
        curve_significant = std::abs(coef[2]) > 2 * se[2] && std::abs(coef[2]) > 1.0 * typical;
      }
    }
    // The weighted mean difference and its standard error.
    p.offset = w.dot(y) / w.squaredNorm();
    const double offset_se = 1.0 / w.norm();
    const bool offset_significant = std::abs(p.offset) > 2 * offset_se && std::abs(p.offset) > 1.0 * typical;
    const std::string range = varies ? fmt::format("{} from {:g} to {:g}", p.varied, lo, hi) : "the experiments";
    if (p.chi2 / p.count <= 2.0 && !slope_significant && !offset_significant) {
      p.kind = "fits";
      p.words = fmt::format("{}: fits within the noise over {} (mean residual {}).", what, range, signed_sigma(p.mean));
    } else if (curve_significant) {
      p.kind = "curvature";
      p.words = fmt::format("{}: wrong curvature with {}: simulated - measured bends by {:+.4g} at the ends relative to the middle over {}.", what,
                            p.varied, p.curvature, range);
    } else if (slope_significant) {
      p.kind = "trend";
      p.words = fmt::format("{}: wrong trend with {}: simulated - measured goes from {:+.4g} to {:+.4g} over {} (the simulated value {} faster with {} than the measured one).",
                            what, p.varied, p.at_low, p.at_high, range, p.slope > 0 ? "rises" : "falls", p.varied);
      if (p.test == "direct_shear" && p.observable == "peak_shear_stress")
        p.words += " The yield locus has the wrong slope: the internal friction (sliding or rolling friction) is off.";
      if (p.test == "rotating_drum") p.words += " The speed dependence of the dynamic angle is wrong (damping, rolling resistance or cohesion).";
    } else if (offset_significant) {
      p.kind = "offset";
      p.words = fmt::format("{}: a constant offset: simulated {} than measured by {:.4g} ({:.1f} sigma) on average over {}, with no trend.", what,
                            p.offset > 0 ? "higher" : "lower", std::abs(p.offset), std::abs(p.mean), range);
      if (p.test == "direct_shear" && p.observable == "peak_shear_stress")
        p.words += fmt::format(" The yield locus is offset by a constant while its slope fits: {}.",
                               p.offset < 0 ? "cohesion is missing (liquid bridges or van der Waals)" : "the model has too much cohesion");
    } else {
      p.kind = "scatter";
      p.words = fmt::format("{}: misfit without a pattern (chi^2/n = {:.1f} over {}): scattered beyond the stated noise.", what, p.chi2 / p.count, range);
    }
    out.push_back(p);
  }
  return out;
}

std::vector<LocusComparison> yield_loci(const MeasurementSet& measured, const Comparison& comparison) {
  std::vector<ShearValue> observed, simulated;
  for (const Term& t : comparison.terms) {
    if (t.is_outcome() || t.test != "direct_shear") continue;
    observed.push_back({t.experiment, t.observable, t.measured, t.sigma_measured});
    simulated.push_back({t.experiment, t.observable, t.simulated, t.sigma_simulated});
  }
  // Both groupings see the same experiments, so their loci pair by observable and pre-shear.
  const std::vector<YieldLocus> measured_loci = group_yield_loci(measured, observed), simulated_loci = group_yield_loci(measured, simulated);
  std::vector<LocusComparison> out;
  for (const YieldLocus& m : measured_loci)
    for (const YieldLocus& s : simulated_loci)
      if (s.observable == m.observable && s.preshear_stress == m.preshear_stress)
        out.push_back({m, s, compare_yield_loci(m.fit, s.fit)});
  return out;
}

}  // namespace dem::materials
