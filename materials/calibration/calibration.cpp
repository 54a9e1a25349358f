// Calibrate: the surrogate over a Latin hypercube design, NLopt on it, and the contour maps (rules
// in calibration.h); compare is in comparison.cpp, the batches of simulations in
// simulation_batch.cpp, the ledger in ledger.cpp; the diagnosis in diagnosis/diagnosis.cpp.
#include "calibration/calibration.h"
#include "calibration/calibration_support.h"

#include <fmt/format.h>

#include <nlopt.hpp>

#include <algorithm>
#include <optional>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

#include "contact/effect.h"
#include "model/base_properties.h"

namespace dem::materials {

using detail::Clock;
using detail::Job;
using detail::join;
using detail::kNaN;
using detail::Progress;
using detail::rethrow;
using detail::run_batch;
using detail::seconds_since;

// ---- surrogate ----------------------------------------------------------------------------

namespace {

/// Quadratic basis in normalised u: 1, u_i, u_i u_j (i <= j).
int basis_size(int p) { return 1 + p + p * (p + 1) / 2; }

Eigen::VectorXd basis(const Eigen::VectorXd& u) {
  const int p = static_cast<int>(u.size());
  Eigen::VectorXd b(basis_size(p));
  int k = 0;
  b[k++] = 1;
  for (int i = 0; i < p; ++i) b[k++] = u[i];
  for (int i = 0; i < p; ++i)
    for (int j = i; j < p; ++j) b[k++] = u[i] * u[j];
  return b;
}

/// d basis / d u: (basis x p).
Eigen::MatrixXd basis_gradient(const Eigen::VectorXd& u) {
  const int p = static_cast<int>(u.size());
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(basis_size(p), p);
  int k = 1;
  for (int i = 0; i < p; ++i) g(k++, i) = 1;
  for (int i = 0; i < p; ++i)
    for (int j = i; j < p; ++j) {
      g(k, i) += u[j];
      g(k, j) += u[i];
      ++k;
    }
  return g;
}

Eigen::VectorXd to_unit(const std::vector<FitParameter>& box, const Eigen::VectorXd& x) {
  Eigen::VectorXd u(x.size());
  for (int i = 0; i < x.size(); ++i) u[i] = 2 * (x[i] - box[i].min) / (box[i].max - box[i].min) - 1;
  return u;
}

Eigen::VectorXd from_unit(const std::vector<FitParameter>& box, const Eigen::VectorXd& u) {
  Eigen::VectorXd x(u.size());
  for (int i = 0; i < u.size(); ++i) x[i] = box[i].min + 0.5 * (u[i] + 1) * (box[i].max - box[i].min);
  return x;
}

}  // namespace

Eigen::VectorXd Surrogate::predict(const Eigen::VectorXd& x) const { return coefficients * basis(to_unit(box, x)); }

Eigen::MatrixXd Surrogate::jacobian(const Eigen::VectorXd& x) const {
  Eigen::MatrixXd j = coefficients * basis_gradient(to_unit(box, x));  // d/du
  for (int i = 0; i < j.cols(); ++i) j.col(i) *= 2.0 / (box[i].max - box[i].min);
  return j;
}

Surrogate fit_surrogate(const std::vector<FitParameter>& box, const std::vector<std::string>& terms, const Eigen::MatrixXd& points,
                        const Eigen::MatrixXd& values, const Eigen::VectorXd& sigma) {
  Surrogate s;
  s.box = box, s.terms = terms, s.points = points, s.values = values;
  const int n = static_cast<int>(points.rows()), p = static_cast<int>(box.size()), b = basis_size(p);
  Eigen::MatrixXd X(n, b);
  for (int i = 0; i < n; ++i) X.row(i) = basis(to_unit(box, points.row(i).transpose())).transpose();
  // Three forms, each a subset of the quadratic basis: linear (1, u_i), separable (and u_i^2),
  // full (and u_i u_j). Each term takes the form with the smallest leave-one-out error (PRESS,
  // from the hat matrix: e_i / (1 - h_ii)): a design of a few points more than the full quadratic
  // has coefficients would otherwise fit the simulation noise and a response that is not
  // quadratic (a heap that stops forming) with wild curvature between the points.
  std::vector<std::vector<int>> forms(3);
  for (int k = 0; k <= p; ++k) forms[0].push_back(k), forms[1].push_back(k), forms[2].push_back(k);
  for (int i = 0, k = p + 1; i < p; ++i)  // the quadratic terms in basis() order
    for (int j = i; j < p; ++j, ++k) {
      if (i == j) forms[1].push_back(k);
      forms[2].push_back(k);
    }
  s.coefficients = Eigen::MatrixXd::Zero(values.cols(), b);
  s.form.assign(values.cols(), "quadratic");
  const char* names[] = {"linear", "separable", "quadratic"};
  std::vector<double> best_press(values.cols(), std::numeric_limits<double>::infinity());
  for (int f = 0; f < 3; ++f) {
    const int m = static_cast<int>(forms[f].size());
    if (n < m) continue;
    Eigen::MatrixXd Xf(n, m);
    for (int c = 0; c < m; ++c) Xf.col(c) = X.col(forms[f][c]);
    // Least squares through a rank-revealing QR: a design too small for the form still gives the
    // minimum-norm fit of what it can resolve.
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> qr(Xf);
    const Eigen::MatrixXd coef = qr.solve(values);  // (m x terms)
    const Eigen::MatrixXd hat = Xf * qr.pseudoInverse();
    const Eigen::MatrixXd residual = values - Xf * coef;
    for (int t = 0; t < values.cols(); ++t) {
      double press = 0;
      for (int i = 0; i < n && std::isfinite(press); ++i) {
        const double leverage = 1.0 - hat(i, i);
        press = leverage > 1e-6 ? press + std::pow(residual(i, t) / leverage, 2) : std::numeric_limits<double>::infinity();
      }
      // With no finite leave-one-out error (every point needed), the largest form that fits.
      if (press < best_press[t] * (1 - 1e-9) || (!std::isfinite(best_press[t]) && !std::isfinite(press))) {
        best_press[t] = press;
        s.coefficients.row(t).setZero();
        for (int c = 0; c < m; ++c) s.coefficients(t, forms[f][c]) = coef(c, t);
        s.form[t] = names[f];
      }
    }
  }
  const Eigen::MatrixXd fitted = X * s.coefficients.transpose();
  for (int t = 0; t < values.cols(); ++t) {
    const double rms = std::sqrt((fitted.col(t) - values.col(t)).squaredNorm() / std::max(1, n));
    s.fit_rms.push_back(sigma[t] > 0 ? rms / sigma[t] : rms);
  }
  return s;
}

Eigen::MatrixXd latin_hypercube(const std::vector<FitParameter>& box, int n, std::uint64_t seed) {
  const int p = static_cast<int>(box.size());
  std::mt19937_64 random(seed);
  Eigen::MatrixXd best;
  double best_distance = -1;
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::MatrixXd u(n, p);
    for (int j = 0; j < p; ++j) {
      std::vector<int> order(n);
      std::iota(order.begin(), order.end(), 0);
      std::shuffle(order.begin(), order.end(), random);
      std::uniform_real_distribution<double> jitter(0.0, 1.0);
      for (int i = 0; i < n; ++i) u(i, j) = (order[i] + jitter(random)) / n;
    }
    double nearest = std::numeric_limits<double>::infinity();
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b) nearest = std::min(nearest, (u.row(a) - u.row(b)).squaredNorm());
    if (nearest > best_distance) best_distance = nearest, best = u;
  }
  Eigen::MatrixXd x(n, p);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < p; ++j) x(i, j) = box[j].min + best(i, j) * (box[j].max - box[j].min);
  return x;
}

// ---- calibration --------------------------------------------------------------------------

std::vector<FitParameter> fit_parameters(const MaterialModel& model, const std::vector<std::string>& keys) {
  std::vector<FitParameter> out;
  if (keys.empty()) {
    for (const auto& [key, range] : model.tunable) out.push_back({key, range.first, range.second});
    return out;
  }
  for (const std::string& key : keys) {
    if (std::find(model.known.begin(), model.known.end(), key) != model.known.end())
      throw std::invalid_argument(fmt::format("'{}' was measured ({}): it is an input of the model, not fitted; remove it from the "
                                              "measurement file to calibrate it", key, model.particle.sources.count(key) ? model.particle.sources.at(key) : "measurement file"));
    const auto it = model.tunable.find(key);
    if (it != model.tunable.end()) {
      out.push_back({key, it->second.first, it->second.second});
      continue;
    }
    (void)get_parameter(model, key);  // throws for an unknown key
    const BaseProperty* property = find_base_property(key);
    const ParamSpec* spec = property ? &property->spec : find_param(key);
    if (!spec || !spec->tunable)
      throw std::invalid_argument(fmt::format("'{}' has no calibration range: declare it under `tunable:` in the material file", key));
    out.push_back({key, spec->min_value, spec->max_value});
  }
  return out;
}

namespace {

struct SurrogateObjective {
  const Surrogate* surrogate;
  Eigen::VectorXd measured, sigma;
  double chi2(const Eigen::VectorXd& x) const { return ((surrogate->predict(x) - measured).array() / sigma.array()).square().sum(); }
};

double nlopt_objective(const std::vector<double>& u, std::vector<double>&, void* data) {
  const auto* o = static_cast<const SurrogateObjective*>(data);
  const Eigen::VectorXd uu = Eigen::Map<const Eigen::VectorXd>(u.data(), static_cast<Eigen::Index>(u.size()));
  return o->chi2(from_unit(o->surrogate->box, uu));
}

/// Minimises the surrogate chi^2 from several starts; returns the best point (physical).
Eigen::VectorXd minimise(const SurrogateObjective& objective, const std::vector<Eigen::VectorXd>& starts) {
  const auto& box = objective.surrogate->box;
  const unsigned p = static_cast<unsigned>(box.size());
  Eigen::VectorXd best = starts.front();
  double best_value = objective.chi2(best);
  for (const Eigen::VectorXd& start : starts) {
    nlopt::opt opt(p >= 2 ? nlopt::LN_BOBYQA : nlopt::LN_COBYLA, p);
    opt.set_lower_bounds(std::vector<double>(p, -1.0));
    opt.set_upper_bounds(std::vector<double>(p, 1.0));
    opt.set_min_objective(nlopt_objective, const_cast<SurrogateObjective*>(&objective));
    opt.set_xtol_rel(1e-8);
    opt.set_maxeval(4000);
    const Eigen::VectorXd u0 = to_unit(box, start).cwiseMax(-1.0).cwiseMin(1.0);
    std::vector<double> u(u0.data(), u0.data() + u0.size());
    double value = 0;
    try {
      opt.optimize(u, value);
    } catch (const std::exception&) {
      value = nlopt_objective(u, u, const_cast<SurrogateObjective*>(&objective));  // keep the last point
    }
    if (value < best_value) best_value = value, best = from_unit(box, Eigen::Map<Eigen::VectorXd>(u.data(), p));
  }
  return best;
}

MaterialModel with_values(const MaterialModel& model, const std::vector<FitParameter>& box, const Eigen::VectorXd& x) {
  MaterialModel m = model;
  for (size_t i = 0; i < box.size(); ++i) set_parameter(m, box[i].key, x[static_cast<Eigen::Index>(i)]);
  return m;
}

}  // namespace

/// Where a fitted value of a dry bulk solid usually lies, when the material file states none
/// (`plausible:`): its parameter row's (ParamSpec::plausible), which gives sliding friction between
/// particles or against a wall liner 0.1-0.7, restitution 0.1-0.95 and rolling friction (a
/// stand-in for shape) 0-0.4, the span of calibrated values surveyed by Coetzee (2017, Powder
/// Technology 310:104) for dry granular materials. A value outside, or one that runs to the edge
/// of its tunable range, is most often the fit absorbing physics the model lacks (friction raised
/// to 0.8 for missing rolling resistance or cohesion).
std::optional<std::pair<double, double>> plausible_range(const MaterialModel& model, const std::string& key) {
  if (const auto it = model.particle.plausible.find(key); it != model.particle.plausible.end()) return it->second;
  const std::string base = key.substr(key.rfind('.') + 1);
  if (const auto it = model.particle.plausible.find(base); it != model.particle.plausible.end()) return it->second;
  if (const ParamSpec* row = find_param(base)) return row->plausible;
  return std::nullopt;
}

std::vector<std::string> implausible_fits(const MaterialModel& model, const std::vector<FitParameter>& parameters, const std::vector<double>& values,
                                          const std::vector<double>& sigma, std::vector<std::string>& words) {
  std::vector<std::string> keys, said, undetermined;
  for (size_t i = 0; i < parameters.size() && i < values.size(); ++i) {
    const FitParameter& p = parameters[i];
    const double v = values[i], span = p.highest() - p.lowest();
    const auto plausible = plausible_range(model, p.key);
    // Out by more than twice the fitted value's standard error: a truth at the range's edge is not named.
    const double err = i < sigma.size() && std::isfinite(sigma[i]) ? 2 * sigma[i] : 0.0;
    const bool out = plausible && (v + err < plausible->first || v - err > plausible->second);
    // An edge of the range the fit may use; a strength at zero (an effect switched off) is none.
    const bool low = span > 0 && v - p.lowest() < 0.02 * span && p.lowest() != 0, high = span > 0 && p.highest() - v < 0.02 * span;
    if (!out && !low && !high) continue;
    // At an edge with an error of a quarter of the range or more: these data do not determine it,
    // and the edge says nothing of missing physics (control_traits.yaml: restitution 0.3 +- 0.3 in
    // [0.3, 0.85], the data's bulk tests hardly moved by it).
    if (!out && err >= 0.5 * span) {
      undetermined.push_back(fmt::format("{} = {:.3g} +- {:.2g} in [{:g}, {:g}]", p.key, v, sigma[i], p.lowest(), p.highest()));
      continue;
    }
    keys.push_back(p.key);
    const bool own = model.particle.plausible.count(p.key) || model.particle.plausible.count(p.key.substr(p.key.rfind('.') + 1));
    said.push_back(fmt::format("{} = {:.3g}{}{}", p.key, v,
                               out ? fmt::format(", outside {:g} to {:g} ({})", plausible->first, plausible->second,
                                                 own ? "the material file's plausible range" : "what dry bulk solids usually show")
                                   : "",
                               low || high ? fmt::format(", at the edge of its range [{:g}, {:g}]", p.lowest(), p.highest()) : ""));
  }
  if (!said.empty())
    words.push_back(fmt::format("Implausible fit: {}. A fitted value out of its plausible range, or run to the edge of its own, is most often "
                                "the fit absorbing physics the model lacks (diagnose names candidates); check it before designing with it.",
                                join(said, "; ")));
  if (!undetermined.empty())
    words.push_back(fmt::format("Not determined by these experiments: {}. Its error spans much of its range, so the fit's value is "
                                "arbitrary, not a sign of missing physics; an experiment that measures it (for restitution, a drop "
                                "test between particles) would fix it.",
                                join(undetermined, "; ")));
  return keys;
}

namespace {

/// The numeric terms of the first comparison: what the surrogate predicts and the fit matches.
struct Targets {
  std::vector<std::string> names;          ///< term names (experiment/observable)
  Eigen::VectorXd measured_values, sigma;  ///< (terms) measured value; measured and simulation noise combined
  std::map<std::string, int> index;        ///< term name -> its place in names
};

/// What every phase after the first comparison reads: the inputs as the walls' first stage and the
/// budget left them, and the size of a surrogate round.
struct Fit {
  const MaterialModel& model;                   ///< with the walls' first stage
  const MeasurementSet& measured;
  const std::vector<FitParameter>& parameters;
  const CalibrationOptions& options;            ///< as the budget plan left them
  const Targets& targets;
  int p;                                        ///< parameters fitted
  int points;                                   ///< design points of the first round
  int rounds;                                   ///< surrogate rounds before any refinement
  /// Design points of a zoom round: the full rule where the first round's design stood beside
  /// known points (confirmation_design_points), which a smaller box mostly leaves out.
  int later_points;
  int refine_points;                            ///< of a refinement round (refinement_design_points)
};

/// The surrogate rounds' state: the box searched, its optimum, and every point simulated so far.
struct Search {
  std::vector<FitParameter> box;           ///< the box of the round running
  Eigen::VectorXd x_best;                  ///< (p) the last optimum, physical units
  Surrogate full_range;                    ///< of round 1, over the whole parameter box: drawn in the contour maps
  Eigen::MatrixXd all_points, all_values;  ///< (points simulated x p), (points simulated x terms)
  std::vector<Eigen::VectorXd> included;   ///< points the first round takes from EarlierPoints::include
  double seconds_per_point = 0;            ///< [s] what a point (every experiment once) takes: the refinement's estimate
  void add_point(const Eigen::VectorXd& x, const Eigen::VectorXd& v) {
    all_points.conservativeResize(all_points.rows() + 1, Eigen::NoChange);
    all_values.conservativeResize(all_values.rows() + 1, Eigen::NoChange);
    all_points.row(all_points.rows() - 1) = x.transpose();
    all_values.row(all_values.rows() - 1) = v.transpose();
  }
};

/// The wall pairs' restitution fitted first, and the pairs it gave another value ("steel.restitution 0.6").
struct WallStage {
  detail::WallsFirst first;
  std::vector<std::string> moved;
};

/// The parameters fitted (the model's tunable ranges when none are given) and their start values.
void choose_parameters(const MaterialModel& given_model, std::vector<FitParameter>& parameters, CalibrationResult& result) {
  if (parameters.empty()) parameters = fit_parameters(given_model);
  if (parameters.empty()) throw std::invalid_argument("nothing to calibrate: the material declares no `tunable:` ranges and none were given");
  result.parameters = parameters;
  for (const FitParameter& f : parameters) result.start.push_back(get_parameter(given_model, f.key));
}

/// The walls' first stage, and the wall pairs it moved.
WallStage fit_walls_stage(const MaterialModel& given_model, const MeasurementSet& measured, const std::vector<FitParameter>& parameters,
                          const EarlierPoints& earlier, CalibrationOptions& options, CalibrationResult& result) {
  // Stage one: the wall pairs' restitution from their drop tests (walls_first.cpp). The design
  // starts from that model; `before` stays the comparison of the model as given.
  WallStage stage{detail::fit_walls_first(given_model, measured, parameters, options), {}};
  const MaterialModel& model = stage.first.model;
  result.words = stage.first.words;
  // Wall pairs the first stage gave another value: points simulated before (EarlierPoints::known)
  // had the old one and are left out below; a design reduced to stand beside them
  // (confirmation_design_points, design_points_beside_known: any count given with known points)
  // takes the full rule again.
  std::vector<std::string>& moved = stage.moved;
  for (size_t k = 0; k < model.wall_pairs.size() && k < given_model.wall_pairs.size(); ++k)
    for (const auto& [key, value] : model.wall_pairs[k].params)
      if (const auto it = given_model.wall_pairs[k].params.find(key); it == given_model.wall_pairs[k].params.end() || it->second != value)
        moved.push_back(fmt::format("{}.{} {:.3g}", model.wall_pairs[k].material_a == model.name ? model.wall_pairs[k].material_b
                                                                                                 : model.wall_pairs[k].material_a,
                                    key, value));
  if (!moved.empty() && !earlier.known.empty() && options.design_points > 0) options.design_points = 0;
  return stage;
}

/// The start, with replicas: its simulation noise stands for the noise everywhere.
void compare_start(const MaterialModel& given_model, const MeasurementSet& measured, const CalibrationOptions& options, const Comparison* before,
                   CalibrationResult& result) {
  if (before) result.before = *before;
  else result.before = compare(given_model, measured, options), result.simulations += result.before.simulations();
}

/// With a budget, the options reduced to fit it and the words saying so; without, the whole plan
/// in a progress line.
std::string plan_for_budget(const CalibrationOptions& given, Clock::time_point t0, const detail::CommandScope& command, int n, int p,
                            const Comparison& first, CalibrationOptions& options) {
  std::string budget_words;
  if (options.budget_seconds > 0) {
    const BudgetPlan plan = plan_within_budget(options, first, p, 0, 0, seconds_since(t0));
    options = plan.options;
    options.budget_seconds = 0;
    budget_words = fmt::format("Planned for the budget of {}: about {} after the first comparison{}.", detail::duration_text(given.budget_seconds),
                               detail::duration_text(plan.seconds), plan.given_up.empty() ? "" : "; given up: " + join(plan.given_up, "; "));
    if (options.progress) options.progress(budget_words);
    if (command.outermost()) command.count().plan_remaining(n * detail::calibration_passes(options, p));
  } else if (command.outermost() && options.progress) {
    // Without a budget the whole plan, at what the first comparison's simulations cost.
    CalibrationOptions unlimited = options;
    unlimited.budget_seconds = 1e12;
    const BudgetPlan plan = plan_within_budget(unlimited, first, p, 0, 0, seconds_since(t0));
    options.progress(fmt::format("calibrate: the first comparison took {}; the calibration will take about {} more (give --budget to fit it "
                                 "into less)", detail::duration_text(seconds_since(t0)), detail::duration_text(plan.seconds)));
  }
  return budget_words;
}

/// The numeric terms (not the outcomes) of the first comparison, with their combined sigma.
Targets numeric_targets(const Comparison& first) {
  std::vector<Term> numeric;
  for (const Term& t : first.terms)
    if (!t.is_outcome()) numeric.push_back(t);
  if (numeric.empty()) throw std::invalid_argument("no numeric observations to calibrate against");
  Targets targets;
  targets.measured_values.resize(static_cast<Eigen::Index>(numeric.size()));
  targets.sigma.resize(static_cast<Eigen::Index>(numeric.size()));
  std::map<std::string, double> sigma_sim;
  for (size_t i = 0; i < numeric.size(); ++i) {
    targets.names.push_back(numeric[i].name());
    targets.measured_values[i] = numeric[i].measured;
    targets.sigma[i] = std::sqrt(numeric[i].sigma_measured * numeric[i].sigma_measured + numeric[i].sigma_simulated * numeric[i].sigma_simulated);
    sigma_sim[numeric[i].name()] = numeric[i].sigma_simulated;
  }
  for (size_t i = 0; i < targets.names.size(); ++i) targets.index[targets.names[i]] = static_cast<int>(i);
  return targets;
}

/// The design's simulations planned, the first box (the parameters' own) and the start as the
/// last optimum, before any point is simulated.
Search start_search(const Fit& fit, const std::vector<double>& start, Progress& progress) {
  for (const Experiment& e : fit.measured.experiments) progress.plan(e, fit.points + (fit.rounds - 1) * fit.later_points);
  Search search;
  search.box = fit.parameters;
  search.x_best.resize(fit.p);
  for (int i = 0; i < fit.p; ++i) search.x_best[i] = std::clamp(start[i], fit.parameters[i].lowest(), fit.parameters[i].highest());
  search.all_points.resize(0, fit.p);
  search.all_values.resize(0, static_cast<Eigen::Index>(fit.targets.names.size()));
  return search;
}

/// A box `share` of the last box wide around x, inside the limits (at a limit it keeps its width).
std::vector<FitParameter> zoom(const std::vector<FitParameter>& parameters, const Eigen::VectorXd& x, const std::vector<FitParameter>& last,
                               double share) {
  const int p = static_cast<int>(parameters.size());
  std::vector<FitParameter> next = last;
  for (int i = 0; i < p; ++i) {
    const double lowest = parameters[i].lowest(), highest = parameters[i].highest();
    const double half = 0.5 * share * (last[i].max - last[i].min);
    const double lo = std::max(lowest, x[i] - half), hi = std::min(highest, x[i] + half);
    next[i].min = lo, next[i].max = hi;
    if (hi - lo < 2 * half) {
      if (lo == lowest) next[i].max = std::min(highest, lo + 2 * half);
      else next[i].min = std::max(lowest, hi - 2 * half);
    }
  }
  return next;
}

/// Known points: data from the start, where they hold a value of every term, unless the walls'
/// first stage gave a wall pair another value than they were simulated with (a cohesive
/// candidate holds the rebound down, so its drops ask for a livelier wall).
void feed_known_points(const Fit& fit, const EarlierPoints& earlier, const std::vector<std::string>& moved, Search& search, CalibrationResult& result) {
  const std::vector<std::string>& names = fit.targets.names;
  int known = 0;
  if (!moved.empty() && !earlier.known.empty()) {
    const bool one = earlier.known.size() == 1;
    result.words.push_back(fmt::format("The {} point{} simulated before {} left out: the drops gave {} a new value ({}).", earlier.known.size(),
                                       one ? "" : "s", one ? "was" : "were", moved.size() == 1 ? "a wall pair" : "wall pairs", join(moved)));
    if (fit.options.progress) fit.options.progress("calibrate: " + result.words.back());
  }
  for (const SimulatedPoint& point : earlier.known) {
    if (!moved.empty() || static_cast<int>(point.x.size()) != fit.p) continue;
    Eigen::VectorXd v(static_cast<Eigen::Index>(names.size()));
    for (size_t i = 0; i < names.size(); ++i) {
      const auto it = point.values.find(names[i]);
      v[static_cast<Eigen::Index>(i)] = it == point.values.end() ? kNaN : it->second;
    }
    if (v.allFinite()) search.add_point(Eigen::Map<const Eigen::VectorXd>(point.x.data(), fit.p), v), ++known;
  }
  if (known > 0) {
    result.words.push_back(fmt::format("{} point{} simulated before, with a model this one equals there, fed the surrogate beside the "
                                       "design's own.",
                                       known, known == 1 ? "" : "s"));
    if (fit.options.progress) fit.options.progress("calibrate: " + result.words.back());
  }
}

/// The points the first round takes from `include`: inside the box, at most all but one.
std::vector<Eigen::VectorXd> included_points(const Fit& fit, const EarlierPoints& earlier) {
  std::vector<Eigen::VectorXd> included;
  for (const std::vector<double>& x : earlier.include) {
    if (static_cast<int>(x.size()) != fit.p || static_cast<int>(included.size()) + 1 >= fit.points) continue;
    bool inside = true;
    for (int i = 0; i < fit.p; ++i) inside = inside && x[i] >= fit.parameters[i].min && x[i] <= fit.parameters[i].max;
    if (inside) included.push_back(Eigen::Map<const Eigen::VectorXd>(x.data(), fit.p));
  }
  return included;
}

/// The round's design points (points x p): a Latin hypercube in the box, and in the first round
/// the points included from earlier simulations.
Eigen::MatrixXd round_design(const Fit& fit, const Search& search, int round, int later_points) {
  const int points = round == 0 ? fit.points : later_points;
  const int own = round == 0 ? points - static_cast<int>(search.included.size()) : points;
  Eigen::MatrixXd design(points, fit.p);
  design.topRows(own) = latin_hypercube(search.box, own, fit.options.seed + 7919u * static_cast<std::uint64_t>(round));
  for (int k = own; k < points; ++k) design.row(k) = search.included[k - own].transpose();
  return design;
}

/// Every experiment at every design point as one batch; a point with a value of every term joins
/// the points simulated so far.
void simulate_design(const Fit& fit, const Eigen::MatrixXd& design, int round, Search& search, Progress& progress, CalibrationResult& result) {
  const CalibrationOptions& options = fit.options;
  const MeasurementSet& measured = fit.measured;
  const int points = static_cast<int>(design.rows());
  Eigen::MatrixXd values(points, static_cast<Eigen::Index>(fit.targets.names.size()));
  values.setConstant(kNaN);
  std::vector<MaterialModel> models;
  for (int k = 0; k < points; ++k) models.push_back(with_values(fit.model, fit.parameters, design.row(k).transpose()));
  const size_t n_experiments = measured.experiments.size();
  std::vector<Job> jobs;
  for (int k = 0; k < points; ++k)
    for (const Experiment& e : measured.experiments) jobs.push_back({&models[k], &e.setup, options.seed});
  const std::vector<BatchOutcome> outcomes = run_batch(
      jobs, options,
      [&](size_t j, const BatchOutcome& b) {
        const size_t k = j / n_experiments;
        const Experiment& e = measured.experiments[j % n_experiments];
        if (b.error == BatchOutcome::Error::input) return;
        if (b.error != BatchOutcome::Error::none && options.progress)
          options.progress(fmt::format("design point {} skipped: {}: {}", k + 1, e.id, b.message));
        progress.step(e, fmt::format("round {} point {} {}{}", round + 1, k + 1, e.id, b.stored ? ", stored" : ""), b.stored ? 0.0 : b.outcome.wall_seconds);
      },
      [](const BatchOutcome& b) { return b.error == BatchOutcome::Error::input; });
  for (int k = 0; k < points; ++k) {
    bool ok = true;
    for (size_t x = 0; x < n_experiments; ++x) {
      const BatchOutcome& b = outcomes[k * n_experiments + x];
      if (b.error == BatchOutcome::Error::input) rethrow(b);
      if (b.error == BatchOutcome::Error::not_run) throw std::logic_error("calibration: the batch runner left a design simulation not run");
      ++result.simulations;
      if (b.error != BatchOutcome::Error::none) {
        ok = false;
        continue;
      }
      for (const auto& [obs, v] : b.outcome.observables) {
        const auto it = fit.targets.index.find(measured.experiments[x].id + "/" + obs);
        if (it != fit.targets.index.end()) values(k, it->second) = v;
      }
    }
    // Every round's points feed the later surrogates when they lie in their box.
    if (ok && values.row(k).allFinite()) search.add_point(design.row(k).transpose(), values.row(k).transpose());
  }
}

/// The rows of the points simulated so far that lie inside `box`.
std::vector<int> rows_inside(const Search& search, const std::vector<FitParameter>& box) {
  std::vector<int> inside;
  for (int k = 0; k < search.all_points.rows(); ++k) {
    bool in = true;
    for (int i = 0; i < static_cast<int>(box.size()); ++i)
      in = in && search.all_points(k, i) >= box[i].min - 1e-12 && search.all_points(k, i) <= box[i].max + 1e-12;
    if (in) inside.push_back(k);
  }
  return inside;
}

/// The surrogate over every point simulated so far inside the box; returns those points (inside x p).
Eigen::MatrixXd fit_round_surrogate(const Fit& fit, int round, Search& search, CalibrationResult& result) {
  const int p = fit.p;
  const std::vector<FitParameter>& box = search.box;
  const std::vector<int> inside = rows_inside(search, box);
  if (static_cast<int>(inside.size()) < basis_size(p))
    throw std::runtime_error(fmt::format("calibration: only {} of {} design points simulated; need {} for the surrogate", inside.size(), fit.points, basis_size(p)));
  Eigen::MatrixXd P(inside.size(), p), V(inside.size(), search.all_values.cols());
  for (size_t r = 0; r < inside.size(); ++r) P.row(r) = search.all_points.row(inside[r]), V.row(r) = search.all_values.row(inside[r]);
  result.surrogate = fit_surrogate(box, fit.targets.names, P, V, fit.targets.sigma);
  if (round == 0) search.full_range = result.surrogate;
  return P;
}

/// The surrogate's optimum from several starts, over the points P it was fitted to.
void optimise_round(const Fit& fit, const Eigen::MatrixXd& P, int round, Search& search, CalibrationResult& result) {
  const int p = fit.p;
  const std::vector<FitParameter>& box = search.box;
  // Starts: the best design points, the centre of the box and the last optimum when inside.
  SurrogateObjective objective{&result.surrogate, fit.targets.measured_values, fit.targets.sigma};
  std::vector<std::pair<double, int>> ranked;
  for (int r = 0; r < P.rows(); ++r) ranked.push_back({objective.chi2(P.row(r).transpose()), r});
  std::sort(ranked.begin(), ranked.end());
  std::vector<Eigen::VectorXd> starts = {from_unit(box, Eigen::VectorXd::Zero(p))};
  bool last_inside = true;
  for (int i = 0; i < p; ++i) last_inside = last_inside && search.x_best[i] >= box[i].min && search.x_best[i] <= box[i].max;
  if (last_inside) starts.push_back(search.x_best);
  for (int s = 0; s < std::min<int>(fit.options.starts, static_cast<int>(ranked.size())); ++s) starts.push_back(P.row(ranked[s].second).transpose());
  search.x_best = minimise(objective, starts);
  result.surrogate_chi2 = objective.chi2(search.x_best);
  if (fit.options.progress)
    fit.options.progress(fmt::format("round {}: surrogate optimum {} (surrogate chi^2/n {:.2f})", round + 1,
                                     [&] {
                                       std::vector<std::string> v;
                                       for (int i = 0; i < p; ++i) v.push_back(fmt::format("{} = {:.4g}", fit.parameters[i].key, search.x_best[i]));
                                       return join(v);
                                     }(),
                                     result.surrogate_chi2 / static_cast<double>(fit.targets.names.size())));
}

/// One round: a Latin hypercube in `box`, every experiment at every point as one batch (common
/// random numbers: the same packing seed everywhere); the surrogate over every point simulated so
/// far inside the box; its optimum from several starts. A point whose simulation fails is
/// skipped; bad input (CaseError) stops the calibration.
void design_round(const Fit& fit, int round, Search& search, Progress& progress, CalibrationResult& result, int later_points) {
  const Eigen::MatrixXd design = round_design(fit, search, round, later_points);
  simulate_design(fit, design, round, search, progress, result);
  const Eigen::MatrixXd P = fit_round_surrogate(fit, round, search, result);
  optimise_round(fit, P, round, search, result);
}

/// The surrogate rounds: the first over the parameters' own box, each later one around the last optimum.
void run_rounds(const Fit& fit, Search& search, Progress& progress, CalibrationResult& result) {
  for (int round = 0; round < fit.rounds; ++round) {
    if (round > 0) search.box = zoom(fit.parameters, search.x_best, fit.parameters, 0.25);  // a quarter of each range around the last optimum
    design_round(fit, round, search, progress, result, fit.later_points);
  }
}

/// Confirmation with real simulations (replicas, and more packings where the verdict depends on them).
Comparison confirm_optimum(const Fit& fit, Search& search, CalibrationResult& result) {
  const Comparison c = compare(with_values(fit.model, fit.parameters, search.x_best), fit.measured, fit.options);
  result.simulations += c.simulations();
  Eigen::VectorXd v(static_cast<Eigen::Index>(fit.targets.names.size()));
  v.setConstant(kNaN);
  for (const Term& t : c.terms)
    if (const auto it = fit.targets.index.find(t.name()); it != fit.targets.index.end()) v[it->second] = t.simulated;
  if (v.allFinite()) search.add_point(search.x_best, v);  // a point of the next surrogate, like a design point
  return c;
}

/// chi^2 of the simulations at the point simulated in row `row`.
double simulated_chi2(const Targets& targets, const Search& search, int row) {
  return ((search.all_values.row(row).transpose() - targets.measured_values).array() / targets.sigma.array()).square().sum();
}

/// Keys whose optimum lies on an edge of the box that is not the parameter's limit.
std::vector<std::string> edges_reached(const Fit& fit, const Search& search) {
  const std::vector<FitParameter>& box = search.box;
  std::vector<std::string> edges;
  for (int i = 0; i < fit.p; ++i) {
    const double tol = 0.01 * (box[i].max - box[i].min);
    if ((search.x_best[i] <= box[i].min + tol && box[i].min > fit.parameters[i].lowest() + tol) ||
        (search.x_best[i] >= box[i].max - tol && box[i].max < fit.parameters[i].highest() - tol))
      edges.push_back(fit.parameters[i].key);
  }
  return edges;
}

/// Design points of a refinement round in `box`: its rule's (refinement_design_points), and never
/// fewer than the surrogate needs beside the points already inside the box.
int refinement_points(const Fit& fit, const Search& search, const std::vector<FitParameter>& box) {
  return std::max(fit.refine_points, basis_size(fit.p) + 1 - static_cast<int>(rows_inside(search, box).size()));
}

/// The point simulated so far whose simulations lie nearest the measurements (the optimum when none was).
Eigen::VectorXd best_simulated(const Fit& fit, const Search& search) {
  int best_row = 0;
  for (int r = 1; r < search.all_points.rows(); ++r)
    if (simulated_chi2(fit.targets, search, r) < simulated_chi2(fit.targets, search, best_row)) best_row = r;
  return search.all_points.rows() > 0 ? Eigen::VectorXd(search.all_points.row(best_row).transpose()) : search.x_best;
}

/// What a point of a later round takes (every experiment once, `parallel` at a time): the larger of
/// the start comparison's cost and the rounds' own time over the points they simulated, so that
/// points replayed from the store do not make a round look free.
double seconds_per_point(const Fit& fit, const Search& search, const Comparison& start, double rounds_seconds) {
  const double from_start = detail::seconds_per_pass(start, fit.options.parallel);
  const int simulated = fit.points - static_cast<int>(search.included.size()) + (fit.rounds - 1) * fit.later_points + std::max(1, fit.options.replicas);
  return std::max(from_start, rounds_seconds / std::max(1, simulated));
}

/// Refinement: when the simulations miss what the surrogate predicted, or the optimum lies on an
/// edge of the box that is not the parameter's limit, one more round in half the box around the
/// best point simulated so far (the confirmed optimum or a design point), confirmed in turn.
void refine_around_best(const Fit& fit, Search& search, Progress& progress, CalibrationResult& result) {
  const CalibrationOptions& options = fit.options;
  for (int refine = 0; refine < options.refine_rounds; ++refine) {
    const double real = result.after.chi2_per_n(), predicted = result.surrogate_chi2 / static_cast<double>(fit.targets.names.size());
    const bool missed = real > options.fits_within_noise && real > 2 * predicted + 1;
    const std::vector<std::string> edges = edges_reached(fit, search);
    if (!missed && edges.empty()) break;
    if (result.after.chi2 > options.no_rival_above_chi2 && result.surrogate_chi2 > options.no_rival_above_chi2) {
      result.words.push_back(fmt::format("Not refined: the simulations at the surrogate's optimum give chi^2 {:.1f} and the surrogate predicted "
                                         "{:.1f}, both above {:.1f}, where it could not rival the best candidate confirmed so far.",
                                         result.after.chi2, result.surrogate_chi2, options.no_rival_above_chi2));
      if (options.progress) options.progress("calibrate: " + result.words.back());
      break;
    }
    const Eigen::VectorXd centre = best_simulated(fit, search);
    const std::string why = missed ? fmt::format("the simulations at the surrogate's optimum give chi^2/n {:.2f} where it predicted {:.2f}", real, predicted)
                                   : fmt::format("the optimum lies on the edge of the searched box in {}", join(edges));
    const std::vector<FitParameter> box = missed ? zoom(fit.parameters, centre, search.box, 0.5) : zoom(fit.parameters, search.x_best, search.box, 1.0);
    const int points = refinement_points(fit, search, box);
    detail::CommandProgress& count = options.context->count;
    const double takes = (points + std::max(1, options.replicas)) * search.seconds_per_point;
    if (refine >= options.refine_before_deadline && count.elapsed() + takes > options.refine_deadline) {
      result.unrefined = true;
      result.words.push_back(fmt::format("Not refined: {}, but one more round ({} points, about {}) would end past the budget; the surrogate's "
                                         "prediction stands beside the simulations.",
                                         why, points, detail::duration_text(takes)));
      if (options.progress) options.progress("calibrate: " + result.words.back());
      break;
    }
    const Comparison kept_after = result.after;
    const Surrogate kept_surrogate = result.surrogate;
    const Eigen::VectorXd kept_x = search.x_best;
    const double kept_chi2 = result.surrogate_chi2;
    search.box = box;
    if (options.progress) options.progress(fmt::format("calibrate: {}: one more round of {} points around the best point simulated so far", why, points));
    const int n_experiments = static_cast<int>(fit.measured.experiments.size());
    for (const Experiment& e : fit.measured.experiments) progress.plan(e, points);
    if (count.active()) count.plan_more(n_experiments * (points + std::max(1, options.replicas)));
    search.x_best = centre;
    design_round(fit, fit.rounds + refine, search, progress, result, points);
    result.after = confirm_optimum(fit, search, result);
    if (result.after.chi2 <= kept_after.chi2) {
      result.words.push_back(fmt::format("One more surrogate round: {}; refined, the simulations give chi^2/n {:.2f}.", why, result.after.chi2_per_n()));
    } else {
      result.words.push_back(fmt::format("One more surrogate round: {}; its optimum simulated gives chi^2/n {:.2f}, so the first optimum is kept.", why,
                                         result.after.chi2_per_n()));
      result.after = kept_after, result.surrogate = kept_surrogate, search.x_best = kept_x, result.surrogate_chi2 = kept_chi2;
      break;
    }
  }
}

/// The optimum as the result's values, and the model fitted with them.
void keep_optimum(const Fit& fit, const Eigen::VectorXd& x_best, CalibrationResult& result) {
  for (int i = 0; i < fit.p; ++i) result.value.push_back(x_best[i]);
  result.fitted = with_values(fit.model, fit.parameters, x_best);
}

/// Uncertainty and identifiability from the surrogate's Jacobian at the optimum.
void estimate_uncertainty(const Fit& fit, const Eigen::VectorXd& x_best, CalibrationResult& result) {
  const int p = fit.p;
  const std::vector<FitParameter>& parameters = fit.parameters;
  const Eigen::MatrixXd J = result.surrogate.jacobian(x_best);
  const Eigen::VectorXd w = fit.targets.sigma.cwiseInverse().cwiseAbs2();
  const Eigen::MatrixXd F = J.transpose() * w.asDiagonal() * J;
  Eigen::VectorXd half(p);
  for (int i = 0; i < p; ++i) half[i] = 0.5 * (parameters[i].highest() - parameters[i].lowest());
  const Eigen::MatrixXd Fn = half.asDiagonal() * F * half.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Fn);
  const Eigen::VectorXd lambda = eig.eigenvalues().cwiseMax(0.0);
  const double lmax = lambda.maxCoeff();
  result.condition = lambda.minCoeff() > 0 ? lmax / lambda.minCoeff() : std::numeric_limits<double>::infinity();
  // Pseudo-inverse in normalised coordinates: directions with eigenvalue below 1e-12 lmax are unconstrained.
  Eigen::MatrixXd cov_n = Eigen::MatrixXd::Zero(p, p);
  std::vector<bool> flagged(p, false);
  for (int k = 0; k < p; ++k) {
    const Eigen::VectorXd v = eig.eigenvectors().col(k);
    result.eigenvalues.push_back(lambda[k]);
    result.eigenvectors.emplace_back(v.data(), v.data() + p);
    const bool free = !(lambda[k] > 1e-12 * std::max(lmax, 1e-300));
    // sigma along this direction, in half-ranges; > 0.5 means a quarter of the range or more.
    const double spread = free ? std::numeric_limits<double>::infinity() : 1.0 / std::sqrt(lambda[k]);
    if (!free) cov_n += v * v.transpose() / lambda[k];
    if (spread > 0.5)
      for (int i = 0; i < p; ++i)
        if (std::abs(v[i]) > 0.3) flagged[i] = true;
    if (free)
      for (int i = 0; i < p; ++i)
        if (std::abs(v[i]) > 1e-6) cov_n(i, i) = std::numeric_limits<double>::infinity();
  }
  result.correlation.assign(p, std::vector<double>(p, kNaN));
  for (int i = 0; i < p; ++i) {
    result.sigma.push_back(std::sqrt(cov_n(i, i)) * half[i]);
    if (result.sigma.back() > 0.25 * (parameters[i].highest() - parameters[i].lowest())) flagged[i] = true;
    for (int j = 0; j < p; ++j)
      result.correlation[i][j] = std::isfinite(cov_n(i, j)) && std::isfinite(cov_n(i, i) * cov_n(j, j)) && cov_n(i, i) > 0 && cov_n(j, j) > 0
                                     ? cov_n(i, j) / std::sqrt(cov_n(i, i) * cov_n(j, j))
                                     : (i == j ? 1.0 : kNaN);
  }
  for (int i = 0; i < p; ++i)
    if (flagged[i]) result.unidentified.push_back(parameters[i].key);
}

/// Every point simulated, with the simulated value of each term.
void record_points(const Fit& fit, const Search& search, CalibrationResult& result) {
  const std::vector<std::string>& names = fit.targets.names;
  for (Eigen::Index r = 0; r < search.all_points.rows(); ++r) {
    SimulatedPoint point;
    for (int i = 0; i < fit.p; ++i) point.x.push_back(search.all_points(r, i));
    for (size_t t = 0; t < names.size(); ++t) point.values[names[t]] = search.all_values(r, static_cast<Eigen::Index>(t));
    result.points.push_back(std::move(point));
  }
}

/// Words: the fitted values, how far the fit came, correlations, identifiability, implausible
/// values and surrogates that miss their points.
void describe_fit(const Fit& fit, const std::string& budget_words, CalibrationResult& result) {
  const int p = fit.p;
  const std::vector<FitParameter>& parameters = fit.parameters;
  const std::vector<std::string>& names = fit.targets.names;
  std::vector<std::string> fitted;
  for (int i = 0; i < p; ++i)
    fitted.push_back(fmt::format("{} = {:.4g} +- {:.2g} (start {:.4g}, range [{:g}, {:g}]{})", parameters[i].key, result.value[i], result.sigma[i],
                                 result.start[i], parameters[i].lowest(), parameters[i].highest(),
                                 parameters[i].min > parameters[i].lowest() || parameters[i].max < parameters[i].highest()
                                     ? fmt::format(", first designed over [{:g}, {:g}]", parameters[i].min, parameters[i].max)
                                     : ""));
  if (!budget_words.empty()) result.words.push_back(budget_words);
  result.words.push_back("Fitted: " + join(fitted, "; ") + ".");
  result.words.push_back(fmt::format("chi^2/n from {:.2f} at the start to {:.2f} at the fit (real simulations, n = {}); the surrogate predicted {:.2f}.",
                                     result.before.chi2_per_n(), result.after.chi2_per_n(), result.after.n,
                                     result.surrogate_chi2 / static_cast<double>(names.size())));
  if (result.after.chi2_per_n() <= fit.options.fits_within_noise) result.words.push_back("The fitted model reproduces the measurements within their noise.");
  for (int i = 0; i < p; ++i)
    for (int j = i + 1; j < p; ++j)
      if (std::abs(result.correlation[i][j]) > 0.9)
        result.words.push_back(fmt::format("{} and {} are strongly correlated ({:+.2f}): the data fix a combination of them, not each one.",
                                           parameters[i].key, parameters[j].key, result.correlation[i][j]));
  if (!result.unidentified.empty())
    result.words.push_back(fmt::format("Not identified by these data: {} (uncertainty over a quarter of the range, or a direction of the "
                                       "information matrix with no constraint; condition number {:.3g}). Add a test that responds to them "
                                       "differently (Fig. 5: two tests whose contours cross).",
                                       join(result.unidentified), result.condition));
  else result.words.push_back(fmt::format("All parameters are identified (condition number {:.3g}).", result.condition));
  result.implausible = implausible_fits(fit.model, parameters, result.value, result.sigma, result.words);
  for (size_t t = 0; t < names.size(); ++t)
    if (result.surrogate.fit_rms[t] > 1.0)
      result.words.push_back(fmt::format("The surrogate of {} misses its design points by {:.1f} sigma RMS: it is not quadratic over the box.", names[t],
                                         result.surrogate.fit_rms[t]));
}

/// The contour map of the first two parameters.
void draw_contours(int p, const Surrogate& full_range, CalibrationResult& result) {
  if (p >= 2) {
    // The maps span the full range (round 1's surrogate), so every measured contour appears;
    // the result keeps the last round's surrogate.
    CalibrationResult wide = result;
    wide.surrogate = full_range;
    result.contours.push_back(contour_map(wide, 0, 1));
  }
}

}  // namespace

CalibrationResult calibrate(const MaterialModel& given_model, const MeasurementSet& measured, std::vector<FitParameter> parameters,
                            const CalibrationOptions& given, const Comparison* before, const EarlierPoints& earlier) {
  const Clock::time_point t0 = Clock::now();
  // A budget may reduce the options; the walls' fit and the comparisons it calls share its context.
  CalibrationOptions options = detail::within_command(given);
  CalibrationResult result;
  choose_parameters(given_model, parameters, result);
  const int p = static_cast<int>(parameters.size());
  const WallStage walls = fit_walls_stage(given_model, measured, parameters, earlier, options, result);

  const int n = static_cast<int>(measured.experiments.size());
  const detail::CommandScope command(options.context, "calibrate",
                                     n * ((before ? 0 : std::max(1, options.replicas)) + detail::calibration_passes(options, p)));
  compare_start(given_model, measured, options, before, result);
  const std::string budget_words = plan_for_budget(given, t0, command, n, p, result.before, options);
  const Targets targets = numeric_targets(result.before);

  CalibrationOptions full_rule = options;
  if (!earlier.known.empty()) full_rule.design_points = 0;
  const Fit fit{walls.first.model, measured, parameters, options, targets, p, detail::design_points(options, p), std::max(1, options.rounds),
                detail::design_points(full_rule, p), detail::refinement_design_points(full_rule, p)};
  Progress progress{options, "design"};
  Search search = start_search(fit, result.start, progress);
  feed_known_points(fit, earlier, walls.moved, search, result);
  search.included = included_points(fit, earlier);
  const Clock::time_point rounds_began = Clock::now();
  run_rounds(fit, search, progress, result);
  result.after = confirm_optimum(fit, search, result);
  search.seconds_per_point = seconds_per_point(fit, search, result.before, seconds_since(rounds_began));
  refine_around_best(fit, search, progress, result);
  keep_optimum(fit, search.x_best, result);
  estimate_uncertainty(fit, search.x_best, result);
  result.wall_seconds = seconds_since(t0);
  record_points(fit, search, result);
  describe_fit(fit, budget_words, result);
  draw_contours(p, search.full_range, result);
  return result;
}

ContourMap contour_map(const CalibrationResult& result, int px, int py, int grid) {
  const Surrogate& s = result.surrogate;
  ContourMap map;
  map.x_key = s.box[px].key, map.y_key = s.box[py].key;
  const int p = static_cast<int>(s.box.size());
  Eigen::VectorXd x0(p);
  for (int i = 0; i < p; ++i) x0[i] = result.value[i];
  map.fit_x = x0[px], map.fit_y = x0[py];
  // Measured values and sigma of the terms, from the comparison at the start.
  std::map<std::string, std::pair<double, double>> meas;
  std::map<std::string, std::string> test_of;
  for (const Term& t : result.before.terms)
    if (!t.is_outcome())
      meas[t.name()] = {t.measured, std::sqrt(t.sigma_measured * t.sigma_measured + t.sigma_simulated * t.sigma_simulated)}, test_of[t.name()] = t.test;
  // The two terms whose gradients (in sigma per half-range) cross most steeply.
  const Eigen::MatrixXd J = s.jacobian(x0);
  const double hx = 0.5 * (s.box[px].max - s.box[px].min), hy = 0.5 * (s.box[py].max - s.box[py].min);
  int a = 0, b = s.terms.size() > 1 ? 1 : 0;
  double best = -1;
  for (size_t i = 0; i < s.terms.size(); ++i)
    for (size_t j = i + 1; j < s.terms.size(); ++j) {
      const double si = meas[s.terms[i]].second, sj = meas[s.terms[j]].second;
      const double gi[2] = {J(i, px) * hx / si, J(i, py) * hy / si}, gj[2] = {J(j, px) * hx / sj, J(j, py) * hy / sj};
      double score = std::abs(gi[0] * gj[1] - gi[1] * gj[0]);
      if (test_of[s.terms[i]] != test_of[s.terms[j]]) score *= 1.5;
      if (score > best) best = score, a = static_cast<int>(i), b = static_cast<int>(j);
    }
  for (int k = 0; k < grid; ++k) {
    map.x.push_back(s.box[px].min + (s.box[px].max - s.box[px].min) * k / (grid - 1));
    map.y.push_back(s.box[py].min + (s.box[py].max - s.box[py].min) * k / (grid - 1));
  }
  for (int term : {a, b}) {
    ContourMap::Field f;
    f.term = s.terms[term];
    f.label = f.term;
    std::replace(f.label.begin(), f.label.end(), '/', ' ');
    f.measured = meas[f.term].first, f.sigma = meas[f.term].second;
    f.value.assign(grid, std::vector<double>(grid));
    map.fields.push_back(f);
    if (a == b) break;
  }
  map.chi2.assign(grid, std::vector<double>(grid));
  Eigen::VectorXd m(s.terms.size()), sg(s.terms.size());
  for (size_t t = 0; t < s.terms.size(); ++t) m[t] = meas[s.terms[t]].first, sg[t] = meas[s.terms[t]].second;
  for (int iy = 0; iy < grid; ++iy)
    for (int ix = 0; ix < grid; ++ix) {
      Eigen::VectorXd x = x0;
      x[px] = map.x[ix], x[py] = map.y[iy];
      const Eigen::VectorXd v = s.predict(x);
      for (auto& f : map.fields) f.value[iy][ix] = v[std::find(s.terms.begin(), s.terms.end(), f.term) - s.terms.begin()];
      map.chi2[iy][ix] = ((v - m).array() / sg.array()).square().sum();
    }
  return map;
}

}  // namespace dem::materials
