// The error ledger: each calibration's chi^2 per experiment, appended to OUT/ledger.yaml so that
// a user watches the error fall as effects are switched on (calibration.h).
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "calibration/calibration.h"
#include "calibration/calibration_support.h"
#include "contact/effect.h"

namespace dem::materials {

std::vector<std::string> model_effects(const MaterialModel& model) {
  std::vector<std::string> out;
  // Single stages ("none" switches one off), then the lists.
  for (const Stage stage : kStagesSingleFirst)
    for (const ContactSpec::Choice* c : model.contact.choices(stage))
      if (stage_is_additive(stage) || c->model != "none") out.push_back(c->model);
  if (!model.shape.empty()) out.push_back(fmt::format("clump (aspect {:.2f})", get_parameter(model, "clump_aspect_ratio")));
  return out;
}

LedgerEntry ledger_entry(const MaterialModel& model, const Comparison& comparison, const std::string& label, const std::vector<std::string>& parameter_keys) {
  LedgerEntry e;
  e.label = label;
  const std::time_t t = std::time(nullptr);
  std::tm local{};
  localtime_r(&t, &local);
  char buffer[64];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%d %H:%M:%S", &local);
  e.time = buffer;
  e.effects = model_effects(model);
  e.coarse_grain = model.coarse_grain;
  for (const std::string& key : parameter_keys) e.parameters[key] = get_parameter(model, key);
  for (const Term& term : comparison.terms) e.residuals[term.name()] = term.residual;
  e.chi2 = comparison.chi2;
  e.n = comparison.n;
  return e;
}

std::vector<LedgerEntry> read_ledger(const std::string& path) {
  std::vector<LedgerEntry> out;
  if (!std::filesystem::exists(path)) return out;
  try {
    const YAML::Node root = YAML::LoadFile(path);
    for (const YAML::Node& v : root["versions"]) {
      LedgerEntry e;
      e.version = v["version"].as<int>();
      e.label = v["label"].as<std::string>("");
      e.time = v["time"].as<std::string>("");
      if (v["effects"])
        for (const auto& x : v["effects"]) e.effects.push_back(x.as<std::string>());
      if (v["parameters"])
        for (const auto& kv : v["parameters"]) e.parameters[kv.first.as<std::string>()] = kv.second.as<double>();
      if (v["residuals"])
        for (const auto& kv : v["residuals"]) e.residuals[kv.first.as<std::string>()] = kv.second.as<double>();
      e.chi2 = v["chi2"].as<double>(0);
      e.n = v["n"].as<int>(0);
      e.verdict = v["verdict"].as<std::string>("");
      e.coarse_grain = v["coarse_grain"].as<double>(1.0);
      out.push_back(std::move(e));
    }
  } catch (const YAML::Exception& error) {
    throw CaseError(fmt::format("{}:{}:{}: the error ledger cannot be read: {}", path, error.mark.line + 1, error.mark.column + 1, error.msg));
  }
  return out;
}

std::vector<LedgerEntry> append_ledger(const std::string& path, const std::string& material, std::vector<LedgerEntry> entries) {
  std::vector<LedgerEntry> all = read_ledger(path);
  int next = all.empty() ? 1 : all.back().version + 1;
  for (LedgerEntry& e : entries) e.version = next++, all.push_back(std::move(e));
  YAML::Emitter out;
  out << YAML::Comment("Error ledger: every model version of this material with its normalised residual on every observation "
                       "(simulated - measured, in sigma) and chi^2/n. Appended by demdesign calibrate and diagnose.");
  out << YAML::BeginMap << YAML::Key << "material" << YAML::Value << material << YAML::Key << "versions" << YAML::Value << YAML::BeginSeq;
  for (const LedgerEntry& e : all) {
    out << YAML::BeginMap;
    out << YAML::Key << "version" << YAML::Value << e.version;
    out << YAML::Key << "label" << YAML::Value << e.label;
    out << YAML::Key << "time" << YAML::Value << e.time;
    out << YAML::Key << "effects" << YAML::Value << YAML::Flow << e.effects;
    out << YAML::Key << "coarse_grain" << YAML::Value << e.coarse_grain;
    out << YAML::Key << "parameters" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (const auto& [k, v] : e.parameters) out << YAML::Key << k << YAML::Value << v;
    out << YAML::EndMap;
    out << YAML::Key << "chi2" << YAML::Value << e.chi2 << YAML::Key << "n" << YAML::Value << e.n;
    out << YAML::Key << "chi2_per_n" << YAML::Value << e.chi2_per_n();
    if (!e.verdict.empty()) out << YAML::Key << "verdict" << YAML::Value << e.verdict;
    out << YAML::Key << "residuals" << YAML::Value << YAML::BeginMap;
    for (const auto& [k, v] : e.residuals) out << YAML::Key << k << YAML::Value << v;
    out << YAML::EndMap << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
  std::ofstream file(path);
  if (!file) throw std::runtime_error(fmt::format("{}: cannot write the error ledger", path));
  file << out.c_str() << "\n";
  return all;
}

}  // namespace dem::materials
