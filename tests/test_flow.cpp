// Inlets, outlets, mass scaling, restart from a checkpoint, results files.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>
#include <cstdio>
#include <numbers>

#include "output/checkpoint.h"
#include "output/run.h"
#include "sim.h"

namespace dem::test {
namespace {

TEST(Inlet, DeliversItsMassRateWithinTwoPercent) {
  Sim sim(load_case("inlet_outlet.yaml"));
  const double rate = 1.8 / 3.6;  // [kg/s]
  double mass_at_01 = 0;
  while (sim.state.time < 0.5) {
    sim.advance();
    if (mass_at_01 == 0 && sim.state.time >= 0.1) mass_at_01 = sim.state.inlets[0].inserted_mass;
  }
  const double delivered = (sim.state.inlets[0].inserted_mass - mass_at_01) / (sim.state.time - 0.1);
  EXPECT_NEAR(delivered, rate, 0.02 * rate);
  EXPECT_EQ(sim.state.inlets[0].failed, 0);
  // Mass balance: inserted = present + removed by the outlet + lost.
  double present = 0;
  for (size_t p = 0; p < sim.state.size(); ++p) present += 1.0 / sim.state.inv_mass[p];
  EXPECT_GT(sim.state.outlets[0].removed, 10);
  EXPECT_NEAR(sim.state.inlets[0].inserted_mass, present + sim.state.outlets[0].removed_mass, 1e-9);
  EXPECT_EQ(sim.state.lost, 0);
  // Inserted particles never overlap much (no insertion into others or into walls).
  EXPECT_LT(measure(sim.model, sim.state, sim.work).max_overlap_ratio, 0.05);
}

// An inlet with `count` and no mass rate fills its region at each insertion (LIGGGHTS insert/pack)
// until that many particles are in. Without gravity the spheres leave the 0.1 m box at 1 m/s, so
// each insertion finds it empty: the first two place about the same number, at a solids fraction
// below the saturation of random sequential addition of spheres, 0.3841 (Zhang & Torquato 2013,
// Phys. Rev. E 88, 053312), and above two thirds of it; the third places the rest of the 1500 and
// the inlet stops. An inlet with a mass rate and a count stops at the count too.
TEST(Inlet, CountAloneFillsTheRegionAtEachInsertionUntilTheCount) {
  const CaseSpec spec = parse_case_text(R"(
simulation: {duration: 1.0, time_step: 1.0e-5, gravity: [0, 0, 0]}
materials: {beads: {density: 2500, youngs_modulus: 1.0e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5}}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
inlets:
  - {name: pack, material: beads, diameter: 0.01, count: 1500, interval: 0.2, velocity: [0, 0, -1],
     region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}
  - {name: feed, material: beads, diameter: 0.01, mass_rate_kgs: 0.1, count: 10, velocity: [0, 0, -1],
     region: {min: [1, 0, 0], max: [1.1, 0.1, 0.1]}}
)");
  Sim sim(spec);
  std::vector<std::int64_t> after;  // particles of `pack` after each insertion
  while (sim.state.time < 1.0) {
    const std::int64_t before = sim.state.inlets[0].inserted;
    sim.advance();
    if (sim.state.inlets[0].inserted != before) after.push_back(sim.state.inlets[0].inserted);
  }
  ASSERT_EQ(after.size(), 3u);
  const double first = after[0], second = after[1] - after[0];
  const double fraction = first * std::numbers::pi / 6 * 1e-6 / 1e-3;  // spheres' volume / the box's
  std::printf("insertions: %lld, %lld, %lld; first fills %.3f of the box\n", static_cast<long long>(after[0]),
              static_cast<long long>(after[1] - after[0]), static_cast<long long>(after[2] - after[1]), fraction);
  EXPECT_LT(fraction, 0.3841);
  EXPECT_GT(fraction, 2.0 / 3.0 * 0.3841);
  EXPECT_NEAR(second, first, 0.1 * first);
  EXPECT_EQ(after[2], 1500);
  EXPECT_EQ(sim.state.inlets[0].failed, 0) << "a full region ends a filling insertion; it is not a failure";
  EXPECT_EQ(sim.state.inlets[1].inserted, 10);
  EXPECT_EQ(static_cast<std::int64_t>(sim.state.size()), 1510);
}

TEST(Scaling, MassAndStiffnessFactorsReachTheMaterialsAndAreReported) {
  CaseSpec spec = load_case("periodic_compression.yaml");
  spec.simulation.mass_scaling = 100;
  spec.simulation.stiffness_scaling = 0.5;
  const Model model = compile(spec);
  EXPECT_DOUBLE_EQ(model.materials[model.material_index("beads")].density, 2500 * 100.0);
  EXPECT_DOUBLE_EQ(model.materials[model.material_index("beads")].youngs_modulus, 5e7 * 0.5);
  EXPECT_DOUBLE_EQ(model.materials[model.material_index("plate")].density, 7800.0) << "walls are not scaled";
  State state = initial_state(model);
  std::ostringstream log;
  print_setup(model, state, log);
  EXPECT_NE(log.str().find("SCALING: particle density x 100"), std::string::npos) << log.str();
  EXPECT_NE(log.str().find("Young's modulus x 0.5"), std::string::npos);
}

/// A case that exercises everything a checkpoint must hold: clumps, an inlet, an outlet,
/// periodic axes, a servo wall.
CaseSpec busy_case() {
  CaseSpec spec = load_case("clump_pour.yaml");
  spec.particles[0].count = 80;
  InletSpec in;
  in.name = "feed";
  in.material = "gravel";
  in.diameter.value = 0.004;
  in.mass_rate = 0.2;
  in.region_min = Vec3(0.0, 0.0, 0.12);
  in.region_max = Vec3(0.08, 0.08, 0.15);
  spec.inlets.push_back(in);
  OutletSpec out;
  out.name = "low";
  out.region_min = Vec3(-1, -1, -1);
  out.region_max = Vec3(1, 1, 0.004);
  spec.outlets.push_back(out);
  return spec;
}

TEST(Checkpoint, RestartReproducesTheUninterruptedRunBitwise) {
  const std::string dir = (std::filesystem::temp_directory_path() / "demdesign_restart_test").string();
  std::filesystem::remove_all(dir);
  const CaseSpec spec = busy_case();
  Sim straight(spec);
  for (int k = 0; k < 3000; ++k) straight.advance();

  Sim first(spec);
  for (int k = 0; k < 1500; ++k) first.advance();
  save_checkpoint(dir + "/checkpoint.bin", first.model, first.state);
  Sim second(spec);
  second.state = load_checkpoint(dir + "/checkpoint.bin", second.model);
  second.work = Workspace();
  prepare(second.model, second.state, second.work);
  for (int k = 0; k < 1500; ++k) second.advance();

  EXPECT_GT(straight.state.inlets[0].inserted, 10);
  EXPECT_EQ(second.state.step, straight.state.step);
  EXPECT_EQ(state_hash(second.state, second.model.history_width), state_hash(straight.state, straight.model.history_width));
  EXPECT_EQ(second.state.inlets[0].inserted, straight.state.inlets[0].inserted);
  EXPECT_EQ(second.state.outlets[0].removed, straight.state.outlets[0].removed);
  std::filesystem::remove_all(dir);
}

TEST(Checkpoint, RefusesACheckpointOfAnotherModel) {
  const std::string dir = (std::filesystem::temp_directory_path() / "demdesign_restart_model").string();
  CaseSpec spec = load_case("hello_sphere.yaml");
  Sim sim(spec);
  save_checkpoint(dir + "/checkpoint.bin", sim.model, sim.state);
  spec.materials[0].params["restitution"] = 0.3;
  const Model other = compile(spec);
  EXPECT_THROW(load_checkpoint(dir + "/checkpoint.bin", other), std::runtime_error);
  std::filesystem::remove_all(dir);
}

TEST(Run, ResumedRunEndsInTheSameStateAndKeepsEarlierResults) {
  const std::string dir = (std::filesystem::temp_directory_path() / "demdesign_resume_test").string();
  std::filesystem::remove_all(dir);
  CaseSpec spec = busy_case();
  spec.simulation.duration = 0.04;
  spec.output.checkpoint_every = 0.01;
  spec.output.frames_every = 0.01;
  std::ostringstream log;
  RunOptions options;
  options.output_directory = dir + "/a";
  options.progress = false;
  const Model model = compile(spec);
  State a = initial_state(model);
  Workspace wa;
  run(model, a, wa, options, log);

  // Second run stops after 1500 steps (a checkpoint every 0.01 s), then resumes to the end.
  options.output_directory = dir + "/b";
  State b = initial_state(model);
  Workspace wb;
  options.max_steps = 1500;
  run(model, b, wb, options, log);
  ASSERT_TRUE(std::filesystem::exists(dir + "/b/checkpoint.bin"));
  options.max_steps = -1;
  options.resume = true;
  State c;
  Workspace wc;
  run(model, c, wc, options, log);
  EXPECT_EQ(state_hash(c, model.history_width), state_hash(a, model.history_width)) << log.str();
  // Results: frames listed in the XDMF and the scalars of the whole run.
  EXPECT_TRUE(std::filesystem::exists(dir + "/b/particles.xdmf"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/b/run_info.yaml"));
  std::ifstream csv(dir + "/b/scalars.csv");
  std::string line;
  double first_time = -1, last_time = -1;
  std::getline(csv, line);
  const auto columns = std::count(line.begin(), line.end(), ',');
  while (std::getline(csv, line)) {
    EXPECT_EQ(std::count(line.begin(), line.end(), ','), columns) << "every row has every column: " << line;
    const double t = std::stod(line.substr(0, line.find(',')));
    if (first_time < 0) first_time = t;
    last_time = t;
  }
  EXPECT_EQ(first_time, 0.0);
  EXPECT_NEAR(last_time, 0.04, 1e-4);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dem::test
