// What compare, calibrate and diagnose share inside the library (not part of its interface): the
// context of a command (its count, clock and costs), progress with the time left, joining words,
// and running simulations as batches.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "calibration/calibration.h"

namespace dem::materials::detail {

using Clock = std::chrono::steady_clock;

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

inline std::string duration_text(double s) {
  if (s < 90) return fmt::format("{:.0f} s", s);
  if (s < 5400) return fmt::format("{:.0f} min", s / 60);
  return fmt::format("{:.1f} h", s / 3600);
}

/// The measured wall time of a simulation of each experiment (by test and id), shared by every
/// phase of a command (CommandContext): a phase's estimate uses what earlier phases measured.
class SimulationCosts {
 public:
  void add(const std::string& key, double seconds) {
    auto& [sum, count] = by_key_[key];
    sum += seconds, ++count;
    all_sum_ += seconds, ++all_count_;
  }
  /// Mean seconds of a simulation of `key`; of any simulation when none of it ran; NaN when
  /// nothing ran yet.
  double estimate(const std::string& key) const {
    const auto it = by_key_.find(key);
    if (it != by_key_.end()) return it->second.first / it->second.second;
    return all_count_ > 0 ? all_sum_ / all_count_ : kNaN;
  }
  /// Mean seconds of a simulation in a pass over the experiments (each experiment's mean
  /// weighs alike); NaN when nothing ran yet.
  /// `size`: the apparatus' size tag of the keys counted (Progress::key; "" at full size).
  double pass_mean(const std::string& size = "") const {
    double sum = 0;
    int keys = 0;
    for (const auto& [key, v] : by_key_) {
      const size_t at = key.find('@');
      if ((at == std::string::npos ? std::string() : key.substr(at)) != size) continue;
      sum += v.first / v.second, ++keys;
    }
    return keys == 0 ? kNaN : sum / keys;
  }

 private:
  std::map<std::string, std::pair<double, int>> by_key_;
  double all_sum_ = 0;
  int all_count_ = 0;
};

/// Wall seconds the last simulation of each set-up took in a command (CommandContext), so that a
/// batch can start its longest simulations first. Only the order of a batch depends on it, never
/// an outcome. The workers of a batch note their simulations from their own threads.
class SetupCosts {
 public:
  /// [s]; when no simulation of this set-up has run yet, longer than any that has, ordered by
  /// what usually takes longest (simulation_batch.cpp).
  double of(const TestSetup& setup) const;
  void note(const TestSetup& setup, double seconds);

 private:
  mutable std::mutex mutex_;
  std::map<std::string, double> seconds_;
};

/// The whole command's count: the simulations planned in all (compare, calibrate and diagnose
/// each plan theirs when they begin; a diagnosis plans again as it learns how many candidates it
/// confirms), those done, and when the command began. The outermost command's CommandScope starts
/// it; the commands it calls run inside its count.
class CommandProgress {
 public:
  bool active() const { return depth_ > 0; }
  const std::string& what() const { return what_; }
  int done() const { return done_; }
  /// Simulations still planned (at least those of the phase running now).
  int left() const { return std::max(planned_ - done_, 0); }
  double elapsed() const { return seconds_since(t0_); }
  /// From now on `more` simulations remain to be done in all.
  void plan_remaining(int more) { planned_ = done_ + std::max(more, 0); }
  /// `more` simulations added to the plan (a round the results asked for).
  void plan_more(int more) { planned_ += std::max(more, 0); }
  void step() { ++done_; }

 private:
  friend class CommandScope;
  friend class Uncounted;
  int depth_ = 0, planned_ = 0, done_ = 0;  ///< depth: the commands running, one inside the other
  std::string what_;
  Clock::time_point t0_;
};

/// What a command shares with the commands it calls (the compare and the calibrations inside a
/// diagnosis, the fit of the walls' drops inside a calibration): its count, its clock and what its
/// simulations have cost so far. The outermost command makes it (within_command) and hands it down
/// in CalibrationOptions::context, which every copy of the options shares; two commands that do
/// not call each other (two tests in a row, a sweep that calibrates twice) have one each.
/// Rejected: one count and one table of costs per process (function-local statics), through which
/// such commands shared their counts and costs by accident.
struct CommandContext {
  CommandProgress count;
  SimulationCosts costs;   ///< by experiment: the time left in progress lines
  SetupCosts setup_costs;  ///< by set-up: which simulations of a batch start first
};

/// `options` as a command runs with them: their context when they carry one (a command called by
/// another), else a new one (the outermost command).
inline CalibrationOptions within_command(const CalibrationOptions& options) {
  CalibrationOptions out = options;
  if (!out.context) out.context = std::make_shared<CommandContext>();
  return out;
}

/// Simulations run inside it are left out of the command's count (the cheap single-contact fit
/// that precedes a calibration): the count and the plan are as they were before it.
class Uncounted {
 public:
  explicit Uncounted(CommandContext& context) : count_(context.count), done_(count_.done_), planned_(count_.planned_) {}
  ~Uncounted() { count_.done_ = done_, count_.planned_ = planned_; }
  Uncounted(const Uncounted&) = delete;
  Uncounted& operator=(const Uncounted&) = delete;

 private:
  CommandProgress& count_;
  int done_, planned_;
};

/// Marks a command's run in its context: the outermost scope starts the command's count with
/// `planned` simulations; nested scopes (the calibration inside a diagnosis) leave it as it is.
class CommandScope {
 public:
  CommandScope(std::shared_ptr<CommandContext> context, std::string what, int planned) : context_(std::move(context)) {
    CommandProgress& c = context_->count;
    if (c.depth_++ == 0) c.what_ = std::move(what), c.done_ = 0, c.planned_ = planned, c.t0_ = Clock::now();
    outermost_ = c.depth_ == 1;
  }
  ~CommandScope() { --context_->count.depth_; }
  CommandScope(const CommandScope&) = delete;
  CommandScope& operator=(const CommandScope&) = delete;
  bool outermost() const { return outermost_; }
  /// The count of the outermost command this one runs in.
  CommandProgress& count() const { return context_->count; }

 private:
  std::shared_ptr<CommandContext> context_;
  bool outermost_ = false;
};

/// Surrogate design points of one round fitting `k` parameters.
inline int design_points(const CalibrationOptions& o, int k) {
  const int b = 1 + k + k * (k + 1) / 2;
  return o.design_points > 0 ? o.design_points : std::max(b + 1, static_cast<int>(std::ceil(o.design_factor * b)) + 2);
}

/// Design points of one round fitting `k` parameters of which the last `added` change nothing at
/// points already simulated (EarlierPoints::known, the plain fit's): twice the coefficients of the
/// quadratic that involve the added ones, at least k + 2. The fewest a confirmation takes when a
/// budget asks for it; the known points determine the rest.
inline int design_points_beside_known(int k, int added) {
  const auto b = [](int q) { return 1 + q + q * (q + 1) / 2; };
  return std::max(k + 2, 2 * (b(k) - b(k - added)));
}

/// Design points of one round of a confirmation that fits `k` parameters, of which the last
/// `added` change nothing at the plain fit's points (EarlierPoints::known): the design factor
/// applied to the coefficients those points leave open, as design_points applies it to all of
/// them (design factor 2, one parameter added to two fitted: 10 points, against 22 for the whole
/// quadratic), and never fewer than design_points_beside_known. The known points determine
/// the rest; where the walls' first stage moves a wall pair and they are left out, the calibration
/// takes the full rule again (calibration.cpp, fit_walls_stage), and so does a fit with a zoom
/// round (rounds > 1), whose smaller box holds few of them. Rejected: the full rule everywhere,
/// which simulates again, with a third parameter beside them, the plane the plain fit has
/// already mapped.
inline int confirmation_design_points(const CalibrationOptions& o, int k, int added) {
  if (o.design_points > 0 || o.rounds > 1) return design_points(o, k);
  const auto b = [](int q) { return 1 + q + q * (q + 1) / 2; };
  const int open = b(k) - b(k - added);
  return std::min(design_points(o, k), std::max(design_points_beside_known(k, added), static_cast<int>(std::ceil(o.design_factor * open)) + 2));
}

/// Design points of a refinement round fitting `k` parameters (refine_around_best): a
/// design_points given, else those of its design factor (CalibrationOptions::refine_design_factor).
inline int refinement_design_points(const CalibrationOptions& o, int k) {
  CalibrationOptions refining = o;
  if (o.refine_design_factor > 0) refining.design_factor = std::min(o.design_factor, o.refine_design_factor);
  return design_points(refining, k);
}

/// [s] One pass over the experiments (a simulation of each) at the mean cost a packing of
/// `comparison`'s runs, `parallel` simulations at once.
inline double seconds_per_pass(const Comparison& comparison, int parallel) {
  double pass = 0;
  for (const ExperimentRun& run : comparison.runs) pass += run.replicas > 0 ? run.wall_seconds / run.replicas : 0.0;
  return pass / std::max(1, parallel);
}

/// Passes over the experiments of a refinement round and its confirming comparison.
inline int refinement_passes(const CalibrationOptions& o, int k) { return refinement_design_points(o, k) + std::max(1, o.replicas); }

/// Passes over the experiments (a simulation of each) that a calibration of `p` parameters
/// makes after its first comparison: the design rounds and the confirming comparison.
inline int calibration_passes(const CalibrationOptions& o, int p) { return std::max(1, o.rounds) * design_points(o, p) + std::max(1, o.replicas); }

/// The passes of a confirmation adding one parameter to `p` fitted, at confirmation_design_points:
/// what a plan counts for each (a candidate of two parameters, or one whose plain-fit points are
/// left out, costs more; the plan after the screen counts each one's own).
inline int confirmation_passes(const CalibrationOptions& o, int p) {
  return std::max(1, o.rounds) * confirmation_design_points(o, p + 1, 1) + std::max(1, o.replicas);
}

/// Passes over the experiments that a diagnosis makes after its first comparison, fitting `p`
/// parameters and screening `effects` effects and `walls` wall parameters (diagnosis/diagnosis_run.h).
int diagnosis_passes(const CalibrationOptions& o, int p, int effects, int walls);
/// The part of diagnosis_passes after the calibration of the model as it is: the signature screen
/// and the confirmations.
int screen_and_confirmation_passes(const CalibrationOptions& o, int p, int effects, int walls);
/// The signature screen's part of it.
int screen_passes(const CalibrationOptions& o, int effects, int walls);
/// The same with the screen's passes counted `screen` times and the confirmations' `confirmation` times.
double weighted_screen_and_confirmation_passes(const CalibrationOptions& o, int p, int effects, int walls, double screen, double confirmation);
/// What a simulation of the signature screen and of a confirmation costs against one of the model
/// as it is, which the plan after its calibration has measured: a candidate's effect (cohesion,
/// liquid bridges, clumps) slows the flows. On the cross-engine sets (tests/data/cross_engine,
/// 2026-12-05, 68dc73d, one core a simulation) the screens' simulations took 16-19 s on average
/// against 7-8 s for the plain model's, the confirmations' 7.5-9.4 s.
constexpr double kScreenCost = 2.0, kConfirmationCost = 1.2;

/// Which of the candidates, ranked by the residual their signatures explain, are confirmed by
/// recalibration: the leading confirm_candidates the screen passes (or, when the screen passes
/// none, the leading ones anyway); every runner-up the screen cannot tell from the leader (within
/// screen_margin: `undecided`, whatever its rank, so that a budget does not leave it out); and
/// one whose signature changes shape between its two strengths (`nonlinear`); at most
/// confirm_candidates + 2: beyond that the leader and then, band of screen_margin by band, stable
/// signatures before unstable ones. `confirming` holds indices into `ranked`.
struct ConfirmationChoice {
  std::vector<size_t> confirming;
  std::vector<std::string> undecided, nonlinear;
  bool screen_silent = false;
};
ConfirmationChoice choose_confirmations(const std::vector<CandidateResult>& ranked, const CalibrationOptions& options);
/// The band of options.screen_margin below the leader's share (`leader`) that a candidate's share
/// lies in: 0 for those the screen cannot tell from the leader's share, 1 for the next margin, ...
int screen_band(double leader, const CandidateResult& c, const CalibrationOptions& options);

/// [s] of wall time a simulation of candidate `cr` is expected to take in its confirmation, with
/// `parallel` simulations at once: what its own signature simulations took, one core each
/// (CandidateResult::cost over simulations; a simulation taken from the store counts what it took
/// when it ran), so that a rerun from the store does not make the confirmations look free. 0
/// when it has none. A clump's simulations cost several times a sphere's, a cohesive silo's more
/// than a dry one's: in lab_rolling.yaml's diagnosis (2026-12-07, one core each) a drum of clumps
/// took 21.5 s against the plain model's 4.6 s, a silo with liquid bridges 24.4 s against 18.1 s.
double candidate_seconds_per_simulation(const CandidateResult& cr, int parallel);

/// Which candidate confirmations fit what is left of a budget [s], each at its cost [s], in rank
/// order: the first always; a later one when it fits, or when it is tied (the signature screen
/// cannot tell it from the leader), then beyond the budget. `left` is what remains after those
/// kept (negative when the tied ones exceed it). When tied ones would go beyond the budget and
/// `smaller` gives a cheaper cost for some (a confirmation with fewer design points; NaN: none),
/// every confirmation is planned at its cheaper cost (`reduced`).
struct ConfirmationPlan {
  std::vector<size_t> kept, dropped, beyond;  ///< indices into the costs; beyond: kept past the budget
  double left = 0;
  bool reduced = false;  ///< planned at the `smaller` costs
};
ConfirmationPlan fit_confirmations(const std::vector<double>& costs, const std::vector<bool>& tied, double left,
                                   const std::vector<double>& smaller = {});

/// Simulations run at once: `parallel` in this process; under a batch runner (MPI ranks) the
/// count is the runner's, and one is assumed.
inline int workers(const CalibrationOptions& o, size_t jobs) {
  return o.batch ? 1 : static_cast<int>(std::clamp<size_t>(jobs, 1, static_cast<size_t>(std::max(1, o.parallel))));
}

/// A phase's simulations: the planned ones (by experiment), a line as each finishes, and the time
/// left from what each remaining simulation costs (SimulationCosts), not from the phase's mean,
/// shared among the simulations that run at once. When a command is counting
/// (CommandProgress), the line also gives the whole command's count and time left.
/// Lines go to options.progress (the app writes them line-buffered, one per line). The costs and
/// the count are those of options.context; options without one (a phase run outside any
/// command) get a context of their own, which no command counts.
class Progress {
 public:
  Progress(const CalibrationOptions& options, std::string what)
      : options_(options), context_(options.context ? options.context : std::make_shared<CommandContext>()), what_(std::move(what)) {}
  /// The command it counts into.
  CommandContext& context() const { return *context_; }
  /// Plans `count` simulations of `experiment`.
  void plan(const Experiment& experiment, int count = 1) {
    for (int k = 0; k < count; ++k) planned_.push_back(key(experiment));
  }
  /// Simulation of `experiment` finished (`label` says which: point, replica, candidate).
  void step(const Experiment& experiment, const std::string& label, double seconds) {
    SimulationCosts& costs = context_->costs;
    if (seconds > 0) costs.add(key(experiment), seconds);  // (a stored outcome costs nothing, and says nothing of the cost)
    if (const auto it = std::find(planned_.begin(), planned_.end(), key(experiment)); it != planned_.end()) planned_.erase(it);
    ++done_;
    CommandProgress& command = context_->count;
    if (command.active()) command.step();
    if (!options_.progress) return;
    double left = 0;
    for (const std::string& k : planned_) left += costs.estimate(k);
    left /= workers(options_, planned_.size());
    std::string line = fmt::format("{}: simulation {} of {} done ({}, {:.1f} s); {} elapsed, about {} left", what_, done_, done_ + planned_.size(),
                                   label, seconds, duration_text(seconds_since(t0_)), std::isfinite(left) ? duration_text(left) : std::string("? s"));
    if (command.active()) {
      // Beyond this phase: the command's other planned simulations at the mean cost of one.
      const int beyond = std::max(command.left() - static_cast<int>(planned_.size()), 0);
      double all = left + beyond * costs.pass_mean(size_tag()) / workers(options_, static_cast<size_t>(beyond));
      // A budgeted command's first comparison comes before its plan, which fits the budget.
      if (options_.budget_seconds > 0) all = std::min(all, std::max(left, options_.budget_seconds - command.elapsed()));
      line += fmt::format("; {}: simulation {} of about {}, {} elapsed, about {} left", command.what(), command.done(), command.done() + command.left(),
                          duration_text(command.elapsed()), std::isfinite(all) ? duration_text(all) : std::string("? s"));
    }
    options_.progress(line);
  }

 private:
  /// A shrunk apparatus' simulations are timed apart from the full-size ones.
  std::string size_tag() const { return options_.size_factor < 1 ? fmt::format("@{:g}", options_.size_factor) : std::string(); }
  std::string key(const Experiment& e) const { return e.setup.test + "/" + e.id + size_tag(); }
  const CalibrationOptions& options_;
  const std::shared_ptr<CommandContext> context_;
  std::string what_;
  std::vector<std::string> planned_;
  int done_ = 0;
  Clock::time_point t0_ = Clock::now();
};

inline std::string join(const std::vector<std::string>& words, const std::string& sep = ", ") {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : sep) + w;
  return out;
}

/// One simulation of a batch: which model, set-up and packing seed.
struct Job {
  const MaterialModel* model;
  const TestSetup* setup;
  std::uint64_t seed;
};

/// Runs the jobs as one batch through options.batch (or one after the other here). A job's
/// exception becomes its outcome's error (a runner must not throw mid-batch: under MPI every rank
/// has to reach the gather); `done` is called as each outcome is known, and a `fatal` one stops
/// a serial batch.
std::vector<BatchOutcome> run_batch(const std::vector<Job>& jobs, const CalibrationOptions& options,
                                    const std::function<void(size_t, const BatchOutcome&)>& done,
                                    const std::function<bool(const BatchOutcome&)>& fatal);

/// The model with each particle-wall pair's restitution fitted to the rebound heights of the
/// drop tests on that wall (options.walls_first), and what was done in words (empty when
/// nothing was). `parameters` are those the calibration fits itself: their pairs are left.
struct WallsFirst {
  MaterialModel model;
  std::vector<std::string> words;
};
WallsFirst fit_walls_first(const MaterialModel& model, const MeasurementSet& measured, const std::vector<FitParameter>& parameters,
                           const CalibrationOptions& options);

/// The error of a batch outcome thrown again, with its kind.
[[noreturn]] void rethrow(const BatchOutcome& b);

/// Every experiment simulated `replicas` times (seeds options.seed, +1, ...) as one batch; any
/// error stops the comparison (the first in experiment and replica order is thrown). A progress
/// step, labelled prefix + id and replica, as each simulation finishes.
std::vector<ExperimentRun> simulate_experiments(const MaterialModel& model, const std::vector<Experiment>& experiments,
                                                const CalibrationOptions& options, int replicas, Progress* progress,
                                                const std::string& prefix);

/// Each experiment simulated with each model, `replicas` packings each, all one batch (so that
/// every core stays busy): runs[m][e] is model m's run of experiment e. An experiment any model
/// cannot simulate (bad input, a numerical failure) is left out of every model's runs, its error in
/// `failed[e]`; the others still run. A progress step, labelled with the model's name, as each finishes.
struct RunsByModel {
  std::vector<std::vector<ExperimentRun>> runs;
  std::vector<std::string> failed;  ///< per experiment: "" or the first error
};
RunsByModel simulate_with_each(const std::vector<const MaterialModel*>& models, const std::vector<std::string>& names,
                               const std::vector<Experiment>& experiments, const CalibrationOptions& options, int replicas, Progress* progress);

/// A candidate's runs at its two signature strengths (diagnose).
struct SignatureRuns {
  std::vector<ExperimentRun> start;     ///< at its start values, with `replicas` packings
  std::vector<ExperimentRun> stronger;  ///< at the stronger step, one packing
  std::string cannot;                   ///< why the apparatus cannot take it (bad input), or empty
};

/// Every candidate added to `model` at its two signature strengths, its wall restitution fitted
/// again first to the drops when options.walls_first (fit_walls_first with `parameters` and the
/// candidate's own), every experiment simulated: all of them one batch, so that two cores stay
/// busy to the end. A candidate whose set-up is bad input is left out with the reason; any other
/// error stops the diagnosis (the first in candidate, strength, experiment and replica order).
/// A progress step, labelled with the candidate, the strength and the experiment, as each finishes.
std::vector<SignatureRuns> simulate_signatures(const MaterialModel& model, const std::vector<EffectCandidate>& candidates,
                                               const std::vector<FitParameter>& parameters, const MeasurementSet& measured,
                                               const CalibrationOptions& options, int replicas, Progress* progress);

/// One more packing of each experiment (seed after the run's last), added to its run.
void add_packing(const MaterialModel& model, const std::vector<const Experiment*>& experiments, const std::vector<ExperimentRun*>& runs,
                 const CalibrationOptions& options, Progress* progress);

}  // namespace dem::materials::detail
