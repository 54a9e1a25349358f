// Reading measurement files (docs/materials-and-calibration.md). Every key goes through
// MapReader, so a misspelt key names the nearest valid one; tests and observables are checked
// against the virtual tests' own tables (test_names, observable_names).
#include "lab/measurements.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "case/yaml_check.h"
#include "contact/effect.h"
#include "model/base_properties.h"
#include "model/material_model.h"

namespace dem::materials {

namespace {

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

std::string did_you_mean(const std::string& word, const std::vector<std::string>& valid) {
  const std::string hint = nearest_word(word, valid);
  return hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint);
}

/// Outcomes an experiment of `test` may report instead of (or beside) a value.
std::vector<std::string> outcome_names(const std::string& test) {
  if (test == "hopper_discharge") return {"blocked"};
  if (test == "angle_of_repose_cylinder") return {"no_heap"};
  if (test == "rotating_drum") return {"slipping"};
  return {};
}

}  // namespace

std::string outcome_read_as_number(const std::string& test, const std::string& observable, double value) {
  if (test == "angle_of_repose_cylinder" && observable == "angle_deg" && std::abs(value) < 1.0) return "no_heap";
  if (test == "hopper_discharge" && observable == "mass_flow_rate" && value <= 0.0) return "blocked";
  if (test == "rotating_drum" && observable == "dynamic_angle_deg" && std::abs(value) < 1.0) return "slipping";
  return "";
}

namespace {

/// Contact parameters measured directly in `map` (restitution, friction, ...: any effect
/// parameter), as known values with `prefix` before the key; the valid keys are `fixed` and
/// every effect parameter.
void read_known_params(MapReader& map, const std::vector<std::string>& fixed, const std::string& prefix, std::vector<KnownValue>& known) {
  std::vector<std::string> valid = fixed;
  for (const EffectSpec* e : effect_table())
    for (const ParamSpec& p : e->params) valid.emplace_back(p.key);
  for (const std::string& key : map.keys()) {
    if (std::find(fixed.begin(), fixed.end(), key) != fixed.end()) continue;
    const ParamSpec* p = find_param(key);
    if (!p) continue;  // reported by finish() with the nearest valid key
    known.push_back({prefix + key, map.number(key, p->default_value, p->min_value, p->max_value, p->unit), std::string(p->unit), map.where(key)});
  }
  map.finish(valid);
}

/// Base property `key` of `map`, in its range and unit (model/base_properties.h); `fallback`
/// when absent.
double read_property(MapReader& map, std::string_view key, double fallback) {
  const ParamSpec& p = base_property(key).spec;
  return map.number(std::string(key), fallback, p.min_value, p.max_value, p.unit);
}

double read_required_property(MapReader& map, std::string_view key) {
  const ParamSpec& p = base_property(key).spec;
  return map.required_number(std::string(key), p.min_value, p.max_value, p.unit);
}

/// Wall materials measured directly: {youngs_modulus, poisson_ratio, density} and the
/// particle-wall pair's contact parameters (friction, restitution, ...), known as NAME.KEY.
/// The properties one by one rather than over the table (model/base_properties.h): in this order,
/// the key reference's, Young's modulus required and the others steel's when absent. Their key
/// list stays beside them, so that a property the table gains and this reader does not read is
/// refused as an unknown key rather than ignored.
MaterialSpec read_wall(const std::string& name, const YAML::Node& node, const std::string& file, std::vector<KnownValue>& known) {
  MapReader map(node, file, "walls." + name);
  MaterialSpec m;
  m.name = name;
  m.location = map.location();
  m.youngs_modulus = read_required_property(map, "youngs_modulus");
  m.poisson_ratio = read_property(map, "poisson_ratio", 0.3);
  m.density = read_property(map, "density", 7800);
  read_known_params(map, {"youngs_modulus", "poisson_ratio", "density"}, name + ".", known);
  return m;
}

/// The experiment's id and test, also given to its set-up; returns the test, one of test_names().
std::string read_id_and_test(MapReader& map, Experiment& e) {
  e.location = map.location();
  e.id = map.required_string("id", "a name for the experiment, unique in the file");
  const std::vector<std::string> tests = test_names();
  const std::string test = map.required_string("test", "one of " + join(tests));
  if (std::find(tests.begin(), tests.end(), test) == tests.end())
    map.fail("test", fmt::format("'{}' is not a test{}; valid: {}", test, did_you_mean(test, tests), join(tests)));
  e.setup.test = test;
  e.setup.id = e.id;
  e.setup.location = e.location;
  return test;
}

/// What the phases of read_experiment share, once its test is known: its map (experiments[INDEX]),
/// its file, its test and the experiment as read so far.
struct ExperimentReader {
  MapReader& map;
  const std::string& file;
  const std::string& test;
  Experiment& e;

  /// Set-up: numbers and words; which keys a test needs is checked by the test itself
  /// (check_experiments, before anything is simulated).
  void read_setup(const std::vector<MaterialSpec>& walls) {
    const YAML::Node setup = map.node("setup");
    if (!setup) map.fail("setup", fmt::format("missing: the set-up of the {} test, {{key: value, ...}}", test));
    MapReader s(setup, file, map.key_path("setup"));
    s.keys_are_names("SETUP_KEY");
    for (const std::string& key : s.keys()) {
      const YAML::Node v = s.node(key);
      if (!v.IsScalar()) s.fail(key, "must be a number (SI units) or a word (a wall material, `periodic`, ...)");
      double number = 0;
      if (YAML::convert<double>::decode(v, number)) {
        if (!std::isfinite(number)) s.fail(key, "must be a finite number");
        e.setup.numbers[key] = number;
      } else {
        e.setup.words[key] = v.Scalar();
      }
    }
    // Words that name wall materials must be ones the file declares.
    std::vector<std::string> wall_names;
    for (const auto& w : walls) wall_names.push_back(w.name);
    for (const char* key : {"base", "wall", "plate"}) {
      const auto it = e.setup.words.find(key);
      if (it == e.setup.words.end() || wall_names.empty()) continue;
      if (std::find(wall_names.begin(), wall_names.end(), it->second) == wall_names.end())
        s.fail(key, fmt::format("'{}' is not a wall material of this file{}; valid: {} (declared under `walls:`)", it->second,
                                did_you_mean(it->second, wall_names), join(wall_names)));
    }
    s.finish();
  }

  /// Observations: each {value, sigma > 0}, of an observable this test has.
  void read_observed(const std::vector<std::string>& observables) {
    if (const YAML::Node observed = map.node("observed")) {
      MapReader o(observed, file, map.key_path("observed"));
      o.keys_are_names("OBSERVABLE");
      for (const std::string& key : o.keys()) {
        if (key == "outcome")
          o.fail(key, outcome_names(test).empty()
                          ? fmt::format("{} has no outcomes; its observables: {}", test, join(observables))
                          : fmt::format("an outcome is not an observation: write `outcome: {}` beside `observed:` (at the experiment's level, "
                                        "as `id` and `setup`), not under it; outcomes of {}: {}",
                                        outcome_names(test).front(), test, join(outcome_names(test))));
        if (std::find(observables.begin(), observables.end(), key) == observables.end())
          o.fail(key, fmt::format("'{}' is not an observable of {}{}; valid: {}", key, test, did_you_mean(key, observables), join(observables)));
        MapReader v(o.node(key), file, o.key_path(key));
        Observation obs;
        obs.location = v.location();
        obs.value = v.required_number("value", -1e12, 1e12);
        if (!v.has("sigma")) v.fail("sigma", "missing: the one-standard-deviation repeatability of the value, > 0");
        obs.sigma = v.required_number("sigma", 0, 1e12);
        if (!(obs.sigma > 0)) v.fail("sigma", fmt::format("is {:g}; valid: > 0 (one standard deviation of the measurement)", obs.sigma));
        v.finish();
        e.observed[key] = obs;
      }
      o.finish();
    }
  }

  /// `outcome`, when given; returns whether it is `none`, which says that a value which looks like
  /// an outcome (take_outcomes_written_as_numbers) is meant as a number.
  bool read_outcome() {
    bool as_number = false;
    if (map.has("outcome")) {
      std::vector<std::string> outcomes = outcome_names(test);
      if (outcomes.empty()) map.fail("outcome", fmt::format("{} has no outcomes; remove the key", test));
      outcomes.push_back("none");
      e.outcome = map.string("outcome", "", outcomes);
      as_number = e.outcome == "none";
      if (as_number) e.outcome.clear();
    }
    return as_number;
  }

  /// An outcome written as a number, as a lab writes it: no heap as an angle of 0, an arch as no
  /// flow, a bed that slides without an avalanche as a drum angle of 0. It is compared as the
  /// outcome it means, with a warning, unless the file says `outcome: none` (`as_number`).
  void take_outcomes_written_as_numbers(bool as_number) {
    for (auto it = e.observed.begin(); it != e.observed.end() && e.outcome.empty() && !as_number;) {
      const auto& [key, obs] = *it;
      const std::string read = outcome_read_as_number(test, key, obs.value);
      if (read.empty()) {
        ++it;
        continue;
      }
      const bool no_heap = read == "no_heap", no_flow = read == "blocked";
      e.outcome = read, e.outcome_read_from = key;
      e.warnings.push_back(fmt::format("{}: observed.{} = {:g}: most likely {}; compared as `outcome: {}`, not as a number with sigma {:g}. "
                                       "Write `outcome: {}` beside `observed:` (at the experiment's level) and leave out the value to say "
                                       "so, or `outcome: none` to compare the number",
                                       obs.location.str(), key, obs.value,
                                       no_heap ? "no heap formed" : no_flow ? "the orifice arched" : "the bed slid without avalanching",
                                       e.outcome, obs.sigma, e.outcome));
      it = e.observed.erase(it);
    }
  }

  /// An experiment observes a value or an outcome.
  void refuse_nothing_observed(const std::vector<std::string>& observables) const {
    if (e.observed.empty() && e.outcome.empty())
      map.fail("observed", fmt::format("missing: what was observed, e.g. {{{}: {{value: V, sigma: S}}}}{}", observables.front(),
                                       outcome_names(test).empty() ? "" : fmt::format(", or outcome: {}", join(outcome_names(test)))));
  }
};

Experiment read_experiment(const YAML::Node& node, const std::string& file, size_t index, const std::vector<MaterialSpec>& walls) {
  MapReader map(node, file, fmt::format("experiments[{}]", index));
  Experiment e;
  const std::string test = read_id_and_test(map, e);
  ExperimentReader reader{map, file, test, e};
  reader.read_setup(walls);
  const std::vector<std::string> observables = observable_names(test);
  reader.read_observed(observables);
  const bool as_number = reader.read_outcome();
  reader.take_outcomes_written_as_numbers(as_number);
  reader.refuse_nothing_observed(observables);
  map.finish();
  return e;
}

}  // namespace

MeasurementSet parse_measurements(const std::string& text, const std::string& name) {
  const YAML::Node root = parse_yaml(text, name);
  try {
    MeasurementSet set;
    set.file = name;
    MapReader top(root, name, "");
    set.material = top.string("material", "");
    if (const YAML::Node particles = top.node("particles")) {
      MapReader p(particles, name, "particles");
      if (p.has("diameter")) set.diameter = read_size_distribution(p, name), set.has_diameter = true;
      // The density is the set's own (MeasurementSet::density, apply_measured); every other
      // property of a material's `properties:` stated here is a known value, as a contact parameter is.
      set.density = read_property(p, "density", 0);
      std::vector<std::string> read_keys = {"diameter"};
      for (const std::string& key : material_property_keys()) {
        read_keys.push_back(key);
        if (key == "density" || !p.has(key)) continue;
        const std::string_view unit = base_property(key).spec.unit;
        set.known.push_back({key, read_property(p, key, 0), std::string(unit), p.where(key)});
      }
      read_known_params(p, read_keys, "", set.known);
    }
    if (const YAML::Node walls = top.node("walls")) {
      if (!walls.IsMap()) top.fail("walls", "must map wall material names to {youngs_modulus, poisson_ratio, density, friction, ...}");
      for (const auto& kv : walls) set.walls.push_back(read_wall(kv.first.as<std::string>(), kv.second, name, set.known));
    }
    const YAML::Node experiments = top.node("experiments");
    if (!experiments || !experiments.IsSequence() || experiments.size() == 0)
      top.fail("experiments", "missing: a list of {id, test, setup, observed}");
    std::set<std::string> ids;
    for (size_t k = 0; k < experiments.size(); ++k) {
      Experiment e = read_experiment(experiments[k], name, k, set.walls);
      if (!ids.insert(e.id).second)
        throw CaseError(fmt::format("{}: experiments[{}].id: '{}' is used twice; ids must be unique", e.location.str(), k, e.id));
      set.warnings.insert(set.warnings.end(), e.warnings.begin(), e.warnings.end());
      set.experiments.push_back(std::move(e));
    }
    top.finish();
    return set;
  } catch (const YAML::Exception& e) {
    throw CaseError(fmt::format("{}:{}:{}: {}", name, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
}

void check_experiments(const MaterialModel& model, const MeasurementSet& set, const TestOptions& options) {
  TestOptions check = options;
  check.validate_only = true, check.progress = false, check.on_final = nullptr;
  for (const Experiment& e : set.experiments) run_virtual_test(model, e.setup, check);
}

void apply_measured(MaterialModel& model, const MeasurementSet& measured) {
  if (measured.has_diameter) model.diameter = measured.diameter;
  if (measured.density > 0) {
    model.particle.density = measured.density;
    model.particle.sources["density"] = "measured (" + measured.file + ")";
  }
  for (const MaterialSpec& w : measured.walls) {
    auto it = std::find_if(model.walls.begin(), model.walls.end(), [&](const MaterialSpec& m) { return m.name == w.name; });
    if (it != model.walls.end()) *it = w;
    else model.walls.push_back(w);
  }
  // Measured values are inputs: set, marked as measured, and never fitted.
  for (const KnownValue& k : measured.known) {
    const auto dot = k.key.find('.');
    if (dot != std::string::npos) {
      const std::string wall = k.key.substr(0, dot);
      const bool paired = std::any_of(model.wall_pairs.begin(), model.wall_pairs.end(),
                                      [&](const InteractionSpec& in) { return in.material_a == wall || in.material_b == wall; });
      if (!paired) {
        InteractionSpec pair;
        pair.material_a = model.name, pair.material_b = wall;
        model.wall_pairs.push_back(pair);
      }
    }
    try {
      set_parameter(model, k.key, k.value);
    } catch (const std::invalid_argument& e) {
      throw CaseError(fmt::format("{}: {}", k.location.str(), e.what()));
    }
    model.particle.sources[k.key] = fmt::format("measured ({})", k.location.str());
    model.tunable.erase(k.key);
    model.known.push_back(k.key);
  }
}

MeasurementSet read_measurements(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw CaseError(fmt::format("{}: cannot open the measurement file", path));
  std::stringstream text;
  text << in.rdbuf();
  return parse_measurements(text.str(), path);
}

}  // namespace dem::materials
