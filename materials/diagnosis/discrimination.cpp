#include "diagnosis/discrimination.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "calibration/calibration_support.h"

namespace dem::materials {

namespace {

/// A lab's repeatability of an observable of value v (one sigma), where the file gives none.
double typical_sigma(const std::string& observable, double v) {
  if (observable.find("angle") != std::string::npos) return 1.0;                      // [deg]
  if (observable.find("restitution") != std::string::npos) return 0.02;
  if (observable == "bulk_density") return 0.01 * std::abs(v);                        // 1 %
  if (observable == "mass_flow_rate") return 0.02 * std::abs(v);                      // 2 %
  if (observable.find("shear_stress") != std::string::npos) return 0.03 * std::abs(v);  // 3 %
  return 0.02 * std::abs(v);
}

/// The quantity an experiment of `test` is usually varied by, and the factors tried beyond it.
struct Variation {
  const char* test;
  const char* key;
  double low, high;  ///< factors on the file's value
};
constexpr Variation kVariations[] = {
    {"drop_rebound", "drop_height", 0.1, 5.0},       {"angle_of_repose_cylinder", "lift_speed", 0.2, 4.0},
    {"rotating_drum", "rpm", 0.3, 3.0},              {"hopper_discharge", "orifice_diameter", 0.7, 1.5},
    {"direct_shear", "normal_stress", 0.25, 4.0},    {"bulk_density", "pour_height", 0.0, 5.0},
};

double diameter_of(const MaterialModel& m) {
  const SizeDistributionSpec& d = m.diameter;
  switch (d.kind) {
    case SizeDistributionSpec::Kind::fixed: return d.value;
    case SizeDistributionSpec::Kind::normal: return d.mean;
    case SizeDistributionSpec::Kind::uniform: return 0.5 * (d.min + d.max);
    case SizeDistributionSpec::Kind::discrete: return d.largest();
  }
  return d.value;
}

}  // namespace

std::vector<Experiment> separating_candidates(const MaterialModel& model, const MeasurementSet& measured, const std::map<std::string, double>& apart) {
  std::vector<Experiment> out;
  std::vector<double> promise;  // of each variant: how far apart the models lie on the experiment it varies
  const std::string wall = model.walls.empty() ? std::string() : model.walls.front().name;
  std::map<std::string, bool> present;
  for (const Experiment& e : measured.experiments) {
    present[e.setup.test] = true;
    for (const Variation& v : kVariations) {
      if (e.setup.test != v.test) continue;
      const auto it = e.setup.numbers.find(v.key);
      const double now = it == e.setup.numbers.end() ? 0.0 : it->second;
      for (const double factor : {v.low, v.high}) {
        const double value = now > 0 ? now * factor : (factor > 1 ? 0.05 : 0.0);
        if (!(value > 0) || value == now) continue;
        Experiment x = e;
        x.setup.numbers[v.key] = value;
        x.id = fmt::format("{} at {} {:.4g}", e.id, v.key, value);
        x.outcome.clear();
        out.push_back(std::move(x));
        promise.push_back(apart.count(e.id) ? apart.at(e.id) : 0.0);
      }
    }
  }
  // Standard set-ups of the tests the file lacks, sized from the particle diameter d.
  const double d = diameter_of(model);
  const auto standard = [&](const std::string& test, std::map<std::string, double> numbers, std::map<std::string, std::string> words,
                            std::vector<std::string> observables) {
    if (present[test]) return;
    Experiment x;
    x.id = fmt::format("{} (a standard set-up)", test);
    x.setup.test = test, x.setup.numbers = std::move(numbers), x.setup.words = std::move(words);
    x.setup.location.file = "(proposed experiment)";
    for (const std::string& o : observables) x.observed[o] = Observation{0.0, 0.0, {}};
    out.push_back(std::move(x));
    promise.push_back(std::numeric_limits<double>::infinity());
  };
  if (!wall.empty()) {
    standard("drop_rebound", {{"drop_height", 0.1}}, {{"plate", wall}}, {"restitution"});
    standard("bulk_density", {{"cup_diameter", 16 * d}, {"cup_height", 12 * d}}, {{"base", wall}}, {"bulk_density"});
    standard("angle_of_repose_cylinder", {{"cylinder_diameter", 16 * d}, {"cylinder_height", 20 * d}, {"fill_height", 14 * d}, {"lift_speed", 0.05}},
             {{"base", wall}}, {"angle_deg"});
    standard("rotating_drum", {{"drum_diameter", 30 * d}, {"drum_depth", 6 * d}, {"fill_fraction", 0.35}, {"rpm", 20}}, {{"ends", "periodic"}, {"wall", wall}},
             {"dynamic_angle_deg"});
    standard("hopper_discharge", {{"silo_diameter", 16 * d}, {"orifice_diameter", 6 * d}, {"fill_height", 14 * d}}, {{"wall", wall}}, {"mass_flow_rate"});
    standard("direct_shear", {{"cell_length", 8 * d}, {"cell_width", 8 * d}, {"preshear_stress", 4000}, {"normal_stress", 2000}, {"shear_velocity", 0.005}}, {},
             {"peak_shear_stress", "steady_shear_stress"});
  }
  // Standard set-ups first (no experiment of their test is in the file), then the variants of the
  // experiments the models already disagree on most; otherwise in the file's order.
  std::vector<size_t> order(out.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) { return promise[x] > promise[y]; });
  std::vector<Experiment> ordered;
  for (const size_t k : order) ordered.push_back(std::move(out[k]));
  return ordered;
}

std::map<std::string, double> apart_by_experiment(const Comparison& a, const Comparison& b) {
  std::map<std::string, double> out;
  for (const Term& x : a.terms) {
    if (x.is_outcome()) continue;
    for (const Term& y : b.terms) {
      if (y.name() != x.name()) continue;
      const double sigma = std::sqrt(x.sigma_simulated * x.sigma_simulated + y.sigma_simulated * y.sigma_simulated + x.sigma_measured * x.sigma_measured);
      const double apart = sigma > 0 ? std::abs(x.simulated - y.simulated) / sigma : 0.0;
      out[x.experiment] = std::max(out[x.experiment], apart);
    }
  }
  return out;
}

SeparationSearch separating_experiments(const MaterialModel& a, const std::string& name_a, const MaterialModel& b, const std::string& name_b,
                                        const MeasurementSet& measured, const CalibrationOptions& options, const SeparationPlan& plan) {
  SeparationSearch search;
  std::vector<Experiment> candidates = separating_candidates(a, measured, plan.apart);
  search.candidates = static_cast<int>(candidates.size());
  if (plan.most >= 0 && static_cast<int>(candidates.size()) > plan.most) {
    for (size_t k = static_cast<size_t>(plan.most); k < candidates.size(); ++k) search.untried.push_back(candidates[k].id);
    candidates.resize(static_cast<size_t>(plan.most));
  }
  const int replicas = std::max(1, std::min(options.replicas, options.signature_replicas));
  detail::Progress progress{options, fmt::format("experiments that could separate {} from {}", name_a, name_b)};
  for (const Experiment& e : candidates) progress.plan(e, 2 * replicas);
  detail::CommandProgress& command = progress.context().count;
  if (command.active()) command.plan_remaining(command.left() + 2 * replicas * static_cast<int>(candidates.size()));
  // Both models on every candidate, one batch; a candidate either cannot run (a set-up out of
  // range for these particles) is skipped.
  const detail::RunsByModel both = detail::simulate_with_each({&a, &b}, {name_a, name_b}, candidates, options, replicas, &progress);
  std::vector<Separator>& out = search.found;
  for (size_t c = 0; c < candidates.size(); ++c) {
    const Experiment& e = candidates[c];
    if (!both.failed[c].empty()) {
      if (options.progress) options.progress(fmt::format("  {} skipped: {}", e.id, both.failed[c]));
      continue;
    }
    const ExperimentRun* runs[2] = {&both.runs[0][c], &both.runs[1][c]};
    for (const auto& [observable, given] : e.observed) {
      if (!runs[0]->mean.count(observable) || !runs[1]->mean.count(observable)) continue;
      Separator s;
      s.id = e.id, s.setup = e.setup, s.observable = observable;
      s.predicted_a = runs[0]->mean.at(observable), s.predicted_b = runs[1]->mean.at(observable);
      const double lab = given.sigma > 0 ? given.sigma : typical_sigma(observable, 0.5 * (s.predicted_a + s.predicted_b));
      const double sa = runs[0]->sigma.at(observable), sb = runs[1]->sigma.at(observable);
      s.sigma = std::sqrt(lab * lab + sa * sa + sb * sb);
      s.separation = s.sigma > 0 ? std::abs(s.predicted_a - s.predicted_b) / s.sigma : 0.0;
      std::string setup;
      for (const auto& [k, v] : e.setup.numbers) setup += fmt::format("{}{} {:.4g}", setup.empty() ? "" : ", ", k, v);
      s.words = fmt::format("{} ({}): {} predicts {} = {:.4g}, {} predicts {:.4g}, {:.1f} sigma apart (lab repeatability {:.3g})", e.id, setup, name_a,
                            observable, s.predicted_a, name_b, s.predicted_b, s.separation, lab);
      out.push_back(std::move(s));
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const Separator& x, const Separator& y) { return x.separation > y.separation; });
  return search;
}

}  // namespace dem::materials
