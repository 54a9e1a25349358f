// Yield loci: the weighted Mohr-Coulomb fit, the grouping of direct shear values into loci and
// the words comparing a simulated locus with the measured one (rules in yield_locus.h).
#include "lab/yield_locus.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

namespace dem::materials {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDegrees = 180.0 / std::numbers::pi;

/// Normal stresses that differ by more than rounding, counted.
int distinct_normal_stresses(const std::vector<LocusPoint>& points) {
  std::vector<double> sigma;
  for (const LocusPoint& p : points) sigma.push_back(p.normal_stress);
  std::sort(sigma.begin(), sigma.end());
  int count = sigma.empty() ? 0 : 1;
  for (size_t k = 1; k < sigma.size(); ++k)
    if (sigma[k] - sigma[k - 1] > 1e-9 * std::max({std::abs(sigma[k]), std::abs(sigma[k - 1]), 1.0})) ++count;
  return count;
}

/// Why `points` cannot be fitted, or "" when they can.
std::string unfittable(const std::vector<LocusPoint>& points) {
  for (const LocusPoint& p : points)
    if (!std::isfinite(p.normal_stress) || !std::isfinite(p.shear_stress) || !std::isfinite(p.error) || p.error <= 0)
      return fmt::format("the point at a normal stress of {:g} Pa{} has no finite shear stress with a standard error above zero "
                         "(a weighted fit needs one)", p.normal_stress, p.experiment.empty() ? "" : " (" + p.experiment + ")");
  const int distinct = distinct_normal_stresses(points);
  if (distinct == 0) return "no shear test";
  if (distinct == 1)
    return fmt::format("shear tests at one normal stress only ({:g} Pa): a yield locus needs two or more", points.front().normal_stress);
  return "";
}

/// A set-up number; NaN when the set-up lacks it.
double setup_number(const TestSetup& setup, const std::string& key) {
  const auto it = setup.numbers.find(key);
  return it == setup.numbers.end() ? kNaN : it->second;
}

const Experiment* find_experiment(const MeasurementSet& set, const std::string& id) {
  for (const Experiment& e : set.experiments)
    if (e.id == id) return &e;
  return nullptr;
}

std::string angle_text(const YieldLocusFit& f) { return fmt::format("{:.1f} +- {:.1f} deg", f.friction_angle, f.friction_angle_sigma); }
std::string cohesion_text(const YieldLocusFit& f) {
  const double c = std::abs(f.cohesion) < 0.5 ? 0.0 : f.cohesion;  // no "-0 Pa" for a zero intercept
  return fmt::format("{:.0f} +- {:.0f} Pa", c, f.cohesion_sigma);
}

/// The slope's part of the words; "" when the angles agree within 2 sigma.
std::string slope_words(const YieldLocusFit& measured, const YieldLocusFit& simulated) {
  const double difference = simulated.friction_angle - measured.friction_angle;
  const double sigma = std::hypot(measured.friction_angle_sigma, simulated.friction_angle_sigma);
  if (std::abs(difference) <= 2 * sigma) return "";
  const std::string angles = fmt::format("phi {} against {} measured", angle_text(simulated), angle_text(measured));
  if (difference < 0)
    return fmt::format("is flatter ({}): more friction between particles, rolling resistance or particle shape (clumps) raise it", angles);
  return fmt::format("is steeper ({}): less friction between particles or rolling resistance, or rounder particles, lower it", angles);
}

/// The intercept's part of the words; "" when the cohesions agree within 2 sigma.
std::string intercept_words(const YieldLocusFit& measured, const YieldLocusFit& simulated) {
  const double difference = simulated.cohesion - measured.cohesion;
  const double sigma = std::hypot(measured.cohesion_sigma, simulated.cohesion_sigma);
  if (std::abs(difference) <= 2 * sigma) return "";
  const std::string by = fmt::format("by a cohesion of {:.0f} +- {:.0f} Pa (c {} against {} measured)", std::abs(difference), sigma,
                                     cohesion_text(simulated), cohesion_text(measured));
  if (difference < 0)
    return fmt::format("lies lower {}: {}", by,
                       simulated.cohesion_zero ? "the simulation lacks the intercept; liquid bridges or van der Waals cohesion give one"
                                               : "the simulated cohesion is too weak; stronger liquid bridges or cohesion raise it");
  return fmt::format("lies higher {}: {}", by,
                     measured.cohesion_zero ? "the measured material shows no intercept; the simulated cohesion (liquid bridges, van der Waals) "
                                              "should be weaker or switched off"
                                            : "the simulated cohesion is too strong; weaker liquid bridges or cohesion lower it");
}

}  // namespace

YieldLocusFit fit_yield_locus(const std::vector<LocusPoint>& points) {
  YieldLocusFit fit;
  fit.points = static_cast<int>(points.size());
  fit.reason = unfittable(points);
  if (!fit.reason.empty()) return fit;
  // Weighted sums about the weighted mean normal stress (the same solution as the normal
  // equations, without their cancellation): S = sum w, Sxx' = sum w (x - xm)^2.
  double weight = 0, mean_x = 0, mean_y = 0;
  for (const LocusPoint& p : points) {
    const double w = 1 / (p.error * p.error);
    weight += w, mean_x += w * p.normal_stress, mean_y += w * p.shear_stress;
  }
  mean_x /= weight, mean_y /= weight;
  double spread = 0, covariation = 0;
  for (const LocusPoint& p : points) {
    const double w = 1 / (p.error * p.error), dx = p.normal_stress - mean_x;
    spread += w * dx * dx, covariation += w * dx * (p.shear_stress - mean_y);
  }
  const double slope = covariation / spread, intercept = mean_y - slope * mean_x;
  // Covariance of (c, tan phi): var(tan phi) = 1/Sxx' = S/D, var(c) = 1/S + xm^2/Sxx' = Sxx/D,
  // cov = -xm/Sxx' = -Sx/D, with D = S Sxx - Sx^2 of the raw sums.
  const double var_slope = 1 / spread, var_intercept = 1 / weight + mean_x * mean_x / spread, covariance = -mean_x / spread;
  for (const LocusPoint& p : points) {
    const double r = (p.shear_stress - intercept - slope * p.normal_stress) / p.error;
    fit.chi2 += r * r;
  }
  fit.fitted = true;
  fit.dof = fit.points - 2;
  fit.chi2_per_dof = fit.dof > 0 ? fit.chi2 / fit.dof : kNaN;
  // phi = atan(tan phi): d phi = d(tan phi) / (1 + tan^2 phi), in degrees.
  fit.friction_angle = std::atan(slope) * kDegrees;
  fit.friction_angle_sigma = std::sqrt(var_slope) / (1 + slope * slope) * kDegrees;
  fit.cohesion = intercept;
  fit.cohesion_sigma = std::sqrt(var_intercept);
  fit.correlation = covariance / std::sqrt(var_slope * var_intercept);
  fit.cohesion_zero = std::abs(fit.cohesion) <= 2 * fit.cohesion_sigma;
  return fit;
}

std::string YieldLocus::label() const {
  if (observable == "peak_shear_stress") return fmt::format("peak shear stress after pre-shear at {:g} kPa", preshear_stress / 1000);
  return "steady shear stress at the pre-shear stresses";
}

std::vector<YieldLocus> group_yield_loci(const MeasurementSet& set, const std::vector<ShearValue>& values) {
  // Keyed by (peak 0 / steady 1, pre-shear stress): the peaks by pre-shear first, the steady states last.
  std::map<std::pair<int, double>, YieldLocus> by_key;
  for (const ShearValue& v : values) {
    const bool peak = v.observable == "peak_shear_stress";
    if (!peak && v.observable != "steady_shear_stress") continue;
    const Experiment* e = find_experiment(set, v.experiment);
    if (!e || e->setup.test != "direct_shear") continue;
    // The peak is sheared at normal_stress, the steady state at the end of the pre-shear (yield_locus.h).
    const double preshear = setup_number(e->setup, "preshear_stress");
    const double sigma = peak ? setup_number(e->setup, "normal_stress") : preshear;
    if (!std::isfinite(sigma) || !std::isfinite(preshear)) continue;
    YieldLocus& locus = by_key[{peak ? 0 : 1, peak ? preshear : 0.0}];
    locus.observable = v.observable;
    locus.preshear_stress = peak ? preshear : 0.0;
    locus.points.push_back({sigma, v.value, v.error, v.experiment});
  }
  std::vector<YieldLocus> out;
  for (auto& entry : by_key) {
    YieldLocus& locus = entry.second;
    std::stable_sort(locus.points.begin(), locus.points.end(),
                     [](const LocusPoint& a, const LocusPoint& b) { return a.normal_stress < b.normal_stress; });
    locus.fit = fit_yield_locus(locus.points);
    out.push_back(std::move(locus));
  }
  return out;
}

std::vector<YieldLocus> measured_yield_loci(const MeasurementSet& set) {
  std::vector<ShearValue> values;
  for (const Experiment& e : set.experiments)
    for (const auto& [observable, o] : e.observed) values.push_back({e.id, observable, o.value, o.sigma});
  return group_yield_loci(set, values);
}

std::string compare_yield_loci(const YieldLocusFit& measured, const YieldLocusFit& simulated) {
  if (!measured.fitted) return "No comparison of the loci: the measured locus has no fit (" + measured.reason + ").";
  if (!simulated.fitted) return "No comparison of the loci: the simulated locus has no fit (" + simulated.reason + ").";
  const std::string slope = slope_words(measured, simulated), intercept = intercept_words(measured, simulated);
  if (slope.empty() && intercept.empty())
    return fmt::format("The simulated locus agrees with the measured one within the noise (phi {} against {} measured, c {} against {}).",
                       angle_text(simulated), angle_text(measured), cohesion_text(simulated), cohesion_text(measured));
  if (intercept.empty()) return "The simulated locus " + slope + ".";
  if (slope.empty()) return "The simulated locus " + intercept + ".";
  return "The simulated locus " + slope + "; it also " + intercept + ".";
}

}  // namespace dem::materials
