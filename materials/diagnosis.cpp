// Diagnosis: which missing effect explains the misfit (rules in calibration.h; its budget plan in
// diagnosis_budget.cpp).
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <functional>
#include <fstream>
#include <limits>
#include <set>
#include <stdexcept>

#include "calibration.h"
#include "calibration_support.h"
#include "discrimination.h"

namespace dem::materials {

using detail::join;
using detail::Progress;
using detail::simulate_experiments;

// ---- diagnosis ----------------------------------------------------------------------------

double bic(double chi2, int k, int n) { return chi2 + k * std::log(static_cast<double>(std::max(n, 1))); }

namespace {

/// Wall parameters the fit leaves out (friction and restitution of each particle-wall pair, the
/// rolling friction when the model rolls), as candidates: a test that misses because of a wall
/// points at the wall's parameter, not at missing physics. Measured ones are inputs, and those
/// fitted first to their own drop tests are settled: neither is offered.
std::vector<EffectCandidate> wall_parameter_candidates(const MaterialModel& model, const std::vector<FitParameter>& fitted) {
  std::vector<EffectCandidate> out;
  std::vector<std::string> keys = {"friction", "restitution"};
  if (model.contact.rolling.model != "none") keys.emplace_back("rolling_friction");
  const auto listed = [](const std::vector<std::string>& list, const std::string& key) { return std::find(list.begin(), list.end(), key) != list.end(); };
  std::vector<std::string> fitted_keys;
  for (const FitParameter& p : fitted) fitted_keys.push_back(p.key);
  for (const InteractionSpec& pair : model.wall_pairs) {
    const std::string wall = pair.material_a == model.name ? pair.material_b : pair.material_a;
    for (const std::string& key : keys) {
      const std::string full = wall + "." + key;
      if (listed(fitted_keys, full) || listed(fitted_keys, "wall." + key) || listed(model.known, full) || listed(model.fitted_first, full)) continue;
      const ParamSpec* p = find_param(key);
      if (!p) continue;
      const double lo = p->min_value, hi = std::min(p->max_value, 1.0);  // friction above 1 is not a wall liner's
      const double now = std::clamp(get_parameter(model, full), lo, hi), step = 0.2 * (hi - lo);
      const double start = now + step <= hi ? now + step : now - step;
      EffectCandidate c;
      c.name = full;
      c.kind = "parameter";
      c.title = fmt::format("the {} of the particles on {}", key, wall);
      c.why = fmt::format("tests on {} walls miss while the others fit: the particle-wall {} (a parameter, now {:.3g}, not calibrated)", wall, key, now);
      c.switch_on = fmt::format("calibrate it with the others (--params ...,{})", full);
      c.description = fmt::format("{}: a wall parameter, not physics the model lacks", c.title);
      c.parameters = {{full, {lo, hi}}};
      c.start = {{full, start}};
      c.stronger = {{full, std::clamp(now + 2.0 * (start - now), lo, hi)}};
      if (now == get_parameter(model, full)) c.unchanged = {{full, now}};
      c.add = [](MaterialModel&) {};
      out.push_back(std::move(c));
    }
  }
  return out;
}

/// Candidate experiments simulated to separate a rival, however little of the budget is left.
constexpr int kFewestSeparators = 4;

/// Whether every parameter the candidate adds has a value where it changes nothing: the plain
/// fit's points are then points of the candidate's space (EarlierPoints::known).
bool takes_plain_points(const EffectCandidate& c, const CandidateResult& cr) {
  return std::all_of(cr.adds.begin(), cr.adds.end(), [&](const FitParameter& a) { return c.unchanged.count(a.key) > 0; });
}

}  // namespace

Diagnosis diagnose(const MaterialModel& model, const MeasurementSet& measured, std::vector<FitParameter> parameters, const CalibrationOptions& given) {
  Diagnosis d;
  CalibrationOptions options = given;  // a budget may reduce it
  if (parameters.empty()) parameters = fit_parameters(model);
  const int experiments = static_cast<int>(measured.experiments.size()), fitted = static_cast<int>(parameters.size());
  const int walls = static_cast<int>(wall_parameter_candidates(model, parameters).size());
  const int lacking = static_cast<int>(missing_effects(model).size());
  const detail::CommandScope command("diagnose",
                                     experiments * (std::max(1, options.replicas) + detail::diagnosis_passes(options, fitted, lacking, walls)));
  detail::CommandProgress& count = detail::CommandProgress::shared();
  if (options.progress) options.progress("diagnose: calibrating the model as it is");
  // With a budget: the starting model is compared first (a simulation of each experiment is then
  // timed) and the rest planned to fit; the calibration uses that comparison as its start.
  if (options.budget_seconds > 0) {
    const detail::Clock::time_point t0 = detail::Clock::now();
    const Comparison first = compare(model, measured, options);
    const BudgetPlan plan = plan_within_budget(options, first, fitted, lacking, walls, detail::seconds_since(t0));
    options = plan.options;
    if (command.outermost()) count.plan_remaining(experiments * detail::diagnosis_passes(options, fitted, lacking, walls));
    options.budget_seconds = 0;  // planned once, for the whole diagnosis
    d.words.push_back(fmt::format("Planned for the budget of {}: about {} after the first comparison{}.", detail::duration_text(given.budget_seconds),
                                  detail::duration_text(plan.seconds), plan.given_up.empty() ? "" : "; given up: " + join(plan.given_up, "; ")));
    if (options.progress) options.progress(d.words.back());
    d.base = calibrate(model, measured, parameters, options, &first);
  } else {
    d.base = calibrate(model, measured, parameters, options);
  }
  if (options.on_partial) options.on_partial(d, "the model as it is, calibrated; signatures next");
  const Comparison& base = d.base.after;
  const int n = base.n;
  d.base_bic = bic(base.chi2, static_cast<int>(parameters.size()), n);
  const bool fits = base.chi2_per_n() <= options.fits_within_noise;
  // No candidate can be recommended when the model already fits within the noise, nor when even
  // an effect that took up all of the misfit (chi^2 -> 0) with one parameter more would not lower
  // BIC by the margin (Delta BIC <= chi^2 - ln n): the screen and the confirmations are then not
  // run, unless candidates were named with options.effects.
  const double most_gain = base.chi2 - std::log(static_cast<double>(std::max(n, 1)));
  if ((fits || most_gain <= options.bic_margin) && options.effects.empty()) {
    if (command.outermost()) count.plan_remaining(0);
    if (fits)
      d.words.push_back(fmt::format("No effect recommended: the model as it is fits within the noise after calibration (chi^2/n = {:.2f} <= {:.2g}); "
                                    "no candidate was screened (name some with --effects to screen them anyway).",
                                    base.chi2_per_n(), options.fits_within_noise));
    else
      d.words.push_back(fmt::format("No effect recommended: the model misfits (chi^2/n = {:.2f}), but over {} terms even an effect that took up "
                                    "all of chi^2 = {:.1f} with one parameter more would lower BIC by at most {:.1f}, not more than the margin "
                                    "{:.0f}; no candidate was screened. More experiments, or more packings where they scatter, let the data decide.",
                                    base.chi2_per_n(), n, base.chi2, most_gain, options.bic_margin));
    if (options.progress) options.progress("diagnose: " + d.words.back());
    return d;
  }
  // With a budget, the screen and the confirmations are planned again into what is left of it, at
  // the cost per simulation measured so far: the calibration's design points (friction near the
  // top of its range, slower flows) cost more than the first comparison, on which the first plan
  // was made.
  if (given.budget_seconds > 0 && command.outermost() && count.done() > 0) {
    const double pass = experiments * count.elapsed() / count.done();
    const BudgetPlan rest = plan_screen_within_budget(options, pass, fitted, lacking, walls, given.budget_seconds - count.elapsed(), given.budget_seconds);
    if (!rest.given_up.empty()) {
      options = rest.options;
      d.words.push_back(fmt::format("Planned again after calibrating the model as it is ({} spent, at {:.1f} s a simulation, a candidate's "
                                    "screen simulations counted at {:.1f} times that): about {} for the screen and the confirmations; given up: {}.",
                                    detail::duration_text(count.elapsed()), count.elapsed() / count.done(), detail::kScreenCost,
                                    detail::duration_text(rest.seconds), join(rest.given_up, "; ")));
      if (options.progress) options.progress("diagnose: " + d.words.back());
    }
  }

  // Sigma of each term (measurement and simulation noise) and the residual vector.
  const int nt = static_cast<int>(base.terms.size());
  Eigen::VectorXd r(nt), sig(nt);
  for (int i = 0; i < nt; ++i) {
    const Term& t = base.terms[i];
    r[i] = t.residual;
    sig[i] = t.is_outcome() ? 1.0 / options.outcome_residual : std::sqrt(t.sigma_measured * t.sigma_measured + t.sigma_simulated * t.sigma_simulated);
  }
  // What the fitted parameters can already do (surrogate Jacobian, in sigma units), to take out of each signature.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(nt, static_cast<Eigen::Index>(parameters.size()));
  {
    Eigen::VectorXd x(parameters.size());
    for (size_t i = 0; i < parameters.size(); ++i) x[static_cast<Eigen::Index>(i)] = d.base.value[i];
    const Eigen::MatrixXd J = d.base.surrogate.jacobian(x);
    for (int i = 0; i < nt; ++i) {
      const auto it = std::find(d.base.surrogate.terms.begin(), d.base.surrogate.terms.end(), base.terms[i].name());
      if (it != d.base.surrogate.terms.end()) A.row(i) = J.row(it - d.base.surrogate.terms.begin()) * 0.5 / sig[i];
    }
    for (size_t j = 0; j < parameters.size(); ++j) A.col(static_cast<Eigen::Index>(j)) *= (parameters[j].max - parameters[j].min);
  }
  // The candidates: every effect the model lacks and every wall parameter it does not fit, or
  // those options.effects names.
  std::vector<EffectCandidate> effects;
  std::vector<EffectCandidate> all = missing_effects(d.base.fitted);
  if (options.wall_candidates)
    for (EffectCandidate& c : wall_parameter_candidates(d.base.fitted, parameters)) all.push_back(std::move(c));
  const std::vector<std::string> known = candidate_names();
  for (const std::string& name : options.effects)
    if (std::find(known.begin(), known.end(), name) == known.end() && name.find('.') == std::string::npos)
      throw std::invalid_argument(fmt::format("--effects: '{}' is not a candidate; valid: {}, or a wall parameter WALL.KEY", name, join(known, ", ")));
  for (EffectCandidate& c : all)
    if (options.effects.empty() || std::find(options.effects.begin(), options.effects.end(), c.name) != options.effects.end())
      effects.push_back(std::move(c));
  // Each candidate's signature at two strengths: its start values with replicas (the base
  // comparison's first packings: common random numbers; this run is also the "before" of its
  // confirmation), and a step twice as far with one packing.
  std::map<std::string, Comparison> at_start;
  std::vector<std::string> left_out;  // candidates whose simulations could not run
  const int replicas = std::max(1, std::min(options.replicas, options.signature_replicas));
  Progress progress{options, "signatures"};
  for (size_t k = 0; k < effects.size(); ++k)
    for (const Experiment& e : measured.experiments) progress.plan(e, replicas + 1);
  if (command.outermost())
    count.plan_remaining(experiments * static_cast<int>(effects.size()) * (replicas + 1) +
                         (fits ? 0 : experiments * options.confirm_candidates * detail::calibration_passes(options, fitted + 1)));
  std::map<std::string, double> floor;
  for (const Term& t : base.terms) floor[t.name()] = t.sigma_simulated;
  const bool removable = A.cols() > 0 && A.norm() > 0;
  const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> fitted_directions(removable ? A : Eigen::MatrixXd::Zero(nt, 1));
  const auto orthogonal = [&](const Eigen::VectorXd& s) { return removable ? Eigen::VectorXd(s - A * fitted_directions.solve(s)) : s; };
  // Multiple of the added strength that best cancels r (0 when the step does not reduce it).
  const auto cancelling = [&](const Eigen::VectorXd& s_perp, const Eigen::VectorXd& s) {
    const double ss = s_perp.squaredNorm();
    if (!(ss > 1e-12 * std::max(1.0, s.squaredNorm()) && r.squaredNorm() > 0)) return 0.0;
    return std::max(0.0, -s_perp.dot(r) / ss);
  };
  const auto explained_by = [&](const Eigen::VectorXd& s_perp, const Eigen::VectorXd& s) {
    const double ss = s_perp.squaredNorm(), rr = r.squaredNorm();
    return cancelling(s_perp, s) > 0 ? (s_perp.dot(r) * s_perp.dot(r)) / (ss * rr) : 0.0;
  };
  // Every candidate's runs at both strengths, one batch.
  const std::vector<detail::SignatureRuns> signature_runs =
      detail::simulate_signatures(d.base.fitted, effects, parameters, measured, options, replicas, &progress);
  for (size_t index = 0; index < effects.size(); ++index) {
    const EffectCandidate& c = effects[index];
    CandidateResult cr;
    cr.name = c.name, cr.title = c.title, cr.description = c.description, cr.why = c.why, cr.switch_on = c.switch_on, cr.kind = c.kind;
    for (const auto& [key, range] : c.parameters) cr.adds.push_back({key, range.first, range.second});
    cr.k = static_cast<int>(parameters.size() + cr.adds.size());
    Eigen::VectorXd perp[2];
    double strength_needed = 0;  // of the added parameter, from the linear screen at either strength
    // A candidate the apparatus cannot take (clumps too large to fill a drum from a lattice) is
    // left out with the reason, not the whole diagnosis.
    const std::string& cannot = signature_runs[index].cannot;
    for (int strength = 0; strength < 2 && cannot.empty(); ++strength) {
      const std::vector<ExperimentRun>& runs = strength == 0 ? signature_runs[index].start : signature_runs[index].stronger;
      const Comparison changed = compare_runs(measured, runs, options, floor);
      Eigen::VectorXd s = Eigen::VectorXd::Zero(nt);
      for (int i = 0; i < nt; ++i)
        for (const Term& u : changed.terms)
          if (u.name() == base.terms[i].name()) s[i] = (u.simulated - base.terms[i].simulated) / sig[i];
      perp[strength] = orthogonal(s);
      (strength == 0 ? cr.explained_start : cr.explained_stronger) = explained_by(perp[strength], s);
      if (c.parameters.size() == 1) {
        const auto& [key, range] = *c.parameters.begin();
        const auto at = strength == 1 && c.stronger.count(key) ? c.stronger.at(key) : c.start.at(key);
        strength_needed = std::max(strength_needed, range.first + cancelling(perp[strength], s) * (at - range.first));
      }
      if (strength == 0) {
        cr.signature.assign(s.data(), s.data() + s.size());
        at_start[c.name] = changed;
      }
    }
    if (!cannot.empty()) {
      left_out.push_back(fmt::format("{} left out: its simulations cannot run in these experiments ({}).", c.name, cannot));
      if (options.progress) options.progress(left_out.back());
      continue;
    }
    cr.explained = std::max(cr.explained_start, cr.explained_stronger);
    // An effect's recalibration designs its first round over the strengths the screen points to,
    // twice what it needs and at least the stronger step, with the effect's whole range as the
    // limit the fit may move into: a cohesion range spans strengths at which the bed clings to the
    // drum and arches in the hopper, simulations several times as long that say only "too strong".
    if (cr.kind != "parameter" && cr.adds.size() == 1 && c.stronger.count(cr.adds[0].key)) {
      FitParameter& added = cr.adds[0];
      const double upper = std::clamp(std::max(c.stronger.at(added.key), 2.0 * strength_needed), added.min, added.max);
      if (upper < added.max) added.limit_min = added.min, added.limit_max = added.max, added.max = upper;
    }
    const double norms = perp[0].norm() * perp[1].norm();
    cr.agreement = norms > 0 ? perp[0].dot(perp[1]) / norms : 1.0;
    d.candidates.push_back(std::move(cr));
    if (options.on_partial) options.on_partial(d, fmt::format("signatures: {} of {} candidates", d.candidates.size(), effects.size()));
  }
  std::stable_sort(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& a, const CandidateResult& b) { return a.explained > b.explained; });
  if (options.progress && !d.candidates.empty()) {
    std::vector<std::string> ranked;
    for (const CandidateResult& c : d.candidates)
      ranked.push_back(fmt::format("{} {:.0f} % ({:.0f} % at the start, {:.0f} % stronger)", c.name, 100 * c.explained, 100 * c.explained_start,
                                   100 * c.explained_stronger));
    options.progress("diagnose: share of the residual each signature explains: " + join(ranked, "; "));
  }

  if (fits) {
    d.words.push_back(fmt::format("No effect recommended: the model as it is fits within the noise after calibration (chi^2/n = {:.2f} <= {:.2g}).",
                                  base.chi2_per_n(), options.fits_within_noise));
  } else {
    // Confirm the leading candidates by adding each and recalibrating.
    // The signature is a linear screen from one step to the effect's start values; a strong,
    // nonlinear effect (cohesion at a start far from the truth) can overshoot and show little
    // projection. When no candidate passes the screen although the model misfits, the leading
    // ones are confirmed anyway: recalibration, not the screen, decides.
    const detail::ConfirmationChoice choice = detail::choose_confirmations(d.candidates, options);
    std::map<std::string, int> design_points_of;  // a confirmation's design points, where a budget reduced them
    const bool screen_silent = choice.screen_silent;
    std::vector<size_t> confirming = choice.confirming;
    std::vector<std::string> undecided = choice.undecided, nonlinear = choice.nonlinear;
    // With a budget, the confirmations are fitted into what is left of it, at the cost per
    // simulation this diagnosis has measured so far: a candidate's simulations (cohesion, a wetter
    // bed) may cost several times the first comparison's, on which the plan was made. The leader
    // is always confirmed, and so is every candidate the screen cannot tell from it: confirming
    // one of two the screen cannot separate would name it on a coin toss. The result says by how
    // much that exceeds the budget.
    if (given.budget_seconds > 0 && command.outermost() && count.done() > 0 && confirming.size() > 1) {
      const double per_simulation = count.elapsed() / count.done();
      double left = given.budget_seconds - count.elapsed();
      std::vector<double> costs;
      std::vector<bool> tied;
      for (const size_t rank : confirming) {
        costs.push_back(experiments * detail::calibration_passes(options, d.candidates[rank].k) * per_simulation);
        tied.push_back(std::find(undecided.begin(), undecided.end(), d.candidates[rank].name) != undecided.end());
      }
      // A candidate whose plain-fit points are points of its own space (EffectCandidate::unchanged)
      // can be confirmed with fewer design points of its own: the cost a tie past the budget
      // falls back on (fit_confirmations).
      std::vector<double> smaller(costs.size(), detail::kNaN);
      std::map<std::string, int> fewer_points;
      for (size_t k = 0; k < confirming.size(); ++k) {
        const CandidateResult& cr = d.candidates[confirming[k]];
        const auto it = std::find_if(effects.begin(), effects.end(), [&](const EffectCandidate& c) { return c.name == cr.name; });
        const bool beside_plain = it != effects.end() && takes_plain_points(*it, cr);
        CalibrationOptions o = options;
        o.design_points = detail::design_points_beside_known(cr.k, static_cast<int>(cr.adds.size()));
        if (!beside_plain || o.design_points >= detail::design_points(options, cr.k)) continue;
        smaller[k] = experiments * detail::calibration_passes(o, cr.k) * per_simulation;
        fewer_points[cr.name] = o.design_points;
      }
      const detail::ConfirmationPlan plan = detail::fit_confirmations(costs, tied, left, smaller);
      if (plan.reduced) {
        design_points_of = fewer_points;
        for (size_t k = 0; k < costs.size(); ++k)
          if (std::isfinite(smaller[k])) costs[k] = smaller[k];
        std::vector<std::string> which;
        for (const auto& [name, points] : fewer_points) which.push_back(fmt::format("{} {}", name, points));
        d.words.push_back(fmt::format("To fit the budget of {} with a tie, the confirmations design fewer points ({} a round, against {}): "
                                      "the plain fit's points, where each candidate changes nothing, determine the rest of their surrogates.",
                                      detail::duration_text(given.budget_seconds), join(which),
                                      detail::design_points(options, d.candidates[confirming.front()].k)));
        if (options.progress) options.progress("diagnose: " + d.words.back());
      }
      std::vector<size_t> kept;
      std::vector<std::string> dropped, beyond;
      double each = 0;
      for (const size_t k : plan.kept) kept.push_back(confirming[k]);
      for (const size_t k : plan.beyond) beyond.push_back(d.candidates[confirming[k]].name);
      for (const size_t k : plan.dropped) dropped.push_back(d.candidates[confirming[k]].name), each = costs[k];
      if (!beyond.empty()) {
        d.words.push_back(fmt::format("The budget of {} is exceeded by about {}: the signature screen cannot tell {} from {}, so each is "
                                      "recalibrated.", detail::duration_text(given.budget_seconds), detail::duration_text(-plan.left),
                                      d.candidates.front().name, join(beyond, ", ")));
        if (options.progress) options.progress("diagnose: " + d.words.back());
      }
      if (!dropped.empty()) {
        confirming = kept;
        const auto gone = [&](const std::string& name) { return std::find(dropped.begin(), dropped.end(), name) != dropped.end(); };
        std::erase_if(undecided, gone), std::erase_if(nonlinear, gone);
        d.words.push_back(fmt::format("Within the budget of {} ({} spent, at {:.1f} s a simulation), {} {} not recalibrated (about {} each): run "
                                      "again with a larger --budget, or with --effects {} (the simulations done are kept in the store).",
                                      detail::duration_text(given.budget_seconds), detail::duration_text(count.elapsed()), per_simulation,
                                      join(dropped, ", "), dropped.size() == 1 ? "was" : "were", detail::duration_text(each), join(dropped, ",")));
        if (options.progress) options.progress("diagnose: " + d.words.back());
      }
    }
    const auto options_for = [&](const std::string& name) {
      CalibrationOptions o = options;
      if (const auto it = design_points_of.find(name); it != design_points_of.end()) o.design_points = it->second;
      return o;
    };
    if (command.outermost()) {
      int passes = 0;
      for (const size_t rank : confirming) passes += detail::calibration_passes(options_for(d.candidates[rank].name), d.candidates[rank].k);
      count.plan_remaining(experiments * passes);
    }
    for (const size_t rank : confirming) {
      CandidateResult& cr = d.candidates[rank];
      const auto it = std::find_if(effects.begin(), effects.end(), [&](const EffectCandidate& c) { return c.name == cr.name; });
      MaterialModel with = d.base.fitted;
      it->add(with);
      for (const auto& [key, v] : it->start) set_parameter(with, key, v);
      std::vector<FitParameter> params = parameters;
      params.insert(params.end(), cr.adds.begin(), cr.adds.end());
      // Its signature runs are two points of its design, taken from the store: the fitted
      // parameters at the base's values, its own at the start and at the stronger step.
      EarlierPoints earlier;
      earlier.include.assign(2, std::vector<double>(d.base.value.begin(), d.base.value.end()));
      for (const FitParameter& added : cr.adds) {
        earlier.include[0].push_back(it->start.at(added.key));
        earlier.include[1].push_back(it->stronger.count(added.key) ? it->stronger.at(added.key) : it->start.at(added.key));
      }
      // Every point the model as it is was simulated at is a point of the candidate's space too,
      // its own parameters where it changes nothing: the candidate's surrogate takes them as data.
      if (takes_plain_points(*it, cr))
        for (SimulatedPoint point : d.base.points) {
          for (const FitParameter& added : cr.adds) point.x.push_back(it->unchanged.at(added.key));
          earlier.known.push_back(std::move(point));
        }
      // A runner-up that cannot rival the best candidate confirmed so far (its simulations beyond
      // that one's BIC by twice the margin) is neither refined (when its surrogate lies beyond too)
      // nor given more packings (calibration.h, no_rival_above_chi2).
      CalibrationOptions confirming_options = options_for(cr.name);
      for (const CandidateResult& done : d.candidates)
        if (done.confirmed)
          confirming_options.no_rival_above_chi2 = std::min(confirming_options.no_rival_above_chi2,
                                                          done.bic + 2 * options.rival_margin - cr.k * std::log(static_cast<double>(std::max(n, 1))));
      if (options.progress) options.progress(fmt::format("diagnose: confirming {} (recalibrating {} parameters)", cr.name, params.size()));
      cr.fit = calibrate(with, measured, params, confirming_options, &at_start.at(cr.name), earlier);
      cr.confirmed = true;
      cr.chi2 = cr.fit.after.chi2;
      cr.bic = bic(cr.chi2, cr.k, cr.fit.after.n);
      cr.delta_bic = d.base_bic - cr.bic;
      if (options.on_partial) options.on_partial(d, fmt::format("{} confirmed by recalibration", cr.name));
    }
    // Why more than the leaders were recalibrated: said after the verdict.
    std::vector<std::string> why_recalibrated;
    if (!undecided.empty())
      why_recalibrated.push_back(fmt::format("The signature screen cannot tell {} from {} (their signatures explain within {:.0f} % of each other, "
                                             "at its noise): each was recalibrated.",
                                             d.candidates.front().name, join(undecided, ", "), 100 * options.screen_margin));
    if (!nonlinear.empty())
      why_recalibrated.push_back(fmt::format("The signature of {} changes shape between its two strengths (the linear screen cannot be trusted for "
                                             "it): recalibrated.", join(nonlinear, ", ")));
    std::stable_sort(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& a, const CandidateResult& b) {
      if (a.confirmed != b.confirmed) return a.confirmed;
      return a.confirmed ? a.bic < b.bic : a.explained > b.explained;
    });
    const CandidateResult* best = d.candidates.empty() || !d.candidates.front().confirmed ? nullptr : &d.candidates.front();
    if (best && best->delta_bic > options.bic_margin) {
      d.recommended = best->name;
      // Which patterns the effect answers.
      std::vector<std::string> misfits;
      for (const Pattern& p : d.base.after.patterns)
        if (p.kind != "fits") misfits.push_back(p.words);
      if (best->kind == "parameter")
        d.words.push_back(fmt::format("Not missing physics: {} ({}), which the fit left out, explains the misfit ({}). Calibrated with the "
                                      "others it comes to {:.3g}, chi^2/n falls from {:.2f} to {:.2f} and BIC from {:.1f} to {:.1f} (by {:.1f} > "
                                      "margin {:.0f}). {}; or measure it and state it in the measurement file.",
                                      best->name, best->title, best->why, get_parameter(best->fit.fitted, best->name), base.chi2_per_n(),
                                      best->fit.after.chi2_per_n(), d.base_bic, best->bic, best->delta_bic, options.bic_margin, best->switch_on));
      else
        d.words.push_back(fmt::format("Most likely missing: {} ({}; switch it on with `{}`). Why: {}. It could explain {:.0f} % of the weighted residual of the calibrated model; "
                                      "added and recalibrated, chi^2/n falls from {:.2f} to {:.2f} and BIC from {:.1f} to {:.1f} "
                                      "(by {:.1f} > margin {:.0f}, with {} more parameter{}).",
                                      best->name, best->title, best->switch_on, best->why, 100 * best->explained, base.chi2_per_n(),
                                      best->fit.after.chi2_per_n(), d.base_bic, best->bic, best->delta_bic, options.bic_margin, best->adds.size(),
                                      best->adds.size() == 1 ? "" : "s"));
      if (!misfits.empty()) d.words.push_back("Where the model without it fails: " + join(misfits, " "));
      for (const CandidateResult& c : d.candidates)
        if (&c != best && c.confirmed && c.delta_bic > options.bic_margin && c.bic - best->bic < options.rival_margin) {
          d.rivals.push_back(c.name);
          d.words.push_back(fmt::format("These data do not tell {} from {}: added instead and recalibrated, {} reaches BIC {:.1f}, only "
                                        "{:.1f} above (< {:.0f}, no strong evidence). Measure where the two act differently to decide ({}: {}; {}: {}).",
                                        best->name, c.name, c.name, c.bic, c.bic - best->bic, options.rival_margin, best->name,
                                        best->why, c.name, c.why));
          // Which experiment would decide: both fitted models simulated on candidates.
          if (options.propose_experiments) {
            SeparationPlan plan;
            plan.apart = apart_by_experiment(best->fit.after, c.fit.after);
            // With a budget, as many candidate experiments as what is left of it pays for, the
            // most promising first, and never fewer than kFewestSeparators.
            if (given.budget_seconds > 0 && command.outermost() && count.done() > 0) {
              const double per_candidate = 2 * std::max(1, std::min(options.replicas, options.signature_replicas)) * count.elapsed() / count.done();
              plan.most = std::max(kFewestSeparators, static_cast<int>((given.budget_seconds - count.elapsed()) / per_candidate));
            }
            SeparationSearch search = separating_experiments(best->fit.fitted, best->name, c.fit.fitted, c.name, measured, options, plan);
            std::vector<Separator>& found = search.found;
            if (!found.empty() && found.front().separation >= options.separation_needed)
              d.words.push_back(fmt::format("To tell {} from {}, measure {}.", best->name, c.name, found.front().words));
            else
              d.words.push_back(fmt::format("No experiment tried separates {} from {} by {:.0f} sigma{}.", best->name, c.name, options.separation_needed,
                                            found.empty() ? "" : fmt::format(" (best: {})", found.front().words)));
            if (!search.untried.empty())
              d.words.push_back(fmt::format("Within the budget of {}, {} of {} candidate experiments were simulated, those of the experiments on "
                                            "which the two fitted models already lie furthest apart; not tried: {}.",
                                            detail::duration_text(given.budget_seconds), search.candidates - static_cast<int>(search.untried.size()),
                                            search.candidates, join(search.untried, "; ")));
            if (found.size() > 3) found.resize(3);
            d.separators[c.name] = std::move(found);
          }
        }
    } else {
      d.words.push_back(fmt::format("No effect recommended: the model misfits (chi^2/n = {:.2f}) but no candidate lowers BIC by more than {:.0f}{}.",
                                    base.chi2_per_n(), options.bic_margin,
                                    best ? fmt::format(" (best: {}, by {:.1f})", best->name, best->delta_bic) : ""));
    }
    d.words.insert(d.words.end(), why_recalibrated.begin(), why_recalibrated.end());
    if (screen_silent && !d.candidates.empty())
      d.words.push_back("The signatures explained little of the misfit (they are a linear screen from one step to each effect's start "
                        "values); the leading candidates were confirmed by recalibration anyway.");
  }
  d.words.insert(d.words.end(), left_out.begin(), left_out.end());
  for (CandidateResult& cr : d.candidates) {
    const std::string screen = fmt::format("explains {:.0f} % of the residual ({:.0f} % at its start, {:.0f} % at twice the step; agreement {:.2f})",
                                           100 * cr.explained, 100 * cr.explained_start, 100 * cr.explained_stronger, cr.agreement);
    cr.words = cr.confirmed ? fmt::format("{}: {}; recalibrated chi^2/n = {:.2f}, BIC {:.1f} ({:+.1f} against the model as it is).", cr.name, screen,
                                          cr.fit.after.chi2_per_n(), cr.bic, -cr.delta_bic)
                            : fmt::format("{}: {} (signature only, not confirmed).", cr.name, screen);
  }
  return d;
}

}  // namespace dem::materials
