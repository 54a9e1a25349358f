// What compare, calibrate and diagnose share inside the library (not part of its interface):
// progress with the time left, joining words, and running simulations as batches.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
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

/// Counts simulations against a planned total and prints the time left.
struct Progress {
  const CalibrationOptions& options;
  std::string what;
  int total = 0, done = 0;
  Clock::time_point t0 = Clock::now();
  void step(const std::string& item) {
    ++done;
    if (!options.progress) return;
    const double elapsed = seconds_since(t0);
    const double left = done > 0 ? elapsed / done * std::max(0, total - done) : 0;
    options.progress(fmt::format("{} {}/{}: {} ({} elapsed, about {} left)", what, done, total, item, duration_text(elapsed), duration_text(left)));
  }
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
/// step, labelled prefix + id, when the last replica of an experiment is known.
std::vector<ExperimentRun> simulate_experiments(const MaterialModel& model, const std::vector<Experiment>& experiments,
                                                const CalibrationOptions& options, int replicas, Progress* progress,
                                                const std::string& prefix);

}  // namespace dem::materials::detail
