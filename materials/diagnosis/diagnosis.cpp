// Diagnosis: which missing effect explains the misfit (rules in calibration/calibration.h; its budget plan in
// calibration/budget.cpp).
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

#include "calibration/calibration.h"
#include "calibration/calibration_support.h"
#include "contact/effect.h"
#include "diagnosis/discrimination.h"

namespace dem::materials {

using detail::join;
using detail::Progress;
using detail::simulate_experiments;

// ---- diagnosis ----------------------------------------------------------------------------

double bic(double chi2, int k, int n) { return chi2 + k * std::log(static_cast<double>(std::max(n, 1))); }

double noise_line(const CalibrationOptions& options, int n, int k) {
  if (options.fits_within_noise <= 0) return options.fits_within_noise;  // no model fits: every candidate is tried
  // Wilson-Hilferty: chi^2_nu's 95 % point is nu (1 - 2/(9 nu) + 1.645 sqrt(2/(9 nu)))^3.
  const double nu = std::max(1, n - k), c = 2.0 / (9.0 * nu);
  const double q95 = nu * std::pow(1.0 - c + 1.645 * std::sqrt(c), 3);
  return std::max(options.fits_within_noise, q95 / std::max(n, 1));
}

std::string verdict_words(Verdict v) {
  switch (v) {
    case Verdict::nothing_missing: return "nothing missing";
    case Verdict::missing: return "missing";
    case Verdict::cannot_tell: return "cannot tell";
    case Verdict::improves: return "improves, not explained";
    case Verdict::parameter: return "a parameter";
    case Verdict::none_found: return "no effect found";
  }
  return "";
}

namespace {

/// The parameter rows a wall candidate is offered for (ParamSpec::wall_candidate) of the model's
/// active effects: the friction of its tangential law, the restitution of its damping, the
/// rolling friction when it rolls. In the order of their keys (friction, restitution,
/// rolling_friction), which the candidates and so the diagnosis' output follow. Rejected: the
/// order of the stages, in which damping comes before the tangential stage, and of the table,
/// in which a registered effect's row would land wherever it was registered.
std::vector<const ParamSpec*> wall_candidate_params(const ContactSpec& contact) {
  std::vector<const ParamSpec*> rows;
  for (const Stage stage : kStages)
    for (const ContactSpec::Choice* choice : contact.choices(stage))
      if (const EffectSpec* effect = find_effect(stage, choice->model))  // nullptr: "none", the stage is off
        for (const ParamSpec& p : effect->params)
          if (p.wall_candidate) rows.push_back(&p);
  std::sort(rows.begin(), rows.end(), [](const ParamSpec* a, const ParamSpec* b) { return a->key < b->key; });
  // A key two active effects share is one parameter (find_param), offered once.
  rows.erase(std::unique(rows.begin(), rows.end(), [](const ParamSpec* a, const ParamSpec* b) { return a->key == b->key; }), rows.end());
  return rows;
}

/// Wall parameters the fit leaves out (wall_candidate_params of each particle-wall pair), as
/// candidates: a test that misses because of a wall points at the wall's parameter, not at
/// missing physics. Measured ones are inputs, and those fitted first to their own drop tests are
/// settled: neither is offered.
std::vector<EffectCandidate> wall_parameter_candidates(const MaterialModel& model, const std::vector<FitParameter>& fitted) {
  std::vector<EffectCandidate> out;
  const std::vector<const ParamSpec*> params = wall_candidate_params(model.contact);
  const auto listed = [](const std::vector<std::string>& list, const std::string& key) { return std::find(list.begin(), list.end(), key) != list.end(); };
  std::vector<std::string> fitted_keys;
  for (const FitParameter& p : fitted) fitted_keys.push_back(p.key);
  for (const InteractionSpec& pair : model.wall_pairs) {
    const std::string wall = pair.material_a == model.name ? pair.material_b : pair.material_a;
    for (const ParamSpec* p : params) {
      const std::string key(p->key), full = wall + "." + key;
      if (listed(fitted_keys, full) || listed(fitted_keys, "wall." + key) || listed(model.known, full) || listed(model.fitted_first, full)) continue;
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

/// The apparatus' size factor of a diagnosis that cannot meet its budget at full size
/// (DiagnosisRun::shrink): the lab tests' smallest sizes still hold a bed (a 75 mm silo for a 30 mm
/// orifice, an 80 mm drum of 6 mm beads).
constexpr double kShrunkSize = 0.5;

/// Candidate experiments simulated to separate a rival, however little of the budget is left.
constexpr int kFewestSeparators = 4;

/// Whether every parameter the candidate adds has a value where it changes nothing: the plain
/// fit's points are then points of the candidate's space (EarlierPoints::known).
bool takes_plain_points(const EffectCandidate& c, const CandidateResult& cr) {
  return std::all_of(cr.adds.begin(), cr.adds.end(), [&](const FitParameter& a) { return c.unchanged.count(a.key) > 0; });
}

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

namespace {

// The screen's state (defined with the screen, below).
struct ScreenResidual;
struct ScreenBasis;
struct SignaturePass;
struct CandidateScreen;

/// The state a diagnosis passes from phase to phase; diagnose() below reads as the list of them.
class DiagnosisRun {
 public:
  DiagnosisRun(const MaterialModel& model, const MeasurementSet& measured, std::vector<FitParameter> parameters, const CalibrationOptions& given)
      : model_(model),
        measured_(measured),
        parameters_(parameters.empty() ? fit_parameters(model) : std::move(parameters)),
        given_(given),
        options_(detail::within_command(given)),
        experiments_(static_cast<int>(measured.experiments.size())),
        fitted_(static_cast<int>(parameters_.size())),
        walls_(static_cast<int>(wall_parameter_candidates(model, parameters_).size())),
        lacking_(static_cast<int>(missing_effects(model).size())),
        command_(options_.context, "diagnose",
                 experiments_ * (std::max(1, options_.replicas) + detail::diagnosis_passes(options_, fitted_, lacking_, walls_))),
        count_(command_.count()) {}

  void calibrate_as_it_is();
  void check_at_full_size();
  bool nothing_to_look_for();
  void replan_for_the_screen();
  void screen_signatures();
  bool fits_as_it_is() const { return fits_; }
  void say_it_fits();
  void confirm_leaders();
  void write_verdict();
  void describe_candidates();
  Diagnosis result() {
    if (!implausible_.empty()) d_.words.insert(d_.words.begin() + std::min<std::ptrdiff_t>(1, std::ssize(d_.words)), implausible_);
    return std::move(d_);
  }

 private:
  const MaterialModel& model_;
  const MeasurementSet& measured_;
  const std::vector<FitParameter> parameters_;
  const CalibrationOptions& given_;
  CalibrationOptions options_;  ///< a budget may reduce it; the commands it calls share its context
  const int experiments_, fitted_, walls_, lacking_;
  const detail::CommandScope command_;
  detail::CommandProgress& count_;
  Diagnosis d_;
  int n_ = 0;            ///< terms of the base comparison
  bool fits_ = false;    ///< the model as it is fits within the noise
  double line_ = 0;      ///< its chi^2/n line
  std::vector<EffectCandidate> effects_;           ///< the candidates screened
  std::map<std::string, Comparison> at_start_;     ///< each candidate's comparison at its start values
  std::vector<std::string> left_out_;              ///< candidates whose simulations could not run
  std::vector<std::string> undecided_, nonlinear_, unconfirmed_;
  std::string screen_leader_;  ///< the screen's first: the candidates are ranked again by their fits later
  bool screen_silent_ = false;
  std::string implausible_;                        ///< the plain fit's values out of the plausible

  std::string shrunk_words_;      ///< why and how the apparatus was shrunk (shrink)
  double full_size_reserve_ = 0;  ///< [s] of the budget kept for the full-size check of a shrunk diagnosis
  double cost_mark_seconds_ = 0;  ///< the command's time and simulations when the apparatus was shrunk:
  int cost_mark_done_ = 0;        ///< later costs are measured from there

  bool budgeted() const { return given_.budget_seconds > 0 && command_.outermost() && count_.done() > 0; }
  /// [s] wall time a simulation has cost so far, at the apparatus' present size.
  double seconds_per_simulation() const {
    const int done = count_.done() - cost_mark_done_;
    return done > 0 ? (count_.elapsed() - cost_mark_seconds_) / done : count_.elapsed() / std::max(1, count_.done());
  }
  double confirmation_seconds_per_simulation(const CandidateResult& cr) const;
  bool shrink(Comparison& first, double size, const std::string& why);
  void unshrink();
  const EffectCandidate& effect_of(const CandidateResult& cr) const {
    return *std::find_if(effects_.begin(), effects_.end(), [&](const EffectCandidate& c) { return c.name == cr.name; });
  }
  void say(std::string words) {
    d_.words.push_back(std::move(words));
    if (options_.progress) options_.progress("diagnose: " + d_.words.back());
  }
  ScreenResidual screen_residual() const;
  void choose_candidates();
  void plan_signatures(SignaturePass& pass);
  ScreenBasis screen_basis(ScreenResidual residual) const;
  void screen_candidate(const EffectCandidate& c, const detail::SignatureRuns& runs, const ScreenBasis& basis, SignaturePass& pass);
  CandidateResult entry_of(const EffectCandidate& c) const;
  bool leave_out(const EffectCandidate& c, const detail::SignatureRuns& runs);
  void measure_strengths(const EffectCandidate& c, const detail::SignatureRuns& signature_runs, const ScreenBasis& basis, CandidateResult& cr,
                         CandidateScreen& screen);
  Eigen::VectorXd signature_of_runs(const ScreenBasis& basis, const Comparison& changed, std::vector<std::string>& flips) const;
  double own_runs_chi2(const ScreenBasis& basis, double reachable, const Eigen::VectorXd& s) const;
  void rank_candidate(const EffectCandidate& c, const ScreenBasis& basis, SignaturePass& pass, CandidateScreen& screen, CandidateResult& cr);
  void rank_by_share();
  template <class SignatureOf, class OwnChi2>
  std::string weaker_strength(const EffectCandidate& c, double multiple, double linear, double rr, const SignatureOf& signature_of,
                              const OwnChi2& own_chi2, int replicas, const std::map<std::string, double>& floor, detail::Progress& progress,
                              double& measured_chi2, CandidateResult& cr);
  void fit_confirmations_to_budget(std::vector<size_t>& confirming, std::map<std::string, int>& design_points_of);
  CalibrationOptions confirmation_options(const CandidateResult& cr) const;
  void confirm(CandidateResult& cr, const CalibrationOptions& options);
  void separate(const CandidateResult& best, const CandidateResult& rival);
  std::vector<std::string> unexplained_by(const CandidateResult& best) const;
  std::string next_to_confirm(const CandidateResult& best) const;
};

// ---- the model as it is --------------------------------------------------------------------

/// With a budget the starting model is compared first (a simulation of each experiment is then
/// timed) and the rest planned to fit; the calibration uses that comparison as its start.
void DiagnosisRun::calibrate_as_it_is() {
  if (options_.progress) options_.progress("diagnose: calibrating the model as it is");
  const detail::Clock::time_point t0 = detail::Clock::now();
  // A shrunk apparatus asked for (--size-factor) is another experiment: the model as it is is
  // compared at full size first, and the shrinking corrected (shrink).
  const double asked = options_.size_factor;
  const bool correct_asked = asked < 1 && options_.correct_size;
  if (correct_asked) options_.size_factor = 1;
  Comparison first = compare(model_, measured_, options_);
  if (correct_asked)
    shrink(first, asked, fmt::format("As asked (--size-factor {:g}), the rest is simulated on the apparatus shrunk to size factor {:g}", asked, asked));
  if (options_.budget_seconds > 0) {
    BudgetPlan plan = plan_within_budget(options_, first, fitted_, lacking_, walls_, detail::seconds_since(t0) + full_size_reserve_);
    if (plan.seconds > given_.budget_seconds - detail::seconds_since(t0) && options_.size_factor == 1) {
      const BudgetPlan at_full_size = plan;
      Comparison full = first;
      const std::string why = fmt::format("At full size the budget of {} cannot be met (about {} after the first comparison at the least); the rest is "
                                          "simulated on the apparatus shrunk to size factor {:g}",
                                          detail::duration_text(given_.budget_seconds), detail::duration_text(at_full_size.seconds), kShrunkSize);
      if (shrink(first, kShrunkSize, why)) {
        plan = plan_within_budget(options_, first, fitted_, lacking_, walls_, detail::seconds_since(t0) + full_size_reserve_);
        if (plan.seconds + full_size_reserve_ >= at_full_size.seconds) {  // shrunk, a pass costs as much: nothing gained
          unshrink();
          first = std::move(full), plan = at_full_size;
        }
      }
    }
    options_ = plan.options;
    if (command_.outermost()) count_.plan_remaining(experiments_ * detail::diagnosis_passes(options_, fitted_, lacking_, walls_));
    options_.budget_seconds = 0;  // planned once, for the whole diagnosis
    say(fmt::format("Planned for the budget of {}: about {} after the first comparison{}.", detail::duration_text(given_.budget_seconds),
                    detail::duration_text(plan.seconds), plan.given_up.empty() ? "" : "; given up: " + join(plan.given_up, "; ")));
  } else if (command_.outermost() && options_.progress) {
    // Without a budget the whole plan, at what the first comparison's simulations cost (a
    // candidate's at kScreenCost and kConfirmationCost times that).
    double pass = 0;
    for (const ExperimentRun& run : first.runs) pass += run.replicas > 0 ? run.wall_seconds / run.replicas : 0.0;
    pass /= std::max(1, options_.parallel);
    const double passes = detail::calibration_passes(options_, fitted_) +
                          detail::weighted_screen_and_confirmation_passes(options_, fitted_, lacking_, walls_, detail::kScreenCost, detail::kConfirmationCost);
    options_.progress(fmt::format("diagnose: the first comparison took {}; the whole diagnosis will take about {} more (give --budget to fit it "
                                  "into less)", detail::duration_text(detail::seconds_since(t0)), detail::duration_text(pass * passes)));
  }
  if (!shrunk_words_.empty()) say(shrunk_words_);
  d_.base = calibrate(model_, measured_, parameters_, options_, &first);
  if (options_.on_partial) options_.on_partial(d_, "the model as it is, calibrated; signatures next");
  n_ = d_.base.after.n;
  // A plain fit that had to go out of the plausible to come near the data is a sign in itself.
  // It is said after the verdict, which leads the words.
  for (const std::string& w : d_.base.words)
    if (w.rfind("Implausible fit:", 0) == 0) {
      implausible_ = "The model as it is: " + w;
      if (options_.progress) options_.progress("diagnose: " + implausible_);
    }
  d_.base_bic = bic(d_.base.after.chi2, fitted_, n_);
  line_ = noise_line(options_, n_, fitted_);
  fits_ = d_.base.after.chi2_per_n() <= line_;
}

/// A file whose diagnosis cannot meet the budget at full size, even with every reduction, is
/// diagnosed on a shrunk apparatus (kShrunkSize: a lab file of 6 mm beads then holds about a third
/// of its particles a pass, the silos keeping their orifices), and so is one whose user asked for a size factor
/// (CalibrationOptions::correct_size), corrected to full size: the same packings of the
/// model as it is are simulated shrunk, and each observation's shift (full-size mean minus shrunk
/// mean, with the noise of both) is added to every later simulation at that size. The shift is
/// measured at the start values only, so the model finally named is compared at full size before
/// its grade stands (check_at_full_size), and full size is kept whenever it fits the budget.
/// Rejected: shrinking without the correction (the 75 mm silo and 40 mm cup of a lab file of 6 mm
/// beads then move mass flow and bulk density by 3 sigma, which reads as missing physics); a shift
/// measured for each candidate (a full-size pass each, the cost the shrinking saves).
bool DiagnosisRun::shrink(Comparison& first, double size, const std::string& why) {
  CalibrationOptions small = options_;
  small.size_factor = size;
  small.size_shift.clear();
  const int replicas = std::max(1, options_.replicas);
  detail::Progress progress{small, fmt::format("compare at size {:g}", size)};
  for (const Experiment& e : measured_.experiments) progress.plan(e, replicas);
  if (command_.outermost()) count_.plan_more(experiments_ * replicas);
  cost_mark_seconds_ = count_.elapsed(), cost_mark_done_ = count_.done();
  std::vector<ExperimentRun> runs;
  try {
    runs = detail::simulate_experiments(model_, measured_.experiments, small, replicas, &progress, "");
  } catch (const CaseError& e) {
    cost_mark_seconds_ = 0, cost_mark_done_ = 0;
    shrunk_words_ = fmt::format("{}, but it cannot be: {}; it stays at full size.", why, e.what());
    return false;
  }
  // An outcome (an arch, no heap, a slipping bed) is the same at either size; only observations
  // that are numbers at both sizes are shifted.
  const auto categorical = [](const ExperimentRun& r) {
    return std::any_of(r.flag_fraction.begin(), r.flag_fraction.end(), [](const auto& f) {
      return f.second > 0 && (f.first == "blocked" || f.first == "no_heap" || f.first == "slipping");
    });
  };
  std::map<std::string, SizeShift> shift;
  std::vector<std::string> moved;
  for (const Term& t : first.terms) {
    const auto k = static_cast<size_t>(std::find_if(measured_.experiments.begin(), measured_.experiments.end(),
                                                    [&](const Experiment& e) { return e.id == t.experiment; }) -
                                       measured_.experiments.begin());
    if (t.is_outcome() || k >= runs.size() || k >= first.runs.size()) continue;
    const ExperimentRun &full = first.runs[k], &shrunk = runs[k];
    if (categorical(full) || categorical(shrunk) || !shrunk.mean.count(t.observable) || !full.mean.count(t.observable)) continue;
    const SizeShift s{full.mean.at(t.observable) - shrunk.mean.at(t.observable), std::hypot(full.sigma.at(t.observable), shrunk.sigma.at(t.observable))};
    shift[t.name()] = s;
    const double noise = std::hypot(t.sigma_measured, t.sigma_simulated), in_sigma = noise > 0 ? -s.shift / noise : 0.0;
    if (std::abs(in_sigma) >= 0.1) moved.push_back(fmt::format("{} {:+.3g} ({:+.1f} sigma)", t.name(), -s.shift, in_sigma));
  }
  for (ExperimentRun& run : runs)
    for (auto& [observable, values] : run.values)
      if (const auto s = shift.find(run.id + "/" + observable); s != shift.end()) {
        for (double& v : values) v += s->second.shift;
        run.mean[observable] += s->second.shift;
      }
  // The full-size check of the model finally named: a comparison with replicas, at the first
  // comparison's cost, kept out of the budget the rest is planned into.
  double full_pass = 0;
  std::int64_t full_particles = 0, shrunk_particles = 0;
  for (const ExperimentRun& run : first.runs) full_pass += run.replicas > 0 ? run.wall_seconds / run.replicas : 0.0, full_particles += run.particles;
  for (const ExperimentRun& run : runs) shrunk_particles += run.particles;
  full_size_reserve_ = full_pass * replicas / std::max(1, options_.parallel);
  small.size_shift = shift;
  first = compare_runs(measured_, runs, small);
  options_.size_factor = size, options_.size_shift = shift;
  d_.size_factor = size, d_.size_shift = shift;
  shrunk_words_ = fmt::format("{} ({} particles a pass instead of {}), corrected to full size by what the shrinking does to each observation "
                              "of the model as it is (shrunk minus full): {}. The model finally named is compared at full size.",
                              why, shrunk_particles, full_particles,
                              moved.empty() ? "every observation within 0.1 sigma" : join(moved, ", ") + ", the others within 0.1 sigma");
  return true;
}

/// Back to full size: the shrunk apparatus saves nothing.
void DiagnosisRun::unshrink() {
  options_.size_factor = 1, options_.size_shift.clear();
  d_.size_factor = 1, d_.size_shift.clear();
  full_size_reserve_ = 0, cost_mark_seconds_ = 0, cost_mark_done_ = 0;
  shrunk_words_.clear();
}

/// A shrunk diagnosis' best candidate, at its fitted values, compared at full size: its grade
/// rests on the apparatus the measurements were taken in. An effect named missing that misfits
/// there is said to improve the fit, not to explain it.
void DiagnosisRun::check_at_full_size() {
  if (d_.size_factor == 1 || d_.best.empty()) return;
  const auto best = std::find_if(d_.candidates.begin(), d_.candidates.end(), [&](const CandidateResult& c) { return c.name == d_.best; });
  if (best == d_.candidates.end()) return;
  CalibrationOptions full = options_;
  full.size_factor = 1, full.size_shift.clear();
  if (options_.progress) options_.progress(fmt::format("diagnose: the model with {} compared at full size", best->name));
  if (command_.outermost()) count_.plan_remaining(experiments_ * std::max(1, full.replicas));
  d_.full_size = compare(best->fit.fitted, measured_, full);
  const double line = noise_line(options_, d_.full_size.n, best->k), at = d_.full_size.chi2_per_n(), shrunk = best->fit.after.chi2_per_n();
  if (at <= line) {
    say(fmt::format("Checked at full size: the model with {} fits within the noise there too (chi^2/n {:.2f} <= {:.2f}; shrunk and corrected "
                    "{:.2f}).", best->name, at, line, shrunk));
    return;
  }
  std::vector<std::string> worst;
  for (const Term& t : d_.full_size.terms)
    if (std::abs(t.residual) > 2) worst.push_back(fmt::format("{} {:+.1f} sigma", t.name(), t.residual));
  if (d_.grade != Verdict::missing && d_.grade != Verdict::cannot_tell) {
    say(fmt::format("At full size the model with {} gives chi^2/n {:.2f} (shrunk and corrected {:.2f}).", best->name, at, shrunk));
    return;
  }
  d_.grade = Verdict::improves;
  d_.recommended.clear();
  d_.unexplained = worst;
  say(fmt::format("At full size the model with {} misfits (chi^2/n {:.2f} > {:.2f}; shrunk and corrected it gave {:.2f}): {} improves the fit "
                  "but is not confirmed as what is missing. Still unexplained at full size: {}. A larger --budget diagnoses at full size.",
                  best->name, at, line, shrunk, best->name, worst.empty() ? "no single term beyond 2 sigma" : join(worst, "; ")));
}

/// No candidate can be recommended when the model already fits within the noise, nor when even
/// an effect that took up all of the misfit (chi^2 -> 0) with one parameter more would not lower
/// BIC by the margin (Delta BIC <= chi^2 - ln n): the screen and the confirmations are then not
/// run, unless candidates were named with options.effects.
bool DiagnosisRun::nothing_to_look_for() {
  const Comparison& base = d_.base.after;
  const double most_gain = base.chi2 - std::log(static_cast<double>(std::max(n_, 1)));
  if (!(fits_ || most_gain <= options_.bic_margin) || !options_.effects.empty()) return false;
  if (command_.outermost()) count_.plan_remaining(0);
  d_.grade = fits_ ? Verdict::nothing_missing : Verdict::none_found;
  if (fits_)
    say(fmt::format("No effect recommended: the model as it is fits within the noise after calibration (chi^2/n = {:.2f} <= {:.2f}); "
                    "no candidate was screened (name some with --effects to screen them anyway).",
                    base.chi2_per_n(), line_));
  else
    say(fmt::format("No effect recommended: the model misfits (chi^2/n = {:.2f}), but over {} terms even an effect that took up "
                    "all of chi^2 = {:.1f} with one parameter more would lower BIC by at most {:.1f}, not more than the margin "
                    "{:.0f}; no candidate was screened. More experiments, or more packings where they scatter, let the data decide.",
                    base.chi2_per_n(), n_, base.chi2, most_gain, options_.bic_margin));
  return true;
}

/// With a budget, the screen and the confirmations are planned again into what is left of it, at
/// the cost per simulation measured so far: the calibration's design points (friction near the
/// top of its range, slower flows) cost more than the first comparison, on which the first plan
/// was made.
void DiagnosisRun::replan_for_the_screen() {
  if (!budgeted()) return;
  const double pass = experiments_ * seconds_per_simulation();
  const BudgetPlan rest = plan_screen_within_budget(options_, pass, fitted_, lacking_, walls_,
                                                    given_.budget_seconds - count_.elapsed() - full_size_reserve_, given_.budget_seconds);
  if (rest.given_up.empty()) return;
  options_ = rest.options;
  say(fmt::format("Planned again after calibrating the model as it is ({} spent, at {:.1f} s a simulation, a candidate's "
                  "screen simulations counted at {:.1f} times that): about {} for the screen and the confirmations; given up: {}.",
                  detail::duration_text(count_.elapsed()), seconds_per_simulation(), detail::kScreenCost, detail::duration_text(rest.seconds),
                  join(rest.given_up, "; ")));
}

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
  Eigen::VectorXd at_start;    ///< the signature at the start values
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
/// Rejected: the two strengths alone, with which rolling resistance explained 0 % of
/// lab_rolling.yaml's misfit on a fit pinned at friction 0.9 (its start step was about twice what
/// the data hold), and the linear share (a threshold makes it meaningless).
template <class SignatureOf, class OwnChi2>
std::string DiagnosisRun::weaker_strength(const EffectCandidate& c, double multiple, double linear, double rr, const SignatureOf& signature_of,
                                          const OwnChi2& own_chi2, int replicas, const std::map<std::string, double>& floor,
                                          detail::Progress& progress, double& measured_chi2, CandidateResult& cr) {
  if (c.parameters.size() != 1 || !(multiple > 0.05 && multiple < 0.9) || measured_chi2 <= rr * (1 - linear)) return "";
  const auto& [key, range] = *c.parameters.begin();
  if (!c.start.count(key)) return "";
  const double from = c.unchanged.count(key) ? c.unchanged.at(key) : range.first;
  const double value = from + multiple * (c.start.at(key) - from);
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
    if (strength == 0) screen.at_start = s;
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
  cr.agreement = signature && norms > 0 ? perp[0].dot(perp[1]) / norms : 1.0;
  cr.stable = cr.agreement >= 0.5 && screen.flips.empty();
  const double linear = std::max(cr.explained_start, cr.explained_stronger);
  const auto signature_of = [&](const Comparison& changed) { return signature_of_runs(basis, changed, screen.flips); };
  const auto own_chi2 = [&](const Eigen::VectorXd& s) { return own_runs_chi2(basis, screen.reachable, s); };
  const std::string weaker = cr.stable ? std::string() : weaker_strength(c, basis.cancelling(perp[0], screen.at_start), linear, rr, signature_of, own_chi2,
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

// ---- the confirmations ---------------------------------------------------------------------

/// Confirms the leading candidates by adding each and recalibrating. The signature is a linear
/// screen from one step to the effect's start values; a strong, nonlinear effect (cohesion at a
/// start far from the truth) can overshoot and show little projection. When no candidate passes
/// the screen although the model misfits, the leading ones are confirmed anyway: recalibration,
/// not the screen, decides. Of those the screen chooses, the stable ones go first in the order of
/// their expected BIC gain per second of simulation, so that a budget that keeps only one keeps
/// the most promising one the screen can vouch for.
void DiagnosisRun::confirm_leaders() {
  const detail::ConfirmationChoice choice = detail::choose_confirmations(d_.candidates, options_);
  screen_silent_ = choice.screen_silent;
  std::vector<size_t> confirming = choice.confirming;
  undecided_ = choice.undecided, nonlinear_ = choice.nonlinear;
  screen_leader_ = d_.candidates.empty() ? "" : d_.candidates.front().name;
  // Bands of the screen's margin below the leader's share: within a band the screen cannot rank,
  // and the stable, cheaper candidate goes first; across bands the larger share does, stable or
  // not (an unstable candidate's share is its own runs' chi^2, not the linear screen's estimate).
  // Rejected: stable ones first across every band, with which a budget that kept one confirmation
  // recalibrated sjkr (stable, 17 %) and not the rolling resistance its own runs put first (68 %)
  // on lab_rolling.yaml.
  const double leader = d_.candidates.empty() ? 0.0 : d_.candidates.front().explained;
  const auto band = [&](const CandidateResult& c) { return detail::screen_band(leader, c, options_); };
  std::stable_sort(confirming.begin(), confirming.end(), [&](size_t a, size_t b) {
    const CandidateResult &x = d_.candidates[a], &y = d_.candidates[b];
    if (band(x) != band(y)) return band(x) < band(y);
    if (x.stable != y.stable) return x.stable;
    return x.expected_gain / std::max(x.cost, 1.0) > y.expected_gain / std::max(y.cost, 1.0);
  });
  std::map<std::string, int> design_points_of;  // a confirmation's design points, where a budget reduced them
  fit_confirmations_to_budget(confirming, design_points_of);
  const auto options_for = [&](const CandidateResult& cr) {
    CalibrationOptions o = confirmation_options(cr);
    if (const auto it = design_points_of.find(cr.name); it != design_points_of.end()) o.design_points = it->second;
    return o;
  };
  if (command_.outermost()) {
    int passes = 0;
    for (const size_t rank : confirming) passes += detail::calibration_passes(options_for(d_.candidates[rank]), d_.candidates[rank].k);
    count_.plan_remaining(experiments_ * passes);
  }
  for (const size_t rank : confirming) confirm(d_.candidates[rank], options_for(d_.candidates[rank]));
  for (const CandidateResult& c : d_.candidates)
    if (!c.confirmed && c.explained >= 0.05)
      unconfirmed_.push_back(fmt::format("{} ({:.0f} %{})", c.name, 100 * c.explained, c.stable ? "" : ", unstable"));
}

/// With a budget, the confirmations are fitted into what is left of it, each at what its own
/// candidate's screen simulations cost (confirmation_seconds_per_simulation): a candidate's
/// simulations (clumps, cohesion, a wetter bed) may cost several times the first comparison's,
/// on which the plan was made. The first is
/// always confirmed, and so is every candidate the screen cannot tell from the leader:
/// confirming one of two the screen cannot separate would name it on a coin toss. The result
/// says by how much that exceeds the budget.
void DiagnosisRun::fit_confirmations_to_budget(std::vector<size_t>& confirming, std::map<std::string, int>& design_points_of) {
  if (!budgeted() || confirming.size() <= 1) return;
  const double left = given_.budget_seconds - count_.elapsed() - full_size_reserve_;
  std::vector<double> costs, per_simulation;
  std::vector<int> points;  // each confirmation's design points a round
  std::vector<bool> tied;
  for (const size_t rank : confirming) {
    const CalibrationOptions o = confirmation_options(d_.candidates[rank]);
    per_simulation.push_back(confirmation_seconds_per_simulation(d_.candidates[rank]));
    points.push_back(detail::design_points(o, d_.candidates[rank].k));
    costs.push_back(experiments_ * detail::calibration_passes(o, d_.candidates[rank].k) * per_simulation.back());
    tied.push_back(std::find(undecided_.begin(), undecided_.end(), d_.candidates[rank].name) != undecided_.end());
  }
  // A candidate whose plain-fit points are points of its own space (EffectCandidate::unchanged)
  // can be confirmed with fewer design points of its own: the cost a tie past the budget falls
  // back on (fit_confirmations).
  std::vector<double> smaller(costs.size(), detail::kNaN);
  std::map<std::string, int> fewer_points;
  for (size_t k = 0; k < confirming.size(); ++k) {
    const CandidateResult& cr = d_.candidates[confirming[k]];
    CalibrationOptions o = options_;
    o.design_points = detail::design_points_beside_known(cr.k, static_cast<int>(cr.adds.size()));
    if (!takes_plain_points(effect_of(cr), cr) || o.design_points >= points[k]) continue;
    smaller[k] = experiments_ * detail::calibration_passes(o, cr.k) * per_simulation[k];
    fewer_points[cr.name] = o.design_points;
  }
  const detail::ConfirmationPlan plan = detail::fit_confirmations(costs, tied, left, smaller);
  if (plan.reduced) {
    design_points_of = fewer_points;
    for (size_t k = 0; k < costs.size(); ++k)
      if (std::isfinite(smaller[k])) costs[k] = smaller[k];
    std::vector<std::string> which;
    for (const auto& [name, points] : fewer_points) which.push_back(fmt::format("{} {}", name, points));
    say(fmt::format("To fit the budget of {} with a tie, the confirmations design fewer points ({} a round, against {}): the plain "
                    "fit's points, where each candidate changes nothing, determine the rest of their surrogates.",
                    detail::duration_text(given_.budget_seconds), join(which), detail::design_points(options_, d_.candidates[confirming.front()].k)));
  }
  std::vector<size_t> kept;
  std::vector<std::string> dropped, beyond;
  std::vector<std::string> each;  // the dropped ones with their costs
  for (const size_t k : plan.kept) kept.push_back(confirming[k]);
  for (const size_t k : plan.beyond) beyond.push_back(d_.candidates[confirming[k]].name);
  for (const size_t k : plan.dropped)
    dropped.push_back(d_.candidates[confirming[k]].name), each.push_back(fmt::format("{} about {}", dropped.back(), detail::duration_text(costs[k])));
  if (!beyond.empty())
    say(fmt::format("The budget of {} is exceeded by about {}: the signature screen cannot tell {} from {}, so each is recalibrated.",
                    detail::duration_text(given_.budget_seconds), detail::duration_text(-plan.left), d_.candidates[confirming.front()].name,
                    join(beyond, ", ")));
  if (dropped.empty()) return;
  confirming = kept;
  const auto gone = [&](const std::string& name) { return std::find(dropped.begin(), dropped.end(), name) != dropped.end(); };
  std::erase_if(undecided_, gone), std::erase_if(nonlinear_, gone);
  say(fmt::format("Within the budget of {} ({} spent; each confirmation counted at what its candidate's screen simulations cost), {} {} "
                  "not recalibrated ({}): run again with a larger --budget, or with --effects {} (the simulations done are kept in the store).",
                  detail::duration_text(given_.budget_seconds), detail::duration_text(count_.elapsed()), join(dropped, ", "),
                  dropped.size() == 1 ? "was" : "were", join(each, ", "), join(dropped, ",")));
}

/// A candidate's confirmation options: where the plain fit's points are points of its space, its
/// design covers only what they leave open (confirmation_design_points).
CalibrationOptions DiagnosisRun::confirmation_options(const CandidateResult& cr) const {
  CalibrationOptions o = options_;
  if (takes_plain_points(effect_of(cr), cr)) o.design_points = detail::confirmation_design_points(options_, cr.k, static_cast<int>(cr.adds.size()));
  return o;
}

/// One candidate added at its start values and recalibrated with the fitted parameters.
void DiagnosisRun::confirm(CandidateResult& cr, const CalibrationOptions& options) {
  const EffectCandidate& effect = effect_of(cr);
  MaterialModel with = d_.base.fitted;
  effect.add(with);
  for (const auto& [key, v] : effect.start) set_parameter(with, key, v);
  std::vector<FitParameter> params = parameters_;
  params.insert(params.end(), cr.adds.begin(), cr.adds.end());
  // Its signature runs are two points of its design, taken from the store: the fitted parameters
  // at the base's values, its own at the start and at the stronger step.
  EarlierPoints earlier;
  earlier.include.assign(2, std::vector<double>(d_.base.value.begin(), d_.base.value.end()));
  for (const FitParameter& added : cr.adds) {
    earlier.include[0].push_back(effect.start.at(added.key));
    earlier.include[1].push_back(effect.stronger.count(added.key) ? effect.stronger.at(added.key) : effect.start.at(added.key));
  }
  // Every point the model as it is was simulated at is a point of the candidate's space too, its
  // own parameters where it changes nothing: the candidate's surrogate takes them as data.
  if (takes_plain_points(effect, cr))
    for (SimulatedPoint point : d_.base.points) {
      for (const FitParameter& added : cr.adds) point.x.push_back(effect.unchanged.at(added.key));
      earlier.known.push_back(std::move(point));
    }
  // A runner-up that cannot rival the best candidate confirmed so far (its simulations beyond
  // that one's BIC by twice the margin) is neither refined (when its surrogate lies beyond too)
  // nor given more packings (calibration.h, no_rival_above_chi2).
  CalibrationOptions confirming = options;
  for (const CandidateResult& done : d_.candidates)
    if (done.confirmed)
      confirming.no_rival_above_chi2 = std::min(confirming.no_rival_above_chi2,
                                                done.bic + 2 * options_.rival_margin - cr.k * std::log(static_cast<double>(std::max(n_, 1))));
  if (options_.progress) options_.progress(fmt::format("diagnose: confirming {} (recalibrating {} parameters)", cr.name, params.size()));
  cr.fit = calibrate(with, measured_, params, confirming, &at_start_.at(cr.name), earlier);
  cr.confirmed = true;
  cr.chi2 = cr.fit.after.chi2;
  cr.bic = bic(cr.chi2, cr.k, cr.fit.after.n);
  cr.delta_bic = d_.base_bic - cr.bic;
  if (options_.on_partial) options_.on_partial(d_, fmt::format("{} confirmed by recalibration", cr.name));
}

// ---- the verdict ---------------------------------------------------------------------------

/// The terms the model with `best` still misses by more than 2 sigma, worst first.
std::vector<std::string> DiagnosisRun::unexplained_by(const CandidateResult& best) const {
  std::vector<const Term*> worst;
  for (const Term& t : best.fit.after.terms)
    if (std::abs(t.residual) > 2) worst.push_back(&t);
  std::sort(worst.begin(), worst.end(), [](const Term* a, const Term* b) { return std::abs(a->residual) > std::abs(b->residual); });
  std::vector<std::string> out;
  for (const Term* t : worst) out.push_back(fmt::format("{} {:+.1f} sigma", t->name(), t->residual));
  return out;
}

/// The unconfirmed candidate with the largest expected gain, stable ones first.
std::string DiagnosisRun::next_to_confirm(const CandidateResult& best) const {
  const CandidateResult* next = nullptr;
  for (const CandidateResult& c : d_.candidates) {
    if (c.confirmed || &c == &best || c.kind == "parameter") continue;
    if (!next || (c.stable && !next->stable) || (c.stable == next->stable && c.expected_gain > next->expected_gain)) next = &c;
  }
  return next ? next->name : "";
}

/// The grade (Verdict) and its words. "Missing" only when the model with the best effect fits
/// within the noise and beats every other confirmed candidate by the BIC margin; two that both
/// fit within it are a tie, with the experiment that would tell them apart; an effect that
/// lowers BIC by the margin but leaves a misfit is said to improve the fit, with what it leaves
/// unexplained and the candidate to confirm next, and is not named as missing (nor written into
/// the calibrated material).
void DiagnosisRun::write_verdict() {
  const Comparison& base = d_.base.after;
  std::stable_sort(d_.candidates.begin(), d_.candidates.end(), [](const CandidateResult& a, const CandidateResult& b) {
    if (a.confirmed != b.confirmed) return a.confirmed;
    return a.confirmed ? a.bic < b.bic : a.explained > b.explained;
  });
  const CandidateResult* best = d_.candidates.empty() || !d_.candidates.front().confirmed ? nullptr : &d_.candidates.front();
  if (!best || best->delta_bic <= options_.bic_margin) {
    d_.grade = Verdict::none_found;
    say(fmt::format("No effect recommended: the model misfits (chi^2/n = {:.2f}) but no candidate lowers BIC by more than {:.0f}{}.", base.chi2_per_n(),
                    options_.bic_margin, best ? fmt::format(" (best: {}, by {:.1f})", best->name, best->delta_bic) : ""));
    return;
  }
  d_.best = best->name;
  const double line = noise_line(options_, best->fit.after.n, best->k);
  const bool fits = best->fit.after.chi2_per_n() <= line;
  std::vector<const CandidateResult*> rivals;
  for (const CandidateResult& c : d_.candidates)
    if (&c != best && c.confirmed && c.delta_bic > options_.bic_margin && c.bic - best->bic < options_.bic_margin) rivals.push_back(&c);
  std::vector<std::string> misfits;  // which patterns the effect answers
  for (const Pattern& p : d_.base.after.patterns)
    if (p.kind != "fits") misfits.push_back(p.words);
  const std::string gain = fmt::format("chi^2/n falls from {:.2f} to {:.2f} and BIC from {:.1f} to {:.1f} (by {:.1f} > margin {:.0f}", base.chi2_per_n(),
                                       best->fit.after.chi2_per_n(), d_.base_bic, best->bic, best->delta_bic, options_.bic_margin);
  if (best->kind == "parameter" && fits) {
    d_.grade = Verdict::parameter, d_.recommended = best->name;
    say(fmt::format("Not missing physics: {} ({}), which the fit left out, explains the misfit ({}). Calibrated with the others it comes to "
                    "{:.3g}, {}). {}; or measure it and state it in the measurement file.",
                    best->name, best->title, best->why, get_parameter(best->fit.fitted, best->name), gain, best->switch_on));
  } else if (!fits) {
    d_.grade = Verdict::improves;
    d_.unexplained = unexplained_by(*best);
    d_.confirm_next = next_to_confirm(*best);
    say(fmt::format("{} improves the fit but does not explain it: {}), but chi^2/n {:.2f} stays above the noise line {:.2f}. Still unexplained: "
                    "{}. {}",
                    best->name, gain, best->fit.after.chi2_per_n(), line, d_.unexplained.empty() ? "no single term beyond 2 sigma" : join(d_.unexplained, "; "),
                    d_.confirm_next.empty() ? "No other candidate was screened worth confirming: the misfit may be physics no candidate has, "
                                              "or a measurement to check."
                                            : fmt::format("Confirm next: {} (demdesign diagnose MATERIAL MEASUREMENTS --effects {}).", d_.confirm_next,
                                                          d_.confirm_next)));
  } else {
    d_.grade = rivals.empty() ? Verdict::missing : Verdict::cannot_tell;
    d_.recommended = best->name;
    say(fmt::format("{}: {} ({}; switch it on with `{}`). Why: {}. It could explain {:.0f} % of the weighted residual of the calibrated model; "
                    "added and recalibrated it fits within the noise (chi^2/n {:.2f} <= {:.2f}): {}, with {} more parameter{}).",
                    rivals.empty() ? "Missing" : "Most likely missing, but not told apart", best->name, best->title, best->switch_on, best->why,
                    100 * best->explained, best->fit.after.chi2_per_n(), line, gain, best->adds.size(), best->adds.size() == 1 ? "" : "s"));
  }
  if (!misfits.empty()) say("Where the model without it fails: " + join(misfits, " "));
  for (const CandidateResult* rival : rivals) {
    d_.rivals.push_back(rival->name);
    say(fmt::format("Cannot tell {} from {}: added instead and recalibrated, {} reaches BIC {:.1f}, only {:.1f} above (< {:.0f}). Measure where the "
                    "two act differently to decide ({}: {}; {}: {}).",
                    best->name, rival->name, rival->name, rival->bic, rival->bic - best->bic, options_.bic_margin, best->name, best->why, rival->name,
                    rival->why));
    if (options_.propose_experiments) separate(*best, *rival);
  }
}

/// Which experiment would tell `best` from `rival`: both fitted models simulated on candidates.
void DiagnosisRun::separate(const CandidateResult& best, const CandidateResult& rival) {
  SeparationPlan plan;
  plan.apart = apart_by_experiment(best.fit.after, rival.fit.after);
  // With a budget, as many candidate experiments as what is left of it pays for, the most
  // promising first, and never fewer than kFewestSeparators.
  if (budgeted()) {
    const double per_candidate = 2 * std::max(1, std::min(options_.replicas, options_.signature_replicas)) * seconds_per_simulation();
    plan.most = std::max(kFewestSeparators, static_cast<int>((given_.budget_seconds - count_.elapsed() - full_size_reserve_) / per_candidate));
  }
  SeparationSearch search = separating_experiments(best.fit.fitted, best.name, rival.fit.fitted, rival.name, measured_, options_, plan);
  std::vector<Separator>& found = search.found;
  if (!found.empty() && found.front().separation >= options_.separation_needed)
    say(fmt::format("To tell {} from {}, measure {}.", best.name, rival.name, found.front().words));
  else
    say(fmt::format("No experiment tried separates {} from {} by {:.0f} sigma{}.", best.name, rival.name, options_.separation_needed,
                    found.empty() ? "" : fmt::format(" (best: {})", found.front().words)));
  if (!search.untried.empty())
    say(fmt::format("Within the budget of {}, {} of {} candidate experiments were simulated, those of the experiments on which the two "
                    "fitted models already lie furthest apart; not tried: {}.",
                    detail::duration_text(given_.budget_seconds), search.candidates - static_cast<int>(search.untried.size()), search.candidates,
                    join(search.untried, "; ")));
  if (found.size() > 3) found.resize(3);
  d_.separators[rival.name] = std::move(found);
}

/// Why more than the leaders were recalibrated, what was left unconfirmed, and each candidate's
/// line: its screen, its rank's reason and, when confirmed, its fit.
void DiagnosisRun::describe_candidates() {
  if (!fits_) {
    if (!undecided_.empty())
      d_.words.push_back(fmt::format("The signature screen cannot tell {} from {} (their signatures explain within {:.0f} % of each other, at its "
                                     "noise): each was recalibrated.",
                                     screen_leader_, join(undecided_, ", "), 100 * options_.screen_margin));
    if (!nonlinear_.empty())
      d_.words.push_back(fmt::format("The signature of {} changes shape between its two strengths (the linear screen cannot be trusted for it): "
                                     "recalibrated.", join(nonlinear_, ", ")));
    if (screen_silent_ && !d_.candidates.empty())
      d_.words.push_back("The signatures explained little of the misfit (they are a linear screen from one step to each effect's start "
                         "values); the leading candidates were confirmed by recalibration anyway.");
    if (!unconfirmed_.empty())
      d_.words.push_back(fmt::format("Screened but not recalibrated: {}; their shares are the screen's estimate, not a fit.", join(unconfirmed_, "; ")));
  }
  d_.words.insert(d_.words.end(), left_out_.begin(), left_out_.end());
  for (CandidateResult& cr : d_.candidates) {
    const std::string screen = fmt::format("explains {:.0f} % of the residual ({:.0f} % at its start, {:.0f} % at twice the step; agreement {:.2f}; {})",
                                           100 * cr.explained, 100 * cr.explained_start, 100 * cr.explained_stronger, cr.agreement, cr.ranked_why);
    cr.words = cr.confirmed ? fmt::format("{}: {}; recalibrated chi^2/n = {:.2f}, BIC {:.1f} ({:+.1f} against the model as it is).", cr.name, screen,
                                          cr.fit.after.chi2_per_n(), cr.bic, -cr.delta_bic)
                            : fmt::format("{}: {} (signature only, not confirmed).", cr.name, screen);
  }
}

}  // namespace

Diagnosis diagnose(const MaterialModel& model, const MeasurementSet& measured, std::vector<FitParameter> parameters, const CalibrationOptions& given) {
  DiagnosisRun run(model, measured, std::move(parameters), given);
  run.calibrate_as_it_is();
  if (run.nothing_to_look_for()) return run.result();
  run.replan_for_the_screen();
  run.screen_signatures();
  if (run.fits_as_it_is()) {
    run.say_it_fits();
  } else {
    run.confirm_leaders();
    run.write_verdict();
    run.check_at_full_size();
  }
  run.describe_candidates();
  return run.result();
}

}  // namespace dem::materials
