// Where a time series from a run is steady, found from the data (not assumed), and whether an
// outflow is blocking up.
//
// Steady state: MSER-5 (Marginal Standard Error Rule, White 1997, "An effective truncation
// heuristic for bias reduction in simulation output", Simulation 69(6); MSER-5: White, Cobb and
// Spratt 2000) picks the truncation point d of the warm-up as the one that minimises
//   MSER(d) = sum_{j>d} (z_j - zbar_d)^2 / (m - d)^2,   d <= m/2,
// over the m batch means z_j of 5 consecutive samples (batch size 1 for series under 40
// samples). The remainder is then checked for a trend: a least-squares line through its
// batch means (10 to 30 non-overlapping batches, so that autocorrelation does not inflate the
// significance) must not have a slope that is both significant (|t| > 3) and relevant (the
// change it makes over the interval > 2 % of max(|mean|, std dev)). When MSER's choice fails the
// check, the last half of the series is tried. The remainder must hold at least 10 samples.
// Rejected alternative: a fixed "last 50 %" window, which hides runs that never settle.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace dem {

/// The steady part of a time series, or why there is none.
struct SteadyState {
  bool found = false;
  std::size_t first = 0;     ///< index of the first sample of the steady part
  std::size_t samples = 0;   ///< samples in the steady part
  double t_start = 0;        // [s]
  double t_end = 0;          // [s]
  double mean = 0;           ///< of the samples in [t_start, t_end], in the series' unit
  double std_dev = 0;        ///< of the samples (spread of the signal)
  double std_error = 0;      ///< of the mean, from non-overlapping batch means
  double trend_per_s = 0;    ///< least-squares slope over the steady part [unit/s]
  std::string why;           ///< when not found: "still rising: +12 % over 2-4 s", "too short: ..."
};

/// Finds the steady part of y(t) (t ascending). Never throws; short or empty input gives
/// found = false with the reason.
SteadyState find_steady_state(std::span<const double> t, std::span<const double> y);

/// Rate of a cumulative series (e.g. outlet mass [kg] -> [kg/s]): at each t_i the difference
/// quotient over the rows within [t_i - window/2, t_i + window/2] (one-sided at the ends), so
/// uneven row spacing is handled. window <= 0: ten times the median row spacing.
std::vector<double> rate_of(std::span<const double> t, std::span<const double> cumulative, double window = 0);

/// Mean and standard deviation of the samples with t in [t0, t1], and the standard error of
/// the mean from non-overlapping batch means (10 to 30 batches, so that correlated samples do
/// not make it look smaller than it is; the standard deviation over sqrt(n) below 10 samples).
struct IntervalStats {
  double mean = 0, std_dev = 0, std_error = 0;
  std::size_t samples = 0;
};
IntervalStats average_over(std::span<const double> t, std::span<const double> y, double t0, double t1);

/// Mean of independent samples and its standard error sqrt(s^2 / n) (0 for one sample); the
/// replicas of a simulation, the drops of a clump. Needs one sample.
std::pair<double, double> mean_and_standard_error(std::span<const double> samples);

/// Least-squares slope of y(t) over [begin, end) and its t statistic, computed on batch means
/// (10 to 30 batches) so that correlated noise does not look significant.
struct Trend {
  double slope = 0;   // [unit/s]
  double t_stat = 0;  ///< slope / its standard error; +-inf for an exact non-flat line
  double start_value = 0;  ///< fitted value at t[begin]
};
Trend trend_of(std::span<const double> t, std::span<const double> y, std::size_t begin, std::size_t end);

/// Blockage rule. Over the last third of the run, straight lines are fitted (on batch means)
/// to the outflow rate Q(t) and the hold-up mass H(t) = inserted - removed - lost. Blocked when
/// both hold:
///   the outflow falls: slope_Q < 0, |t| > 3, and the fitted fall over the window exceeds 20 %
///     of the fitted outflow at the window's start;
///   the hold-up rises: slope_H > 0, |t| > 3, and the rise over the window exceeds 5 % of the
///     mass that the starting outflow would carry out in the window.
/// An outflow that falls while the hold-up falls too (the feed stopped) is not a blockage.
struct Blockage {
  bool blocked = false;
  double outflow_change = 0;  ///< [-] fitted change over the window / outflow at its start
  double holdup_change = 0;   // [kg] fitted change over the window
  double window_start = 0;    // [s]
  std::string text;           ///< what was found, in words
};
Blockage detect_blockage(std::span<const double> t, std::span<const double> outflow, std::span<const double> holdup);

/// The rule above, in words, for reports.
inline constexpr const char* kBlockageRule =
    "over the last third of the run, the outflow falls (fitted fall > 20 % of its value at the start of that "
    "window, slope |t| > 3 on batch means) while the hold-up (inserted - removed - lost mass) rises (fitted rise > "
    "5 % of the mass the starting outflow carries out in the window, |t| > 3)";

}  // namespace dem
