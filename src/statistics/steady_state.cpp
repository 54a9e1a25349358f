// Steady-state detection (MSER-5 and a trend check), rates of cumulative series, blockage.
#include "statistics/steady_state.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace dem {
namespace {

constexpr std::size_t kMinSamples = 10;     ///< in a steady part
constexpr double kTrendT = 3.0;             ///< |t| of a slope that counts as significant
constexpr double kTrendRelevance = 0.02;    ///< of max(|mean|, std dev)

/// Non-overlapping batch means of y over [begin, end): floor(sqrt(L)) batches clamped to
/// [10, 30] (fewer when there are fewer samples); the samples that do not fill a batch are
/// dropped at the start, so the latest data always count.
struct Batches {
  std::vector<double> time, value;
};
Batches batch_means(std::span<const double> t, std::span<const double> y, std::size_t begin, std::size_t end) {
  Batches b;
  const std::size_t length = end > begin ? end - begin : 0;
  if (length == 0) return b;
  std::size_t count = std::clamp<std::size_t>(static_cast<std::size_t>(std::sqrt(double(length))), 10, 30);
  count = std::min(count, length);
  const std::size_t size = length / count;
  std::size_t k = end - count * size;
  for (std::size_t j = 0; j < count; ++j) {
    double st = 0, sy = 0;
    for (std::size_t i = 0; i < size; ++i, ++k) st += t[k], sy += y[k];
    b.time.push_back(st / double(size));
    b.value.push_back(sy / double(size));
  }
  return b;
}

double mean_of(std::span<const double> v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / double(v.size());
}

/// Sample standard deviation (n - 1).
double std_dev_of(std::span<const double> v) {
  if (v.size() < 2) return 0.0;
  const double m = mean_of(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / double(v.size() - 1));
}

/// Statistics of the candidate steady part [first, n) and whether it passes the trend check.
SteadyState evaluate(std::span<const double> t, std::span<const double> y, std::size_t first, const char* where) {
  const std::size_t n = y.size();
  SteadyState s;
  s.first = first;
  s.samples = n - first;
  s.t_start = t[first];
  s.t_end = t[n - 1];
  const std::span<const double> part = y.subspan(first);
  s.mean = mean_of(part);
  s.std_dev = std_dev_of(part);
  const Batches b = batch_means(t, y, first, n);
  s.std_error = b.value.size() >= 2 ? std_dev_of(b.value) / std::sqrt(double(b.value.size())) : s.std_dev;
  const Trend trend = trend_of(t, y, first, n);
  s.trend_per_s = trend.slope;
  const double change = trend.slope * (s.t_end - s.t_start);
  const double scale = std::max(std::abs(s.mean), s.std_dev);
  const bool significant = std::abs(trend.t_stat) > kTrendT;
  const bool relevant = std::abs(change) > kTrendRelevance * scale;
  s.found = !(significant && relevant);
  if (!s.found) {
    const char* direction = change > 0 ? "rising" : "falling";
    const std::string amount = std::abs(s.mean) > s.std_dev
                                   ? fmt::format("{:+.0f} %", 100.0 * change / std::abs(s.mean))
                                   : fmt::format("by {:.3g} ({:.1f} std dev)", change, std::abs(change) / std::max(s.std_dev, 1e-300));
    s.why = fmt::format("still {}: {} over {} ({:.3g} s to {:.3g} s)", direction, amount, where, s.t_start, s.t_end);
  }
  return s;
}

}  // namespace

Trend trend_of(std::span<const double> t, std::span<const double> y, std::size_t begin, std::size_t end) {
  Trend trend;
  const Batches b = batch_means(t, y, begin, end);
  const std::size_t k = b.value.size();
  if (k == 0) return trend;
  const double tm = mean_of(b.time), ym = mean_of(b.value);
  trend.start_value = ym;
  if (k < 3) return trend;
  double sxx = 0, sxy = 0;
  for (std::size_t j = 0; j < k; ++j) sxx += (b.time[j] - tm) * (b.time[j] - tm), sxy += (b.time[j] - tm) * (b.value[j] - ym);
  if (sxx <= 0) return trend;
  trend.slope = sxy / sxx;
  double residual = 0;
  for (std::size_t j = 0; j < k; ++j) {
    const double r = b.value[j] - ym - trend.slope * (b.time[j] - tm);
    residual += r * r;
  }
  const double se = std::sqrt(residual / double(k - 2) / sxx);
  // An exact line has no residual: any slope is then certain (up to rounding of the data).
  const double rounding = 1e-12 * std::max(std::abs(ym), 1e-300) * std::sqrt(double(k)) / std::sqrt(sxx);
  if (se <= rounding)
    trend.t_stat = std::abs(trend.slope) <= rounding ? 0.0 : std::copysign(std::numeric_limits<double>::infinity(), trend.slope);
  else
    trend.t_stat = trend.slope / se;
  trend.start_value = ym + trend.slope * (t[begin] - tm);
  return trend;
}

SteadyState find_steady_state(std::span<const double> t, std::span<const double> y) {
  const std::size_t n = std::min(t.size(), y.size());
  if (n < kMinSamples) {
    SteadyState s;
    s.samples = n;
    s.why = fmt::format("too short: {} samples, at least {} needed", n, kMinSamples);
    return s;
  }
  t = t.first(n), y = y.first(n);
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(y[i]) || !std::isfinite(t[i])) {
      SteadyState s;
      s.why = fmt::format("not finite at t = {:.3g} s", t[i]);
      return s;
    }

  // MSER over batch means of 5 (of 1 for short series), truncation d <= m/2 batches, keeping at
  // least kMinSamples samples.
  const std::size_t batch = n >= 40 ? 5 : 1;
  const std::size_t m = n / batch;
  std::vector<double> z(m);
  for (std::size_t j = 0; j < m; ++j) {
    double s = 0;
    for (std::size_t i = 0; i < batch; ++i) s += y[j * batch + i];
    z[j] = s / double(batch);
  }
  const std::size_t d_max = std::min(m / 2, (n - kMinSamples) / batch);
  // Suffix sums give every candidate's sum of squared deviations in O(m).
  std::vector<double> sum(m + 1, 0.0), sum2(m + 1, 0.0);
  for (std::size_t j = m; j-- > 0;) sum[j] = sum[j + 1] + z[j], sum2[j] = sum2[j + 1] + z[j] * z[j];
  std::size_t best = 0;
  double best_value = std::numeric_limits<double>::infinity();
  for (std::size_t d = 0; d <= d_max; ++d) {
    const double count = double(m - d);
    const double squares = std::max(0.0, sum2[d] - sum[d] * sum[d] / count);
    const double value = squares / (count * count);
    if (value < best_value) best_value = value, best = d;
  }

  const std::size_t half = n / 2;
  const SteadyState chosen = evaluate(t, y, best * batch, best * batch + batch > half ? "the last half" : "the part after the warm-up");
  if (chosen.found) return chosen;
  if (half > best * batch) {
    SteadyState last_half = evaluate(t, y, half, "the last half");
    return last_half;
  }
  return chosen;
}

std::vector<double> rate_of(std::span<const double> t, std::span<const double> cumulative, double window) {
  const std::size_t n = std::min(t.size(), cumulative.size());
  std::vector<double> rate(n, 0.0);
  if (n < 2) return rate;
  if (window <= 0) {
    std::vector<double> steps;
    for (std::size_t i = 1; i < n; ++i)
      if (t[i] > t[i - 1]) steps.push_back(t[i] - t[i - 1]);
    if (steps.empty()) return rate;
    std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
    window = 10.0 * steps[steps.size() / 2];
  }
  std::size_t lo = 0, hi = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (t[lo] < t[i] - 0.5 * window) ++lo;
    if (hi < i) hi = i;
    while (hi + 1 < n && t[hi + 1] <= t[i] + 0.5 * window) ++hi;
    std::size_t a = lo, b = hi;
    if (a == b) a = i > 0 ? i - 1 : i, b = i + 1 < n ? i + 1 : i;
    const double span = t[b] - t[a];
    rate[i] = span > 0 ? (cumulative[b] - cumulative[a]) / span : 0.0;
  }
  return rate;
}

std::pair<double, double> mean_and_standard_error(std::span<const double> samples) {
  const double n = static_cast<double>(samples.size());
  double sum = 0, ss = 0;
  for (double v : samples) sum += v;
  const double mean = sum / n;
  for (double v : samples) ss += (v - mean) * (v - mean);
  return {mean, samples.size() > 1 ? std::sqrt(ss / (n - 1) / n) : 0.0};
}

IntervalStats average_over(std::span<const double> t, std::span<const double> y, double t0, double t1) {
  IntervalStats s;
  const std::size_t n = std::min(t.size(), y.size());
  const double slack = 1e-9 * std::max(std::abs(t0), std::abs(t1));
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (t[i] >= t0 - slack && t[i] <= t1 + slack) sum += y[i], ++s.samples;
  if (s.samples == 0) return s;
  s.mean = sum / double(s.samples);
  for (std::size_t i = 0; i < n; ++i)
    if (t[i] >= t0 - slack && t[i] <= t1 + slack) sum2 += (y[i] - s.mean) * (y[i] - s.mean);
  s.std_dev = s.samples > 1 ? std::sqrt(sum2 / double(s.samples - 1)) : 0.0;
  s.std_error = s.std_dev / std::sqrt(double(s.samples));
  if (s.samples >= 20) {
    std::size_t begin = 0;
    while (begin < n && t[begin] < t0 - slack) ++begin;
    const Batches b = batch_means(t, y, begin, begin + s.samples);
    if (b.value.size() >= 2) s.std_error = std_dev_of(b.value) / std::sqrt(double(b.value.size()));
  }
  return s;
}

Blockage detect_blockage(std::span<const double> t, std::span<const double> outflow, std::span<const double> holdup) {
  Blockage b;
  const std::size_t n = std::min({t.size(), outflow.size(), holdup.size()});
  if (n < kMinSamples) {
    b.text = fmt::format("not judged: {} rows, at least {} needed", n, kMinSamples);
    return b;
  }
  b.window_start = t[n - 1] - (t[n - 1] - t[0]) / 3.0;
  std::size_t begin = 0;
  while (begin < n && t[begin] < b.window_start) ++begin;
  if (n - begin < 6) {
    b.text = "not judged: fewer than 6 rows in the last third of the run";
    return b;
  }
  const double window = t[n - 1] - t[begin];
  const Trend q = trend_of(t, outflow, begin, n), h = trend_of(t, holdup, begin, n);
  const double q_start = q.start_value;
  const double q_fall = -q.slope * window;  // > 0 when falling
  b.outflow_change = q_start > 0 ? -q_fall / q_start : 0.0;
  b.holdup_change = h.slope * window;
  const bool outflow_falls = q_start > 0 && q.slope < 0 && std::abs(q.t_stat) > kTrendT && q_fall > 0.2 * q_start;
  const bool holdup_rises =
      q_start > 0 && h.slope > 0 && std::abs(h.t_stat) > kTrendT && b.holdup_change > 0.05 * q_start * window;
  b.blocked = outflow_falls && holdup_rises;
  b.text = fmt::format("over {:.3g} s to {:.3g} s the outflow changed by {:+.0f} % and the hold-up by {:+.3g} kg{}",
                       t[begin], t[n - 1], 100.0 * b.outflow_change, b.holdup_change,
                       b.blocked ? ": BLOCKAGE" : (outflow_falls ? " (outflow falls, hold-up does not rise: not a blockage)" : ""));
  return b;
}

}  // namespace dem
