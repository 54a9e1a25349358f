// What compare, calibrate and diagnose share inside the library (not part of its interface):
// progress with the time left, joining words, and running simulations as batches.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "calibration.h"

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
/// phase of a command in this process: a phase's estimate uses what earlier phases measured.
class SimulationCosts {
 public:
  static SimulationCosts& shared() {
    static SimulationCosts costs;
    return costs;
  }
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

 private:
  std::map<std::string, std::pair<double, int>> by_key_;
  double all_sum_ = 0;
  int all_count_ = 0;
};

/// A phase's simulations: the planned ones (by experiment), a line as each finishes, and the time
/// left from what each remaining simulation costs (SimulationCosts), not from the phase's mean.
/// Lines go to options.progress (the app writes them line-buffered, one per line).
class Progress {
 public:
  Progress(const CalibrationOptions& options, std::string what) : options_(options), what_(std::move(what)) {}
  /// Plans `count` simulations of `experiment`.
  void plan(const Experiment& experiment, int count = 1) {
    for (int k = 0; k < count; ++k) planned_.push_back(key(experiment));
  }
  /// Simulation of `experiment` finished (`label` says which: point, replica, candidate).
  void step(const Experiment& experiment, const std::string& label, double seconds) {
    SimulationCosts& costs = SimulationCosts::shared();
    if (seconds > 0) costs.add(key(experiment), seconds);  // (a stored outcome costs nothing, and says nothing of the cost)
    if (const auto it = std::find(planned_.begin(), planned_.end(), key(experiment)); it != planned_.end()) planned_.erase(it);
    ++done_;
    if (!options_.progress) return;
    double left = 0;
    for (const std::string& k : planned_) left += costs.estimate(k);
    options_.progress(fmt::format("{}: simulation {} of {} done ({}, {:.1f} s); {} elapsed, about {} left", what_, done_,
                                  done_ + planned_.size(), label, seconds, duration_text(seconds_since(t0_)),
                                  std::isfinite(left) ? duration_text(left) : std::string("? s")));
  }

 private:
  static std::string key(const Experiment& e) { return e.setup.test + "/" + e.id; }
  const CalibrationOptions& options_;
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

/// The error of a batch outcome thrown again, with its kind.
[[noreturn]] void rethrow(const BatchOutcome& b);

/// Every experiment simulated `replicas` times (seeds options.seed, +1, ...) as one batch; any
/// error stops the comparison (the first in experiment and replica order is thrown). A progress
/// step, labelled prefix + id and replica, as each simulation finishes.
std::vector<ExperimentRun> simulate_experiments(const MaterialModel& model, const std::vector<Experiment>& experiments,
                                                const CalibrationOptions& options, int replicas, Progress* progress,
                                                const std::string& prefix);

}  // namespace dem::materials::detail
