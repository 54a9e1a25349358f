// Rolling resistance against closed form (validation RR-1, RR-2), both rolling models.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sim.h"

namespace dem::test {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// Loads a rolling case with the chosen model and lets the ball settle on the floor first
/// (no transients from the initial drop of the contact), then returns the sim at rest.
Sim settled_ball(const std::string& case_name, const std::string& model, const Vec3& gravity) {
  CaseSpec spec = load_case(case_name);
  spec.contact.rolling.model = model;
  spec.simulation.gravity = gravity;
  spec.particles[0].velocity = Vec3::Zero();
  spec.particles[0].angular_velocity = Vec3::Zero();
  Sim sim(spec);
  const double settle = sim.state.time + 0.05;
  while (sim.state.time < settle) {
    sim.advance();
    sim.state.vx[0] = sim.state.vy[0] = 0;  // settle the normal direction only
    sim.state.wx[0] = sim.state.wy[0] = sim.state.wz[0] = 0;
  }
  return sim;
}

class RollingModels : public ::testing::TestWithParam<const char*> {};

TEST_P(RollingModels, RR1BallRollingOnFloorStopsAtClosedFormDistance) {
  // RR-1: a = (5/7) mu_r g; mu_r = 0.1, v0 = 1 m/s -> stops after 0.7136 m and 1.4271 s; then stays.
  Sim sim = settled_ball("rr1_rolling_resistance.yaml", GetParam(), Vec3(0, 0, -9.81));
  const double R = sim.state.radius[0];
  sim.state.vx[0] = 1.0;
  sim.state.wy[0] = 1.0 / R;
  const double x0 = sim.state.x[0], t0 = sim.state.time;
  double stop_time = -1;
  while (sim.state.time < t0 + 2.0) {
    sim.advance();
    if (stop_time < 0 && sim.state.vx[0] <= 1e-3) stop_time = sim.state.time - t0;
  }
  const double distance = sim.state.x[0] - x0;
  EXPECT_NEAR(distance, 0.7136, 0.02 * 0.7136);
  EXPECT_NEAR(stop_time, 1.4271, 0.02 * 1.4271);
  // Stop and stay: after a further 0.5 s at rest it has not crept.
  const double x_stop = sim.state.x[0];
  for (double until = sim.state.time + 0.5; sim.state.time < until;) sim.advance();
  EXPECT_LT(std::abs(sim.state.x[0] - x_stop), 1e-5);
  EXPECT_LT(std::abs(sim.state.vx[0]), 1e-3);
}

TEST_P(RollingModels, RR2BallOnInclineRestsBelowCriticalAngleAndRollsAbove) {
  // RR-2: at rest for tan(theta) <= mu_r (theta_c = 5.71 deg for mu_r = 0.1); above,
  // a = (5/7) g (sin theta - mu_r cos theta): 0.52671 m/s^2 at 10 deg. Tolerance 2 %.
  const double g = 9.81;
  {
    const double theta = 5.0 * kDeg;
    Sim sim = settled_ball("rr2_incline.yaml", GetParam(), Vec3(g * std::sin(theta), 0, -g * std::cos(theta)));
    const double x0 = sim.state.x[0];
    for (double until = sim.state.time + 0.5; sim.state.time < until;) sim.advance();
    EXPECT_LT(std::abs(sim.state.x[0] - x0), 1e-4) << "5 deg must hold";
  }
  {
    const double theta = 10.0 * kDeg;
    Sim sim = settled_ball("rr2_incline.yaml", GetParam(), Vec3(g * std::sin(theta), 0, -g * std::cos(theta)));
    // Measure the acceleration between 0.2 s and 0.7 s of rolling (past the onset).
    for (double until = sim.state.time + 0.2; sim.state.time < until;) sim.advance();
    const double v1 = sim.state.vx[0], t1 = sim.state.time;
    for (double until = sim.state.time + 0.5; sim.state.time < until;) sim.advance();
    const double a = (sim.state.vx[0] - v1) / (sim.state.time - t1);
    EXPECT_NEAR(a, 0.52671, 0.02 * 0.52671);
    // Rolling without slip: contact point at rest.
    EXPECT_NEAR(sim.state.vx[0] - sim.state.radius[0] * sim.state.wy[0], 0.0, 1e-3 * sim.state.vx[0]);
  }
}

INSTANTIATE_TEST_SUITE_P(AiModelAandC, RollingModels, ::testing::Values("cdt", "epsd"));

}  // namespace
}  // namespace dem::test
