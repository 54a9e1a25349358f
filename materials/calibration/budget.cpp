// The plan of a calibration or diagnosis within a time budget: how many passes each phase takes,
// which reductions come first, and which confirmations a screen's tie keeps (calibration.h,
// calibration_support.h).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "calibration/calibration.h"
#include "calibration/calibration_support.h"

namespace dem::materials {

namespace detail {
int screen_passes(const CalibrationOptions& o, int effects, int walls) {
  if (effects + walls == 0) return 0;
  const int screened = effects + (o.wall_candidates ? walls : 0);
  return screened * (std::max(1, std::min(o.replicas, o.signature_replicas)) + 1);  // two strengths
}

double weighted_screen_and_confirmation_passes(const CalibrationOptions& o, int p, int effects, int walls, double screen, double confirmation) {
  if (effects + walls == 0) return 0.0;
  return screen * screen_passes(o, effects, walls) + confirmation * o.confirm_candidates * detail::confirmation_passes(o, p);
}

int screen_and_confirmation_passes(const CalibrationOptions& o, int p, int effects, int walls) {
  return static_cast<int>(weighted_screen_and_confirmation_passes(o, p, effects, walls, 1.0, 1.0));
}

int diagnosis_passes(const CalibrationOptions& o, int p, int effects, int walls) {
  // The calibration and its confirming comparison, then the screen and the confirmations.
  return detail::calibration_passes(o, p) + screen_and_confirmation_passes(o, p, effects, walls);
}

int screen_band(double leader, const CandidateResult& c, const CalibrationOptions& options) {
  return static_cast<int>(std::floor((leader - c.explained) / std::max(options.screen_margin, 1e-6)));
}

ConfirmationChoice choose_confirmations(const std::vector<CandidateResult>& ranked, const CalibrationOptions& options) {
  ConfirmationChoice out;
  out.screen_silent = std::none_of(ranked.begin(), ranked.end(), [](const CandidateResult& c) { return c.explained >= 0.05; });
  const double leader = ranked.empty() ? 0.0 : ranked.front().explained;
  const auto chosen = [&](const CandidateResult& cr, int rank) {
    const bool tied = rank > 0 && cr.explained >= 0.05 && leader - cr.explained <= options.screen_margin;
    if (tied) out.undecided.push_back(cr.name);
    if (rank < options.confirm_candidates && (cr.explained >= 0.05 || out.screen_silent)) return true;
    if (tied) return true;
    if (cr.explained >= 0.05 && cr.agreement < 0.5) return out.nonlinear.push_back(cr.name), true;
    return false;
  };
  for (size_t rank = 0; rank < ranked.size(); ++rank)
    if (chosen(ranked[rank], static_cast<int>(rank))) out.confirming.push_back(rank);
  // More chosen than may be confirmed: the leader stays, and the rest go by the screen's band
  // below the leader's share and, within a band the screen cannot rank, stable signatures before
  // unstable ones. An unstable candidate's share is the chi^2 of its own few runs after a linear
  // recalibration, which noise can bring near 0 on a file of few terms; a stable one's rests on
  // two strengths that agree. Rejected: the cut in rank order, with which three wall parameters
  // whose signatures were noise (agreement -0.15 to 0.05, "100 %") took the places of the liquid
  // bridges (96 %, agreement 0.99) that made the data.
  const auto cap = static_cast<size_t>(std::max(1, options.confirm_candidates + 2));
  if (out.confirming.size() > cap) {
    const auto band = [&](size_t rank) { return screen_band(leader, ranked[rank], options); };
    const auto after_leader = out.confirming.begin() + (out.confirming.front() == 0 ? 1 : 0);
    std::stable_sort(after_leader, out.confirming.end(), [&](size_t a, size_t b) {
      if (band(a) != band(b)) return band(a) < band(b);
      return ranked[a].stable && !ranked[b].stable;
    });
    out.confirming.resize(cap);
    std::sort(out.confirming.begin(), out.confirming.end());
    const auto left_out = [&](const std::string& name) {
      return std::none_of(out.confirming.begin(), out.confirming.end(), [&](size_t rank) { return ranked[rank].name == name; });
    };
    std::erase_if(out.undecided, left_out);
    std::erase_if(out.nonlinear, left_out);
  }
  return out;
}

double candidate_seconds_per_simulation(const CandidateResult& cr, int parallel) {
  return cr.simulations > 0 && cr.cost > 0 ? cr.cost / cr.simulations / std::max(1, parallel) : 0.0;
}

ConfirmationPlan fit_confirmations(const std::vector<double>& costs, const std::vector<bool>& tied, double left, const std::vector<double>& smaller) {
  const auto fit = [&](const std::vector<double>& cost) {
    ConfirmationPlan plan;
    double rest = left;
    for (size_t k = 0; k < cost.size(); ++k) {
      const bool fits = plan.kept.empty() || cost[k] <= rest;
      if (!fits && !tied[k]) {
        plan.dropped.push_back(k);
        continue;
      }
      if (!fits) plan.beyond.push_back(k);
      plan.kept.push_back(k), rest -= cost[k];
    }
    plan.left = rest;
    return plan;
  };
  ConfirmationPlan plan = fit(costs);
  if (plan.beyond.empty() || std::none_of(smaller.begin(), smaller.end(), [](double c) { return std::isfinite(c); })) return plan;
  std::vector<double> cheaper = costs;
  for (size_t k = 0; k < std::min(costs.size(), smaller.size()); ++k)
    if (std::isfinite(smaller[k])) cheaper[k] = smaller[k];
  plan = fit(cheaper);
  plan.reduced = true;
  return plan;
}

}  // namespace detail

namespace {

/// The ladder of reductions applied in turn until `passes` passes of `pass` seconds fit `left`.
BudgetPlan fit_to_budget(const CalibrationOptions& options, double pass, double left, double budget, int candidates,
                         const std::function<double(const CalibrationOptions&)>& passes) {
  BudgetPlan plan{options, {}, 0};
  const auto seconds = [&](const CalibrationOptions& o) { return passes(o) * pass; };
  struct Step {
    const char* words;
    void (*apply)(CalibrationOptions&);
    bool diagnosis_only;
  };
  // What goes first costs the least insight. The wall parameters' screen goes late: a wall pair
  // the starting material only guessed (a steel restitution) misfits like missing physics, and
  // without the screen a diagnosis would offer an effect to absorb it.
  const Step ladder[] = {
      {"one surrogate round instead of two (no zoom on the optimum)", [](CalibrationOptions& o) { o.rounds = 1; }, false},
      {"design factor 1 instead of 2 (fewer design points)", [](CalibrationOptions& o) { o.design_factor = std::min(o.design_factor, 1.0); }, false},
      {"signatures with one packing", [](CalibrationOptions& o) { o.signature_replicas = 1; }, true},
      {"design factor 0.5", [](CalibrationOptions& o) { o.design_factor = std::min(o.design_factor, 0.5); }, false},
      {"two packings per comparison instead of three", [](CalibrationOptions& o) { o.replicas = std::min(o.replicas, 2); }, false},
      {"wall parameters not screened", [](CalibrationOptions& o) { o.wall_candidates = false; }, true},
      {"one candidate confirmed instead of two", [](CalibrationOptions& o) { o.confirm_candidates = std::min(o.confirm_candidates, 1); }, true},
  };
  plan.seconds = seconds(plan.options);
  for (const Step& step : ladder) {
    if (plan.seconds <= left) break;
    if (step.diagnosis_only && candidates == 0) continue;
    CalibrationOptions reduced = plan.options;
    step.apply(reduced);
    const double s = seconds(reduced);
    if (s < plan.seconds) plan.options = reduced, plan.seconds = s, plan.given_up.emplace_back(step.words);
  }
  if (plan.seconds > left)
    plan.given_up.push_back(fmt::format("still about {} at the least: the budget of {} cannot be met with these experiments (use --size-factor, or "
                                        "fewer experiments)",
                                        detail::duration_text(plan.seconds), detail::duration_text(budget)));
  return plan;
}

}  // namespace

BudgetPlan plan_within_budget(const CalibrationOptions& options, const Comparison& first, int p, int effects, int walls, double spent) {
  // One pass: a simulation of every experiment, at the measured mean cost of each; passes run
  // `parallel` simulations at once.
  const double pass = detail::seconds_per_pass(first, options.parallel);
  // A candidate's simulations counted at what they cost against the plain model's, as the plan
  // made again after the plain fit counts them (plan_screen_within_budget). Rejected: every pass
  // at the first comparison's cost, which planned 15 min where a lab file of 6 mm beads then took
  // 28 (2026-12-07, 8472b1d).
  return fit_to_budget(options, pass, options.budget_seconds - spent, options.budget_seconds, effects + walls, [&](const CalibrationOptions& o) {
    return detail::calibration_passes(o, p) +
           detail::weighted_screen_and_confirmation_passes(o, p, effects, walls, detail::kScreenCost, detail::kConfirmationCost);
  });
}

BudgetPlan plan_screen_within_budget(const CalibrationOptions& options, double pass, int p, int effects, int walls, double left, double budget) {
  // Passes of the plain model's cost: a candidate's simulations cost more (kScreenCost,
  // kConfirmationCost).
  return fit_to_budget(options, pass, left, budget, effects + walls, [&](const CalibrationOptions& o) {
    return detail::weighted_screen_and_confirmation_passes(o, p, effects, walls, detail::kScreenCost, detail::kConfirmationCost);
  });
}

}  // namespace dem::materials
