// Oblique impacts and spin: Chung & Ooi (2011) tests 4 to 8 (validation CO-4 to CO-7).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <string>

#include "sim.h"
#include "validation/validation.h"

namespace dem::test {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

using validation::CurvePoint;
using validation::Rebound;
using validation::Test5Result;

const std::string kCases = std::string(DEMDESIGN_SOURCE_DIR) + "/cases";

Rebound oblique_impact(double angle_deg) { return validation::test4_impact(kCases, angle_deg); }
double test6_beta(double chi, const std::string& coulomb_cap, bool nylon = false) { return validation::test6_beta(kCases, chi, coulomb_cap, nylon); }
Test5Result test5(double psi1) { return validation::test5(kCases, psi1); }
double test8_beta(double chi) { return validation::test8_beta(kCases, chi); }

TEST(ChungOoi, Test4SlidingRegimeMatchesRigidBodyResult) {
  // CO-4, gross sliding (theta >= 32.5 deg), exact: Vt' = Vt - mu (1+e) Vn,
  // w' = -(5/2) mu (1+e) Vn / R, patch angle atan((Vt' + R w')/(e Vn)). Tolerance 1 %.
  const double e = 0.98, mu = 0.092, R = 0.0025;
  for (double angle : {35.0, 45.0, 60.0, 80.0}) {
    const double vn = 3.9 * std::cos(angle * kDeg), vt = 3.9 * std::sin(angle * kDeg);
    const double vt_after = vt - mu * (1 + e) * vn;
    const double w_after = -2.5 * mu * (1 + e) * vn / R;
    const Rebound r = oblique_impact(angle);
    EXPECT_NEAR(r.vx / vt, vt_after / vt, 0.01 * vt_after / vt) << angle;
    // Our spin about +y: contact-point velocity vx - R wy; the paper's w' has the sign of the
    // contact-point slip reduction, so w_paper = -wy.
    EXPECT_NEAR(-r.wy, w_after, 0.01 * std::abs(w_after)) << angle;
    const double patch = std::atan((r.vx - R * r.wy) / r.vz) / kDeg;
    const double expected_patch = std::atan((vt - 3.5 * mu * (1 + e) * vn) / (e * vn)) / kDeg;
    EXPECT_NEAR(patch, expected_patch, 0.01 * std::abs(expected_patch) + 0.05) << angle;
  }
  // Spot values printed in validation CO-4: 45 deg e_t 0.81784, w' -502.35 rad/s, patch 20.296 deg.
  const Rebound r45 = oblique_impact(45.0);
  EXPECT_NEAR(r45.vx / (3.9 * std::sin(45 * kDeg)), 0.81784, 0.01 * 0.81784);
  EXPECT_NEAR(r45.wy, 502.35, 0.01 * 502.35);
}

TEST(ChungOoi, Test4StickingRegimeGivesNegativeReboundAngles) {
  // CO-4: below about 30 degrees tangential compliance reverses the contact-patch velocity
  // (Maw, Barber & Fawcett 1976): the patch rebound angle must be negative somewhere in 10-30 deg,
  // while it is positive in the sliding regime.
  const double R = 0.0025;
  double most_negative = 0;
  for (double angle : {10.0, 15.0, 20.0, 25.0, 30.0}) {
    const Rebound r = oblique_impact(angle);
    most_negative = std::min(most_negative, std::atan((r.vx - R * r.wy) / r.vz) / kDeg);
  }
  EXPECT_LT(most_negative, -1.0);
}

TEST(ChungOoi, Test6SpinningSphereOnPlaneSlidingRegime) {
  // CO-6: chi = 3.5 mu (1+e) Vn / Vtc; sliding (chi <= 1): beta = -Vtc'/Vtc = chi - 1. Tol 2 %.
  // The closed form takes the normal impulse as m (1+e) Vn. The no-tension convention makes that
  // exact for the impulse friction sees (with tension allowed, friction sees only the
  // compressive part, 3 % more than m (1+e) Vn at e = 0.5), so e is taken from the rebound.
  const double mu = 0.4, vn = 0.2, R = 0.1;
  for (double angle : {67.5, 70.0, 75.0, 80.0, 85.0}) {  // chi = 0.94 ... 0.19
    const double vtc = vn * std::tan(angle * kDeg);
    CaseSpec spec = load_case("co6_spin_impact.yaml");
    spec.contact.damping.options["end_of_contact"] = "clip";
    spec.particles[0].angular_velocity = Vec3(0, -vtc / R, 0);  // contact point moves at +vtc in x
    const Rebound r = validation::bounce(spec, 5e-3);
    const double e = r.vz / vn;
    const double vtc_after = r.vx - R * r.wy;
    const double chi = 3.5 * mu * (1 + e) * vn / vtc;
    ASSERT_LE(chi, 1.0);
    EXPECT_NEAR(-vtc_after / vtc, chi - 1.0, 0.02 * std::abs(chi - 1.0) + 1e-3) << angle;
    EXPECT_NEAR(e, 0.55028, 0.005) << "no-tension restitution for e = 0.5 (validation CO-3)";
  }
}

// --- Chung & Ooi tests 5, 6 and 8 against the paper's curves --------------------------------
// Published points: Chung & Ooi (2011) figures as digitised by the Kratos DEMApplication team
// (KratosMultiphysics/Kratos, applications/DEMApplication/test_examples/basic_benchmarks/
// paper_data/benchmark6_graph1.dat @1bfdba24, benchmark5_graph{1,2}.dat @650ccb26, and
// tests/DEM3D_chung_ooi_tests/paper_data_5_to_8/benchmark8_graph1.dat @5924ef79). On the sliding
// points, where beta = chi - 1 exactly, the digitised values sit up to 0.016 off.
//
// Tolerances for a curve of beta: each point within 0.04 (validation CO-6 asks 0.03 for chi > 1;
// 0.01 more for the digitisation), and the curve's error as Kratos measures it,
// sum |beta - beta_paper| / sum |beta_paper|, at most 10 % (Kratos' bound for test 4's curves).

/// Checks the model's values against a published curve with the tolerances above.
template <typename Model>
void expect_curve(std::span<const CurvePoint> paper, Model model, double point_tolerance = 0.04) {
  double error = 0, size = 0;
  for (const CurvePoint& p : paper) {
    const double value = model(p.x);
    EXPECT_NEAR(value, p.y, point_tolerance) << "at " << p.x;
    error += std::abs(value - p.y);
    size += std::abs(p.y);
  }
  EXPECT_LE(error / size, 0.10);
}

// Test 6, beta against chi: aluminium alloy and nylon spheres (app/validation/validation.cpp holds the curves).
TEST(ChungOoi, Test6SpringCapReproducesThePublishedCurveOfAluminium) {
  // coulomb_cap: spring, sliding and sticking regimes up to chi = 5.75 (largest deviation 0.034,
  // at chi 2.5-3.0).
  expect_curve(validation::kTest6Aluminium, [](double chi) { return test6_beta(chi, "spring"); });
  // Beyond chi = 6.2 the contact no longer slides at the end of the impact and beta levels off at
  // -0.11, where the aluminium curve keeps falling; the nylon curve of the same figure and the
  // paper's test 8 case B level off at -0.11 as the model does (below). Checked here as a known
  // difference, so that a change of the model there is seen.
  for (const CurvePoint& p : validation::kTest6AluminiumTail) {
    const double beta = test6_beta(p.x, "spring");
    EXPECT_NEAR(beta, -0.112, 0.005) << "chi " << p.x;
    EXPECT_GT(beta - p.y, 0.09) << "chi " << p.x;
  }
}

TEST(ChungOoi, Test6SpringCapReproducesThePublishedCurveOfNylon) {
  // The whole curve, chi 0.18 ... 24, with its jump between chi 5.8 and 7.8 (largest deviation
  // 0.013, on a sliding point).
  expect_curve(validation::kTest6Nylon, [](double chi) { return test6_beta(chi, "spring", true); }, 0.03);
}

TEST(ChungOoi, Test6TotalCapKeepsItsNumbers) {
  // The default cap (coulomb_cap: total) is unchanged: its beta at the paper's chi (values of
  // 2026-12-03 at 59f3876's default kernel, which the spring cap left as it was). It misses the
  // sticking regime of the paper: peak 0.166 at chi 1.45 (paper 0.119), sign change near chi 3.4
  // (paper 2.5), -0.084 at chi 24. An independent integration of the same law gives these to 0.001.
  constexpr CurvePoint kTotalCap[] = {
      {0.1762, -0.81794171893945389},  {0.3524, -0.63588343787890733},  {0.5507, -0.43099037809283464},
      {0.7709, -0.20346918916245865},  {0.9692, 0.0014238706236152907}, {1.1894, 0.13389653545883221},
      {1.4537, 0.16623628181506794},   {1.7401, 0.16384581856254068},   {2.0925, 0.14076518075944258},
      {2.4890, 0.10225490372587195},   {2.9956, 0.046251601781862592},  {3.6344, -0.023385499212948208},
      {4.5154, -0.098325138724499342}, {5.7489, -0.067357970004827836}, {7.8194, -0.074193294880743041},
      {11.8943, -0.079026248245371189}, {24.0088, -0.083539850570359259}};
  for (const CurvePoint& p : kTotalCap) EXPECT_NEAR(test6_beta(p.x, "total"), p.y, 1e-9) << "chi " << p.x;
}

// Test 5, steel: psi1 = Vt/(mu Vn) against psi2 = V'ct/(mu V'n) (contact point) and against
// R w'/(mu Vn). Points at which the paper's contact slides throughout.
TEST(ChungOoi, Test5SteelSphereSlidingRegimeMatchesThePaper) {
  // Where the contact slides throughout: R w'/(mu Vn) = -2.5 (1+e) = -5 and psi2 = psi1 - 7
  // (e = 1), and the paper's points; 2 % as Kratos checks test 5 (sliding points only).
  for (const CurvePoint& p : validation::kTest5SteelSpinSliding) {
    const Test5Result r = test5(p.x);
    EXPECT_NEAR(r.spin, -5.0, 0.02 * 5.0) << "psi1 " << p.x;
    EXPECT_NEAR(r.spin, p.y, 0.02 * 5.0) << "psi1 " << p.x;
  }
  for (const CurvePoint& p : validation::kTest5SteelPsi2Sliding) {
    const Test5Result r = test5(p.x);
    EXPECT_NEAR(r.psi2, p.x - 7.0, 0.02 * std::abs(p.x - 7.0)) << "psi1 " << p.x;
    EXPECT_NEAR(r.psi2, p.y, 0.02 * std::abs(p.y)) << "psi1 " << p.x;
  }
}

TEST(ChungOoi, Test5SteelSphereStickingRegimeIsTheNoSlipSpring) {
  // Below psi1 = 5 the paper's DEM curve reverses the contact point in proportion to psi1
  // (psi2 = -0.75 ... -0.85 psi1 up to psi1 = 3.3; its FEM curve stays near 0 up to psi1 = 1),
  // which the Mindlin no-slip stiffness kt = 8 G* a does not do with either cap (e = 1: no
  // damping, and the elastic load is the load). A contact that sticks throughout returns the
  // contact-point velocity almost unchanged: V'ct/Vct = 0.955 for nu = 0.3, from an independent
  // integration of m_t x'' = -kt x (m_t = m/3.5, kt/kn = 6 G*/E* = 1.235, kn = 4/3 E* a) over a
  // Hertz impact; the reversal comes only for psi1 = 1.7 ... 6 (lowest psi2 -1.45 near
  // psi1 = 4.5, paper -2.79 at 4). Checked: that stick limit to 2 %, and where the reversal is.
  const Test5Result small = test5(0.05);
  EXPECT_NEAR(small.psi2 / 0.05, 0.955, 0.02 * 0.955);
  double lowest = 0, at = 0;
  for (double psi1 = 1.0; psi1 <= 7.0; psi1 += 0.5) {
    const Test5Result r = test5(psi1);
    if (r.psi2 < lowest) lowest = r.psi2, at = psi1;
  }
  EXPECT_NEAR(at, 4.5, 0.5);
  EXPECT_LT(lowest, -1.3);
}

// Test 8, beta against chi for the sphere on a larger sphere; cases A and B of the figure agree
// up to chi = 5.77 and part beyond it (A: -0.204, -0.248, -0.318; B: -0.106, -0.108, -0.106).
TEST(ChungOoi, Test8SphereOnLargerSphereMatchesThePublishedCurve) {
  // coulomb_cap: spring (the case's), against case B, which the model follows over the whole
  // range (largest deviation 0.033 at chi 2.99; case A falls beyond chi 6 as test 6's aluminium
  // curve does).
  expect_curve(validation::kTest8CaseB, test8_beta);
}

TEST(ChungOoi, Test7SpinningPairWithoutSlipKeepsItsSpin) {
  // CO-7: equal and opposite spins, no slip at the contact: w' = w0 and Vt' = 0 (1e-6 relative).
  for (double w0 : {0.175, 2.0, 22.86}) {
    const validation::PairRebound r = validation::test7_pair(kCases, w0);
    ASSERT_TRUE(r.touched);
    for (size_t p = 0; p < 2; ++p) {
      const double sign = p == 0 ? 1.0 : -1.0;
      EXPECT_NEAR(r.wy[p], sign * w0, 1e-6 * w0) << w0;
      EXPECT_NEAR(r.vz[p], 0.0, 1e-6 * 0.2) << w0;
      EXPECT_NEAR(std::abs(r.vx[p]), 0.5 * 0.2, 0.005 * 0.1) << w0;  // e = 0.5
    }
  }
}

TEST(CoulombCap, SpringAbsFnCapsTheSpringAtMuTimesTheWholeNormalForce) {
  // One Hertz contact with restitution damping (e = 0.5), friction 0.2, its spring stretched far
  // beyond the limit so that it slides: the tangential force is the capped spring alone, mu times
  // the elastic normal force (`spring`) or mu times |elastic + damping| (`spring_abs_fn`, LIGGGHTS
  // tangential history). Approaching, the damping adds to the load; parting fast, the damped
  // normal force pulls (tension) and its magnitude is still the load.
  for (const std::string cap : {"spring", "spring_abs_fn"}) {
    const Model model = compile(parse_case_text(R"(
simulation: {duration: 1.0e-5, time_step: 1.0e-7, gravity: [0, 0, 0]}
materials: {alumina: {density: 4000, youngs_modulus: 3.8e11, poisson_ratio: 0.23, restitution: 0.5, friction: 0.2}}
contact: {normal: hertz, damping: restitution, tangential: {model: mindlin, coulomb_cap: )" + cap + R"(}}
particles: [{material: alumina, diameter: 0.005, positions: [[0, 0, 0]]}]
)"));
    for (const double vn : {-2.0, 5.0}) {  // [m/s] approaching, parting
      ASSERT_EQ(model.history_width, 3) << "the spring is the only history";
      OneContact c(model, 0.0025, 0.0025, 1.3e-4);  // normal along x
      c.history[1] = 1.0;  // [m] the spring, along y, stretched far beyond any limit
      c.b.vn[0] = vn;
      c.force_at(model, 1e-6);
      const double ft = std::hypot(c.b.ftx[0], c.b.fty[0], c.b.ftz[0]);
      const double load = cap == "spring" ? c.b.fn_elastic[0] : std::abs(c.b.fn[0]);
      EXPECT_NEAR(ft, 0.2 * load, 1e-12 * load) << cap << ", vn " << vn;
      if (vn > 0) {
        EXPECT_LT(c.b.fn[0], 0.0) << "the damping pulls: the test must reach tension";
      } else {
        EXPECT_GT(c.b.fn[0], 1.5 * c.b.fn_elastic[0]) << "the damping must weigh in the load";
      }
    }
  }
}

}  // namespace
}  // namespace dem::test
