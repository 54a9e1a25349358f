// Normal impacts against closed form: Chung & Ooi (2011) tests 1-3, linear spring CL-3.
// Reference numbers: validation CO-1, CO-2, CO-3, CL-3 (computed from the closed forms and
// ODE integrations of the same laws; written here so the suite needs nothing outside the project).
#include <gtest/gtest.h>

#include <algorithm>

#include "sim.h"

namespace dem::test {
namespace {

struct ImpactRecord {
  double max_overlap = 0;   // [m]
  double max_force = 0;     // [N]
  double contact_time = 0;  // [s]
  double rebound_speed = 0; // [m/s] normal speed of the moving particle after contact
};

/// Steps a sphere-sphere (two particles) or sphere-wall (one particle) impact until the bodies
/// have separated, recording overlap, force and the time in contact.
ImpactRecord record_impact(Sim& sim, double max_time) {
  ImpactRecord r;
  bool touched = false;
  const bool pair = sim.state.size() == 2;
  auto overlap = [&]() {
    const State& s = sim.state;
    return pair ? overlap_of(s, 0, 1) : s.radius[0] - s.z[0];
  };
  while (sim.state.time < max_time) {
    sim.advance();
    const double d = overlap();
    if (d > 0) {
      touched = true;
      r.contact_time += sim.model.dt;
      r.max_overlap = std::max(r.max_overlap, d);
      const State& s = sim.state;
      r.max_force = std::max(r.max_force, std::sqrt(s.fx[0] * s.fx[0] + s.fy[0] * s.fy[0] + s.fz[0] * s.fz[0]));
    } else if (touched) {
      break;
    }
  }
  const State& s = sim.state;
  r.rebound_speed = pair ? std::abs(s.vx[0]) : s.vz[0];
  return r;
}

TEST(ChungOoi, Test1GlassSpheresElasticHertz) {
  // CO-1 glass: total overlap 274.11 um, 10.697 kN, 40.34 us; tolerance 1 %.
  Sim sim(load_case("co1_elastic_impact.yaml"));
  const ImpactRecord r = record_impact(sim, 1e-4);
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
  Sim sim(spec);
  const ImpactRecord r = record_impact(sim, 1e-4);
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
    Sim sim(spec);
    const ImpactRecord r = record_impact(sim, 2e-3);
    EXPECT_NEAR(r.max_overlap, row.overlap, 0.01 * row.overlap) << "E = " << row.E;
    EXPECT_NEAR(r.max_force, row.force, 0.01 * row.force) << "E = " << row.E;
    EXPECT_NEAR(r.contact_time, row.time, 0.01 * row.time) << "E = " << row.E;
    EXPECT_NEAR(r.rebound_speed, 0.2, 1e-4 * 0.2);
  }
}

double restitution_obtained(const std::string& end_of_contact, const std::string& normal, double e_in,
                            double* contact_time = nullptr) {
  CaseSpec spec = load_case("co3_restitution.yaml");
  for (auto& m : spec.materials) m.params["restitution"] = e_in;
  spec.contact.damping.options["end_of_contact"] = end_of_contact;
  spec.contact.normal.model = normal;
  if (normal == "linear")  // LIGGGHTS hooke stiffness from V_char = 3.9 m/s (validation CL-3)
    for (auto& m : spec.materials) m.params["characteristic_velocity"] = 3.9;
  Sim sim(spec);
  const ImpactRecord r = record_impact(sim, 1e-4);
  if (contact_time) *contact_time = r.contact_time;
  return r.rebound_speed / 3.9;
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
