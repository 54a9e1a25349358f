// Clumps as rigid bodies: template mass properties through the model, torque-free rotation
// (angular momentum and energy conserved, intermediate-axis instability), contact with walls.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "bodies/rigid_body.h"
#include "sim.h"

namespace dem::test {
namespace {

constexpr double kPi = std::numbers::pi;

/// A case with one clump `spheres` (YAML list) of material density 1000, no gravity, no walls.
CaseSpec one_clump(const std::string& spheres, const std::string& angular_velocity) {
  return parse_case_text(
      "simulation: {duration: 1.0, gravity: [0, 0, 0], time_step: 1e-4, unsafe_time_step: warn}\n"
      "materials:\n  m: {density: 1000, youngs_modulus: 1e7, restitution: 0.5}\n"
      "clumps:\n  c:\n    spheres: " + spheres + "\n"
      "particles:\n  - {material: m, clump: c, diameter: 0.01, positions: [[0, 0, 0]], angular_velocity: " +
          angular_velocity + "}\n",
      "one_clump");
}

double kinetic_energy(const State& s) {
  const Bodies& b = s.bodies;
  const double momentum[3] = {b.lx[0], b.ly[0], b.lz[0]};
  double pi[3];
  rotate_back({b.qw[0], b.qx[0], b.qy[0], b.qz[0]}, momentum, pi);
  return 0.5 * (pi[0] * pi[0] / b.ix[0] + pi[1] * pi[1] / b.iy[0] + pi[2] * pi[2] / b.iz[0]);
}

TEST(Clumps, DumbbellTemplateGetsExactMassAndInertia) {
  // Two touching spheres of diameter D (no overlap): volume-equivalent diameter 2^(1/3) D.
  // Instance with d_eq = 0.01 m: sphere radius r = 0.005 / 2^(1/3); Ixx = 2 (2/5 m r^2),
  // Iyy = Izz = 2 (2/5 m r^2 + m r^2), m = rho 4/3 pi r^3 each.
  Sim sim(one_clump("[{centre: [-0.5, 0, 0], diameter: 1}, {centre: [0.5, 0, 0], diameter: 1}]", "[0, 0, 0]"));
  const Bodies& b = sim.state.bodies;
  ASSERT_EQ(b.size(), 1u);
  const double r = 0.005 / std::cbrt(2.0), m = 1000 * 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(b.mass[0], 2 * m, 1e-9 * m);
  const double axial = 2 * 0.4 * m * r * r, transverse = 2 * (0.4 * m * r * r + m * r * r);
  EXPECT_NEAR(b.ix[0], axial, 1e-6 * axial);  // principal moments ascending: axis first
  EXPECT_NEAR(b.iy[0], transverse, 1e-6 * transverse);
  EXPECT_NEAR(b.iz[0], transverse, 1e-6 * transverse);
  EXPECT_EQ(sim.state.size(), 2u);
  EXPECT_NEAR(sim.state.radius[0], r, 1e-12);
}

TEST(Clumps, SmallAngleSineAndCosineMatchTheLibrary) {
  // The series used below 0.1 rad agrees with libm to a few units in the last place, and the
  // library itself is used above.
  for (double x = -0.2; x <= 0.2; x += 1.37e-4) {
    double s = 0, c = 0;
    sin_cos(x, s, c);
    EXPECT_NEAR(s, std::sin(x), 4e-17 + 2e-16 * std::abs(std::sin(x))) << x;
    EXPECT_NEAR(c, std::cos(x), 2.5e-16) << x;
  }
  double s = 0, c = 0;
  sin_cos(1e-9, s, c);
  EXPECT_DOUBLE_EQ(s, 1e-9);
  EXPECT_DOUBLE_EQ(c, 1.0);
}

TEST(Clumps, TorqueFreeRotationConservesMomentumAndEnergy) {
  // An asymmetric clump spinning about a generic axis: L exactly, E to 1e-5 over 10^4 steps.
  Sim sim(one_clump("[{centre: [0, 0, 0], diameter: 1}, {centre: [0.6, 0, 0], diameter: 0.8}, "
                    "{centre: [0, 0.5, 0], diameter: 0.6}]",
                    "[3, -7, 11]"));
  const Bodies& b = sim.state.bodies;
  const double l0[3] = {b.lx[0], b.ly[0], b.lz[0]};
  const double e0 = kinetic_energy(sim.state);
  for (int k = 0; k < 10000; ++k) sim.advance();
  EXPECT_EQ(b.lx[0], l0[0]);
  EXPECT_EQ(b.ly[0], l0[1]);
  EXPECT_EQ(b.lz[0], l0[2]);
  EXPECT_NEAR(kinetic_energy(sim.state), e0, 1e-5 * e0);
  const double q2 = b.qw[0] * b.qw[0] + b.qx[0] * b.qx[0] + b.qy[0] * b.qy[0] + b.qz[0] * b.qz[0];
  EXPECT_NEAR(q2, 1.0, 1e-12);
}

TEST(Clumps, IntermediateAxisIsUnstableAndOthersAreStable) {
  // Three collinear-free spheres give distinct principal moments. Spinning about the axis of
  // the largest or smallest moment (plus a 1e-3 perturbation) stays put; about the
  // intermediate axis the body flips (Dzhanibekov effect): the body-frame momentum component
  // along that axis reverses sign, while |L| and E stay conserved.
  const std::string spheres = "[{centre: [-0.6, 0, 0], diameter: 1}, {centre: [0.6, 0, 0], diameter: 1}, "
                              "{centre: [0, 0.45, 0], diameter: 0.7}]";
  for (int axis = 0; axis < 3; ++axis) {
    Sim sim(one_clump(spheres, "[0, 0, 0]"));
    Bodies& b = sim.state.bodies;
    ASSERT_LT(b.ix[0], b.iy[0]);
    ASSERT_LT(b.iy[0], b.iz[0]);
    // Body-frame momentum: 20 rad/s about `axis`, 1e-3 of that about the others.
    const double inertia[3] = {b.ix[0], b.iy[0], b.iz[0]};
    double pi[3] = {0.02 * inertia[0], 0.02 * inertia[1], 0.02 * inertia[2]};
    pi[axis] = 20.0 * inertia[axis];
    double l[3];
    const Quaternion q{b.qw[0], b.qx[0], b.qy[0], b.qz[0]};
    rotate(q, pi, l);
    b.lx[0] = l[0], b.ly[0] = l[1], b.lz[0] = l[2];
    const double e0 = kinetic_energy(sim.state);
    double smallest_ratio = 1.0;
    for (int k = 0; k < 20000; ++k) {  // 2 s, tens of turns
      sim.advance();
      double now[3];
      rotate_back({b.qw[0], b.qx[0], b.qy[0], b.qz[0]}, l, now);
      smallest_ratio = std::min(smallest_ratio, now[axis] / pi[axis]);
    }
    EXPECT_NEAR(kinetic_energy(sim.state), e0, 1e-5 * e0) << "axis " << axis;
    if (axis == 1) EXPECT_LT(smallest_ratio, -0.9) << "intermediate axis must flip";
    else EXPECT_GT(smallest_ratio, 0.99) << "axis " << axis << " must stay stable";
  }
}

TEST(Clumps, PouredClumpsComeToRestOnTheFloorWithoutOverlapping) {
  CaseSpec spec = load_case("clump_pour.yaml");
  spec.particles[0].count = 60;
  Sim sim(spec);
  EXPECT_EQ(sim.state.bodies.size(), 60u);
  EXPECT_EQ(sim.state.size(), 180u);
  while (sim.state.time < 0.4) sim.advance();
  const Scalars s = measure(sim.model, sim.state, sim.work);
  // At rest: under 1 % of the potential energy they fell through (about 1.4e-2 J).
  EXPECT_LT(s.kinetic_translation + s.kinetic_rotation, 1.4e-4);
  EXPECT_LT(s.max_overlap_ratio, 0.05);
  for (size_t p = 0; p < sim.state.size(); ++p) EXPECT_GT(sim.state.z[p], 0.0);
}

}  // namespace
}  // namespace dem::test
