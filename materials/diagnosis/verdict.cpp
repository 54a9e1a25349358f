// The verdict in three grades (missing, improves, cannot tell), what the best model still misses,
// the experiment that separates a tie, and each candidate described in words.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "diagnosis/diagnosis_run.h"
#include "diagnosis/discrimination.h"

namespace dem::materials::diagnosis {

namespace {

/// Candidate experiments simulated to separate a rival, however little of the budget is left.
constexpr int kFewestSeparators = 4;

}  // namespace

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

/// The unconfirmed candidate with the largest expected gain, stable ones first, among those whose
/// signature explains a share of the residual (a stable signature that explains nothing is no
/// lead: cdt at 0 % was once advised before sjkr at 19 %).
std::string DiagnosisRun::next_to_confirm(const CandidateResult& best) const {
  const CandidateResult* next = nullptr;
  for (const CandidateResult& c : d_.candidates) {
    if (c.confirmed || &c == &best || c.kind == "parameter" || c.explained < 0.05) continue;
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
  // A runner-up confirmed without its refinement round (CandidateResult::unrefined) is a rival at
  // the better of its simulations and its surrogate's prediction: it is never ruled out on a fit
  // the budget cut short.
  const auto rival_bic = [&](const CandidateResult& c) {
    return c.unrefined ? bic(std::min(c.chi2, c.fit.surrogate_chi2), c.k, c.fit.after.n) : c.bic;
  };
  std::vector<const CandidateResult*> rivals;
  for (const CandidateResult& c : d_.candidates)
    if (&c != best && c.confirmed && d_.base_bic - rival_bic(c) > options_.bic_margin && rival_bic(c) - best->bic < options_.bic_margin)
      rivals.push_back(&c);
  // An effect not recalibrated is not ruled out when it would fit with as many parameters as the
  // data have terms (any effect then may, with the fitted parameters), or when the screen put it
  // within the BIC margin of the best (the screen's estimates compared with each other: a
  // recalibration lowers chi^2 far below the linear screen's estimate).
  const int n = best->fit.after.n;
  const auto exact = [&](const CandidateResult& c) { return n <= c.k; };
  const double best_screened = bic(best->screen_chi2, best->k, n);
  std::vector<const CandidateResult*> unconfirmed;
  for (const CandidateResult& c : d_.candidates)
    if (!c.confirmed && c.kind != "parameter" && c.explained >= 0.05 &&
        (exact(c) || bic(c.screen_chi2, c.k, n) - best_screened < options_.bic_margin))
      unconfirmed.push_back(&c);
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
    const bool told_apart = rivals.empty() && unconfirmed.empty();
    d_.grade = told_apart ? Verdict::missing : Verdict::cannot_tell;
    d_.recommended = best->name;
    say(fmt::format("{}: {} ({}; switch it on with `{}`). Why: {}. It could explain {:.0f} % of the weighted residual of the calibrated model; "
                    "added and recalibrated it fits within the noise (chi^2/n {:.2f} <= {:.2f}): {}, with {} more parameter{}).",
                    told_apart ? "Missing" : "Most likely missing, but not told apart", best->name, best->title, best->switch_on, best->why,
                    100 * best->explained, best->fit.after.chi2_per_n(), line, gain, best->adds.size(), best->adds.size() == 1 ? "" : "s"));
    if (!unconfirmed.empty()) {
      std::vector<std::string> names{best->name}, each;
      for (const CandidateResult* c : unconfirmed) {
        d_.unconfirmed_rivals.push_back(c->name), names.push_back(c->name);
        each.push_back(fmt::format("{} ({:.0f} %{}; {})", c->name, 100 * c->explained, c->stable ? "" : ", unstable",
                                   exact(*c) ? fmt::format("{} fitted parameters for {} measured terms: it may fit them as well", c->k, n)
                                             : fmt::format("the screen put it within the BIC margin of {}", best->name)));
      }
      say(fmt::format("Not ruled out, not recalibrated: {}. Confirm {} with `demdesign diagnose MATERIAL MEASUREMENTS --effects {}` (the simulations "
                      "done are kept in the store).",
                      join(each, "; "), unconfirmed.size() == 1 ? "it" : "them", join(names, ",")));
    }
  }
  if (!misfits.empty()) say("Where the model without it fails: " + join(misfits, " "));
  for (const CandidateResult* rival : rivals) {
    d_.rivals.push_back(rival->name);
    // Two models that both misfit are not a tie to separate: an experiment that tells them apart
    // would decide between two wrong answers.
    if (d_.grade == Verdict::improves) {
      say(fmt::format("{} improves it about as much (BIC {:.1f}, {:.1f} above {}'s, within the margin {:.0f}); neither explains the data, so no "
                      "experiment is sought to tell them apart.",
                      rival->name, rival->bic, rival->bic - best->bic, best->name, options_.bic_margin));
      continue;
    }
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
    const bool two_sided = effect_of(cr).two_sided;
    const std::string screen = fmt::format("explains {:.0f} % of the residual ({:.0f} % {}, {:.0f} % {}; agreement {:.2f}; {})", 100 * cr.explained,
                                           100 * cr.explained_start, two_sided ? "a step below its value" : "at its start", 100 * cr.explained_stronger,
                                           two_sided ? "a step above" : "at twice the step", cr.agreement, cr.ranked_why);
    const std::string unrefined =
        cr.unrefined ? fmt::format(" A refinement round its surrogate asked for did not fit the budget: the surrogate predicts chi^2/n {:.2f}, and as a rival "
                                   "it counts at the better of the two.",
                                   cr.fit.surrogate_chi2 / std::max(1, cr.fit.after.n))
                     : "";
    cr.words = cr.confirmed ? fmt::format("{}: {}; recalibrated chi^2/n = {:.2f}, BIC {:.1f} ({:+.1f} against the model as it is).{}", cr.name, screen,
                                          cr.fit.after.chi2_per_n(), cr.bic, -cr.delta_bic, unrefined)
                            : fmt::format("{}: {} (signature only, not confirmed).", cr.name, screen);
  }
}

}  // namespace dem::materials::diagnosis
