// Diagnosis: which missing effect explains the misfit (rules in calibration/calibration.h; its budget plan in
// calibration/budget.cpp). This file holds the grades' words, the wall parameters offered as
// candidates, the phases before the screen (the model as it is, a shrunk apparatus and its
// full-size check) and diagnose() itself, the list of the phases (diagnosis_run.h).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "contact/effect.h"
#include "diagnosis/diagnosis_run.h"

namespace dem::materials {

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

namespace diagnosis {

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

/// The apparatus' size factor of a diagnosis that cannot meet its budget at full size
/// (DiagnosisRun::shrink): the lab tests' smallest sizes still hold a bed (a 75 mm silo for a 30 mm
/// orifice, an 80 mm drum of 6 mm beads).
constexpr double kShrunkSize = 0.5;

}  // namespace

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
      // A guess may be off either way: probed a step below and a step above it, three tenths of
      // the range each, where the range allows both. Rejected: two steps upward from the guess
      // (a fifth of the range each), with which a liner friction guessed at 0.5 for LIGGGHTS'
      // 0.15 showed 0 %: a rougher liner leaves a drum bed that slides as it was.
      const double now = std::clamp(get_parameter(model, full), lo, hi);
      const double wide = 0.3 * (hi - lo), narrow = 0.2 * (hi - lo);
      const bool two_sided = now - wide >= lo && now + wide <= hi;
      const double step = two_sided ? wide : narrow;
      const double start = two_sided ? now - step : now + step <= hi ? now + step : now - step;
      EffectCandidate c;
      c.name = full;
      c.kind = "parameter";
      c.title = fmt::format("the {} of the particles on {}", key, wall);
      c.why = fmt::format("tests on {} walls miss while the others fit: the particle-wall {} (a parameter, now {:.3g}, not calibrated)", wall, key, now);
      c.switch_on = fmt::format("calibrate it with the others (--params ...,{})", full);
      c.description = fmt::format("{}: a wall parameter, not physics the model lacks", c.title);
      c.parameters = {{full, {lo, hi}}};
      c.start = {{full, start}};
      c.stronger = {{full, two_sided ? now + step : std::clamp(now + 2.0 * (start - now), lo, hi)}};
      c.two_sided = two_sided;
      if (now == get_parameter(model, full)) c.unchanged = {{full, now}};
      c.add = [](MaterialModel&) {};
      out.push_back(std::move(c));
    }
  }
  return out;
}

// ---- the model as it is --------------------------------------------------------------------

/// Guessed wall parameters (wall_parameter_candidates) the data depend on are calibrated with the
/// others: each is simulated a step below and a step above its guess, one packing each, beside the
/// first comparison, and one that moves the first comparison's chi^2 by more than the BIC margin
/// (the evidence an effect needs to be named) on either side, up or down, becomes a fitted
/// parameter of every fit that follows: a guess the data depend on is not left a guess. Rejected:
/// only a wall whose probe lowers that chi^2. The probes stand at the other parameters' start
/// values, and those hide the wall: on LIGGGHTS beads with rolling resistance on a smooth liner
/// (particle-liner friction 0.15, guessed 0.5) the liner at 0.2 matches the drum's slipping and
/// the oblique drop's spin but leaves the sliding bed 8 deg too steep with the particles' guessed
/// friction, and chi^2 rises from 95 to 101. Rejected: the guess kept, and offered to the screen
/// only. On that set every effect recalibrated with the guess frozen left chi^2/n at 4.6-6.7
/// ("improves, not explained"), and the liner's friction, once the screen had found it (29 %),
/// recalibrated alone or beside each effect on the few design points a confirmation has, stayed
/// near the guess (0.55, chi^2/n 5.0), past 50 minutes for a budget of 30.
void DiagnosisRun::probe_guessed_walls(const Comparison& first) {
  if (!options_.wall_candidates || !(first.chi2 > 0)) return;
  // Those the drops settle first (CalibrationOptions::walls_first) are not guesses: left out.
  std::vector<std::string> settled;
  if (options_.walls_first) {
    CalibrationOptions quiet = options_;
    quiet.progress = nullptr;
    settled = detail::fit_walls_first(model_, measured_, parameters_, quiet).model.fitted_first;
  }
  std::vector<EffectCandidate> walls = wall_parameter_candidates(model_, parameters_);
  std::erase_if(walls, [&](const EffectCandidate& c) { return std::find(settled.begin(), settled.end(), c.name) != settled.end(); });
  if (walls.empty()) return;
  std::vector<MaterialModel> models;
  std::vector<std::string> names;
  std::vector<double> at;
  for (const EffectCandidate& c : walls)
    for (const std::map<std::string, double>* values : {&c.start, &c.stronger}) {
      MaterialModel m = model_;
      for (const auto& [key, v] : *values) set_parameter(m, key, v);
      models.push_back(std::move(m));
      at.push_back(values->begin()->second);
      names.push_back(fmt::format("{} at {:.3g} ", c.name, at.back()));
    }
  std::vector<const MaterialModel*> pointers;
  for (const MaterialModel& m : models) pointers.push_back(&m);
  detail::Progress progress{options_, "wall probes"};
  for (size_t k = 0; k < models.size(); ++k)
    for (const Experiment& e : measured_.experiments) progress.plan(e, 1);
  if (command_.outermost()) count_.plan_more(experiments_ * static_cast<int>(models.size()));
  const detail::RunsByModel runs = detail::simulate_with_each(pointers, names, measured_.experiments, options_, 1, &progress);
  if (std::any_of(runs.failed.begin(), runs.failed.end(), [](const std::string& f) { return !f.empty(); })) return;  // the fit meets it
  std::map<std::string, double> floor;
  for (const Term& t : first.terms) floor[t.name()] = t.sigma_simulated;
  for (size_t w = 0; w < walls.size(); ++w) {
    const EffectCandidate& c = walls[w];
    double chi2[2], moved = 0;
    for (size_t side = 0; side < 2; ++side) {
      chi2[side] = compare_runs(measured_, runs.runs[2 * w + side], options_, floor).chi2;
      moved = std::max(moved, std::abs(chi2[side] - first.chi2));
    }
    if (moved <= options_.bic_margin) continue;
    const auto& [key, range] = *c.parameters.begin();
    parameters_.push_back({key, range.first, range.second});
    guessed_walls_.push_back(fmt::format("{} ({}) is a guess, {:.3g}, that the data depend on: the first comparison's chi^2 of {:.1f} becomes "
                                         "{:.1f} at {:.3g} and {:.1f} at {:.3g}. It was calibrated with the others (measure it and state it in the "
                                         "measurement file to spare the fit a parameter).",
                                         key, c.title, get_parameter(model_, key), first.chi2, chi2[0], at[2 * w], chi2[1], at[2 * w + 1]));
    if (options_.progress) options_.progress("diagnose: " + guessed_walls_.back());
  }
  fitted_ = static_cast<int>(parameters_.size());
  walls_ = static_cast<int>(wall_parameter_candidates(model_, parameters_).size());
}

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
  probe_guessed_walls(first);
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
    const double pass = detail::seconds_per_pass(first, options_.parallel);
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


}  // namespace diagnosis

Diagnosis diagnose(const MaterialModel& model, const MeasurementSet& measured, std::vector<FitParameter> parameters, const CalibrationOptions& given) {
  diagnosis::DiagnosisRun run(model, measured, std::move(parameters), given);
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
