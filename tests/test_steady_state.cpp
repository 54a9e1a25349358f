// Steady-state detection (MSER-5 + trend check), rates of cumulative series, blockage rule, on
// synthetic series with known answers (fixed seeds).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "statistics/steady_state.h"

namespace dem::test {
namespace {

struct Series {
  std::vector<double> t, y;
};

/// y = plateau (1 - exp(-t/tau)) + N(0, noise), n rows over [0, duration].
Series exponential_rise(double plateau, double tau, double noise, double duration, int n, unsigned seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> gauss(0.0, noise);
  Series s;
  for (int i = 0; i < n; ++i) {
    const double t = duration * i / (n - 1);
    s.t.push_back(t);
    s.y.push_back(plateau * (1 - std::exp(-t / tau)) + gauss(random));
  }
  return s;
}

TEST(SteadyState, ExponentialTransientEndsWhereItDecaysIntoTheNoise) {
  const double plateau = 100, tau = 0.5, noise = 2;
  // The transient is within the noise once plateau exp(-t/tau) < noise: t* = tau ln(plateau/noise).
  const double t_decayed = tau * std::log(plateau / noise);  // 1.96 s
  for (unsigned seed : {1u, 2u, 3u, 4u, 5u}) {
    const Series s = exponential_rise(plateau, tau, noise, 10.0, 500, seed);
    const SteadyState st = find_steady_state(s.t, s.y);
    ASSERT_TRUE(st.found) << st.why;
    // Stated tolerance: not before t* - tau (the transient would bias the mean), and not later
    // than t* + 5 tau (a quarter of this run): MSER errs on the late, conservative side.
    EXPECT_GE(st.t_start, t_decayed - tau) << "seed " << seed;
    EXPECT_LE(st.t_start, t_decayed + 5 * tau) << "seed " << seed;
    EXPECT_NEAR(st.mean, plateau, 2 * st.std_error) << "seed " << seed;
    EXPECT_NEAR(st.std_dev, noise, 0.2 * noise);
    EXPECT_GT(st.std_error, 0);
    EXPECT_LT(st.std_error, st.std_dev);
    EXPECT_DOUBLE_EQ(st.t_end, 10.0);
    EXPECT_EQ(st.samples, 500 - st.first);
  }
}

TEST(SteadyState, PureRampIsStillRising) {
  std::mt19937_64 random(7);
  std::normal_distribution<double> gauss(0.0, 0.5);
  Series s;
  for (int i = 0; i < 300; ++i) s.t.push_back(0.01 * i), s.y.push_back(10 + 5 * s.t.back() + gauss(random));
  const SteadyState st = find_steady_state(s.t, s.y);
  EXPECT_FALSE(st.found);
  EXPECT_NE(st.why.find("still rising"), std::string::npos) << st.why;
  EXPECT_NE(st.why.find("%"), std::string::npos) << st.why;
  // The falling ramp says so.
  for (double& v : s.y) v = 40 - v;
  const SteadyState falling = find_steady_state(s.t, s.y);
  EXPECT_FALSE(falling.found);
  EXPECT_NE(falling.why.find("still falling"), std::string::npos) << falling.why;
}

TEST(SteadyState, PureNoiseIsSteadyFromTheStart) {
  std::mt19937_64 random(11);
  std::normal_distribution<double> gauss(3.0, 1.0);
  Series s;
  for (int i = 0; i < 400; ++i) s.t.push_back(0.05 * i), s.y.push_back(gauss(random));
  const SteadyState st = find_steady_state(s.t, s.y);
  ASSERT_TRUE(st.found) << st.why;
  EXPECT_LT(st.t_start, 0.1 * s.t.back());
  EXPECT_NEAR(st.mean, 3.0, 2 * st.std_error);
  EXPECT_NEAR(st.trend_per_s, 0.0, 0.05);
}

TEST(SteadyState, ConstantSeriesAndTooShortSeries) {
  std::vector<double> t, y;
  for (int i = 0; i < 50; ++i) t.push_back(i), y.push_back(2.5);
  const SteadyState st = find_steady_state(t, y);
  ASSERT_TRUE(st.found) << st.why;
  EXPECT_EQ(st.first, 0u);
  EXPECT_DOUBLE_EQ(st.mean, 2.5);
  EXPECT_DOUBLE_EQ(st.std_dev, 0.0);

  const std::vector<double> few_t{0, 1, 2}, few_y{1, 2, 3};
  const SteadyState short_series = find_steady_state(few_t, few_y);
  EXPECT_FALSE(short_series.found);
  EXPECT_NE(short_series.why.find("too short"), std::string::npos);
  EXPECT_FALSE(find_steady_state({}, {}).found);
}

TEST(SteadyState, RateOfACumulativeSeriesWithUnevenRows) {
  // m(t) = 2 t + 0.5 t^2 sampled unevenly: the central difference of a quadratic is exact at the
  // window's centre when the window is symmetric, and close otherwise.
  std::vector<double> t, m;
  double time = 0;
  for (int i = 0; i < 200; ++i) {
    t.push_back(time);
    m.push_back(2 * time + 0.5 * time * time);
    time += (i % 3 == 0) ? 0.02 : 0.005;
  }
  const std::vector<double> rate = rate_of(t, m, 0.1);
  for (size_t i = 20; i + 20 < t.size(); ++i) EXPECT_NEAR(rate[i], 2 + t[i], 0.03) << "t = " << t[i];
  // Default window, constant rate: exact everywhere.
  std::vector<double> linear;
  for (double v : t) linear.push_back(3.5 * v);
  for (double r : rate_of(t, linear)) EXPECT_NEAR(r, 3.5, 1e-9);
}

TEST(SteadyState, AverageOverAnInterval) {
  const std::vector<double> t{0, 1, 2, 3, 4}, y{10, 1, 2, 3, 10};
  const IntervalStats s = average_over(t, y, 1, 3);
  EXPECT_EQ(s.samples, 3u);
  EXPECT_DOUBLE_EQ(s.mean, 2.0);
  EXPECT_DOUBLE_EQ(s.std_dev, 1.0);
}

/// Inflow 10 kg/s; outflow follows it after a fill-up; when `block_at` < duration the outflow
/// decays from then on (material accumulates). Noisy outflow.
struct Flow {
  std::vector<double> t, outflow, holdup;
};
Flow synthetic_flow(double block_at, unsigned seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> gauss(0.0, 0.8);
  Flow f;
  const double dt = 0.02, inflow = 10;
  double held = 0;
  for (int i = 0; i <= 500; ++i) {
    const double t = i * dt;
    double q = inflow * (1 - std::exp(-t / 0.5));
    if (t > block_at) q *= std::exp(-(t - block_at) / 1.5);
    q = std::max(0.0, q + gauss(random));
    held += (inflow - q) * dt;
    f.t.push_back(t), f.outflow.push_back(q), f.holdup.push_back(held);
  }
  return f;
}

TEST(Blockage, FlaggedWhenOutflowFallsAndHoldUpRises) {
  const Flow f = synthetic_flow(6.0, 3);
  const Blockage b = detect_blockage(f.t, f.outflow, f.holdup);
  EXPECT_TRUE(b.blocked) << b.text;
  EXPECT_LT(b.outflow_change, -0.2);
  EXPECT_GT(b.holdup_change, 0);
}

TEST(Blockage, NotFlaggedOnSteadyFlowNorWhenTheFeedStops) {
  const Flow steady = synthetic_flow(1e9, 3);
  const Blockage b = detect_blockage(steady.t, steady.outflow, steady.holdup);
  EXPECT_FALSE(b.blocked) << b.text;
  // Feed stops at 7 s: the outflow falls, but the hold-up falls too (the system empties).
  Flow drain = steady;
  double held = 0;
  for (size_t i = 0; i < drain.t.size(); ++i) {
    if (drain.t[i] > 7) drain.outflow[i] = 10 * std::exp(-(drain.t[i] - 7) / 0.7);
    const double inflow = drain.t[i] > 7 ? 0 : 10;
    held += (inflow - drain.outflow[i]) * 0.02;
    drain.holdup[i] = std::max(held, 0.0);
  }
  const Blockage d = detect_blockage(drain.t, drain.outflow, drain.holdup);
  EXPECT_FALSE(d.blocked) << d.text;
}

}  // namespace
}  // namespace dem::test
