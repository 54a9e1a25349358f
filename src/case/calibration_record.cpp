#include "case/calibration_record.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "case/yaml_check.h"

namespace dem {

namespace {

std::vector<double> numbers(MapReader& map, const std::string& key, size_t size) {
  const YAML::Node list = map.node(key);
  if (!list || !list.IsSequence() || list.size() != size)
    map.fail(key, fmt::format("must be a list of {} numbers, one per entry of 'parameters'", size));
  std::vector<double> out;
  for (const YAML::Node& v : list) out.push_back(MapReader::finite_number(v, map, key));
  return out;
}

/// Inverse of the standard normal distribution function (Acklam's rational approximation,
/// relative error below 1.2e-9), for the Latin hypercube's strata.
double normal_quantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02, 1.383577518672690e+02, -3.066479806614716e+01,
                             2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02, 6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00, -2.549732539343734e+00, 4.374664141464968e+00,
                             2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00};
  const double low = 0.02425;
  if (p < low) {
    const double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) / ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - low) return -normal_quantile(1 - p);
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

}  // namespace

CalibrationRecord read_calibration_record(const YAML::Node& node, const std::string& file) {
  MapReader map(node, file, "calibration");
  CalibrationRecord r;
  r.location = map.location();
  r.command = map.string("command", "", {"calibrate", "diagnose"});
  r.measurements = map.string("measurements", "");
  r.date = map.string("date", "");
  r.engine = map.string("engine", "");
  if (const YAML::Node effects = map.node("effects")) {
    if (!effects.IsSequence()) map.fail("effects", "must be a list of effect names");
    for (const YAML::Node& e : effects) r.effects.push_back(e.as<std::string>());
  }
  const YAML::Node parameters = map.node("parameters");
  if (!parameters || !parameters.IsSequence() || parameters.size() == 0)
    map.fail("parameters", "must list the fitted parameters, e.g. [friction, restitution]");
  for (const YAML::Node& p : parameters) r.parameters.push_back(p.as<std::string>());
  const size_t n = r.parameters.size();
  r.value = numbers(map, "value", n);
  r.sigma = numbers(map, "sigma", n);
  for (double s : r.sigma)
    if (!(s >= 0)) map.fail("sigma", "standard deviations must not be negative");
  r.chi2_per_n = map.number("chi2_per_n", 0.0, 0.0, 1e12);
  r.stiffness_scaling = map.number("stiffness_scaling", 1.0, 1e-9, 1e9);
  r.coarse_grain = map.number("coarse_grain", 1.0, 1.0, kMostCoarseGrain, "-");
  const YAML::Node rows = map.node("correlation");
  if (!rows || !rows.IsSequence() || rows.size() != n) map.fail("correlation", fmt::format("must be a {0} x {0} matrix (a list of {0} rows)", n));
  Eigen::MatrixXd c(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  for (size_t i = 0; i < n; ++i) {
    if (!rows[i].IsSequence() || rows[i].size() != n) map.fail("correlation", fmt::format("row {} must hold {} numbers", i + 1, n));
    std::vector<double> row;
    for (size_t j = 0; j < n; ++j) row.push_back(MapReader::finite_number(rows[i][j], map, "correlation"));
    r.correlation.push_back(row);
    for (size_t j = 0; j < n; ++j) c(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = row[j];
  }
  for (Eigen::Index i = 0; i < c.rows(); ++i)
    for (Eigen::Index j = 0; j < c.cols(); ++j) {
      if (std::abs(c(i, j) - c(j, i)) > 1e-9) map.fail("correlation", "must be symmetric");
      if (i == j && std::abs(c(i, i) - 1) > 1e-9) map.fail("correlation", "its diagonal must be 1");
      if (std::abs(c(i, j)) > 1 + 1e-9) map.fail("correlation", "entries must lie in [-1, 1]");
    }
  if (Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(c).eigenvalues().minCoeff() < -1e-6)
    map.fail("correlation", "must be positive semi-definite (a correlation matrix of real parameters)");
  map.finish();
  return r;
}

std::vector<std::vector<double>> posterior_samples(const CalibrationRecord& record, int count, std::uint64_t seed,
                                                   const std::vector<std::pair<double, double>>& ranges) {
  const Eigen::Index n = static_cast<Eigen::Index>(record.parameters.size());
  Eigen::MatrixXd c(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) c(i, j) = record.correlation[i][j];
  // A positive semi-definite matrix: its square root from the eigen decomposition (Cholesky
  // would fail on an exactly singular correlation, which a product-only fit gives).
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c);
  const Eigen::MatrixXd root = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Latin hypercube: parameter j of set k lies in stratum perm_j[k] of count equal-probability strata.
  Eigen::MatrixXd z(count, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    std::vector<int> strata(static_cast<size_t>(count));
    std::iota(strata.begin(), strata.end(), 0);
    std::shuffle(strata.begin(), strata.end(), random);
    for (int k = 0; k < count; ++k)
      z(k, j) = normal_quantile(std::clamp((strata[static_cast<size_t>(k)] + uniform(random)) / count, 1e-12, 1 - 1e-12));
  }
  std::vector<std::vector<double>> out(static_cast<size_t>(count), std::vector<double>(static_cast<size_t>(n)));
  for (int k = 0; k < count; ++k) {
    const Eigen::VectorXd u = root * z.row(k).transpose();
    for (Eigen::Index j = 0; j < n; ++j) {
      double v = record.value[j] + record.sigma[j] * u[j];
      if (!ranges.empty()) v = std::clamp(v, ranges[j].first, ranges[j].second);
      out[k][j] = v;
    }
  }
  return out;
}

}  // namespace dem
