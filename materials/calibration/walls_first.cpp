// The first stage of a calibration: each particle-wall pair's restitution from the drop tests on
// that wall. A drop is a single contact of one particle with the plate, so its rebound height
// measures the pair's restitution and nothing of the bulk; fitting it alone, before the bulk
// tests, keeps a guessed wall value from misfitting the drops while the bulk parameters bend to
// absorb it, and from looking like missing physics to a diagnosis (the staged procedure of the
// source paper: single-contact parameters from their own tests, bulk parameters from bulk tests).
//
// Only the normal rebound is used. The tangential restitution of an oblique drop depends on the
// pair's friction and rolling resistance together (a sliding and a rolling particle rebound
// alike), so it stays in the bulk comparison, where it is a signature of rolling resistance.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "calibration/calibration_support.h"
#include "model/material_model.h"

namespace dem::materials::detail {

WallsFirst fit_walls_first(const MaterialModel& model, const MeasurementSet& measured, const std::vector<FitParameter>& parameters,
                           const CalibrationOptions& options) {
  WallsFirst out{model, {}};
  if (!options.walls_first) return out;
  const auto listed = [](const std::vector<std::string>& list, const std::string& key) { return std::find(list.begin(), list.end(), key) != list.end(); };
  std::vector<std::string> fitted_keys;
  for (const FitParameter& p : parameters) fitted_keys.push_back(p.key);
  const ParamSpec* spec = find_param("restitution");
  if (!spec) return out;
  for (const InteractionSpec& pair : model.wall_pairs) {
    const std::string wall = pair.material_a == model.name ? pair.material_b : pair.material_a;
    const std::string key = wall + ".restitution";
    if (listed(fitted_keys, key) || listed(fitted_keys, "wall.restitution") || listed(model.known, key)) continue;
    // The drops on this wall, with their rebound height only.
    MeasurementSet drops;
    drops.file = measured.file;
    for (const Experiment& e : measured.experiments) {
      const auto plate = e.setup.words.find("plate");
      const auto rebound = e.observed.find("restitution");
      if (e.setup.test != "drop_rebound" || plate == e.setup.words.end() || plate->second != wall || rebound == e.observed.end()) continue;
      Experiment only = e;
      only.observed = {{"restitution", rebound->second}};
      only.outcome.clear();
      drops.experiments.push_back(std::move(only));
    }
    if (drops.experiments.empty()) continue;
    CalibrationOptions sub = within_command(options);  // inside the calibration's command, left out of its count below
    sub.walls_first = false;
    sub.budget_seconds = 0;  // a few hundred drops of a tenth of a second: outside any budget
    sub.rounds = 2, sub.design_factor = 2.0, sub.design_points = 0;
    sub.replicas = std::max(2, options.replicas);
    sub.progress = nullptr, sub.on_partial = nullptr, sub.on_final = nullptr;
    const FitParameter box{key, std::max(spec->min_value, 0.05), std::min(spec->max_value, 1.0)};
    const double before = get_parameter(out.model, key);
    CalibrationResult fit;
    {
      const Uncounted aside(*sub.context);
      fit = calibrate(out.model, drops, {box}, sub);
    }
    if (!fit.unidentified.empty()) {
      out.words.push_back(fmt::format("{} kept at {:.3g}: the {} drop test{} on {} do not pin it down.", key, before, drops.experiments.size(),
                                      drops.experiments.size() == 1 ? "" : "s", wall));
      continue;
    }
    if (!listed(out.model.fitted_first, key)) out.model.fitted_first.push_back(key);
    // Drops that agree with the value given (within two sigma of the fit) leave it: the data
    // do not ask for another, and the bulk tests then run with the material as it was written.
    if (std::abs(fit.value[0] - before) <= 2.0 * fit.sigma[0]) {
      out.model.particle.sources[key] = fmt::format("confirmed by the rebound heights of the drop tests on {} (fitted {:.4g} +- {:.2g})", wall,
                                                    fit.value[0], fit.sigma[0]);
      out.words.push_back(fmt::format("{} = {:.3g} kept: the rebound heights of the {} drop test{} on {} agree with it (fitted alone: {:.3g} +- {:.2g}).", key,
                                      before, drops.experiments.size(), drops.experiments.size() == 1 ? "" : "s", wall, fit.value[0], fit.sigma[0]));
      continue;
    }
    set_parameter(out.model, key, fit.value[0]);
    out.model.particle.sources[key] = fmt::format("fitted first to the rebound heights of the drop tests on {}: {:.4g} +- {:.2g}", wall, fit.value[0], fit.sigma[0]);
    out.words.push_back(fmt::format("{} fitted first to the rebound heights of the {} drop test{} on {} (a single contact measures it): {:.3g} +- {:.2g} "
                                    "(start {:.3g}; those drops' chi^2/n {:.2f}); the bulk fit keeps it.",
                                    key, drops.experiments.size(), drops.experiments.size() == 1 ? "" : "s", wall, fit.value[0], fit.sigma[0], before,
                                    fit.after.chi2_per_n()));
  }
  if (options.progress)
    for (const std::string& w : out.words) options.progress(w);
  return out;
}

}  // namespace dem::materials::detail
