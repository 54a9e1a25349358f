// The chute's narrowest section against the stream's fill, and the stream profiles (choke.h).
#include "report/choke.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "output/run.h"
#include "report/report_analysis.h"
#include "statistics/stream_profile.h"

namespace dem::report {

const char* const kChokeRule =
    "fill = m / (rho A L): the time-mean mass m in the box across the chute's narrowest section over the mass that section (free "
    "area A, box length L along the flow) would hold at the material's poured bulk density rho; choke margin = 1 - fill. Verdict "
    "by a common chute design rule, stated as assumed (no published source is checked here): a chute should run at most one "
    "third full at its narrowest section; fill below 1/3 ample, below 2/3 adequate, below 1 tight (choke risk), 1 or "
    "more choked.";

namespace {

namespace fs = std::filesystem;

/// The design value named exactly `name`, or NaN.
double design_named(const std::vector<std::pair<std::string, double>>& design, const std::string& name) {
  for (const auto& [n, value] : design)
    if (n == name) return value;
  return kNaN;
}

/// `text` as a quoted CSV field (double quotes inside become single quotes).
std::string quoted(std::string text) {
  std::replace(text.begin(), text.end(), '"', '\'');
  return "\"" + text + "\"";
}

/// The profiles of the run's binned sensors from its final state, in the real material's mass
/// (divided by the mass scaling), with their depths at `bulk_density` [kg/m^3]. An empty bin's
/// velocity is NaN (a gap in the plot, not a stream at rest).
std::vector<StreamProfile> profiles_of(const Model& model, const State& state, double bulk_density) {
  std::vector<StreamProfile> out;
  for (const StreamProfileRow& row : stream_profile_rows(model, state.stream_profiles)) {
    if (out.empty() || out.back().sensor != row.sensor) {
      out.emplace_back();
      out.back().sensor = row.sensor, out.back().width = row.width, out.back().length = row.length, out.back().window = row.window;
    }
    StreamProfile& p = out.back();
    const double mass = row.mass / model.mass_scaling;  // [kg]
    p.lateral.push_back(row.lateral);
    p.mass.push_back(mass);
    p.depth.push_back(stream_depth(mass, bulk_density, row.width, row.length));
    p.velocity.push_back(row.mass > 0 ? row.velocity : kNaN);
  }
  return out;
}

/// The choke sensor's mass over the run's interval against its section's design values.
ChokeResult choke_of(const RunReportInput& in, const RunAnalysis& run, const MaterialFacts& material) {
  ChokeResult c;
  c.material = material;
  const auto box = std::find_if(run.boxes.begin(), run.boxes.end(), [](const BoxResult& b) { return b.name == kChokeSensor; });
  if (box == run.boxes.end()) return c;
  c.sensor = box->name;
  c.area = design_named(in.design, "choke_section_area_m2");
  c.length = design_named(in.design, "choke_section_length_m");
  c.height = design_named(in.design, "choke_section_at_height_m");
  // The run's kilograms are the model's: a mass-scaled particle weighs mass_scaling times the real one.
  const double scaling = in.model->mass_scaling;
  c.mass = box->mass.at_run.mean / scaling, c.mass_error = box->mass.at_run.std_error / scaling;
  if (!(c.area > 0 && c.length > 0))
    c.missing = "no design values choke_section_area_m2 and choke_section_length_m (the section's free area and the box's length "
                "along the flow; the transfer_chute generator gives them)";
  else if (!(material.bulk_density > 0))
    c.missing = "no bulk density: the case feeds no material (no inlet and no particle set)";
  else
    c.fill = choke_fill(c.mass, c.mass_error, material.bulk_density, c.area, c.length);
  return c;
}

}  // namespace

ChokeVerdict choke_verdict(double fill) {
  if (std::isnan(fill)) return ChokeVerdict::unknown;
  if (fill < kAmpleFill) return ChokeVerdict::ample;
  if (fill < kAdequateFill) return ChokeVerdict::adequate;
  if (fill < 1) return ChokeVerdict::tight;
  return ChokeVerdict::choked;
}

const char* choke_verdict_text(ChokeVerdict verdict) {
  switch (verdict) {
    case ChokeVerdict::ample: return "ample";
    case ChokeVerdict::adequate: return "adequate";
    case ChokeVerdict::tight: return "tight: choke risk";
    case ChokeVerdict::choked: return "choked";
    case ChokeVerdict::unknown: break;
  }
  return "unknown";
}

ChokeFill choke_fill(double mass, double mass_error, double bulk_density, double area, double length) {
  ChokeFill f;
  // NaN fails every comparison, so NaN inputs give NaN too.
  if (!(bulk_density > 0 && area > 0 && length > 0)) return f;
  const double full = bulk_density * area * length;  // [kg] the section filled at the poured bulk density
  f.fill = mass / full;
  f.fill_error = mass_error / full;
  f.margin = 1 - f.fill;
  f.verdict = choke_verdict(f.fill);
  return f;
}

double stream_depth(double mass, double bulk_density, double width, double length) {
  if (!(bulk_density > 0 && width > 0 && length > 0)) return kNaN;
  return mass / (bulk_density * width * length);
}

void find_choke_and_profiles(const RunReportInput& in, RunAnalysis& run) {
  const bool choke = std::any_of(run.boxes.begin(), run.boxes.end(), [](const BoxResult& b) { return b.name == kChokeSensor; });
  if (!choke && profile_bin_total(*in.model) == 0) return;
  const MaterialFacts material = material_facts(in);
  run.profiles = profiles_of(*in.model, *in.state, material.bulk_density);
  run.choke = choke_of(in, run, material);
}

void add_choke_metrics(RunAnalysis& run) {
  if (run.choke.sensor.empty() || std::isnan(run.choke.fill.fill)) return;
  run.metrics.values.emplace_back("choke_fill", run.choke.fill.fill);
  run.metrics.values.emplace_back("choke_margin", run.choke.fill.margin);
}

void write_choke_csv(const RunAnalysis& run, const std::string& report_dir) {
  const ChokeResult& c = run.choke;
  if (c.sensor.empty() || std::isnan(c.fill.fill)) return;
  std::string csv =
      "sensor,section_area_m2,section_length_m,section_height_m,mass_kg,mass_std_error_kg,bulk_density_kg_m3,bulk_density_source,"
      "bulk_density_assumed,fill,fill_std_error,margin,verdict,t_start_s,t_end_s,rule\n";
  csv += fmt::format("{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{},{},{:.6g},{:.6g},{:.6g},{},{:.6g},{:.6g},{}\n", quoted(c.sensor), c.area,
                     c.length, c.height, c.mass, c.mass_error, c.material.bulk_density, quoted(c.material.bulk_source),
                     c.material.bulk_assumed ? 1 : 0, c.fill.fill, c.fill.fill_error, c.fill.margin, quoted(choke_verdict_text(c.fill.verdict)),
                     run.run_t0, run.run_t1, quoted(kChokeRule));
  write_file_atomically((fs::path(report_dir) / "choke.csv").string(), csv);
}

}  // namespace dem::report
