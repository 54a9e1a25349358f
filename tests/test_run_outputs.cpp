// What a run reports beyond its scalars: first arrivals timed to the step, the velocity and
// particle flux through a plane sensor, the loads on a mesh by component with their standard
// errors, an outlet that takes what leaves the domain, and the drive of a belt that brings a
// stream up to its speed. Each against a closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <sstream>

#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "output/run.h"
#include "report/report.h"
#include "report/report_analysis.h"

namespace dem {
namespace {

namespace fs = std::filesystem;
constexpr double kG = 9.81;

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

RunSummary run_quietly(const Model& model, State& state, const fs::path& out) {
  Workspace work;
  RunOptions options;
  options.output_directory = out.string();
  options.progress = false;
  std::ostringstream log;
  return run(model, state, work, options, log);
}

/// The `mean` column of a series in steady_state.csv (series,unit,found,t_start_s,t_end_s,mean,...).
double read_steady_mean(const fs::path& csv, const std::string& series) {
  std::ifstream in(csv);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("\"" + series + "\"", 0) == 0) {
      std::stringstream fields(line.substr(series.size() + 3));
      std::string cell;
      for (int k = 0; k < 5; ++k) std::getline(fields, cell, ',');
      return std::stod(cell);
    }
  return std::nan("");
}

const RunEvent* event(const RunSummary& s, const std::string& what) {
  for (const RunEvent& e : s.events)
    if (e.what == what) return &e;
  return nullptr;
}

// One sphere falls from rest at z = 0.5 m through a plane sensor at z = 0, into an outlet box
// whose top is at z = -0.3 m, and (a second sphere beside it, outside the outlet) out of the
// domain's floor at z = -1.1 m. Free fall: z(t) = 0.5 - g t^2 / 2, exact under the kick-drift-
// kick integrator, so each event is the first step at or after sqrt(2 h / g). The scalars' rows
// are 2000 steps apart: the times do not come from them.
TEST(RunOutputs, FirstArrivalsAreTimedToTheStepInFreeFall) {
  const CaseSpec spec = parse_case_text(R"(
simulation: {duration: 0.6, time_step: 1.0e-5, gravity: [0, 0, -9.81], domain: {min: [-1, -1, -1.1], max: [1, 1, 0.6]}}
materials: {beads: {density: 2500, youngs_modulus: 1.0e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5}}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
particles:
  - {material: beads, diameter: 0.01, positions: [[0, 0, 0.5], [0.5, 0, 0.5]]}
outlets:
  - {name: bin, region: {min: [-0.2, -0.2, -1.0], max: [0.2, 0.2, -0.3]}}
sensors:
  - {name: level0, plane: {point: [0, 0, 0], normal: [0, 0, -1]}, region: {min: [-0.2, -0.2, -0.1], max: [0.2, 0.2, 0.1]}}
output: {scalars_every: 2000}
)");
  const Model model = compile(spec);
  State state = initial_state(model);
  const fs::path out = fs::temp_directory_path() / "demdesign_first_arrivals_test";
  fs::remove_all(out);
  const RunSummary summary = run_quietly(model, state, out);
  const double dt = model.dt;
  ASSERT_DOUBLE_EQ(dt, 1e-5);
  struct Expected {
    const char* what;
    double fall;  // [m]
  };
  for (const Expected& x : {Expected{"first across sensor level0", 0.5}, Expected{"first at outlet bin", 0.8}, Expected{"first out of the domain", 1.6}}) {
    const RunEvent* e = event(summary, x.what);
    ASSERT_NE(e, nullptr) << x.what << "\n" << events_csv(summary.events);
    const double exact = std::sqrt(2 * x.fall / kG);
    EXPECT_GE(e->time, exact - 1e-9) << x.what;
    EXPECT_LT(e->time, exact + dt + 1e-9) << x.what << ": " << e->time << " s against " << exact << " s";
    EXPECT_NEAR(e->time, e->step * dt, 1e-9);
  }
  EXPECT_EQ(event(summary, "first at outlet bin")->particle, 0);
  EXPECT_EQ(event(summary, "first out of the domain")->particle, 1);
  // events.csv holds them, in the order they happened.
  const std::string csv = read(out / "events.csv");
  EXPECT_LT(csv.find("first across sensor level0"), csv.find("first at outlet bin")) << csv;
  EXPECT_LT(csv.find("first at outlet bin"), csv.find("first out of the domain")) << csv;
}

// A free-falling stream: an inlet feeds 0.5 kg/s of 10 mm spheres at 1 m/s downwards, 0.3 m
// above a horizontal plane sensor. At the plane every sphere moves at sqrt(1 + 2 g 0.3) = 2.636
// m/s straight down, and particles cross it at the inlet's rate over one sphere's mass. The
// stream leaves the domain's floor, which an outlet with `region: domain` takes: nothing is
// spilled, nothing lost.
TEST(RunOutputs, PlaneSensorVelocityAndCountFlowOfAFallingStreamAndADomainOutlet) {
  const CaseSpec spec = parse_case_text(R"(
simulation: {duration: 1.5, gravity: [0, 0, -9.81], domain: {min: [-0.3, -0.3, -0.2], max: [0.3, 0.3, 0.5]}}
materials: {beads: {density: 2500, youngs_modulus: 1.0e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5}}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
inlets:
  - {name: feed, material: beads, diameter: 0.01, mass_rate_kgs: 0.5, region: {min: [-0.1, -0.1, 0.3], max: [0.1, 0.1, 0.4]}, velocity: [0, 0, -1]}
outlets:
  - {name: exit, region: domain}
sensors:
  - {name: level0, plane: {point: [0, 0, 0], normal: [0, 0, -1]}, region: {min: [-0.2, -0.2, -0.1], max: [0.2, 0.2, 0.1]}}
output: {scalars_every: 100}
)");
  const Model model = compile(spec);
  ASSERT_EQ(model.domain_outlet, 0);
  State state = initial_state(model);
  const fs::path out = fs::temp_directory_path() / "demdesign_plane_sensor_test";
  fs::remove_all(out);
  const RunSummary summary = run_quietly(model, state, out);
  EXPECT_EQ(state.lost, 0) << "what leaves the domain goes to the outlet";
  EXPECT_GT(state.outlets[0].removed, 300);
  EXPECT_NEAR(state.lost_mass, 0.0, 1e-15);

  report::RunReportInput input;
  input.model = &model, input.state = &state, input.scalars = summary.scalars, input.events = summary.events;
  input.sensors = model.sensors;
  const report::RunMetrics metrics = report::write_run_report(input, (out / "report").string());
  EXPECT_DOUBLE_EQ(metrics.get("spillage_kg"), 0.0);
  // Every sphere crosses at 2.636 m/s, from the inlet's box (0.30 to 0.40 m, 1 m/s): the height
  // varies, so the speed over the sensor's slab (4 radii) spreads by about 3 %.
  const double speed = std::sqrt(1.0 + 2 * kG * 0.35);
  EXPECT_NEAR(metrics.get("sensor_level0_speed_m_s"), speed, 0.03 * speed);
  const std::string steady = read(out / "report" / "steady_state.csv");
  EXPECT_NE(steady.find("sensor level0 particles through"), std::string::npos) << steady;
  const double sphere = 2500 * std::numbers::pi / 6 * 1e-6;  // [kg]
  // Particles through the plane per second: the inlet's rate over one sphere's mass (the slab
  // estimator holds about three spheres at a time: a few per cent of noise over the interval).
  const double count = read_steady_mean(out / "report" / "steady_state.csv", "sensor level0 particles through");
  EXPECT_NEAR(count, 0.5 / sphere, 0.1 * 0.5 / sphere);
  EXPECT_NEAR(metrics.get("sensor_level0_t_h") / 3.6, 0.5, 0.05);
  const std::string html = read(out / "report" / "report.html");
  EXPECT_NE(html.find("particles through [1/s]"), std::string::npos);
  EXPECT_NE(html.find("First arrivals"), std::string::npos);
  const RunEvent* e = event(summary, "first across sensor level0");
  ASSERT_NE(e, nullptr);
  // The first sphere starts at most 0.1 m higher than 0.3 m, at 1 m/s: it crosses between the
  // fall times from 0.3 and from 0.4 m (plus the inlet's first insertion at t = 0).
  const auto fall = [](double h) { return (-1.0 + std::sqrt(1.0 + 2 * kG * h)) / kG; };
  EXPECT_GE(e->time, fall(0.3) - 1e-9);
  EXPECT_LE(e->time, fall(0.4) + model.dt);
}

// A bed of spheres at rest on a mesh floor: the floor carries its weight, F = (0, 0, -m g)
// (the particles push down), with no tangential part, and the torque about the origin is
// r_c x F for the bed's centre of mass r_c.
TEST(RunOutputs, MeshLoadsByComponentCarryTheBedsWeight) {
  const CaseSpec spec = parse_case_text(R"(
simulation: {duration: 0.8, gravity: [0, 0, -9.81], domain: {min: [-0.1, -0.1, -0.05], max: [0.1, 0.1, 0.3]}}
materials:
  beads: {density: 2500, youngs_modulus: 1.0e7, poisson_ratio: 0.25, restitution: 0.3, friction: 0.5, rolling_friction: 0.1}
  steel: {density: 7800, youngs_modulus: 2.0e11, poisson_ratio: 0.3, restitution: 0.3, friction: 0.5, rolling_friction: 0.1}
contact: {normal: hertz, damping: restitution, tangential: mindlin, rolling: epsd}
meshes:
  - name: floor
    material: steel
    vertices: [[-0.1, -0.1, 0], [0.1, -0.1, 0], [0.1, 0.1, 0], [-0.1, 0.1, 0]]
    triangles: [[0, 1, 2], [0, 2, 3]]
walls:
  - {name: x0, plane: {point: [-0.03, 0, 0], normal: [1, 0, 0]}, material: steel}
  - {name: x1, plane: {point: [0.05, 0, 0], normal: [-1, 0, 0]}, material: steel}
  - {name: y0, plane: {point: [0, -0.04, 0], normal: [0, 1, 0]}, material: steel}
  - {name: y1, plane: {point: [0, 0.04, 0], normal: [0, -1, 0]}, material: steel}
particles:
  - {material: beads, diameter: 0.008, count: 150, region: {min: [-0.025, -0.035, 0.01], max: [0.045, 0.035, 0.08]}}
output: {scalars_every: 400}
)");
  const Model model = compile(spec);
  State state = initial_state(model);
  double mass = 0;
  for (std::size_t p = 0; p < state.size(); ++p) mass += 1.0 / state.inv_mass[p];
  const fs::path out = fs::temp_directory_path() / "demdesign_mesh_loads_test";
  fs::remove_all(out);
  const RunSummary summary = run_quietly(model, state, out);
  double cx = 0, cy = 0;
  for (std::size_t p = 0; p < state.size(); ++p) cx += state.x[p] / state.inv_mass[p] / mass, cy += state.y[p] / state.inv_mass[p] / mass;

  report::RunReportInput input;
  input.model = &model, input.state = &state, input.scalars = summary.scalars;
  const report::RunMetrics metrics = report::write_run_report(input, (out / "report").string());
  // mesh_loads.csv: mesh,component,unit,mean,std_error,...; the side walls take part of the
  // weight by friction, at most a few per cent in a bed this shallow.
  std::ifstream csv(out / "report" / "mesh_loads.csv");
  std::string line;
  std::getline(csv, line);
  std::map<std::string, std::pair<double, double>> load;  // component -> (mean, std error)
  while (std::getline(csv, line)) {
    std::stringstream fields(line);
    std::string mesh, component, unit, mean, error;
    std::getline(fields, mesh, ','), std::getline(fields, component, ','), std::getline(fields, unit, ',');
    std::getline(fields, mean, ','), std::getline(fields, error, ',');
    load[component] = {std::stod(mean), std::stod(error)};
  }
  ASSERT_EQ(load.size(), 6u);
  const double weight = mass * kG;
  EXPECT_NEAR(load["fz"].first, -weight, 0.05 * weight);
  // A packing at rest may lock in friction against the floor, balanced by the side walls.
  EXPECT_NEAR(load["fx"].first, 0.0, 0.05 * weight);
  EXPECT_NEAR(load["fy"].first, 0.0, 0.05 * weight);
  EXPECT_LT(load["fz"].second, 0.02 * weight) << "a bed at rest: a small standard error";
  // T = r x F with F = (0, 0, Fz): Tx = y Fz, Ty = -x Fz.
  EXPECT_NEAR(load["tx"].first, cy * load["fz"].first, 0.1 * weight * 0.01);
  EXPECT_NEAR(load["ty"].first, -cx * load["fz"].first, 0.1 * weight * 0.01);
  EXPECT_NEAR(metrics.get("force_floor_N"), weight, 0.05 * weight);
}

// A stream of m_dot = 2 kg/s of 20 mm spheres dropped from rest (no horizontal velocity) a few
// centimetres onto a flat belt whose surface moves at v = 1 m/s, carried 0.9 m and thrown off its
// end into an outlet. In steady state the belt gives the stream the momentum it carries away,
// m_dot v per second, so the belt pull is F_t = m_dot v; at a constant belt speed its work over
// any slip F_t v t is twice the kinetic energy gained, so the drive power is P = m_dot v^2: half
// carried away as kinetic energy (m_dot v^2 / 2), half dissipated by friction while the particles
// slip up to speed, whatever the friction law. Rolling resistance makes a sphere end at belt speed
// (without it a sphere only rolls at 2 v / 7). The report's belt drive, averaged over the steady
// state, must give both within 10 % (the rate counted at the outlet; what falls off the belt's
// sides leaves below belt speed and is kept under 2 % of the feed).
TEST(RunOutputs, BeltDriveOfAStreamBroughtUpToSpeedIsMassFlowTimesSpeedSquared) {
  const CaseSpec spec = parse_case_text(R"(
simulation: {duration: 3.5, gravity: [0, 0, -9.81], seed: 3, domain: {min: [-1.1, -0.4, -0.3], max: [0.4, 0.4, 0.3]}}
materials:
  ore: {density: 2600, youngs_modulus: 2.0e7, poisson_ratio: 0.25, restitution: 0.3, friction: 0.7, rolling_friction: 0.3}
  rubber: {density: 1200, youngs_modulus: 1.0e7, poisson_ratio: 0.45, restitution: 0.3, friction: 0.7, rolling_friction: 0.3}
contact: {normal: hertz, damping: restitution, tangential: mindlin, rolling: epsd}
meshes:
  - name: belt
    material: rubber
    vertices: [[-1.0, -0.3, 0], [0, -0.3, 0], [0, 0.3, 0], [-1.0, 0.3, 0]]
    triangles: [[0, 1, 2], [0, 2, 3]]
    surface_velocity: {linear: [1.0, 0, 0]}
inlets:
  - {name: feed, material: ore, diameter: 0.02, mass_rate_kgs: 2.0, region: {min: [-0.95, -0.08, 0.03], max: [-0.75, 0.08, 0.09]}, velocity: [0, 0, 0]}
outlets:
  - {name: off_the_end, region: {min: [0.02, -0.4, -0.3], max: [0.4, 0.4, 0.3]}}
output: {scalars_every: 100}
)");
  const double v = 1.0;  // [m/s]
  const Model model = compile(spec);
  State state = initial_state(model);
  const fs::path out = fs::temp_directory_path() / "demdesign_belt_drive_test";
  fs::remove_all(out);
  const RunSummary summary = run_quietly(model, state, out);

  report::RunReportInput input;
  input.model = &model, input.state = &state, input.scalars = summary.scalars;
  const report::RunAnalysis analysis = report::analyse_run(input);
  ASSERT_TRUE(analysis.steady) << analysis.metrics.steady_text;
  ASSERT_EQ(analysis.drives.size(), 1u);
  const report::Drive& belt = analysis.drives[0];
  ASSERT_EQ(belt.kind, report::DriveKind::belt);
  const double m_dot = analysis.primary.at_run.mean / 3.6;  // [kg/s] from t/h, at the outlet
  std::cout << "belt drive: m_dot " << m_dot << " kg/s, pull " << belt.effort.at_run.mean << " +- " << belt.effort.at_run.std_error
            << " N (m_dot v = " << m_dot * v << "), power " << belt.power.at_run.mean << " +- " << belt.power.at_run.std_error
            << " W (m_dot v^2 = " << m_dot * v * v << "), over " << analysis.interval_text << "\n";
  EXPECT_NEAR(m_dot, 2.0, 0.1) << "the outflow carries the feed";
  EXPECT_LT(analysis.last.lost_mass, 0.02 * analysis.last.inserted_mass) << "little falls off the sides";
  EXPECT_NEAR(belt.effort.at_run.mean, m_dot * v, 0.1 * m_dot * v);
  EXPECT_NEAR(belt.power.at_run.mean, m_dot * v * v, 0.1 * m_dot * v * v);
  EXPECT_NEAR(belt.check.at_run.mean, belt.power.at_run.mean, 1e-9 * std::abs(belt.power.at_run.mean)) << "P = F_t v on a flat belt";
  EXPECT_LT(belt.power.at_run.std_error, 0.05 * m_dot * v * v);
}

TEST(RunOutputs, DomainOutletErrorsNameTheKey) {
  const std::string base = R"(
simulation: {duration: 1}
materials: {beads: {density: 2500, youngs_modulus: 1.0e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5}}
particles:
  - {material: beads, diameter: 0.01, positions: [[0, 0, 0.5]]}
)";
  try {
    compile(parse_case_text(base + "outlets:\n  - {name: exit, region: domain}\n", "no_domain.yaml"));
    ADD_FAILURE() << "a domain outlet without a domain";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("no_domain.yaml:7"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("simulation.domain"), std::string::npos) << e.what();
  }
  try {
    std::string two = base + "outlets:\n  - {name: a, region: domain}\n  - {name: b, region: domain}\n";
    two.replace(two.find("{duration: 1}"), 13, "{duration: 1, domain: {min: [-1, -1, -1], max: [1, 1, 1]}}");
    compile(parse_case_text(two, "two.yaml"));
    ADD_FAILURE() << "two domain outlets";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("outlets[1].region"), std::string::npos) << e.what();
  }
  try {
    parse_case_text(base + "outlets:\n  - {name: exit, region: sky}\n", "sky.yaml");
    ADD_FAILURE() << "region: sky";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("'sky' is not a region"), std::string::npos) << e.what();
  }
}

// A particle placed under the floor (a one-sided plane: its normal points to where particles
// belong) never touches it and falls through; an inlet wholly under it feeds nothing the floor
// holds. Both are warned of at the start, naming the wall; particles above it are not.
TEST(RunOutputs, ParticlesAndInletsBehindAPlaneWallAreWarnedOf) {
  const std::string text = R"(
simulation: {duration: 0.01}
materials: {beads: {density: 2500, youngs_modulus: 1.0e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5}}
walls:
  - {name: floor, material: beads, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
particles:
  - {material: beads, diameter: 0.01, positions: [[0, 0, 0.1], [0, 0, -0.2], [0.1, 0, -0.3], [0.2, 0, 0.003]]}
inlets:
  - {name: below, material: beads, diameter: 0.01, mass_rate_kgs: 0.1, region: {min: [0, 0, -0.5], max: [0.1, 0.1, -0.4]}}
  - {name: above, material: beads, diameter: 0.01, mass_rate_kgs: 0.1, region: {min: [0, 0, 0.4], max: [0.1, 0.1, 0.5]}}
)";
  const Model model = compile(parse_case_text(text, "behind.yaml"));
  const State state = initial_state(model);
  const std::vector<std::string> warnings = particles_behind_walls(model, state);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(warnings[0].find("2 particles (the first with id 1) start wholly behind plane wall 'floor'"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[1].find("inlet 'below' lies wholly behind plane wall 'floor'"), std::string::npos) << warnings[1];
  std::ostringstream log;
  print_setup(model, state, log);
  EXPECT_NE(log.str().find("WARNING: 2 particles"), std::string::npos) << log.str();
}

}  // namespace
}  // namespace dem
