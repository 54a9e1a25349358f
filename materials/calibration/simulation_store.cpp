#include "calibration/simulation_store.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "contact/effect.h"
#include "model/base_properties.h"
#include "output/run.h"

namespace dem::materials {

namespace {

std::string number(double v) { return fmt::format("{:.17g}", v); }

/// A material as a line of the inputs that key a stored simulation: its name, its base properties
/// in table order, its contact parameters.
void describe(std::string& out, const std::string& key, const MaterialSpec& m) {
  out += fmt::format("{}: {{name: {}", key, m.name);
  for (const BaseProperty& b : base_properties())
    if (b.field) out += fmt::format(", {}: {}", b.spec.key, number(m.*b.field));
  for (const auto& [k, v] : m.params) out += fmt::format(", {}: {}", k, number(v));
  out += "}\n";
}

void describe(std::string& out, const std::string& key, const ContactSpec::Choice& c) {
  out += fmt::format("contact.{}: {}", key, c.model);
  for (const auto& [k, v] : c.options) out += fmt::format(" {}={}", k, v);
  out += "\n";
}

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const unsigned char c : text) h = (h ^ c) * 0x100000001b3ULL;
  return h;
}

std::string file_of(const std::string& folder, const std::string& test, const std::string& inputs) {
  return (std::filesystem::path(folder) / fmt::format("{}-{:016x}.yaml", test, fnv1a(inputs))).string();
}

/// `meaning` counts changes of what the same inputs simulate within one version, so a stored
/// simulation of an older meaning is run again; a change of one test moves that test's alone.
/// 2: a wall that does not state a contact parameter leaves it to the particles (before: mixed
/// with the parameter's default). 3: the silo's floor an exact disc (before: facets). 4: a
/// clump's mass counted once in the direct shear's bulk density and the silo's initial mass
/// (before: once per sphere). The drop test's 5: a clump's drop the mean of 12 orientations, and
/// every drop started just above the plate (its fall is ballistic).
int meaning_of(const std::string& test) { return test == "drop_rebound" ? 5 : 4; }

}  // namespace

std::string simulation_inputs(const MaterialModel& model, const TestSetup& setup, const TestOptions& options) {
  // The lab tests' time-step rule is written out, so a change of it runs them again.
  std::string out = fmt::format("engine: demdesign {}\nmeaning: {}\ntest: {}\n", DEMDESIGN_VERSION, meaning_of(setup.test), setup.test);
  for (const auto& [k, v] : setup.numbers) out += fmt::format("setup.{}: {}\n", k, number(v));
  for (const auto& [k, v] : setup.words) out += fmt::format("setup.{}: {}\n", k, v);
  out += fmt::format("time_step: {{rayleigh_fraction: {}, steps_per_contact: {}}}\n",
                     number(options.rayleigh_fraction > 0 ? options.rayleigh_fraction : kLabRayleighFraction), number(kLabStepsPerContact));
  out += fmt::format("seed: {}\nsize_factor: {}\nmass_scaling: {}\nstiffness_scaling: {}\n", options.seed, number(options.size_factor),
                     number(model.mass_scaling), number(model.stiffness_scaling));
  // Parcels are another simulation of the same material (core/coarse_grain.h): keyed by their
  // factor, written only when there are parcels, so the stored simulations of real particles
  // keep the keys they were stored under.
  if (model.coarse_grain != 1.0) out += fmt::format("coarse_grain: {}\n", number(model.coarse_grain));
  describe(out, "particle", model.particle);
  const ContactSpec& c = model.contact;
  // Single stages, then the lists: the order the stored simulations are keyed by.
  for (const Stage stage : kStagesSingleFirst)
    for (const ContactSpec::Choice* choice : c.choices(stage)) describe(out, std::string(stage_name(stage)), *choice);
  const SizeDistributionSpec& d = model.diameter;
  out += fmt::format("diameter: {{kind: {}, value: {}, mean: {}, std: {}, min: {}, max: {}, values: [{}], mass_fractions: [{}]}}\n",
                     static_cast<int>(d.kind), number(d.value), number(d.mean), number(d.std_dev), number(d.min), number(d.max),
                     fmt::join(d.values, ", "), fmt::join(d.mass_fractions, ", "));
  for (const ClumpTemplateSpec& s : model.shape) {
    out += "shape:";
    for (size_t k = 0; k < s.radii.size(); ++k)
      out += fmt::format(" [{}, {}, {}, {}]", number(s.centres[k].x()), number(s.centres[k].y()), number(s.centres[k].z()), number(s.radii[k]));
    out += "\n";
  }
  for (const MaterialSpec& w : model.walls) describe(out, "wall", w);
  for (const InteractionSpec& p : model.wall_pairs) {
    out += fmt::format("pair: {{{}, {}", p.material_a, p.material_b);
    for (const auto& [k, v] : p.params) out += fmt::format(", {}: {}", k, number(v));
    out += "}\n";
  }
  return out;
}

std::optional<SimulatedOutcome> load_simulation(const std::string& folder, const std::string& test, const std::string& inputs) {
  const std::string path = file_of(folder, test, inputs);
  if (!std::filesystem::is_regular_file(path)) return std::nullopt;
  try {
    const YAML::Node root = YAML::LoadFile(path);
    if (root["inputs"].as<std::string>() != inputs) return std::nullopt;  // another simulation with the same hash
    const YAML::Node o = root["outcome"];
    SimulatedOutcome out;
    for (const auto& kv : o["observables"]) out.observables[kv.first.as<std::string>()] = kv.second.as<double>();
    for (const auto& kv : o["uncertainty"]) out.uncertainty[kv.first.as<std::string>()] = kv.second.as<double>();
    for (const auto& f : o["flags"]) out.flags.push_back(f.as<std::string>());
    for (const auto& n : o["notes"]) out.notes.push_back(n.as<std::string>());
    out.particles = o["particles"].as<std::int64_t>();
    out.simulated_seconds = o["simulated_seconds"].as<double>();
    out.wall_seconds = o["wall_seconds"].as<double>();
    return out;
  } catch (const YAML::Exception&) {
    return std::nullopt;
  }
}

void store_simulation(const std::string& folder, const std::string& test, const std::string& inputs, const SimulatedOutcome& outcome) {
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << YAML::Comment("A finished virtual test of demdesign's calibration: its inputs and its outcome. A simulation with these "
                     "inputs is taken from here instead of being run again; delete the file to run it again.");
  e << YAML::BeginMap;
  e << YAML::Key << "inputs" << YAML::Value << YAML::Literal << inputs;
  e << YAML::Key << "outcome" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "observables" << YAML::Value << YAML::BeginMap;
  for (const auto& [k, v] : outcome.observables) e << YAML::Key << k << YAML::Value << v;
  e << YAML::EndMap << YAML::Key << "uncertainty" << YAML::Value << YAML::BeginMap;
  for (const auto& [k, v] : outcome.uncertainty) e << YAML::Key << k << YAML::Value << v;
  e << YAML::EndMap;
  e << YAML::Key << "flags" << YAML::Value << YAML::Flow << outcome.flags;
  e << YAML::Key << "notes" << YAML::Value << YAML::BeginSeq;
  for (const std::string& n : outcome.notes) e << n;
  e << YAML::EndSeq;
  e << YAML::Key << "particles" << YAML::Value << outcome.particles;
  e << YAML::Key << "simulated_seconds" << YAML::Value << outcome.simulated_seconds;
  e << YAML::Key << "wall_seconds" << YAML::Value << outcome.wall_seconds;
  e << YAML::EndMap << YAML::EndMap;
  write_file_atomically(file_of(folder, test, inputs), std::string(e.c_str()) + "\n");
}

}  // namespace dem::materials
