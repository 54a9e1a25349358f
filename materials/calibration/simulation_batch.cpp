// The simulations of compare and calibrate, run as batches (one after the other, or shared out by
// options.batch, e.g. over MPI ranks), and the replicas of an experiment summarised.
#include "calibration/calibration.h"
#include "calibration/calibration_support.h"

#include <fmt/format.h>

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <thread>
#include <tuple>

#include "calibration/simulation_store.h"
#include "statistics/steady_state.h"
#include "statistics/diagnostics.h"

namespace dem::materials {

using detail::Job;

namespace {

/// The options of one virtual test run of a calibration.
TestOptions test_options(const CalibrationOptions& options, std::uint64_t seed) {
  TestOptions t;
  t.seed = seed;
  t.threads = options.threads;
  t.size_factor = options.size_factor;
  t.rayleigh_fraction = options.rayleigh_fraction;
  if (options.on_final) t.on_final = options.on_final;
  return t;
}

/// A shrunk apparatus' observations carried to full size (CalibrationOptions::size_shift). An
/// outcome (an arch, no heap, a slipping bed) is the same at either size: its 0 is not shifted.
void shift_to_full_size(SimulatedOutcome& out, const TestSetup& setup, const CalibrationOptions& options) {
  if (!(options.size_factor < 1) || options.size_shift.empty()) return;
  if (std::any_of(out.flags.begin(), out.flags.end(), [](const std::string& f) { return f == "blocked" || f == "no_heap" || f == "slipping"; })) return;
  for (auto& [key, v] : out.observables)
    if (const auto s = options.size_shift.find(setup.id + "/" + key); s != options.size_shift.end()) v += s->second.shift;
}

/// Runs one job, or takes its outcome from the store; an exception becomes the outcome's error (a
/// runner must not throw mid-batch: under MPI every rank has to reach the gather). Failed
/// simulations are not stored: they run again.
BatchOutcome run_caught(const Job& job, const CalibrationOptions& options) {
  BatchOutcome b;
  try {
    const bool keep = !options.store.empty() && !options.simulator;
    const TestOptions t = test_options(options, job.seed);
    std::string inputs;
    if (keep) {
      inputs = simulation_inputs(*job.model, *job.setup, t);
      if (std::optional<SimulatedOutcome> stored = load_simulation(options.store, job.setup->test, inputs)) {
        b.outcome = std::move(*stored);
        b.error = BatchOutcome::Error::none, b.stored = true;
        shift_to_full_size(b.outcome, *job.setup, options);
        return b;
      }
    }
    b.outcome = options.simulator ? options.simulator(*job.model, *job.setup, t) : run_virtual_test(*job.model, *job.setup, t);
    b.error = BatchOutcome::Error::none;
    if (keep) {
      try {
        store_simulation(options.store, job.setup->test, inputs, b.outcome);
      } catch (const std::exception& e) {
        b.outcome.notes.push_back(fmt::format("not stored: {}", e.what()));  // the outcome itself stands
      }
    }
    shift_to_full_size(b.outcome, *job.setup, options);
  } catch (const CaseError& e) {
    b.error = BatchOutcome::Error::input, b.message = e.what();
  } catch (const NumericalError& e) {
    b.error = BatchOutcome::Error::numerical, b.message = e.what();
  } catch (const std::exception& e) {
    b.error = BatchOutcome::Error::other, b.message = e.what();
  }
  return b;
}

/// Where a set-up usually ranks by its cost, before any simulation of it has run: a hopper's
/// discharge (the smaller orifice first), a shear test, a drum (the slower first), a lifted
/// cylinder, a pour, a drop.
double usual_rank(const TestSetup& setup) {
  const auto number = [&](const char* key, double otherwise) {
    const auto it = setup.numbers.find(key);
    return it == setup.numbers.end() || !(it->second > 0) ? otherwise : it->second;
  };
  if (setup.test == "hopper_discharge") return 5 + 1 / (1 + 100 * number("orifice_diameter", 1.0));  // [m]
  if (setup.test == "direct_shear") return 4;
  if (setup.test == "rotating_drum") return 3 + 1 / (1 + number("rpm", 1e9));
  if (setup.test == "angle_of_repose_cylinder") return 2;
  if (setup.test == "bulk_density") return 1;
  return 0;
}

/// A set-up's test and every value of it, as one word.
std::string setup_key(const TestSetup& setup) {
  std::string out = setup.test;
  for (const auto& [k, v] : setup.numbers) out += fmt::format(";{}={}", k, v);
  for (const auto& [k, v] : setup.words) out += fmt::format(";{}={}", k, v);
  return out;
}

/// Appends one replica's outcome to a run (values, extraction errors, flags, cost).
void append_replica(ExperimentRun& run, const SimulatedOutcome& out, std::map<std::string, int>& flags) {
  for (const auto& [key, v] : out.observables) run.values[key].push_back(v);
  for (const auto& [key, u] : out.uncertainty) run.extraction[key].push_back(u);
  for (const std::string& f : out.flags) ++flags[f];
  if (run.replicas == 0) run.notes = out.notes, run.particles = out.particles;
  run.wall_seconds += out.wall_seconds;
  ++run.replicas;
}

/// Mean, standard error and flag fractions of a run from its replicas.
void summarise(ExperimentRun& run, const std::map<std::string, int>& flags) {
  for (const auto& [key, list] : run.values) {
    const double n = static_cast<double>(list.size());
    std::tie(run.mean[key], run.sigma[key]) = mean_and_standard_error(list);
    // Two replicas that happen to agree must not make the mean look surer than each run's own
    // extraction says: the standard error is at least that of the runs' errors, averaged.
    const auto e = run.extraction.find(key);
    if (e != run.extraction.end() && e->second.size() == list.size()) {
      double uu = 0;
      for (double u : e->second) uu += u * u;
      run.sigma[key] = std::max(run.sigma[key], std::sqrt(uu / n / n));
    }
  }
  run.flag_fraction.clear();
  for (const auto& [f, count] : flags) run.flag_fraction[f] = static_cast<double>(count) / run.replicas;
}

/// The flags of a run counted back from their fractions.
std::map<std::string, int> flag_counts(const ExperimentRun& run) {
  std::map<std::string, int> out;
  for (const auto& [f, fraction] : run.flag_fraction) out[f] = static_cast<int>(std::lround(fraction * run.replicas));
  return out;
}

/// Runs a batch and throws the first error in batch order.
std::vector<BatchOutcome> run_batch_or_throw(const std::vector<Job>& jobs, const CalibrationOptions& options,
                                             const std::function<void(size_t, const BatchOutcome&)>& done) {
  std::vector<BatchOutcome> outcomes =
      detail::run_batch(jobs, options, done, [](const BatchOutcome& b) { return b.error != BatchOutcome::Error::none; });
  for (const BatchOutcome& b : outcomes)
    if (b.error != BatchOutcome::Error::none) detail::rethrow(b);
  return outcomes;
}

}  // namespace

double detail::SetupCosts::of(const TestSetup& setup) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto it = seconds_.find(setup_key(setup));
  return it == seconds_.end() ? 1e12 * (1 + usual_rank(setup)) : it->second;
}

void detail::SetupCosts::note(const TestSetup& setup, double seconds) {
  const std::lock_guard<std::mutex> lock(mutex_);
  seconds_[setup_key(setup)] = seconds;
}

[[noreturn]] void detail::rethrow(const BatchOutcome& b) {
  if (b.error == BatchOutcome::Error::input) throw CaseError(b.message);
  if (b.error == BatchOutcome::Error::numerical) throw NumericalError(b.message);
  throw std::runtime_error(b.message);
}

std::vector<BatchOutcome> detail::run_batch(const std::vector<Job>& jobs, const CalibrationOptions& options,
                                            const std::function<void(size_t, const BatchOutcome&)>& done,
                                            const std::function<bool(const BatchOutcome&)>& fatal) {
  const auto simulate = [&](size_t k) { return run_caught(jobs[k], options); };
  if (options.batch) {
    std::vector<BatchOutcome> out = options.batch(jobs.size(), simulate, done, fatal);
    if (out.size() != jobs.size())
      throw std::logic_error(fmt::format("calibration: the batch runner returned {} outcomes for {} simulations", out.size(), jobs.size()));
    return out;
  }
  std::vector<BatchOutcome> out(jobs.size());
  const size_t workers = std::min(jobs.size(), static_cast<size_t>(std::max(1, options.parallel)));
  if (workers <= 1) {
    // Each simulation runs with `threads` OpenMP threads (run_virtual_test sets and restores them).
    for (size_t k = 0; k < jobs.size(); ++k) {
      out[k] = simulate(k);
      done(k, out[k]);
      if (fatal(out[k])) break;
    }
    return out;
  }
  // Workers take the jobs longest first, by what each set-up last cost in this command (a set-up
  // not yet run counts as longer than any that has, in the order of what usually takes longest,
  // and jobs of equal cost keep their batch order): the batch ends when its last simulation does, and a hopper discharge started last would keep one core
  // busy alone for a minute. After a fatal outcome only jobs before it in batch order still
  // start, so every job before the first fatal one has its outcome, as in the serial loop.
  // A batch run outside any command (options without a context) knows no costs.
  SetupCosts own;
  SetupCosts& setup_costs = options.context ? options.context->setup_costs : own;
  std::vector<double> cost(jobs.size());
  for (size_t k = 0; k < jobs.size(); ++k) cost[k] = setup_costs.of(*jobs[k].setup);
  std::vector<size_t> order(jobs.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return cost[a] > cost[b]; });
  std::atomic<size_t> next{0};
  std::atomic<size_t> first_fatal{jobs.size()};
  std::mutex reporting;
  const auto work = [&] {
    omp_set_num_threads(std::max(1, options.threads));  // this thread's own OpenMP setting
    for (size_t i = next++; i < jobs.size(); i = next++) {
      const size_t k = order[i];
      if (k > first_fatal) continue;
      out[k] = simulate(k);
      if (out[k].error == BatchOutcome::Error::none && !out[k].stored) setup_costs.note(*jobs[k].setup, out[k].outcome.wall_seconds);
      const std::lock_guard<std::mutex> lock(reporting);
      done(k, out[k]);
      if (fatal(out[k])) first_fatal = std::min(first_fatal.load(), k);
    }
  };
  std::vector<std::thread> pool;
  for (size_t w = 0; w < workers; ++w) pool.emplace_back(work);
  for (std::thread& t : pool) t.join();
  return out;
}

namespace {

/// The runs of `experiments`, each from `replicas` outcomes in experiment and replica order from `first`.
std::vector<ExperimentRun> runs_of(const std::vector<Experiment>& experiments, const std::vector<BatchOutcome>& outcomes, size_t first, int replicas) {
  std::vector<ExperimentRun> runs;
  for (size_t e = 0; e < experiments.size(); ++e) {
    ExperimentRun run;
    run.id = experiments[e].id, run.test = experiments[e].setup.test;
    std::map<std::string, int> flags;
    for (int r = 0; r < replicas; ++r) append_replica(run, outcomes[first + e * replicas + r].outcome, flags);
    summarise(run, flags);
    runs.push_back(std::move(run));
  }
  return runs;
}

}  // namespace

std::vector<ExperimentRun> detail::simulate_experiments(const MaterialModel& model, const std::vector<Experiment>& experiments,
                                                        const CalibrationOptions& options, int replicas, Progress* progress,
                                                        const std::string& prefix) {
  replicas = std::max(1, replicas);
  std::vector<Job> jobs;
  for (const Experiment& e : experiments)
    for (int r = 0; r < replicas; ++r) jobs.push_back({&model, &e.setup, options.seed + static_cast<std::uint64_t>(r)});
  const std::vector<BatchOutcome> outcomes = run_batch_or_throw(jobs, options, [&](size_t k, const BatchOutcome& b) {
    const size_t e = k / static_cast<size_t>(replicas);
    if (b.error == BatchOutcome::Error::none && progress)
      progress->step(experiments[e], fmt::format("{}{}, replica {} of {}{}", prefix, experiments[e].id, k % replicas + 1, replicas, b.stored ? ", stored" : ""),
                     b.stored ? 0.0 : b.outcome.wall_seconds);
  });
  return runs_of(experiments, outcomes, 0, replicas);
}

detail::RunsByModel detail::simulate_with_each(const std::vector<const MaterialModel*>& models, const std::vector<std::string>& names,
                                               const std::vector<Experiment>& experiments, const CalibrationOptions& options, int replicas,
                                               Progress* progress) {
  replicas = std::max(1, replicas);
  RunsByModel out;
  out.failed.assign(experiments.size(), std::string());
  std::vector<Job> jobs;
  for (const MaterialModel* model : models)
    for (const Experiment& e : experiments)
      for (int r = 0; r < replicas; ++r) jobs.push_back({model, &e.setup, options.seed + static_cast<std::uint64_t>(r)});
  const size_t per_model = experiments.size() * static_cast<size_t>(replicas);
  const std::vector<BatchOutcome> outcomes = run_batch(
      jobs, options,
      [&](size_t k, const BatchOutcome& b) {
        if (b.error != BatchOutcome::Error::none || !progress) return;
        const Experiment& e = experiments[(k % per_model) / static_cast<size_t>(replicas)];
        progress->step(e, fmt::format("{} {}, replica {} of {}{}", names[k / per_model], e.id, k % replicas + 1, replicas, b.stored ? ", stored" : ""),
                       b.stored ? 0.0 : b.outcome.wall_seconds);
      },
      [](const BatchOutcome&) { return false; });
  for (size_t k = 0; k < outcomes.size(); ++k) {
    std::string& failed = out.failed[(k % per_model) / static_cast<size_t>(replicas)];
    if (outcomes[k].error != BatchOutcome::Error::none && failed.empty()) failed = outcomes[k].message;
  }
  for (size_t m = 0; m < models.size(); ++m) {
    out.runs.push_back(runs_of(experiments, outcomes, m * per_model, replicas));
    for (size_t e = 0; e < experiments.size(); ++e)
      if (!out.failed[e].empty()) out.runs.back()[e] = ExperimentRun{};
  }
  return out;
}

std::vector<detail::SignatureRuns> detail::simulate_signatures(const MaterialModel& model, const std::vector<EffectCandidate>& candidates,
                                                               const std::vector<FitParameter>& parameters, const MeasurementSet& measured,
                                                               const CalibrationOptions& options, int replicas, Progress* progress) {
  replicas = std::max(1, replicas);
  const std::vector<Experiment>& experiments = measured.experiments;
  std::vector<SignatureRuns> out(candidates.size());
  // The models: two per candidate (its start values, then the stronger step). The wall
  // restitution fitted first to the drops is fitted again with the candidate on (a cohesion that
  // also damps the rebound would otherwise show a drop misfit the staged calibration of that model
  // does not have): the signature is that of the staged model.
  std::vector<MaterialModel> models(2 * candidates.size());
  for (size_t c = 0; c < candidates.size(); ++c) {
    const EffectCandidate& candidate = candidates[c];
    for (int strength = 0; strength < 2 && out[c].cannot.empty(); ++strength) {
      MaterialModel& with = models[2 * c + strength];
      with = model;
      candidate.add(with);
      for (const auto& [key, v] : candidate.start) {
        const auto stronger = candidate.stronger.find(key);
        set_parameter(with, key, strength == 1 && stronger != candidate.stronger.end() ? stronger->second : v);
      }
      if (!options.walls_first) continue;
      std::vector<FitParameter> all_fitted = parameters;
      for (const auto& [key, range] : candidate.parameters) all_fitted.push_back({key, range.first, range.second});
      CalibrationOptions quiet = options;
      quiet.progress = nullptr;
      try {
        with = fit_walls_first(with, measured, all_fitted, quiet).model;
      } catch (const CaseError& e) {
        out[c].cannot = e.what();
      }
    }
  }
  struct Place {
    size_t candidate, experiment;
    int strength, replica, of;
  };
  std::vector<Job> jobs;
  std::vector<Place> places;
  std::vector<size_t> begin(candidates.size(), jobs.size());
  for (size_t c = 0; c < candidates.size(); ++c) {
    if (!out[c].cannot.empty()) continue;
    begin[c] = jobs.size();
    for (int strength = 0; strength < 2; ++strength) {
      const int of = strength == 0 ? replicas : 1;
      for (size_t e = 0; e < experiments.size(); ++e)
        for (int r = 0; r < of; ++r) {
          jobs.push_back({&models[2 * c + strength], &experiments[e].setup, options.seed + static_cast<std::uint64_t>(r)});
          places.push_back({c, e, strength, r, of});
        }
    }
  }
  const std::vector<BatchOutcome> outcomes = run_batch(
      jobs, options,
      [&](size_t k, const BatchOutcome& b) {
        if (b.error != BatchOutcome::Error::none || !progress) return;
        const Place& at = places[k];
        const Experiment& e = experiments[at.experiment];
        progress->step(e, fmt::format("{} {} {}, replica {} of {}{}", candidates[at.candidate].name, at.strength == 0 ? "start" : "stronger", e.id,
                                      at.replica + 1, at.of, b.stored ? ", stored" : ""),
                       b.stored ? 0.0 : b.outcome.wall_seconds);
      },
      [](const BatchOutcome&) { return false; });
  // Bad input leaves its candidate out; any other error stops, the first in batch order.
  for (size_t k = 0; k < outcomes.size(); ++k) {
    const BatchOutcome& b = outcomes[k];
    if (b.error == BatchOutcome::Error::input) {
      if (out[places[k].candidate].cannot.empty()) out[places[k].candidate].cannot = b.message;
    } else if (b.error != BatchOutcome::Error::none) {
      rethrow(b);
    }
  }
  for (size_t c = 0; c < candidates.size(); ++c) {
    if (!out[c].cannot.empty()) continue;
    out[c].start = runs_of(experiments, outcomes, begin[c], replicas);
    out[c].stronger = runs_of(experiments, outcomes, begin[c] + experiments.size() * static_cast<size_t>(replicas), 1);
  }
  return out;
}

void detail::add_packing(const MaterialModel& model, const std::vector<const Experiment*>& experiments, const std::vector<ExperimentRun*>& runs,
                         const CalibrationOptions& options, Progress* progress) {
  std::vector<Job> jobs;
  for (size_t k = 0; k < experiments.size(); ++k) jobs.push_back({&model, &experiments[k]->setup, options.seed + static_cast<std::uint64_t>(runs[k]->replicas)});
  const std::vector<BatchOutcome> outcomes = run_batch_or_throw(jobs, options, [&](size_t k, const BatchOutcome& b) {
    if (b.error == BatchOutcome::Error::none && progress)
      progress->step(*experiments[k], fmt::format("{}, replica {} added{}", experiments[k]->id, runs[k]->replicas + 1, b.stored ? ", stored" : ""),
                     b.stored ? 0.0 : b.outcome.wall_seconds);
  });
  for (size_t k = 0; k < runs.size(); ++k) {
    std::map<std::string, int> flags = flag_counts(*runs[k]);
    append_replica(*runs[k], outcomes[k].outcome, flags);
    summarise(*runs[k], flags);
  }
}

}  // namespace dem::materials
