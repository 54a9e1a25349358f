#include "validation/validation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/model.h"
#include "core/particles.h"
#include "core/state.h"
#include "core/step.h"
#include "core/workspace.h"

namespace dem::validation {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// A compiled case with its state, stepped one step at a time.
struct Stepper {
  Model model;
  State state;
  Workspace work;
  explicit Stepper(const CaseSpec& spec) : model(compile(spec)), state(initial_state(model)) { prepare(model, state, work); }
  void advance() { step(model, state, work); }
  size_t slot(std::int64_t id) const {
    for (size_t p = 0; p < state.size(); ++p)
      if (state.id[p] == id) return p;
    return 0;
  }
};

double overlap_of(const State& s, size_t i, size_t j) {
  const double dx = s.x[i] - s.x[j], dy = s.y[i] - s.y[j], dz = s.z[i] - s.z[j];
  return s.radius[i] + s.radius[j] - std::sqrt(dx * dx + dy * dy + dz * dz);
}

CaseSpec load(const std::string& cases_dir, const std::string& name) { return parse_case_file(cases_dir + "/" + name); }

constexpr CurvePoint test6_aluminium[] = {
    {0.1762, -0.8200}, {0.3524, -0.6335}, {0.5507, -0.4447}, {0.7709, -0.2428}, {0.9692, -0.0277},
    {1.1894, 0.0974},  {1.4537, 0.1193},  {1.7401, 0.0996},  {2.0925, 0.0579},  {2.4890, 0.0052},
    {2.9956, -0.0497}, {3.6344, -0.1001}, {4.5154, -0.1396}, {5.7489, -0.1748}};
constexpr CurvePoint test6_aluminium_tail[] = {{7.8194, -0.2077}, {11.8943, -0.2582}, {24.0088, -0.3416}};
constexpr CurvePoint test6_nylon[] = {
    {0.1762, -0.8244}, {0.3744, -0.6379}, {0.5727, -0.4425}, {0.7489, -0.2428}, {0.9692, -0.0255}, {1.1894, 0.0930},
    {1.4537, 0.1193},  {1.7401, 0.1171},  {2.0925, 0.0952},  {2.5110, 0.0557},  {2.9956, 0.0074},  {3.6123, -0.0562},
    {4.5154, -0.1199}, {5.7709, -0.1594}, {7.8194, -0.1177}, {11.9163, -0.1133}, {24.0088, -0.1155}};
// Test 4: contact-patch rebound angle [deg] against the impact angle [deg], the paper's DEM curve
// for the alumina sphere (benchmark4_graph3.dat @650ccb26).
constexpr CurvePoint test4_patch_angle[] = {
    {4.9010, 3.7613},   {9.9588, -1.5559},  {14.9346, -5.5438}, {19.9876, -7.5378}, {24.9575, -7.5378},
    {29.9217, -3.5498}, {34.9616, 3.4290},  {39.9197, 11.5710}, {49.8336, 29.3505}, {59.9871, 47.7946},
    {69.7422, 64.5770}, {79.8218, 78.7009}, {84.7833, 84.5166}};
constexpr CurvePoint test5_psi2_sliding[] = {{9.9879, 3.0133}, {12.9607, 6.0133}};
constexpr CurvePoint test5_spin_sliding[] = {{6.0058, -5.0062}, {10.0116, -5.0041}, {20.0000, -4.9905}};
constexpr CurvePoint test8_case_b[] = {
    {0.1872, -0.8152}, {0.3583, -0.6262}, {0.5508, -0.4394}, {0.7647, -0.2378}, {0.9786, -0.0173},
    {1.2139, 0.0961},  {1.4920, 0.1108},  {1.7701, 0.0898},  {2.0909, 0.0583},  {2.5187, 0.0058},
    {2.9893, -0.0488}, {3.6310, -0.1034}, {4.5080, -0.1391}, {5.7701, -0.1622}, {7.8449, -0.1055},
    {11.9091, -0.1076}, {23.9947, -0.1055}};

}  // namespace

const std::span<const CurvePoint> kTest4PatchAngle{test4_patch_angle};
const std::span<const CurvePoint> kTest6Aluminium{test6_aluminium};
const std::span<const CurvePoint> kTest6AluminiumTail{test6_aluminium_tail};
const std::span<const CurvePoint> kTest6Nylon{test6_nylon};
const std::span<const CurvePoint> kTest5SteelPsi2Sliding{test5_psi2_sliding};
const std::span<const CurvePoint> kTest5SteelSpinSliding{test5_spin_sliding};
const std::span<const CurvePoint> kTest8CaseB{test8_case_b};

ImpactRecord record_impact(const CaseSpec& spec, double max_time) {
  Stepper sim(spec);
  ImpactRecord r;
  bool touched = false;
  const bool pair = sim.state.size() == 2;
  auto overlap = [&]() { return pair ? overlap_of(sim.state, 0, 1) : sim.state.radius[0] - sim.state.z[0]; };
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
  r.rebound_speed = pair ? std::abs(sim.state.vx[0]) : sim.state.vz[0];
  return r;
}

Rebound bounce(const CaseSpec& spec, double max_time) {
  Stepper sim(spec);
  bool touched = false;
  while (sim.state.time < max_time) {
    sim.advance();
    const bool touching = sim.state.radius[0] - sim.state.z[0] > 0;
    touched |= touching;
    if (touched && !touching) break;
  }
  return {sim.state.vx[0], sim.state.vz[0], sim.state.wy[0]};
}

double restitution_obtained(const std::string& cases_dir, const std::string& end_of_contact, const std::string& normal, double e_in,
                            double* contact_time) {
  CaseSpec spec = load(cases_dir, "co3_restitution.yaml");
  for (auto& m : spec.materials) m.params["restitution"] = e_in;
  spec.contact.damping.options["end_of_contact"] = end_of_contact;
  spec.contact.normal.model = normal;
  if (normal == "linear")  // LIGGGHTS hooke stiffness from V_char = 3.9 m/s
    for (auto& m : spec.materials) m.params["characteristic_velocity"] = 3.9;
  const ImpactRecord r = record_impact(spec, 1e-4);
  if (contact_time) *contact_time = r.contact_time;
  return r.rebound_speed / 3.9;
}

Rebound test4_impact(const std::string& cases_dir, double angle_deg) {
  CaseSpec spec = load(cases_dir, "co4_oblique_impact.yaml");
  spec.particles[0].velocity = Vec3(3.9 * std::sin(angle_deg * kDeg), 0, -3.9 * std::cos(angle_deg * kDeg));
  return bounce(spec, 1e-4);
}

Test5Result test5(const std::string& cases_dir, double psi1) {
  const double mu = 0.3, vn = 5.0, R = 1e-5;
  CaseSpec spec = load(cases_dir, "co5_oblique_constant_vn.yaml");
  spec.particles[0].velocity = Vec3(psi1 * mu * vn, 0, -vn);
  const Rebound r = bounce(spec, 2e-7);
  // The paper's w' turns the contact point against the slip: w_paper = -wy.
  return {(r.vx - R * r.wy) / (mu * r.vz), -R * r.wy / (mu * vn)};
}

double test6_beta(const std::string& cases_dir, double chi, const std::string& coulomb_cap, bool nylon) {
  const double mu = 0.4, e = 0.5, vn = 0.2, R = 0.1;
  const double vtc = 3.5 * mu * (1 + e) * vn / chi;
  CaseSpec spec = load(cases_dir, "co6_spin_impact.yaml");
  spec.contact.tangential.options["coulomb_cap"] = coulomb_cap;
  if (nylon) {  // the paper's nylon: E 2.5 GPa, nu 0.40, 1000 kg/m^3
    spec.materials[0].youngs_modulus = 2.5e9;
    spec.materials[0].poisson_ratio = 0.40;
    spec.materials[0].density = 1000;
  }
  spec.particles[0].angular_velocity = Vec3(0, -vtc / R, 0);  // contact point moves at +vtc in x
  const Rebound r = bounce(spec, 5e-3);
  return -(r.vx - R * r.wy) / vtc;
}

PairRebound test7_pair(const std::string& cases_dir, double w0) {
  CaseSpec spec = load(cases_dir, "co7_spinning_pair.yaml");
  spec.particles[0].angular_velocity = Vec3(0, w0, 0);
  spec.particles[1].angular_velocity = Vec3(0, -w0, 0);
  Stepper sim(spec);
  PairRebound out;
  while (sim.state.time < 5e-3) {
    sim.advance();
    const bool touching = overlap_of(sim.state, 0, 1) > 0;
    out.touched |= touching;
    if (out.touched && !touching) break;
  }
  for (std::int64_t id = 0; id < 2; ++id) {
    const size_t p = sim.slot(id);
    out.wy[id] = sim.state.wy[p], out.vx[id] = sim.state.vx[p], out.vz[id] = sim.state.vz[p];
  }
  return out;
}

double test8_beta(const std::string& cases_dir, double chi) {
  const double mu = 0.4, e = 0.5, vn = 0.2, R = 0.1, R_large = 0.5;
  const double vtc = 3.5 * mu * (1 + e) * vn / chi;
  CaseSpec spec = load(cases_dir, "co8_sphere_on_large_sphere.yaml");
  spec.particles[0].angular_velocity = Vec3(0, -vtc / R, 0);  // contact point moves at +vtc in z
  Stepper sim(spec);
  const size_t small = sim.slot(0), large = sim.slot(1);
  bool touched = false;
  while (sim.state.time < 5e-3) {
    sim.advance();
    const bool touching = overlap_of(sim.state, small, large) > 0;
    touched |= touching;
    if (touched && !touching) break;
  }
  if (!touched) return std::nan("");
  const State& s = sim.state;
  // Contact-point velocity of the small sphere relative to the large one, along z.
  const double vtc_after = (s.vz[small] - R * s.wy[small]) - (s.vz[large] + R_large * s.wy[large]);
  return -vtc_after / vtc;
}

std::vector<Point> run_benchmarks(const std::string& cases_dir) {
  std::vector<Point> out;
  const std::string paper6 = "Chung & Ooi (2011), test 6 (Kratos' digitisation, benchmark6_graph1.dat)",
                    paper5 = "Chung & Ooi (2011), test 5 (Kratos' digitisation, benchmark5_graph1.dat and _graph2.dat)",
                    paper8 = "Chung & Ooi (2011), test 8 case B (Kratos' digitisation, benchmark8_graph1.dat)";
  auto single = [&](const std::string& benchmark, const std::string& quantity, double model, double reference, double relative,
                    const std::string& source) {
    out.push_back({benchmark, quantity, "", 0, model, reference, relative * std::abs(reference), source});
  };
  // Test 1: elastic impact of two equal spheres at 10 m/s (Hertz closed form, 1 %).
  struct Normal {
    const char* name;
    double E, nu, rho, overlap, force, time;
  };
  for (const Normal& n : {Normal{"CO1 glass", 4.8e10, 0.20, 2800, 274.11e-6, 10.697e3, 40.34e-6},
                          Normal{"CO1 limestone", 2.0e10, 0.25, 2500, 368.30e-6, 7.108e3, 54.20e-6}}) {
    CaseSpec spec = load(cases_dir, "co1_elastic_impact.yaml");
    spec.materials[0].youngs_modulus = n.E, spec.materials[0].poisson_ratio = n.nu, spec.materials[0].density = n.rho;
    const ImpactRecord r = record_impact(spec, 1e-4);
    single(n.name, "peak overlap [m]", r.max_overlap, n.overlap, 0.01, "Hertz closed form");
    single(n.name, "peak force [N]", r.max_force, n.force, 0.01, "Hertz closed form");
    single(n.name, "contact time [s]", r.contact_time, n.time, 0.01, "Hertz closed form");
  }
  // Test 2: a sphere onto a rigid plane at 0.2 m/s.
  for (const Normal& n : {Normal{"CO2 Al alloy", 7.0e10, 0.30, 2699, 49.72e-6, 11.370e3, 731.66e-6},
                          Normal{"CO2 Mg alloy", 4.0e10, 0.35, 1800, 52.12e-6, 7.233e3, 767.07e-6}}) {
    CaseSpec spec = load(cases_dir, "co2_sphere_wall.yaml");
    spec.materials[0].youngs_modulus = n.E, spec.materials[0].poisson_ratio = n.nu, spec.materials[0].density = n.rho;
    const ImpactRecord r = record_impact(spec, 2e-3);
    single(n.name, "peak overlap [m]", r.max_overlap, n.overlap, 0.01, "Hertz closed form");
    single(n.name, "peak force [N]", r.max_force, n.force, 0.01, "Hertz closed form");
    single(n.name, "contact time [s]", r.contact_time, n.time, 0.01, "Hertz closed form");
  }
  // Test 3: restitution obtained = asked (tension allowed at the end of contact).
  for (double e : {0.2, 0.4, 0.6, 0.8, 1.0})
    out.push_back({"CO3 restitution", "e obtained", "e asked", e, restitution_obtained(cases_dir, "tension", "hertz", e), e, 0.005,
                   "definition of the damping law"});
  // Test 4: gross sliding (35-80 deg), rigid-body closed form, 1 %.
  {
    const double e = 0.98, mu = 0.092, R = 0.0025;
    for (double angle : {35.0, 45.0, 60.0, 80.0}) {
      const double vn = 3.9 * std::cos(angle * kDeg), vt = 3.9 * std::sin(angle * kDeg);
      const Rebound r = test4_impact(cases_dir, angle);
      const double et = (vt - mu * (1 + e) * vn) / vt, spin = -2.5 * mu * (1 + e) * vn / R;
      const double patch = std::atan((vt - 3.5 * mu * (1 + e) * vn) / (e * vn)) / kDeg;
      out.push_back({"CO4 sliding", "tangential restitution", "impact angle [deg]", angle, r.vx / vt, et, 0.01 * et, "rigid-body closed form"});
      out.push_back({"CO4 sliding", "spin after [rad/s]", "impact angle [deg]", angle, -r.wy, spin, 0.01 * std::abs(spin), "rigid-body closed form"});
      out.push_back({"CO4 sliding", "patch rebound angle [deg]", "impact angle [deg]", angle, std::atan((r.vx - R * r.wy) / r.vz) / kDeg, patch,
                     0.01 * std::abs(patch) + 0.05, "rigid-body closed form"});
    }
  }
  // Test 4 over the whole range, sticking regime included, against the paper's DEM curve: 1.5 deg
  // a point (the paper's DEM curve and the experiment it reproduces differ by 1 deg at 20 deg).
  for (const CurvePoint& p : kTest4PatchAngle) {
    const Rebound r = test4_impact(cases_dir, p.x);
    out.push_back({"CO4 alumina", "patch rebound angle [deg]", "impact angle [deg]", p.x, std::atan((r.vx - 0.0025 * r.wy) / r.vz) / kDeg, p.y,
                   1.5, "Chung & Ooi (2011), test 4, the paper's DEM curve (Kratos' digitisation, benchmark4_graph3.dat)"});
  }
  // Test 5, steel: the sliding points.
  for (const CurvePoint& p : kTest5SteelSpinSliding)
    out.push_back({"CO5 steel", "R w'/(mu Vn)", "psi1", p.x, test5(cases_dir, p.x).spin, p.y, 0.02 * 5.0, paper5});
  for (const CurvePoint& p : kTest5SteelPsi2Sliding)
    out.push_back({"CO5 steel", "psi2", "psi1", p.x, test5(cases_dir, p.x).psi2, p.y, 0.02 * std::abs(p.y), paper5});
  // Test 6 with the spring cap (the LIGGGHTS and Kratos variant), 0.04 per point (nylon 0.03).
  for (const CurvePoint& p : kTest6Aluminium)
    out.push_back({"CO6 aluminium", "beta", "chi", p.x, test6_beta(cases_dir, p.x, "spring"), p.y, 0.04, paper6});
  for (const CurvePoint& p : kTest6AluminiumTail) {
    Point point{"CO6 aluminium", "beta", "chi", p.x, test6_beta(cases_dir, p.x, "spring"), p.y, 0.04, paper6};
    // Beyond chi = 6.2 the contact no longer slides at its end and beta levels off at -0.11, as
    // the paper's nylon curve and its test 8 case B do (docs/validation.md).
    point.known_difference = true;
    point.note = "CO6 aluminium beyond chi = 6.2: the contact no longer slides at the end of the impact and beta levels off at -0.11, "
                 "where the published aluminium curve keeps falling to -0.34; the paper's nylon curve of the same figure and its test 8 "
                 "(case B) level off at -0.11 as the model does (docs/physics.md, the tangential caps).";
    out.push_back(point);
  }
  for (const CurvePoint& p : kTest6Nylon)
    out.push_back({"CO6 nylon", "beta", "chi", p.x, test6_beta(cases_dir, p.x, "spring", true), p.y, 0.03, paper6});
  // Test 7: equal and opposite spins without slip keep their spin.
  for (double w0 : {0.175, 2.0, 22.86})
    out.push_back({"CO7 spinning pair", "spin after / before", "spin before [rad/s]", w0, test7_pair(cases_dir, w0).wy[0] / w0, 1.0, 1e-6,
                   "no slip: the spin is kept"});
  // Test 8: a sphere on a larger sphere, case B.
  for (const CurvePoint& p : kTest8CaseB)
    out.push_back({"CO8 sphere on sphere", "beta", "chi", p.x, test8_beta(cases_dir, p.x), p.y, 0.04, paper8});
  return out;
}

}  // namespace dem::validation
