#include "calibration/calibrated_material.h"

#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>
#include <utility>

#include "contact/effect.h"
#include "model/base_properties.h"
#include "output/run.h"

namespace dem::materials {

namespace {

std::string number(double v) { return fmt::format("{:.9g}", v); }

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) out += c == '"' || c == '\\' ? std::string("\\") + c : std::string(1, c);
  return out + "\"";
}

std::string choice(const ContactSpec::Choice& c) {
  if (c.options.empty()) return c.model;
  std::string out = "{model: " + c.model;
  for (const auto& [k, v] : c.options) out += fmt::format(", {}: {}", k, v);
  return out + "}";
}

/// `STAGE: MODEL` or `STAGE: [MODEL, ...]`; empty when the stage is off.
std::string stage_text(const ContactSpec& c, Stage stage) {
  const std::string_view key = stage_name(stage);
  if (const std::vector<ContactSpec::Choice>* list = c.additive(stage)) {
    if (list->empty()) return "";
    std::vector<std::string> items;
    for (const auto& ch : *list) items.push_back(choice(ch));
    return fmt::format("{}: [{}]", key, fmt::join(items, ", "));
  }
  const ContactSpec::Choice& ch = *c.single(stage);
  if (ch.model == "none" || ch.model.empty()) return "";
  return fmt::format("{}: {}", key, choice(ch));
}

std::string contact_text(const ContactSpec& c) {
  // Single stages, then the lists.
  std::vector<std::string> parts;
  for (const Stage stage : kStagesSingleFirst)
    if (std::string part = stage_text(c, stage); !part.empty()) parts.push_back(std::move(part));
  return "{" + fmt::format("{}", fmt::join(parts, ", ")) + "}";
}

std::string size_text(const SizeDistributionSpec& d) {
  using Kind = SizeDistributionSpec::Kind;
  switch (d.kind) {
    case Kind::fixed: return number(d.value);
    case Kind::normal:
      return fmt::format("{{distribution: normal, mean: {}, std: {}, min: {}, max: {}}}", number(d.mean), number(d.std_dev), number(d.min), number(d.max));
    case Kind::uniform: return fmt::format("{{distribution: uniform, min: {}, max: {}}}", number(d.min), number(d.max));
    case Kind::discrete: {
      std::vector<std::string> v, f;
      for (double x : d.values) v.push_back(number(x));
      for (double x : d.mass_fractions) f.push_back(number(x));
      return fmt::format("{{distribution: discrete, values: [{}], mass_fractions: [{}]}}", fmt::join(v, ", "), fmt::join(f, ", "));
    }
  }
  return number(d.value);
}

}  // namespace

std::string calibrated_material_text(const CalibrationResult& fit, const CalibratedMaterialSource& source) {
  const MaterialModel& m = fit.fitted;
  const size_t n = fit.parameters.size();
  const double chi2 = fit.after.chi2_per_n();
  std::string out = fmt::format("# Calibrated by demdesign {} on {} ({}): chi^2/n = {:.3g}{}.\n", source.command, source.measurements, source.date,
                                chi2, source.note.empty() ? "" : "; " + source.note);
  out += fmt::format("# A case names it as {{library: NAME}} (this file as NAME.yaml in the case's folder, its materials/ or\n"
                     "# ../materials/, or $DEMDESIGN_MATERIALS); `calibration:` is the fit it came from.\n");
  out += fmt::format("name: {}\n", quoted(m.name));
  const std::string description = m.particle.description.empty() ? m.name : m.particle.description;
  out += fmt::format("description: {}\n", quoted(fmt::format("{} (calibrated by {} on {}, {})", description, source.command,
                                                             std::filesystem::path(source.measurements).filename().string(), source.date)));
  out += fmt::format("contact: {}\n", contact_text(m.contact));
  out += "properties:\n";
  // The material's base properties (the shape's is its own block below), each with its unit unless dimensionless.
  for (const BaseProperty& b : base_properties()) {
    if (!b.field) continue;
    const std::string line = fmt::format("{}: {}", b.spec.key, number(m.particle.*b.field));
    if (b.spec.unit == "-") out += fmt::format("  {}\n", line);
    else out += fmt::format("  {:<30}# [{}]\n", line, b.spec.unit);
  }
  for (const auto& [key, value] : m.particle.params) out += fmt::format("  {}: {}\n", key, number(value));
  // Provenance: the fitted values from this fit, the others as the starting material said.
  std::map<std::string, std::string> sources = m.particle.sources;
  for (size_t k = 0; k < n; ++k)
    sources[fit.parameters[k].key] = fmt::format("calibrated by {} on {} ({}): {} +- {}", source.command, source.measurements, source.date,
                                                  fmt::format("{:.4g}", fit.value[k]), fmt::format("{:.2g}", fit.sigma[k]));
  if (!sources.empty()) {
    out += "sources:\n";
    for (const auto& [key, words] : sources) out += fmt::format("  {}: {}\n", key, quoted(words));
  }
  out += fmt::format("size: {}\n", size_text(m.diameter));
  if (!m.shape.empty()) {
    // The template as the fit simulated it; `size` is each clump's volume-equivalent diameter.
    out += "shape:  # sphere clumps in the clump's own frame (any unit: the size scales them)\n  spheres:\n";
    const ClumpTemplateSpec& c = m.shape.front();
    for (size_t k = 0; k < c.radii.size(); ++k)
      out += fmt::format("    - {{centre: [{}, {}, {}], diameter: {}}}\n", number(c.centres[k].x()), number(c.centres[k].y()),
                         number(c.centres[k].z()), number(2 * c.radii[k]));
  }
  std::vector<std::string> walls;
  for (const InteractionSpec& pair : m.wall_pairs) {
    const std::string wall = pair.material_a == m.name ? pair.material_b : pair.material_a;
    std::vector<std::string> params;
    for (const auto& [key, value] : pair.params) params.push_back(fmt::format("{}: {}", key, number(value)));
    walls.push_back(fmt::format("  {}: {{{}}}\n", wall, fmt::join(params, ", ")));
  }
  if (!walls.empty()) out += "walls:\n" + fmt::format("{}", fmt::join(walls, ""));
  if (!m.tunable.empty()) {
    out += "tunable:\n";
    for (const auto& [key, range] : m.tunable) out += fmt::format("  {}: [{}, {}]\n", key, number(range.first), number(range.second));
  }
  std::vector<std::string> keys, values, sigmas, rows;
  for (size_t k = 0; k < n; ++k) keys.push_back(fit.parameters[k].key), values.push_back(number(fit.value[k])), sigmas.push_back(number(fit.sigma[k]));
  for (size_t i = 0; i < n; ++i) {
    std::vector<std::string> row;
    for (size_t j = 0; j < n; ++j)
      row.push_back(i == j ? "1" : number(i < fit.correlation.size() && j < fit.correlation[i].size() ? fit.correlation[i][j] : 0.0));
    rows.push_back(fmt::format("    - [{}]\n", fmt::join(row, ", ")));
  }
  out += "calibration:\n";
  out += fmt::format("  command: {}\n  measurements: {}\n  date: {}\n  engine: {}\n", source.command, quoted(source.measurements), quoted(source.date),
                     quoted(std::string("demdesign ") + DEMDESIGN_VERSION));
  out += fmt::format("  effects: [{}]\n", fmt::join(model_effects(m), ", "));
  out += fmt::format("  parameters: [{}]\n  value: [{}]\n  sigma: [{}]\n", fmt::join(keys, ", "), fmt::join(values, ", "), fmt::join(sigmas, ", "));
  out += "  correlation:\n" + fmt::format("{}", fmt::join(rows, ""));
  out += fmt::format("  chi2_per_n: {}\n", number(chi2));
  out += fmt::format("  stiffness_scaling: {}\n", number(m.stiffness_scaling));
  // The parcel size of the virtual tests: a case at another coarse_grain is told (core/coarse_grain.h).
  out += fmt::format("  coarse_grain: {}\n", number(m.coarse_grain));
  return out;
}

void write_calibrated_material(const std::string& path, const CalibrationResult& fit, const CalibratedMaterialSource& source) {
  const std::string text = calibrated_material_text(fit, source);
  if (std::filesystem::path(path).has_parent_path()) std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  write_file_atomically(path, text);
}

}  // namespace dem::materials
