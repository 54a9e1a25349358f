// Liner life: depth rates by sliding and by impact, months to wear through, depth per million
// tonnes; the liners of a case's meshes; wear_life.csv and the liner metrics.
#include "report/report_wear.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "output/run.h"
#include "report/report_analysis.h"

namespace dem::report {

namespace {

namespace fs = std::filesystem;

constexpr double kMonthsPerYear = 12.0;
constexpr double kMillimetresPerMetre = 1e3;
constexpr double kTonnesPerMegatonne = 1e6;

/// The entry `name` (a mesh name or "default") of `wear.liners` or of `wear_coefficients` as a
/// liner; none when neither has it (the case reader lets a name be in one of them only).
std::optional<Liner> case_liner(const CaseSpec& spec, const std::string& name) {
  if (const auto it = spec.wear.liners.find(name); it != spec.wear.liners.end()) {
    Liner liner;
    liner.material = it->second.material, liner.origin = "wear.liners." + name;
    liner.thickness = it->second.thickness;
    liner.sliding_coefficient = it->second.sliding_coefficient, liner.impact_coefficient = it->second.impact_coefficient;
    return liner;
  }
  if (const auto it = spec.wear_coefficients.find(name); it != spec.wear_coefficients.end()) {
    Liner liner;
    liner.origin = "wear_coefficients." + name, liner.sliding_coefficient = it->second;
    return liner;
  }
  return std::nullopt;
}

/// One row of wear_life.csv: a zone of mesh `name`'s liner.
std::string zone_row(const RunAnalysis& run, const std::string& name, const MeshWear& w, const WearZone& z, bool worst) {
  const double hours = run.operating_hours;
  const std::string where = worst ? fmt::format("worst_spot,{},{:.6g},{:.6g},{:.6g}", z.triangle, z.centroid.x(), z.centroid.y(), z.centroid.z())
                                  : std::string("mesh_mean,,,,");
  return fmt::format("\"{}\",{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n", name, where, w.liner.material,
                     kMillimetresPerMetre * w.liner.thickness, mm_per_year(z.sliding, hours), mm_per_year(z.impact, hours),
                     mm_per_year(total_rate(z.sliding, z.impact), hours), z.life_months, z.mm_per_megatonne, hours, run.wear_throughput);
}

}  // namespace

double depth_rate(double coefficient, double energy, double area, double interval) {
  if (std::isnan(coefficient) || !(area > 0) || !(interval > 0)) return kNaN;
  // Volume [m^3] = coefficient x energy, spread over the area and the interval: [m/s].
  return coefficient * energy / (area * interval);
}

double total_rate(double sliding, double impact) {
  if (std::isnan(sliding)) return impact;
  if (std::isnan(impact)) return sliding;
  return sliding + impact;
}

double mm_per_year(double rate, double hours_per_year) { return rate * kSecondsPerHour * hours_per_year * kMillimetresPerMetre; }

double life_months(double thickness, double rate, double hours_per_year) {
  if (!(thickness > 0) || std::isnan(rate)) return kNaN;
  if (rate <= 0) return std::numeric_limits<double>::infinity();
  // Years of operation to wear the thickness through, in calendar months.
  return kMonthsPerYear * thickness / (rate * kSecondsPerHour * hours_per_year);
}

double mm_per_megatonne(double rate, double throughput_t_h) {
  if (!(throughput_t_h > 0)) return kNaN;
  // Metres per tonne conveyed: the rate [m/s] over the tonnes a second.
  return rate / (throughput_t_h / kSecondsPerHour) * kMillimetresPerMetre * kTonnesPerMegatonne;
}

WearZone wear_zone(const Liner& liner, double friction_work, double impact_energy, double area, double interval,
                   double hours_per_year, double throughput_t_h) {
  WearZone z;
  // Sliding (Archard) and impact (Bitter's deformation wear), each linear in its energy.
  z.sliding = depth_rate(liner.sliding_coefficient, friction_work, area, interval);
  z.impact = depth_rate(liner.impact_coefficient, impact_energy, area, interval);
  const double rate = total_rate(z.sliding, z.impact);
  z.life_months = life_months(liner.thickness, rate, hours_per_year);
  z.mm_per_megatonne = mm_per_megatonne(rate, throughput_t_h);
  return z;
}

bool has_surface_velocity(const MeshWall& mesh) {
  const SurfaceVelocitySpec& s = mesh.surface_velocity;
  return (s.kind == SurfaceVelocitySpec::Kind::linear && s.velocity.norm() > 0) ||
         (s.kind == SurfaceVelocitySpec::Kind::rotation && s.angular_speed != 0);
}

std::map<std::string, Liner> liners_for(const CaseSpec& spec, const Model& model) {
  std::map<std::string, Liner> out;
  for (const MeshWall& mesh : model.meshes) {
    std::optional<Liner> liner = case_liner(spec, mesh.name);
    if (!liner && !has_surface_velocity(mesh)) liner = case_liner(spec, "default");
    if (liner) out[mesh.name] = *liner;
  }
  return out;
}

std::optional<Liner> liner_of(const RunReportInput& input, const std::string& name) {
  if (const auto it = input.liners.find(name); it != input.liners.end()) return it->second;
  if (const auto it = input.wear_coefficient.find(name); it != input.wear_coefficient.end()) {
    Liner liner;
    liner.origin = "wear coefficient", liner.sliding_coefficient = it->second;
    return liner;
  }
  return std::nullopt;
}

std::vector<std::vector<double>> triangle_life_months(const RunReportInput& input) {
  std::vector<std::vector<double>> out;
  if (!input.model || !input.state) return out;
  const Model& model = *input.model;
  const State& state = *input.state;
  const double interval = state.time - input.records_from;  // [s] the records' interval
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    const TriangleSurface& surface = *model.meshes[m].surface;
    out.emplace_back(surface.size(), kNaN);
    const std::optional<Liner> liner = liner_of(input, model.meshes[m].name);
    if (!liner || m >= state.records.size() || !(interval > 0)) continue;
    // Each triangle as a zone of its own: its friction work and impact energy on its area.
    const TriangleRecords& rec = state.records[m];
    for (std::size_t t = 0; t < surface.size(); ++t)
      if (surface.areas[t] > 0)
        out[m][t] = wear_zone(*liner, at(rec.shear_work, t), at(rec.impact_energy, t), surface.areas[t], interval, input.operating_hours_per_year, kNaN)
                        .life_months;
  }
  return out;
}

void add_liner_metrics(RunAnalysis& run, const Model& model) {
  const auto metric = [&run](const std::string& name, double value) {
    if (std::isfinite(value)) run.metrics.values.emplace_back(key(name), value);
  };
  const double hours = run.operating_hours;
  double shortest = std::numeric_limits<double>::infinity();  // [months]
  for (std::size_t m = 0; m < model.meshes.size() && m < run.mesh_wear.size(); ++m) {
    const MeshWear& w = run.mesh_wear[m];
    if (!w.has_liner) continue;
    const std::string& name = model.meshes[m].name;
    metric("wear_sliding_" + name + "_mm_yr", mm_per_year(w.worst.sliding, hours));
    metric("wear_impact_" + name + "_mm_yr", mm_per_year(w.worst.impact, hours));
    metric("liner_life_" + name + "_months", w.worst.life_months);
    metric("liner_life_mean_" + name + "_months", w.mean.life_months);
    metric("wear_" + name + "_mm_per_Mt", w.worst.mm_per_megatonne);
    if (!std::isnan(w.worst.life_months)) shortest = std::min(shortest, w.worst.life_months);
  }
  metric("liner_life_min_months", shortest);
}

void write_wear_life_csv(const RunAnalysis& run, const Model& model, const std::string& report_dir) {
  if (model.meshes.empty()) return;
  std::string csv = "mesh,zone,triangle,x_m,y_m,z_m,liner_material,thickness_mm,sliding_mm_yr,impact_mm_yr,total_mm_yr,life_months,"
                    "mm_per_Mt,operating_hours_per_year,throughput_t_h\n";
  for (std::size_t m = 0; m < model.meshes.size() && m < run.mesh_wear.size(); ++m) {
    const MeshWear& w = run.mesh_wear[m];
    if (!w.has_liner || run.record_time <= 0) continue;
    csv += zone_row(run, model.meshes[m].name, w, w.worst, true);
    csv += zone_row(run, model.meshes[m].name, w, w.mean, false);
  }
  write_file_atomically((fs::path(report_dir) / "wear_life.csv").string(), csv);
}

}  // namespace dem::report
