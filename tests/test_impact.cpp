// Normal impacts against closed form: Chung & Ooi (2011) tests 1-3, linear spring CL-3.
// Reference numbers: validation CO-1, CO-2, CO-3, CL-3 (computed from the closed forms and
// ODE integrations of the same laws; written here so the suite needs nothing outside the project).
#include <gtest/gtest.h>

#include <algorithm>

#include "sim.h"
#include "validation/validation.h"

namespace dem::test {
namespace {

using validation::ImpactRecord;
using validation::record_impact;

TEST(ChungOoi, Test1GlassSpheresElasticHertz) {
  // CO-1 glass: total overlap 274.11 um, 10.697 kN, 40.34 us; tolerance 1 %.
  const ImpactRecord r = record_impact(load_case("co1_elastic_impact.yaml"), 1e-4);
  EXPECT_NEAR(r.max_overlap, 274.11e-6, 0.01 * 274.11e-6);
  EXPECT_NEAR(r.max_force, 10.697e3, 0.01 * 10.697e3);
  EXPECT_NEAR(r.contact_time, 40.34e-6, 0.01 * 40.34e-6);
  EXPECT_NEAR(r.rebound_speed, 10.0, 1e-4 * 10.0);  // elastic: speed returns to 1e-4
}

TEST(ChungOoi, Test1LimestoneSpheresElasticHertz) {
  // CO-1 limestone (E 20 GPa, nu 0.25, rho 2500): 368.30 um, 7.108 kN, 54.20 us.
  CaseSpec spec = load_case("co1_elastic_impact.yaml");
  spec.materials[0].youngs_modulus = 2.0e10;
  spec.materials[0].poisson_ratio = 0.25;
  spec.materials[0].density = 2500;
  const ImpactRecord r = record_impact(spec, 1e-4);
  EXPECT_NEAR(r.max_overlap, 368.30e-6, 0.01 * 368.30e-6);
  EXPECT_NEAR(r.max_force, 7.108e3, 0.01 * 7.108e3);
  EXPECT_NEAR(r.contact_time, 54.20e-6, 0.01 * 54.20e-6);
}

TEST(ChungOoi, Test2AlAndMgAlloySpheresOnRigidPlane) {
  // CO-2: Al alloy 49.72 um, 11.370 kN, 731.7 us; Mg alloy 52.12 um, 7.233 kN, 767.1 us.
  struct Row { double E, nu, rho, overlap, force, time; };
  for (const Row& row : {Row{7.0e10, 0.30, 2699, 49.72e-6, 11.370e3, 731.66e-6},
                         Row{4.0e10, 0.35, 1800, 52.12e-6, 7.233e3, 767.07e-6}}) {
    CaseSpec spec = load_case("co2_sphere_wall.yaml");
    spec.materials[0].youngs_modulus = row.E;
    spec.materials[0].poisson_ratio = row.nu;
    spec.materials[0].density = row.rho;
    const ImpactRecord r = record_impact(spec, 2e-3);
    EXPECT_NEAR(r.max_overlap, row.overlap, 0.01 * row.overlap) << "E = " << row.E;
    EXPECT_NEAR(r.max_force, row.force, 0.01 * row.force) << "E = " << row.E;
    EXPECT_NEAR(r.contact_time, row.time, 0.01 * row.time) << "E = " << row.E;
    EXPECT_NEAR(r.rebound_speed, 0.2, 1e-4 * 0.2);
  }
}

double restitution_obtained(const std::string& end_of_contact, const std::string& normal, double e_in, double* contact_time = nullptr) {
  return validation::restitution_obtained(std::string(DEMDESIGN_SOURCE_DIR) + "/cases", end_of_contact, normal, e_in, contact_time);
}

TEST(ChungOoi, Test3RestitutionTensionAllowedIsExact) {
  // CO-3: with tension allowed at the end of contact, e obtained = e asked (abs 0.005).
  for (double e : {0.2, 0.4, 0.6, 0.8, 1.0}) EXPECT_NEAR(restitution_obtained("tension", "hertz", e), e, 0.005) << e;
}

TEST(ChungOoi, Test3RestitutionClippedForceComesOutHigher) {
  // CO-3 pitfall, ODE-integrated: clipping at zero gives 0.2 -> 0.32486, 0.4 -> 0.47201,
  // 0.6 -> 0.63229, 0.8 -> 0.80810, 1 -> 1.
  const std::pair<double, double> table[] = {{0.2, 0.32486}, {0.4, 0.47201}, {0.6, 0.63229}, {0.8, 0.80810}, {1.0, 1.0}};
  for (auto [e_in, e_out] : table) EXPECT_NEAR(restitution_obtained("clip", "hertz", e_in), e_out, 0.005) << e_in;
}

TEST(ChungOoi, Test3DampedHertzContactTimes) {
  // ODE contact durations for Al oxide (validation B): e 1: 6.105 us, 0.5: 6.674 us, 0.2: 7.911 us.
  for (auto [e, t] : {std::pair{1.0, 6.105e-6}, std::pair{0.5, 6.674e-6}, std::pair{0.2, 7.911e-6}}) {
    double contact_time = 0;
    restitution_obtained("tension", "hertz", e, &contact_time);
    EXPECT_NEAR(contact_time, t, 0.01 * t) << e;
  }
}

TEST(LinearSpring, RestitutionAndContactTimeMatchClosedForm) {
  // CL-3: kn = 6.08596e7 N/m from V_char = 3.9 m/s; e exact; t_c = pi / sqrt(kn/m - (gn/2m)^2):
  // 6.516 us (e = 1), 6.673 us (0.5), 7.321 us (0.2).
  for (auto [e, t] : {std::pair{1.0, 6.516e-6}, std::pair{0.5, 6.673e-6}, std::pair{0.2, 7.321e-6}}) {
    double contact_time = 0;
    EXPECT_NEAR(restitution_obtained("tension", "linear", e, &contact_time), e, 0.005) << e;
    EXPECT_NEAR(contact_time, t, 0.01 * t) << e;
  }
}

}  // namespace
}  // namespace dem::test
