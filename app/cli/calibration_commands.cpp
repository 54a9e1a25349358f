#include "cli/calibration_commands.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstring>
#include <fstream>
#include <random>
#include <set>
#include <filesystem>
#include <iostream>

#include "calibration/calibrated_material.h"
#include "calibration/calibration.h"
#include "report/calibration_report.h"
#include "cli/cli_checks.h"
#include "pages/html.h"
#include "model/material_model.h"
#include "lab/measurements.h"
#include "campaign/mpi_campaign.h"
#include "output/run.h"

namespace dem::app {

namespace {
namespace fs = std::filesystem;
using namespace dem::materials;

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : text + ",") {
    if (c == ',') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else if (c != ' ') {
      cur += c;
    }
  }
  return out;
}

/// --budget: 30m, 2h, 900s or 900 (seconds).
double wall_time_in_seconds(const std::string& budget) {
  size_t used = 0;
  double value = -1;
  try {
    value = std::stod(budget, &used);
  } catch (const std::exception&) {
  }
  const std::string unit = budget.substr(used);
  const double scale = unit.empty() || unit == "s" ? 1.0 : unit == "m" || unit == "min" ? 60.0 : unit == "h" ? 3600.0 : -1.0;
  if (!(value > 0) || scale < 0) throw CaseError(fmt::format("--budget {}: write a wall time such as 30m, 2h or 900s", budget));
  return value * scale;
}

/// Renders of final states: the model as compared, the fitted one, or the recommended one.
const MaterialModel& shown_model(const std::string& command, const MaterialModel& model, const CalibrationResult& calibration,
                                 const Diagnosis& diagnosis) {
  const MaterialModel* shown = &model;
  if (command == "calibrate") shown = &calibration.fitted;
  if (command == "diagnose") {
    shown = &diagnosis.base.fitted;
    for (const auto& c : diagnosis.candidates)
      if (c.name == diagnosis.recommended && c.confirmed) shown = &c.fit.fitted;
  }
  return *shown;
}
}  // namespace

CalibrationCommands::CalibrationCommands(CLI::App& app, RenderFinal render) : render_(std::move(render)) {
  test_ = app.add_subcommand("test", "run one virtual laboratory test on a material and print its observables");
  test_->add_option("material", material_, "material file (YAML)")->required();
  test_->add_option("--test", test_name_, "drop_rebound, bulk_density, angle_of_repose_cylinder, rotating_drum, hopper_discharge, direct_shear")->required();
  test_->add_option("--set", set_, "set-up value KEY=VALUE (SI units; repeat)");
  test_->add_option("--size-factor", size_factor_, "shrink the apparatus (0, 1] for a fast look")->check(number_in(0, 1, "", true));
  test_->add_option("--seed", seed_, "packing seed")->check(whole_in(0, 2147483647));
  test_->add_option("--threads", threads_, "OpenMP threads")->check(whole_in(1, 1024));
  test_->add_option("--measurements", measurements_, "measurement file whose size, density and walls to use");
  test_->add_option("--png", png_, "render of the final state (default: test_NAME.png)");
  test_->add_option("--stiffness-scaling", stiffness_scaling_, "factor on Young's modulus in the virtual tests (soft particles, longer step)")
      ->check(number_in(1e-9, 1e3));
  test_->add_option("--rayleigh-fraction", rayleigh_fraction_, "time step as a fraction of the Rayleigh time (default: the lab tests' rule)")
      ->check(number_in(0.005, 0.4));
  test_->add_option("--coarse-grain", coarse_grain_, "the apparatus filled with parcels of F x the diameter, F^3 particles each (1: real particles)")
      ->check(number_in(1, kMostCoarseGrain));
  for (CLI::App** cmd : {&compare_, &calibrate_, &diagnose_}) {
    const char* name = cmd == &compare_ ? "compare" : cmd == &calibrate_ ? "calibrate" : "diagnose";
    const char* what = cmd == &compare_ ? "simulate every experiment of a measurement file and compare (report in --out)"
                       : cmd == &calibrate_ ? "fit the material's tunable parameters to the measurements (surrogate + NLopt)"
                                            : "find the physical effect the material model lacks (signatures, recalibration, BIC)";
    *cmd = app.add_subcommand(name, what);
    (*cmd)->add_option("material", material_, "material file (YAML)")->required();
    (*cmd)->add_option("measurements", measurements_, "measurement file (YAML)")->required();
    (*cmd)->add_option("--replicas", replicas_, "packings per experiment (simulation noise)")->check(whole_in(1, 100));
    (*cmd)->add_option("--size-factor", size_factor_, "shrink the apparatus (0, 1] (fewer particles)")->check(number_in(0, 1, "", true));
    (*cmd)->add_option("--threads", threads_, "OpenMP threads of each simulation (default: 1 when simulations run in parallel)")->check(whole_in(1, 1024));
    (*cmd)->add_option("--parallel", parallel_, "simulations run at once in this process, each on its own core (default: the cores; under mpirun the ranks share them instead)")
        ->check(whole_in(1, 1024));
    (*cmd)->add_option("--seed", seed_, "first packing seed")->check(whole_in(0, 2147483647));
    (*cmd)->add_option("--out", out_, "output folder (report, plots, ledger.yaml)");
    (*cmd)->add_flag("--quiet", quiet_, "no progress lines");
    (*cmd)->add_flag("--no-renders", no_renders_, "no renders of the final states in the report");
    (*cmd)->add_flag("--no-store", no_store_,
                     "run every simulation again: neither take outcomes from OUT/simulations/ (kept there as each simulation finishes) nor keep new ones");
    (*cmd)->add_option("--stiffness-scaling", stiffness_scaling_, "factor on Young's modulus in the virtual tests (soft particles, longer step)")
        ->check(number_in(1e-9, 1e3));
    (*cmd)->add_option("--coarse-grain", coarse_grain_,
                       "the virtual tests with parcels of F x the diameter, F^3 particles each, in the real apparatus: the material at "
                       "the parcel size a case with coarse_grain F runs (1: real particles)")
        ->check(number_in(1, kMostCoarseGrain));
    if (cmd != &compare_) {
      (*cmd)->add_option("--params", params_, "parameters to fit, comma separated (default: the material's tunable ranges)");
      (*cmd)->add_option("--rounds", rounds_, "surrogate rounds (2: a quarter-range box around the first optimum)")->check(whole_in(1, 10));
      (*cmd)->add_option("--design-factor", design_factor_, "design points per round = max(b+1, ceil(factor b)+2), b quadratic coefficients")
          ->check(number_in(0, 100, "", true));
      (*cmd)->add_flag("--no-walls-first", no_walls_first_,
                       "leave each wall pair's restitution as the material gives it, instead of fitting it first to the drop tests on that wall");
      (*cmd)->add_option("--budget", budget_,
                         "wall time to fit in, e.g. 30m, 2h, 900s: after the first comparison the rest is planned to fit (fewer rounds, design "
                         "points, packings, candidates) and the report says what was given up");
    }
    if (cmd == &diagnose_) {
      (*cmd)->add_option("--effects", effects_, "effects to consider, comma separated (default: every effect the material lacks)");
      (*cmd)->add_option("--confirm", confirm_, "leading candidates confirmed by recalibration")->check(whole_in(0, 20));
    }
    if (cmd == &compare_) {
      (*cmd)->add_option("--synthetic-from", synthetic_from_,
                         "instead of comparing: simulate this TRUTH material on every experiment of MEASUREMENTS, add Gaussian noise of "
                         "each observation's sigma and write OUT/synthetic_measurements.yaml (synthetic data)");
      (*cmd)->add_option("--noise-seed", noise_seed_, "seed of the added measurement noise (--synthetic-from)")->check(whole_in(0, 2147483647));
      (*cmd)->add_option("--stiffness-check", stiffness_check_,
                         "compare again with the particles this much stiffer and say for each observable whether the stiffness "
                         "(--stiffness-scaling) is high enough for it (OUT/stiffness_check.csv)")
          ->check(number_in(1.01, 1e4));
    }
  }
}

bool CalibrationCommands::parsed() const { return test_->parsed() || compare_->parsed() || calibrate_->parsed() || diagnose_->parsed(); }

int CalibrationCommands::run() {
  // Under MPI, compare, calibrate and diagnose share their simulations among the ranks; a single
  // test and the synthetic data run on rank 0.
  const mpi::World& world = mpi::world();
  const bool campaign = !test_->parsed() && !(compare_->parsed() && !synthetic_from_.empty());
  if (world.active() && world.rank != 0 && !campaign) return 0;
  if (test_->parsed()) return run_test();
  if (compare_->parsed()) return synthetic_from_.empty() ? run_measured("compare") : write_synthetic();
  if (calibrate_->parsed()) return run_measured("calibrate");
  return run_measured("diagnose");
}

int CalibrationCommands::run_test() {
  MaterialModel model = read_material_model(material_);
  if (!measurements_.empty()) apply_measured(model, read_measurements(measurements_));
  model.stiffness_scaling = stiffness_scaling_;
  model.coarse_grain = coarse_grain_;
  TestSetup setup;
  setup.test = test_name_;
  setup.location.file = "--set";
  for (const std::string& kv : set_) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos) throw CaseError(fmt::format("--set {}: write KEY=VALUE", kv));
    const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
    try {
      size_t used = 0;
      const double v = std::stod(value, &used);
      if (used == value.size()) setup.numbers[key] = v;
      else setup.words[key] = value;
    } catch (const std::exception&) {
      setup.words[key] = value;
    }
  }
  TestOptions options;
  options.seed = static_cast<std::uint64_t>(seed_);
  options.size_factor = size_factor_;
  options.rayleigh_fraction = rayleigh_fraction_;
  options.threads = threads_;
  options.progress = true;
  const std::string png = png_.empty() ? fmt::format("test_{}.png", test_name_) : png_;
  if (render_) options.on_final = [&](const Model& m, const State& s) { render_(m, s, png); };
  const SimulatedOutcome out = run_virtual_test(model, setup, options);
  std::cout << fmt::format("{} on {} ({} particles, {:.3g} s simulated, {:.1f} s wall)\n", test_name_, model.name, out.particles, out.simulated_seconds, out.wall_seconds);
  for (const auto& [k, v] : out.observables) {
    const auto u = out.uncertainty.find(k);
    std::cout << fmt::format("  {} = {:.6g}{}\n", k, v, u == out.uncertainty.end() ? "" : fmt::format(" +- {:.2g} (this run's extraction)", u->second));
  }
  for (const auto& f : out.flags) std::cout << "  outcome: " << f << "\n";
  for (const auto& n : out.notes) std::cout << "  note: " << n << "\n";
  if (render_ && fs::exists(png)) std::cout << "  render: " << png << "\n";
  return 0;
}

/// What the phases of compare, calibrate and diagnose share.
struct CalibrationCommands::Campaign {
  std::string command;                          ///< compare, calibrate or diagnose
  std::chrono::steady_clock::time_point t0;     ///< when the command started
  MaterialModel model;                          ///< the material with the measurements' size, density and walls
  MeasurementSet measured;
  CalibrationOptions options;
  std::vector<FitParameter> params;             ///< --params; empty: the material's tunable ranges
  std::vector<std::string> keys;                ///< the fitted parameters' keys, for the ledger
  std::string ledger_path;                      ///< OUT/ledger.yaml
  report::CalibrationReportInput input;         ///< the report, filled as the phases go
  Comparison comparison;                        ///< compare
  CalibrationResult calibration;                ///< calibrate
  Diagnosis diagnosis;                          ///< diagnose
};

int CalibrationCommands::run_measured(const std::string& command) {
  Campaign campaign;
  campaign.command = command;
  campaign.t0 = std::chrono::steady_clock::now();
  read_campaign_inputs(campaign);
  set_campaign_options(campaign);
  start_campaign_report(campaign);
  if (command == "compare") {
    campaign.comparison = compare(campaign.model, campaign.measured, campaign.options);
  } else if (command == "calibrate") {
    campaign.calibration = calibrate(campaign.model, campaign.measured, campaign.params, campaign.options);
  } else {
    report_diagnosis_stages(campaign);
    campaign.diagnosis = diagnose(campaign.model, campaign.measured, campaign.params, campaign.options);
  }
  // Rank 0 alone prints, renders and writes.
  if (mpi::world().rank != 0) return 0;
  if (command == "compare") print_comparison(campaign);
  else if (command == "calibrate") record_calibration(campaign);
  else record_diagnosis(campaign);
  if (campaign.input.ledger.empty()) campaign.input.ledger = read_ledger(campaign.ledger_path);
  const MaterialModel& shown = shown_model(command, campaign.model, campaign.calibration, campaign.diagnosis);
  if (command != "compare") write_calibrated(campaign);
  write_campaign_report(campaign, shown);
  return 0;
}

/// The material with the measurements' size, density and walls at the command's stiffness, every
/// experiment's set-up checked.
void CalibrationCommands::read_campaign_inputs(Campaign& campaign) {
  campaign.model = read_material_model(material_);
  campaign.measured = read_measurements(measurements_);
  if (mpi::world().rank == 0)
    for (const std::string& w : campaign.measured.warnings) std::cout << "warning: " << w << std::endl;
  apply_measured(campaign.model, campaign.measured);
  campaign.model.stiffness_scaling = stiffness_scaling_;
  campaign.model.coarse_grain = coarse_grain_;  // before the check: what an apparatus holds is counted in parcels
  {  // every experiment's set-up checked before the first simulation
    TestOptions check;
    check.size_factor = size_factor_;
    check_experiments(campaign.model, campaign.measured, check);
  }
  // Parameters fitted at one stiffness need not hold at another.
  if (const auto& record = campaign.model.particle.calibration; record && mpi::world().rank == 0) {
    const double ratio = stiffness_scaling_ / record->stiffness_scaling;
    if (ratio > 1.25 || ratio < 0.8)
      std::cout << fmt::format("note: {} was calibrated with its Young's modulus x {:g} in the virtual tests; this {} runs them at x {:g}: "
                               "parameters fitted at one stiffness need not hold at another (--stiffness-scaling {:g} repeats the calibration's)",
                               material_, record->stiffness_scaling, campaign.command, stiffness_scaling_, record->stiffness_scaling)
                << std::endl;
  }
  // Nor need parameters fitted with parcels of one size hold for another (core/coarse_grain.h).
  if (const auto& record = campaign.model.particle.calibration; record && mpi::world().rank == 0 && record->coarse_grain != coarse_grain_)
    std::cout << fmt::format("note: {} was calibrated at coarse_grain {:g}; this {} runs its virtual tests at coarse_grain {:g} "
                             "(--coarse-grain {:g} repeats the calibration's)",
                             material_, record->coarse_grain, campaign.command, coarse_grain_, record->coarse_grain)
              << std::endl;
  if (coarse_grain_ != 1.0 && mpi::world().rank == 0)
    std::cout << fmt::format("coarse graining: the virtual tests run parcels of coarse_grain {:g} ({:g} x the diameter, {:.4g} particles "
                             "each) in the real apparatus\n",
                             coarse_grain_, coarse_grain_, coarse_grain_ * coarse_grain_ * coarse_grain_)
              << std::flush;
}

/// The calibration's options from the command line.
void CalibrationCommands::set_campaign_options(Campaign& campaign) {
  CalibrationOptions& options = campaign.options;
  options.replicas = replicas_;
  options.rounds = rounds_;
  options.design_factor = design_factor_;
  options.walls_first = !no_walls_first_;
  options.confirm_candidates = confirm_;
  options.effects = split(effects_);
  options.size_factor = size_factor_;
  options.threads = threads_;
  options.parallel = parallel_ > 0 ? parallel_ : std::max(1, omp_get_num_procs());
  if (!budget_.empty()) options.budget_seconds = wall_time_in_seconds(budget_);
  if (!no_store_) options.store = (fs::path(out_) / "simulations").string();
  options.seed = static_cast<std::uint64_t>(seed_);
  // Every rank runs the same calibration in lockstep; the simulations of each batch (a design
  // round, the replicas of a comparison) are shared among the ranks and every rank gets every
  // outcome (app/campaign/mpi_campaign.h). Rank 0 alone prints, renders and writes.
  options.batch = mpi::calibration_batch_runner();
  if (!quiet_ && mpi::world().rank == 0) options.progress = [](const std::string& line) { std::cout << line << std::endl; };
}

/// The parameters to fit, the output folder, and the report's heading.
void CalibrationCommands::start_campaign_report(Campaign& campaign) {
  if (!params_.empty()) {
    try {
      campaign.params = fit_parameters(campaign.model, split(params_));
    } catch (const std::invalid_argument& e) {
      throw CaseError(fmt::format("--params: {}", e.what()));
    }
  }
  if (mpi::world().rank == 0) fs::create_directories(out_);
  campaign.ledger_path = (fs::path(out_) / "ledger.yaml").string();
  report::CalibrationReportInput& input = campaign.input;
  input.title = fmt::format("{} {}", campaign.command, campaign.model.name);
  input.material_path = material_, input.measurements_path = measurements_, input.version = "0.1.0";
  input.measured = &campaign.measured;
  input.coarse_grain = campaign.model.coarse_grain;
  for (const auto& p : (campaign.params.empty() ? fit_parameters(campaign.model) : campaign.params)) campaign.keys.push_back(p.key);
}

/// What the diagnosis knows so far goes into the report folder at each stage: an interrupted
/// diagnosis still shows it (the ledger is written once, at the end).
void CalibrationCommands::report_diagnosis_stages(Campaign& campaign) {
  if (mpi::world().rank == 0)
    campaign.options.on_partial = [this, &campaign](const Diagnosis& partial, const std::string& stage) {
      if (stage.rfind("the model as it is", 0) == 0) {
        std::cout << fmt::format("the model as it is, calibrated: chi^2/n = {:.2f}\n", partial.base.after.chi2_per_n());
        for (const auto& t : partial.base.after.terms)
          std::cout << fmt::format("  {:<28} measured {:>10.4g} +- {:<8.2g} simulated {:>10.4g} +- {:<8.2g} residual {:+.2f}\n", t.name(), t.measured,
                                   t.sigma_measured, t.simulated, t.sigma_simulated, t.residual);
        std::cout << std::flush;
      }
      report::CalibrationReportInput so_far = campaign.input;
      so_far.title = fmt::format("{} (in progress: {})", campaign.input.title, stage);
      so_far.diagnosis = &partial;
      so_far.ledger = read_ledger(campaign.ledger_path);
      try {
        report::write_calibration_report(so_far, out_);
      } catch (const std::exception& e) {
        std::cout << "partial report not written: " << e.what() << std::endl;
      }
    };
}

/// compare: chi^2/n, each observable against its measurement, the residual patterns, and the
/// stiffness check when asked for.
void CalibrationCommands::print_comparison(Campaign& campaign) {
  const Comparison& comparison = campaign.comparison;
  campaign.input.comparison = &comparison;
  std::cout << fmt::format("chi^2/n = {:.2f} over {} observations\n", comparison.chi2_per_n(), comparison.n);
  for (const auto& t : comparison.terms)
    std::cout << fmt::format("  {:<28} measured {:>10.4g} +- {:<8.2g} simulated {:>10.4g} +- {:<8.2g} residual {:+.2f}\n", t.name(), t.measured, t.sigma_measured,
                             t.simulated, t.sigma_simulated, t.residual);
  for (const auto& p : comparison.patterns) std::cout << "  " << p.words << "\n";
  if (stiffness_check_ > 0) stiffness_check(campaign.model, campaign.measured, campaign.options, comparison);
}

/// calibrate: the fit's words, and the material before and after it in the ledger.
void CalibrationCommands::record_calibration(Campaign& campaign) {
  const CalibrationResult& calibration = campaign.calibration;
  campaign.input.calibration = &calibration;
  for (const auto& w : calibration.words) std::cout << w << "\n";
  campaign.input.ledger = append_ledger(campaign.ledger_path, campaign.model.name,
                                        {ledger_entry(campaign.model, calibration.before, "start", campaign.keys),
                                         ledger_entry(calibration.fitted, calibration.after, "calibrated", campaign.keys)});
}

/// diagnose: the diagnosis' words and candidates, and in the ledger the material before and after
/// calibration, each confirmed candidate, and the verdict.
void CalibrationCommands::record_diagnosis(Campaign& campaign) {
  const Diagnosis& diagnosis = campaign.diagnosis;
  const std::vector<std::string>& keys = campaign.keys;
  campaign.input.diagnosis = &diagnosis;
  for (const auto& w : diagnosis.words) std::cout << w << "\n";
  for (const auto& c : diagnosis.candidates) std::cout << "  " << c.words << "\n";
  std::vector<LedgerEntry> entries = {ledger_entry(campaign.model, diagnosis.base.before, "start", keys),
                                      ledger_entry(diagnosis.base.fitted, diagnosis.base.after, "calibrated", keys)};
  for (const auto& c : diagnosis.candidates)
    if (c.confirmed) {
      std::vector<std::string> k = keys;
      for (const auto& a : c.adds) k.push_back(a.key);
      entries.push_back(ledger_entry(c.fit.fitted, c.fit.after, "+ " + c.name, k));
    }
  // The verdict goes on the version it judges: the best candidate's, else the model as it is.
  LedgerEntry* judged = &entries[1];
  for (LedgerEntry& e : entries)
    if (!diagnosis.best.empty() && e.label == "+ " + diagnosis.best) judged = &e;
  judged->verdict = verdict_words(diagnosis.grade) + (diagnosis.best.empty() ? "" : ": " + diagnosis.best) +
                    (diagnosis.confirm_next.empty() ? "" : "; confirm next: " + diagnosis.confirm_next) +
                    (diagnosis.rivals.empty() ? "" : "; rivals: " + fmt::format("{}", fmt::join(diagnosis.rivals, ","))) +
                    (diagnosis.unconfirmed_rivals.empty() ? "" : "; not ruled out, not recalibrated: " + fmt::format("{}", fmt::join(diagnosis.unconfirmed_rivals, ",")));
  std::cout << "verdict: " << judged->verdict << "\n";
  campaign.input.ledger = append_ledger(campaign.ledger_path, campaign.model.name, entries);
}

/// The calibrated material as a library file a case can name (the fit, its uncertainty and its
/// effects in one file): the calibration's, or the diagnosis' recommended model (the model as
/// it is, calibrated, when nothing is recommended).
void CalibrationCommands::write_calibrated(const Campaign& campaign) {
  const std::string& command = campaign.command;
  const Diagnosis& diagnosis = campaign.diagnosis;
  const CalibrationResult* fit = command == "calibrate" ? &campaign.calibration : &diagnosis.base;
  std::string note;
  if (command == "diagnose") {
    for (const auto& c : diagnosis.candidates)
      if (c.name == diagnosis.recommended && c.confirmed) fit = &c.fit, note = "with " + c.name + ", the effect it recommended";
    if (diagnosis.grade == Verdict::improves)
      note = fmt::format("without {}, which improves the fit but does not explain it (the diagnosis' verdict)", diagnosis.best);
  }
  const std::string path = (fs::path(out_) / (fs::path(material_).stem().string() + "_calibrated.yaml")).string();
  try {
    write_calibrated_material(path, *fit, {command, measurements_, html::now_text().substr(0, 10), note});
    std::cout << fmt::format("calibrated material: {} (a case names it as {{library: {}}})\n", path, fs::path(path).stem().string());
  } catch (const std::invalid_argument& e) {
    std::cout << fmt::format("calibrated material not written: {}\n", e.what());
  }
}

/// Renders of `shown`'s final states, the wall time, and the report.
void CalibrationCommands::write_campaign_report(Campaign& campaign, const MaterialModel& shown) {
  if (!no_renders_) campaign.input.images = render_tests(shown, campaign.measured, campaign.options);
  campaign.input.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - campaign.t0).count();
  const std::string html = report::write_calibration_report(campaign.input, out_);
  std::cout << fmt::format("report: {} ({:.0f} s)\n", html, campaign.input.wall_seconds);
}

void CalibrationCommands::stiffness_check(const MaterialModel& model, const MeasurementSet& measured, const CalibrationOptions& options,
                                          const Comparison& as_run) {
  MaterialModel stiffer = model;
  stiffer.stiffness_scaling = model.stiffness_scaling * stiffness_check_;
  std::cout << fmt::format("stiffness check: the comparison again with the particles {:g} x stiffer (Young's modulus x {:g})\n", stiffness_check_,
                           stiffer.stiffness_scaling)
            << std::flush;
  const Comparison checked = compare(stiffer, measured, options);
  // An observable is sensitive when it moves by more than one measurement sigma and by more than
  // twice the shift's simulation noise: the fit at this stiffness would then not hold at the other.
  std::string csv = "observable,simulated,simulated_stiffer,shift,shift_in_measurement_sigma,noise,sensitive\n";
  int sensitive = 0;
  std::cout << fmt::format("  {:<28} {:>10} {:>10} {:>9}  verdict\n", "observable", "as run", "stiffer", "shift/sig");
  for (const Term& t : as_run.terms) {
    if (t.is_outcome()) continue;
    const auto other = std::find_if(checked.terms.begin(), checked.terms.end(), [&](const Term& u) { return u.name() == t.name(); });
    if (other == checked.terms.end()) continue;
    const double shift = other->simulated - t.simulated, noise = std::hypot(t.sigma_simulated, other->sigma_simulated);
    const double in_sigma = t.sigma_measured > 0 ? shift / t.sigma_measured : std::numeric_limits<double>::quiet_NaN();
    const bool moved = std::abs(in_sigma) > 1.0 && std::abs(shift) > 2 * noise;
    sensitive += moved;
    std::cout << fmt::format("  {:<28} {:>10.4g} {:>10.4g} {:>+9.2f}  {}\n", t.name(), t.simulated, other->simulated, in_sigma,
                             moved ? "SENSITIVE: the stiffness moves it by more than its measurement sigma" : "good enough");
    csv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.6g},{:.6g},{}\n", t.name(), t.simulated, other->simulated, shift, in_sigma, noise, moved ? 1 : 0);
  }
  std::cout << fmt::format("  {} of the observables depend on the stiffness{}\n", sensitive,
                           sensitive ? ": a calibration at this stiffness holds only for cases run at the same stiffness" : "");
  write_file_atomically((fs::path(out_) / "stiffness_check.csv").string(), csv);
}

std::vector<std::string> CalibrationCommands::render_tests(const MaterialModel& model, const MeasurementSet& measured, const CalibrationOptions& options) {
  std::vector<std::string> out;
  if (!render_) return out;
  std::set<std::string> done;
  fs::create_directories(fs::path(out_) / "renders");
  for (const Experiment& e : measured.experiments) {
    if (!done.insert(e.setup.test).second) continue;
    const std::string png = (fs::path(out_) / "renders" / fmt::format("{}_{}.png", e.setup.test, e.id)).string();
    TestOptions t;
    t.seed = options.seed, t.threads = options.threads, t.size_factor = options.size_factor;
    t.on_final = [&](const Model& m, const State& s) { render_(m, s, png); };
    try {
      (void)run_virtual_test(model, e.setup, t);
      if (fs::exists(png)) out.push_back(png);
    } catch (const std::exception& error) {
      std::cerr << fmt::format("render of {}: {}\n", e.id, error.what());
    }
  }
  return out;
}

/// Text of the template with each observation's `value:` replaced (at the observation's line).
int CalibrationCommands::write_synthetic() {
  MaterialModel truth = read_material_model(synthetic_from_);
  const MeasurementSet measured = read_measurements(measurements_);
  apply_measured(truth, measured);
  truth.stiffness_scaling = stiffness_scaling_;
  truth.coarse_grain = coarse_grain_;
  {
    TestOptions check;
    check.size_factor = size_factor_;
    check_experiments(truth, measured, check);
  }
  std::ifstream in(measurements_);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::mt19937_64 random(static_cast<std::uint64_t>(noise_seed_));
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const Experiment& e : measured.experiments) {
    TestOptions t;
    t.seed = static_cast<std::uint64_t>(seed_), t.threads = threads_, t.size_factor = size_factor_;
    const SimulatedOutcome sim = run_virtual_test(truth, e.setup, t);
    for (const auto& [key, obs] : e.observed) {
      const auto it = sim.observables.find(key);
      if (it == sim.observables.end()) throw CaseError(fmt::format("{}: {}: the truth's simulation gave no {}", obs.location.str(), e.id, key));
      const double value = it->second + obs.sigma * normal(random);
      std::cout << fmt::format("{:<16} {:<20} truth {:.6g}  + noise -> {:.6g} (sigma {:.3g})\n", e.id, key, it->second, value, obs.sigma);
      const int line = obs.location.line - 1;
      if (line < 0 || line >= static_cast<int>(lines.size())) throw CaseError(fmt::format("{}: {}: no line for {}", measurements_, e.id, key));
      std::string& text = lines[line];
      const size_t from = text.find("value:", obs.location.column > 0 ? obs.location.column - 1 : 0);
      if (from == std::string::npos) throw CaseError(fmt::format("{}: write `{}: {{value: ..., sigma: ...}}` on one line", obs.location.str(), key));
      size_t start = from + 6;
      while (start < text.size() && text[start] == ' ') ++start;
      size_t end = start;
      while (end < text.size() && (std::isdigit(static_cast<unsigned char>(text[end])) || std::strchr("+-.eE", text[end]))) ++end;
      text.replace(start, end - start, fmt::format("{:.5g}", value));
    }
  }
  fs::create_directories(out_);
  const std::string path = (fs::path(out_) / "synthetic_measurements.yaml").string();
  std::ofstream file(path);
  file << fmt::format("# SYNTHETIC: values simulated with {} (seed {}, size factor {:g}, stiffness scaling {:g}, coarse grain {:g}) plus "
                      "Gaussian noise of each sigma (noise seed {}), written by `demdesign compare {} {} --synthetic-from {} ...`\n",
                      synthetic_from_, seed_, size_factor_, stiffness_scaling_, coarse_grain_, noise_seed_, material_, measurements_,
                      synthetic_from_);
  for (const std::string& line : lines) file << line << "\n";
  std::cout << "wrote " << path << "\n";
  return 0;
}

}  // namespace dem::app
