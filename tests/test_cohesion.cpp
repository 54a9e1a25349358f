// Cohesion: liquid bridge force and rupture, JKR pull-off and hysteresis, SJKR area law.
// Reference numbers: validation LB-1, LB-2 (section E of the reference output), F.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/forces.h"
#include "sim.h"

namespace dem::test {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(LiquidBridge, ForceFollowsWillettEquation12) {
  // Water, R = 1 mm beads, theta = 0, V = 0.419 nL (liquid content 0.003 shared by 6 bridges):
  // F(S) from validation E, column "Willett eq12" [mN]; F(0) = 2 pi R gamma = 0.45239 mN.
  const Model model = compile(load_case("liquid_bridge_pair.yaml"));
  OneContact c(model, 1e-3, 1e-3, 1e-8);
  const double touching = c.force_at(model, 1e-9);
  EXPECT_NEAR(touching - c.b.fn_elastic[0], -0.45239e-3, 0.005 * 0.45239e-3);
  const std::pair<double, double> curve[] = {{8.190e-6, 0.38570e-3}, {16.380e-6, 0.31727e-3}, {40.949e-6, 0.16974e-3},
                                             {81.899e-6, 0.07145e-3}, {122.848e-6, 0.03770e-3}};
  for (auto [separation, force] : curve) EXPECT_NEAR(c.force_at(model, -separation), -force, 0.005 * force) << separation;
}

TEST(LiquidBridge, FormsOnContactHoldsWhileSeparatingRupturesAtLianDistance) {
  // LB-1: rupture at (1 + theta/2) V^(1/3) = 161.20 um for V = 0.419 nL, theta = 0.
  const Model model = compile(load_case("liquid_bridge_pair.yaml"));
  OneContact c(model, 1e-3, 1e-3, 1e-8);
  EXPECT_EQ(c.force_at(model, -50e-6), 0.0) << "no bridge before the beads have touched";
  c.force_at(model, 1e-7);  // touch: the bridge forms
  EXPECT_LT(c.force_at(model, -100e-6), 0.0) << "bridge holds while separating";
  EXPECT_LT(c.force_at(model, -161.0e-6), 0.0) << "still holds just before the Lian distance";
  EXPECT_EQ(c.force_at(model, -161.4e-6), 0.0) << "ruptured just beyond it";
  EXPECT_EQ(c.force_at(model, -100e-6), 0.0) << "stays ruptured until the next contact";
  EXPECT_NEAR(model.interaction_range, 161.20e-6, 0.005 * 161.20e-6);
}

TEST(LiquidBridge, PairPulledApartInSimulationRupturesAtLianDistance) {
  // The same in a run: bead B driven away at constant speed; the last separation at which it
  // still feels a force is the rupture distance.
  CaseSpec spec = load_case("liquid_bridge_pair.yaml");
  spec.particles[1].velocity = Vec3(0.01, 0, 0);
  spec.materials[0].density = 1e5;  // heavy beads: the bridge barely changes the imposed motion
  Sim sim(spec);
  double last_pull = 0;
  while (sim.state.time < 0.05) {
    sim.advance();
    const size_t a = sim.slot(0), b = sim.slot(1);
    sim.state.vx[a] = 0, sim.state.vx[b] = 0.01;  // imposed motion
    const double separation = -overlap_of(sim.state, a, b);
    if (sim.state.fx[b] < 0) last_pull = separation;
    if (separation > 200e-6) break;
  }
  EXPECT_NEAR(last_pull, 161.20e-6, 0.01 * 161.20e-6);
}

TEST(Jkr, PullOffForceIsThreeHalvesPiWR) {
  // F = 3/2 pi W R*, W = 2 gamma: gamma = 0.05 J/m^2 (W = 0.1), sphere on wall R* = 1 mm: 0.47124 mN;
  // two 1 mm-radius beads R* = 0.5 mm: 0.23562 mN (validation F). Tolerance 0.5 %.
  const Model model = compile(load_case("jkr_pull_off.yaml"));
  for (auto [r_j, expected] : {std::pair{0.0, 1.5 * kPi * 0.1 * 1e-3}, std::pair{1e-3, 1.5 * kPi * 0.1 * 0.5e-3}}) {
    OneContact c(model, 1e-3, r_j, 1e-8);
    c.force_at(model, 1e-6);  // touch
    double most_tensile = 0, last_overlap = 1e-6;
    for (double overlap = 1e-6; overlap > -1e-6; overlap -= 1e-10) {
      const double f = c.force_at(model, overlap);
      if (f < most_tensile) most_tensile = f;
      if (f != 0.0) last_overlap = overlap;
    }
    EXPECT_NEAR(-most_tensile, expected, 0.005 * expected) << "R_j = " << r_j;
    // The neck breaks where d(delta)/da = 0, a_c^3 = pi W R^2 / (8 E*).
    const double E = model.pair_row(0)[0], R = c.b.r_eff[0], W = 0.1;
    const double a_c = std::cbrt(kPi * W * R * R / (8 * E));
    const double delta_c = a_c * a_c / R - std::sqrt(2 * kPi * W * a_c / E);
    EXPECT_NEAR(last_overlap, delta_c, 2e-10) << "R_j = " << r_j;
  }
}

TEST(Jkr, NoAttractionBeforeFirstContact) {
  const Model model = compile(load_case("jkr_pull_off.yaml"));
  OneContact c(model, 1e-3, 0.0, 1e-8);
  EXPECT_EQ(c.force_at(model, -1e-8), 0.0);
  EXPECT_LT(c.force_at(model, 1e-9), 0.0) << "just touching, the neck pulls";
}

TEST(Jkr, ForceFollowsTheContactRadiusWhateverThePath) {
  // On the stable branch each contact radius a gives the overlap delta = a^2/R* - sqrt(2 pi W a / E*)
  // and the force F = 4 E* a^3 / (3 R*) - sqrt(8 pi W E* a^3) in closed form. The kernel solves
  // for a from the step before; jumps of the overlap in either direction must give the same
  // force as the closed form, to 1e-9 of the pull-off force.
  const Model model = compile(load_case("jkr_pull_off.yaml"));
  OneContact c(model, 1e-3, 1e-3, 1e-8);
  const double E = model.pair_row(0)[0], R = c.b.r_eff[0], W = 0.1;
  const double a_c = std::cbrt(kPi * W * R * R / (8 * E)), pull_off = 1.5 * kPi * W * R;
  c.force_at(model, 1e-6);  // touch
  for (const double ratio : {1.05, 20.0, 3.0, 1.5, 60.0, 1.01, 8.0}) {
    const double a = ratio * a_c;
    const double overlap = a * a / R - std::sqrt(2 * kPi * W * a / E);
    const double expected = 4 * E * a * a * a / (3 * R) - std::sqrt(8 * kPi * W * E * a * a * a);
    EXPECT_NEAR(c.force_at(model, overlap), expected, 1e-9 * pull_off) << "a = " << ratio << " a_c";
  }
}

TEST(Sjkr, ForceIsCohesionEnergyDensityTimesContactArea) {
  // k = 3e5 J/m^3, two R = 1 mm spheres: overlap 2 um -> 1.88401 mN, 20 um -> 18.75531 mN.
  CaseSpec spec = load_case("jkr_pull_off.yaml");
  spec.contact.adhesion = {ContactSpec::Choice{"sjkr", {}, {}}};
  spec.materials[0].params = {{"cohesion_energy_density", 3e5}, {"restitution", 0.5}};
  const Model model = compile(spec);
  OneContact c(model, 1e-3, 1e-3, 1e-8);
  for (auto [overlap, force] : {std::pair{2e-6, 1.88401e-3}, std::pair{20e-6, 18.75531e-3}}) {
    const double total = c.force_at(model, overlap);
    EXPECT_NEAR(c.b.fn_elastic[0] - total, force, 0.005 * force) << overlap;
  }
}

}  // namespace
}  // namespace dem::test
