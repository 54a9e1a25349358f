// The screen: each candidate effect's signature at two strengths, ranked by the share of the
// calibrated residual it explains or, for a threshold, by the likelihood of its own runs.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "diagnosis/diagnosis_run.h"

namespace dem::materials::diagnosis {

namespace {

/// A fit held at a bound can still move inward: the least chi^2 of v + A d with the fitted
/// parameters d kept inside their ranges (an active set over the few of them: each free, at its
/// lower or at its upper edge), in A's units of half a range from the fitted `value`. Rejected: no
/// recalibration at all, with which an effect added at its start values to a fit pinned at the top
/// of its friction overshoots every heap and drum and explains nothing (lab_rolling.yaml's rolling
/// resistance at friction 0.9, 0 % where its linear share was 54 %).
double least_chi2_inward(const Eigen::MatrixXd& A, const std::vector<FitParameter>& fitted, const std::vector<double>& value, const Eigen::VectorXd& v) {
  const Eigen::Index p = A.cols();
  std::vector<std::pair<double, double>> room(static_cast<size_t>(p));
  for (Eigen::Index j = 0; j < p; ++j) {
    const FitParameter& f = fitted[static_cast<size_t>(j)];
    const double half = 0.5 * (f.max - f.min), x = value[static_cast<size_t>(j)];
    room[static_cast<size_t>(j)] = half > 0 ? std::make_pair((f.min - x) / half, (f.max - x) / half) : std::make_pair(0.0, 0.0);
  }
  double best = v.squaredNorm();
  int combinations = 1;
  for (Eigen::Index j = 0; j < p; ++j) combinations *= 3;
  for (int code = 0; code < combinations; ++code) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(p);
    std::vector<Eigen::Index> free;
    for (Eigen::Index j = 0, c = code; j < p; ++j, c /= 3) {
      const auto& [low, high] = room[static_cast<size_t>(j)];
      if (c % 3 == 0) free.push_back(j);
      else d[j] = c % 3 == 1 ? low : high;
    }
    if (!free.empty()) {
      Eigen::MatrixXd M(A.rows(), static_cast<Eigen::Index>(free.size()));
      for (size_t k = 0; k < free.size(); ++k) M.col(static_cast<Eigen::Index>(k)) = A.col(free[k]);
      const Eigen::VectorXd step = M.completeOrthogonalDecomposition().solve(-(v + A * d));
      bool inside = true;
      for (size_t k = 0; k < free.size(); ++k) {
        const auto& [low, high] = room[static_cast<size_t>(free[k])];
        inside = inside && step[static_cast<Eigen::Index>(k)] >= low - 1e-12 && step[static_cast<Eigen::Index>(k)] <= high + 1e-12;
        d[free[k]] = step[static_cast<Eigen::Index>(k)];
      }
      if (!inside) continue;
    }
    best = std::min(best, (v + A * d).squaredNorm());
  }
  return best;
}

}  // namespace

// ---- the screen ----------------------------------------------------------------------------

/// The calibrated residual the screen explains, each term in units of its sigma, and what the
/// fitted parameters can already do to it.
struct ScreenResidual {
  Eigen::VectorXd r;    ///< each term's residual
  Eigen::VectorXd sig;  ///< each term's sigma, the unit of a signature
  Eigen::MatrixXd A;    ///< the fitted parameters' surrogate Jacobian, in sigma per half range (least_chi2_inward)
};

/// What every signature is measured against: the residual, the fitted parameters' directions and
/// each term's simulation noise.
struct ScreenBasis : ScreenResidual {
  /// The basis of `residual`, the fitted directions' decomposition computed once.
  ScreenBasis(ScreenResidual residual, std::map<std::string, double> sigma_floor);

  /// Per term, the base comparison's simulation noise: the least a candidate's comparison gives it.
  std::map<std::string, double> floor;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> fitted_directions;
  // The fitted directions are taken out only when the calibrated residual stands (mostly) square to
  // them, as at an interior optimum. A residual that lies along them is one the parameters could
  // not take up (pinned at a bound, or a surrogate whose optimum missed the simulations'): an
  // effect that moves the terms that way then explains it, and is credited.
  bool removable;
  double rr;  ///< the residual's chi^2

  /// A signature with what the fitted parameters can already do taken out (when removable).
  Eigen::VectorXd orthogonal(const Eigen::VectorXd& s) const { return removable ? Eigen::VectorXd(s - A * fitted_directions.solve(s)) : s; }
  /// Multiple of the added strength that best cancels r (0 when the step does not reduce it).
  double cancelling(const Eigen::VectorXd& s_perp, const Eigen::VectorXd& s) const {
    const double ss = s_perp.squaredNorm();
    if (!(ss > 1e-12 * std::max(1.0, s.squaredNorm()) && r.squaredNorm() > 0)) return 0.0;
    return std::max(0.0, -s_perp.dot(r) / ss);
  }
  /// The share of the residual's chi^2 the line through a signature cancels.
  double explained_by(const Eigen::VectorXd& s_perp, const Eigen::VectorXd& s) const {
    const double ss = s_perp.squaredNorm();
    return cancelling(s_perp, s) > 0 ? (s_perp.dot(r) * s_perp.dot(r)) / (ss * rr) : 0.0;
  }
};

ScreenBasis::ScreenBasis(ScreenResidual residual, std::map<std::string, double> sigma_floor)
    : ScreenResidual(std::move(residual)),
      floor(std::move(sigma_floor)),
      fitted_directions(A.cols() > 0 ? A : Eigen::MatrixXd::Zero(r.size(), 1)),
      removable(A.cols() > 0 && A.norm() > 0 && (r - A * fitted_directions.solve(r)).squaredNorm() >= 0.5 * r.squaredNorm()),
      rr(r.squaredNorm()) {}

/// The screen's simulations: the packings of a candidate's start values, and their progress.
struct SignaturePass {
  int replicas;  ///< packings at a candidate's start values (its stronger step has one)
  Progress progress;
};

/// One candidate's screen as its two strengths are measured.
struct CandidateScreen {
  /// A screen not yet measured: its own runs' chi^2 starts at the residual's.
  explicit CandidateScreen(const ScreenBasis& basis) : reachable(basis.orthogonal(basis.r).squaredNorm()), measured_chi2(basis.rr) {}

  Eigen::VectorXd perp[2];     ///< each strength's signature, orthogonal to the fitted directions (ScreenBasis::orthogonal)
  Eigen::VectorXd at[2];       ///< each strength's signature as measured: at the start values and at the stronger step
  double strength_needed = 0;  // of the added parameter, from the linear screen at either strength
  // The better strength's own chi^2 after the linear recalibration: what its change takes off the
  // part of the residual the fitted parameters cannot reach (a fit pinned at a bound reaches
  // nothing more, so the whole residual is not handed to a candidate).
  double reachable;
  double measured_chi2;
  std::vector<std::string> flips;  ///< experiments whose outcome flips: a threshold
};

/// Bounds the first round of an effect's recalibration by the strength its screen points to.
void bound_first_round(const EffectCandidate& c, double strength_needed, CandidateResult& cr) {
  // An effect's recalibration designs its first round over the strengths the screen points to,
  // twice what it needs and at least the stronger step, with the effect's whole range as the
  // limit the fit may move into: a cohesion range spans strengths at which the bed clings to the
  // drum and arches in the hopper, simulations several times as long that say only "too strong".
  if (cr.kind != "parameter" && cr.adds.size() == 1 && c.stronger.count(cr.adds[0].key)) {
    FitParameter& added = cr.adds[0];
    const double upper = std::clamp(std::max(c.stronger.at(added.key), 2.0 * strength_needed), added.min, added.max);
    if (upper < added.max) added.limit_min = added.min, added.limit_max = added.max, added.max = upper;
  }
}

/// An unstable candidate whose two strengths both overshoot (its own runs explain less than the
/// linear share says a fraction `multiple` of its start would) is simulated once more, at that
/// fraction: the likelihood of the data at a strength the data may hold, not only at two that are
/// too strong. Returns the words for its rank (" and at STRENGTH"), or "" when nothing was run.
/// A two-sided candidate (EffectCandidate::two_sided) is simulated on the `side` that explains
/// more: 0 toward its start values, 1 toward its stronger step.
/// Rejected: the two strengths alone, with which rolling resistance explained 0 % of
/// lab_rolling.yaml's misfit on a fit pinned at friction 0.9 (its start step was about twice what
/// the data hold), and the linear share (a threshold makes it meaningless).
template <class SignatureOf, class OwnChi2>
std::string DiagnosisRun::weaker_strength(const EffectCandidate& c, int side, double multiple, double linear, double rr, const SignatureOf& signature_of,
                                          const OwnChi2& own_chi2, int replicas, const std::map<std::string, double>& floor,
                                          detail::Progress& progress, double& measured_chi2, CandidateResult& cr) {
  if (c.parameters.size() != 1 || !(multiple > 0.05 && multiple < 0.9) || measured_chi2 <= rr * (1 - linear)) return "";
  const auto& [key, range] = *c.parameters.begin();
  const std::map<std::string, double>& toward = side == 1 ? c.stronger : c.start;
  if (!toward.count(key)) return "";
  const double from = c.unchanged.count(key) ? c.unchanged.at(key) : range.first;
  const double value = from + multiple * (toward.at(key) - from);
  MaterialModel with = d_.base.fitted;
  c.add(with);
  for (const auto& [k, v] : c.start) set_parameter(with, k, v);
  set_parameter(with, key, value);
  std::vector<ExperimentRun> runs;
  try {
    if (options_.walls_first) {
      std::vector<FitParameter> all_fitted = parameters_;
      all_fitted.push_back({key, range.first, range.second});
      CalibrationOptions quiet = options_;
      quiet.progress = nullptr;
      with = detail::fit_walls_first(with, measured_, all_fitted, quiet).model;
    }
    for (const Experiment& e : measured_.experiments) progress.plan(e, replicas);
    if (command_.outermost()) count_.plan_more(experiments_ * replicas);
    runs = detail::simulate_experiments(with, measured_.experiments, options_, replicas, &progress, fmt::format("{} at {:.3g} ", c.name, value));
  } catch (const CaseError&) {
    return "";
  }
  for (const ExperimentRun& run : runs) cr.cost += run.wall_seconds, cr.simulations += run.replicas;
  measured_chi2 = std::min(measured_chi2, own_chi2(signature_of(compare_runs(measured_, runs, options_, floor))));
  return fmt::format(" (at its start, the stronger step and {:.3g}, where the linear screen points)", value);
}

/// Each candidate's signature at two strengths: its start values with replicas (the base
/// comparison's first packings: common random numbers; this run is also the "before" of its
/// confirmation), and a step twice as far with one packing. A signature is the change of every
/// term in units of its sigma, with what the fitted parameters can already do taken out (the
/// surrogate's directions). A stable candidate (its two strengths agree, no outcome flips) is
/// ranked by the share of the residual the line through its signatures can cancel; an unstable
/// one (a threshold: an orifice that arches, a heap that forms, a bed that starts to slip) by the
/// chi^2 of its own runs after the same linear recalibration of the fitted parameters, the
/// likelihood of the data at the strengths actually simulated. Rejected: the better of the two
/// linear shares for every candidate, which let a cohesion that arches the silo at its start and
/// breaks everything at twice the step (84 % and 1 %, agreement 0.22) lead the ranking.
void DiagnosisRun::screen_signatures() {
  ScreenResidual residual = screen_residual();
  choose_candidates();
  SignaturePass pass{std::max(1, std::min(options_.replicas, options_.signature_replicas)), Progress{options_, "signatures"}};
  plan_signatures(pass);
  const ScreenBasis basis = screen_basis(std::move(residual));
  const std::vector<detail::SignatureRuns> signature_runs =
      detail::simulate_signatures(d_.base.fitted, effects_, parameters_, measured_, options_, pass.replicas, &pass.progress);
  for (size_t index = 0; index < effects_.size(); ++index) screen_candidate(effects_[index], signature_runs[index], basis, pass);
  rank_by_share();
}

/// [s] of wall time a confirmation's simulation of `cr` is expected to take
/// (detail::candidate_seconds_per_simulation), the diagnosis' mean so far where its screen ran none.
double DiagnosisRun::confirmation_seconds_per_simulation(const CandidateResult& cr) const {
  const double screened = detail::candidate_seconds_per_simulation(cr, options_.parallel);
  return screened > 0 ? screened : seconds_per_simulation();
}

/// The calibrated residual and the fitted parameters' surrogate Jacobian, in each term's sigma.
ScreenResidual DiagnosisRun::screen_residual() const {
  const Comparison& base = d_.base.after;
  const int nt = static_cast<int>(base.terms.size());
  Eigen::VectorXd r(nt), sig(nt);
  for (int i = 0; i < nt; ++i) {
    const Term& t = base.terms[i];
    r[i] = t.residual;
    sig[i] = t.is_outcome() ? 1.0 / options_.outcome_residual : std::sqrt(t.sigma_measured * t.sigma_measured + t.sigma_simulated * t.sigma_simulated);
  }
  // What the fitted parameters can already do (surrogate Jacobian, in sigma units), to take out of each signature.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(nt, static_cast<Eigen::Index>(parameters_.size()));
  {
    Eigen::VectorXd x(parameters_.size());
    for (size_t i = 0; i < parameters_.size(); ++i) x[static_cast<Eigen::Index>(i)] = d_.base.value[i];
    const Eigen::MatrixXd J = d_.base.surrogate.jacobian(x);
    for (int i = 0; i < nt; ++i) {
      const auto it = std::find(d_.base.surrogate.terms.begin(), d_.base.surrogate.terms.end(), base.terms[i].name());
      if (it != d_.base.surrogate.terms.end()) A.row(i) = J.row(it - d_.base.surrogate.terms.begin()) * 0.5 / sig[i];
    }
    for (size_t j = 0; j < parameters_.size(); ++j) A.col(static_cast<Eigen::Index>(j)) *= (parameters_[j].max - parameters_[j].min);
  }
  return {std::move(r), std::move(sig), std::move(A)};
}

/// The candidates screened (effects_), the names options.effects gives checked.
void DiagnosisRun::choose_candidates() {
  // The candidates: every effect the model lacks and every wall parameter it does not fit, or
  // those options.effects names.
  std::vector<EffectCandidate> all = missing_effects(d_.base.fitted);
  if (options_.wall_candidates)
    for (EffectCandidate& c : wall_parameter_candidates(d_.base.fitted, parameters_)) all.push_back(std::move(c));
  const std::vector<std::string> known = candidate_names();
  for (const std::string& name : options_.effects)
    if (std::find(known.begin(), known.end(), name) == known.end() && name.find('.') == std::string::npos)
      throw std::invalid_argument(fmt::format("--effects: '{}' is not a candidate; valid: {}, or a wall parameter WALL.KEY", name, join(known, ", ")));
  for (EffectCandidate& c : all)
    if (options_.effects.empty() || std::find(options_.effects.begin(), options_.effects.end(), c.name) != options_.effects.end())
      effects_.push_back(std::move(c));
}

/// Plans the screen's simulations, and for the command's count the confirmations after them.
void DiagnosisRun::plan_signatures(SignaturePass& pass) {
  for (size_t k = 0; k < effects_.size(); ++k)
    for (const Experiment& e : measured_.experiments) pass.progress.plan(e, pass.replicas + 1);
  if (command_.outermost())
    count_.plan_remaining(experiments_ * static_cast<int>(effects_.size()) * (pass.replicas + 1) +
                          (fits_ ? 0 : experiments_ * options_.confirm_candidates * detail::confirmation_passes(options_, fitted_)));
}

/// The screen's basis, with a progress line when the signatures are screened whole.
ScreenBasis DiagnosisRun::screen_basis(ScreenResidual residual) const {
  std::map<std::string, double> floor;
  for (const Term& t : d_.base.after.terms) floor[t.name()] = t.sigma_simulated;
  ScreenBasis basis(std::move(residual), std::move(floor));
  if (!basis.removable && basis.A.cols() > 0 && basis.A.norm() > 0 && options_.progress)
    options_.progress("diagnose: the calibrated residual lies along what the fitted parameters do (a bound or the surrogate held them): "
                      "signatures are screened whole");
  return basis;
}

/// One candidate screened into the ranking (d_.candidates), or left out when its simulations cannot run.
void DiagnosisRun::screen_candidate(const EffectCandidate& c, const detail::SignatureRuns& runs, const ScreenBasis& basis, SignaturePass& pass) {
  CandidateResult cr = entry_of(c);
  if (leave_out(c, runs)) return;
  CandidateScreen screen(basis);
  measure_strengths(c, runs, basis, cr, screen);
  rank_candidate(c, basis, pass, screen, cr);
  bound_first_round(c, screen.strength_needed, cr);
  d_.candidates.push_back(std::move(cr));
  if (options_.on_partial) options_.on_partial(d_, fmt::format("signatures: {} of {} candidates", d_.candidates.size(), effects_.size()));
}

/// A candidate's entry before its screen: its words and the parameters it adds to the fit.
CandidateResult DiagnosisRun::entry_of(const EffectCandidate& c) const {
  CandidateResult cr;
  cr.name = c.name, cr.title = c.title, cr.description = c.description, cr.why = c.why, cr.switch_on = c.switch_on, cr.kind = c.kind;
  for (const auto& [key, range] : c.parameters) cr.adds.push_back({key, range.first, range.second});
  cr.k = static_cast<int>(parameters_.size() + cr.adds.size());
  return cr;
}

/// Whether a candidate is left out (left_out_) because its simulations cannot run.
bool DiagnosisRun::leave_out(const EffectCandidate& c, const detail::SignatureRuns& runs) {
  // A candidate the apparatus cannot take (clumps too large to fill a drum from a lattice) is
  // left out with the reason, not the whole diagnosis.
  if (runs.cannot.empty()) return false;
  left_out_.push_back(fmt::format("{} left out: its simulations cannot run in these experiments ({}).", c.name, runs.cannot));
  if (options_.progress) options_.progress(left_out_.back());
  return true;
}

/// The candidate's signatures at its start values and at the stronger step, with their costs and linear shares.
void DiagnosisRun::measure_strengths(const EffectCandidate& c, const detail::SignatureRuns& signature_runs, const ScreenBasis& basis, CandidateResult& cr,
                                     CandidateScreen& screen) {
  for (int strength = 0; strength < 2; ++strength) {
    const std::vector<ExperimentRun>& runs = strength == 0 ? signature_runs.start : signature_runs.stronger;
    for (const ExperimentRun& run : runs) cr.cost += run.wall_seconds, cr.simulations += run.replicas;
    const Comparison changed = compare_runs(measured_, runs, options_, basis.floor);
    const Eigen::VectorXd s = signature_of_runs(basis, changed, screen.flips);
    screen.at[strength] = s;
    screen.perp[strength] = basis.orthogonal(s);
    screen.measured_chi2 = std::min(screen.measured_chi2, own_runs_chi2(basis, screen.reachable, s));
    (strength == 0 ? cr.explained_start : cr.explained_stronger) = basis.explained_by(screen.perp[strength], s);
    if (c.parameters.size() == 1) {
      const auto& [key, range] = *c.parameters.begin();
      const auto at = strength == 1 && c.stronger.count(key) ? c.stronger.at(key) : c.start.at(key);
      screen.strength_needed = std::max(screen.strength_needed, range.first + basis.cancelling(screen.perp[strength], s) * (at - range.first));
    }
    if (strength == 0) {
      cr.signature.assign(s.data(), s.data() + s.size());
      at_start_[c.name] = changed;
    }
  }
}

/// The change of every term, in its sigma, that a candidate's runs make; an outcome that flips adds its experiment to `flips`.
Eigen::VectorXd DiagnosisRun::signature_of_runs(const ScreenBasis& basis, const Comparison& changed, std::vector<std::string>& flips) const {
  const Comparison& base = d_.base.after;
  const int nt = static_cast<int>(base.terms.size());
  Eigen::VectorXd s = Eigen::VectorXd::Zero(nt);
  for (int i = 0; i < nt; ++i)
    for (const Term& u : changed.terms)
      if (u.name() == base.terms[i].name()) {
        s[i] = (u.simulated - base.terms[i].simulated) / basis.sig[i];
        // An outcome that most packings show on one side and not on the other: a threshold.
        if (base.terms[i].is_outcome() && std::abs(u.simulated - base.terms[i].simulated) >= 0.5 &&
            std::find(flips.begin(), flips.end(), base.terms[i].experiment) == flips.end())
          flips.push_back(base.terms[i].experiment);
      }
  return s;
}

/// The chi^2 of a candidate's own runs after the linear recalibration of the fitted parameters.
double DiagnosisRun::own_runs_chi2(const ScreenBasis& basis, double reachable, const Eigen::VectorXd& s) const {
  return basis.removable ? basis.rr - std::max(0.0, reachable - basis.orthogonal(basis.r + s).squaredNorm())
                         : least_chi2_inward(basis.A, parameters_, d_.base.value, basis.r + s);
}

/// The candidate's place in the ranking: its agreement, stability, expected chi^2 and gain, and why.
void DiagnosisRun::rank_candidate(const EffectCandidate& c, const ScreenBasis& basis, SignaturePass& pass, CandidateScreen& screen, CandidateResult& cr) {
  const auto& perp = screen.perp;
  const double rr = basis.rr, ln_n = std::log(static_cast<double>(std::max(n_, 1)));
  // Strengths that change the terms by less than one sigma in all have no direction to disagree on.
  const double norms = perp[0].norm() * perp[1].norm();
  const bool signature = perp[0].norm() >= 1.0 || perp[1].norm() >= 1.0;
  // A two-sided candidate's steps go opposite ways: a linear response changes the terms oppositely.
  const double sense = c.two_sided ? -1.0 : 1.0;
  cr.agreement = signature && norms > 0 ? sense * perp[0].dot(perp[1]) / norms : 1.0;
  cr.stable = cr.agreement >= 0.5 && screen.flips.empty();
  const double linear = std::max(cr.explained_start, cr.explained_stronger);
  const auto signature_of = [&](const Comparison& changed) { return signature_of_runs(basis, changed, screen.flips); };
  const auto own_chi2 = [&](const Eigen::VectorXd& s) { return own_runs_chi2(basis, screen.reachable, s); };
  const int side = c.two_sided && cr.explained_stronger > cr.explained_start ? 1 : 0;
  const std::string weaker = cr.stable ? std::string() : weaker_strength(c, side, basis.cancelling(perp[side], screen.at[side]), linear, rr, signature_of, own_chi2,
                                                                        pass.replicas, basis.floor, pass.progress, screen.measured_chi2, cr);
  cr.screen_chi2 = cr.stable ? rr * (1 - linear) : screen.measured_chi2;
  cr.explained = rr > 0 ? std::max(0.0, 1 - cr.screen_chi2 / rr) : 0.0;
  cr.expected_gain = rr - cr.screen_chi2 - static_cast<double>(cr.adds.size()) * ln_n;
  cr.ranked_why = cr.stable ? fmt::format("ranked by its linear share, {:.0f} % (its strengths agree, {:.2f})", 100 * linear, cr.agreement)
                            : fmt::format("ranked by its own runs' chi^2 after a linear recalibration{}, {:.1f} of {:.1f} ({}; its linear share "
                                          "would say {:.0f} %)",
                                          weaker, cr.screen_chi2, rr,
                                          screen.flips.empty() ? fmt::format("its strengths disagree, agreement {:.2f}", cr.agreement)
                                                               : fmt::format("an outcome flips: {}", join(screen.flips, ", ")),
                                          100 * linear);
}

/// The candidates ranked by the share of the residual each explains, said in a progress line.
void DiagnosisRun::rank_by_share() {
  std::stable_sort(d_.candidates.begin(), d_.candidates.end(), [](const CandidateResult& a, const CandidateResult& b) { return a.explained > b.explained; });
  if (options_.progress && !d_.candidates.empty()) {
    std::vector<std::string> ranked;
    for (const CandidateResult& c : d_.candidates)
      ranked.push_back(fmt::format("{} {:.0f} % ({:.0f} % at the start, {:.0f} % stronger{})", c.name, 100 * c.explained, 100 * c.explained_start,
                                   100 * c.explained_stronger, c.stable ? "" : "; unstable: by its own runs"));
    options_.progress("diagnose: share of the residual each signature explains: " + join(ranked, "; "));
  }
}

/// Candidates named with options.effects are screened even when the model as it is fits.
void DiagnosisRun::say_it_fits() {
  d_.grade = Verdict::nothing_missing;
  say(fmt::format("No effect recommended: the model as it is fits within the noise after calibration (chi^2/n = {:.2f} <= {:.2f}).",
                  d_.base.after.chi2_per_n(), line_));
}


}  // namespace dem::materials::diagnosis
