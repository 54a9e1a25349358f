// Design runs with calibration uncertainty: the `uncertainty:` section of a case, the parameter
// sets it draws from a calibrated material, and the bands and paired probabilities it reports.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "case/spec.h"
#include "campaign/sweep.h"
#include "campaign/uncertainty.h"

namespace dem::test {
namespace {

namespace fs = std::filesystem;

/// A calibrated material (friction and rolling friction fitted, a wall pair parameter too) and a
/// case with a two-value design sweep that names it, in a fresh folder.
fs::path write_files() {
  const fs::path dir = fs::temp_directory_path() / "demdesign_uncertainty_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "beads_calibrated.yaml") << R"(name: beads
contact: {normal: hertz, damping: restitution, tangential: mindlin, rolling: epsd}
properties: {density: 2500, youngs_modulus: 5.0e6, poisson_ratio: 0.25, restitution: 0.5, friction: 0.45, rolling_friction: 0.2}
size: 0.006
tunable:
  friction: [0.1, 0.9]
  rolling_friction: [0.0, 0.5]
calibration:
  command: diagnose
  measurements: "lab.yaml"
  parameters: [friction, rolling_friction, steel.friction]
  value: [0.45, 0.2, 0.3]
  sigma: [0.05, 0.02, 0.04]
  correlation:
    - [1, -0.5, 0]
    - [-0.5, 1, 0]
    - [0, 0, 1]
  chi2_per_n: 1.1
)";
  std::ofstream(dir / "case.yaml") << R"(simulation: {duration: 0.01}
materials:
  beads: {library: beads_calibrated}
particles:
  - {material: beads, diameter: 0.006, positions: [[0, 0, 0.01]]}
sweep:
  parameters:
    particles[0].positions[0][2]: [0.01, 0.02]
uncertainty: {samples: 8, seed: 3}
)";
  return dir;
}

TEST(Uncertainty, EveryDesignRunsAtTheSameParameterSetsDrawnFromTheCalibration) {
  const fs::path dir = write_files();
  const std::string file = (dir / "case.yaml").string();
  const YAML::Node root = YAML::LoadFile(file);
  const app::SweepPlan plan = app::read_sweep(root, file);
  ASSERT_EQ(plan.samples, 8);
  ASSERT_EQ(plan.design_paths, 1u);
  ASSERT_EQ(plan.variants.size(), 16u);  // 2 designs x 8 parameter sets
  ASSERT_EQ(plan.paths.size(), 3u);
  EXPECT_EQ(plan.paths[1], "materials.beads.friction");
  EXPECT_EQ(plan.paths[2], "materials.beads.rolling_friction");
  ASSERT_EQ(plan.held.size(), 1u);  // the wall pair parameter
  EXPECT_NE(plan.held[0].find("steel.friction"), std::string::npos);
  double mean = 0;
  for (int s = 0; s < 8; ++s) {
    // Design 1 runs at the same parameter sets as design 0.
    EXPECT_EQ(plan.variants[static_cast<size_t>(s)][1].as<double>(), plan.variants[static_cast<size_t>(8 + s)][1].as<double>());
    const double friction = plan.variants[static_cast<size_t>(s)][1].as<double>();
    EXPECT_GT(friction, 0.1);
    EXPECT_LT(friction, 0.9);
    mean += friction / 8;
  }
  EXPECT_NEAR(mean, 0.45, 0.05 * 3 / std::sqrt(8.0));
  EXPECT_NE(plan.variants[0][1].as<double>(), plan.variants[1][1].as<double>());
  EXPECT_EQ(plan.design_label(9), "particles[0].positions[0][2]=0.02");
  // A variant's case overrides the library values and parses; it has neither section.
  const YAML::Node variant = app::variant_case(root, plan, 9);
  EXPECT_FALSE(variant["uncertainty"]);
  EXPECT_FALSE(variant["sweep"]);
  const CaseSpec spec = parse_case_node(variant, file);
  EXPECT_DOUBLE_EQ(spec.materials[0].params.at("friction"), plan.variants[9][1].as<double>());
  EXPECT_DOUBLE_EQ(spec.materials[0].params.at("rolling_friction"), plan.variants[9][2].as<double>());
  // The same seed draws the same sets.
  EXPECT_EQ(app::read_sweep(root, file).variants[5][1].as<double>(), plan.variants[5][1].as<double>());
}

TEST(Uncertainty, ACaseWithoutACalibratedMaterialIsToldWhatToName) {
  const fs::path dir = write_files();
  const std::string file = (dir / "plain.yaml").string();
  std::ofstream(file) << "simulation: {duration: 0.01}\nmaterials:\n  glass: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}\n"
                         "particles:\n  - {material: glass, diameter: 0.006, positions: [[0, 0, 0.01]]}\nuncertainty: {samples: 4}\n";
  try {
    app::read_sweep(YAML::LoadFile(file), file);
    FAIL() << "uncertainty without a calibration was accepted";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("plain.yaml:6"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("_calibrated.yaml"), std::string::npos) << e.what();
  }
}

/// A variant that ran with these metrics.
report::SweepVariant ran(double flow, double spill) {
  report::SweepVariant v;
  v.metrics.values = {{"throughput_t_h", flow}, {"throughput_std_t_h", 0.1}, {"spillage_pct", spill}};
  return v;
}

// Bands are the median and 5/95 % quantiles over the parameter sets; a design better at every
// parameter set beats the other with probability 1, two designs that trade places half the time
// with probability 1/2.
TEST(Uncertainty, BandsAndPairedProbabilities) {
  const fs::path dir = write_files();
  const std::string file = (dir / "case.yaml").string();
  app::SweepPlan plan = app::read_sweep(YAML::LoadFile(file), file);
  std::vector<report::SweepVariant> variants;
  for (int s = 0; s < 8; ++s) variants.push_back(ran(10.0 + s, s % 2 ? 1.0 : 3.0));    // design 0: flow 10..17
  for (int s = 0; s < 8; ++s) variants.push_back(ran(20.0 + s, s % 2 ? 2.0 : 2.0));    // design 1: flow 20..27
  const std::vector<report::Criterion> criteria = {{"throughput_t_h", true, 1.0}, {"spillage_pct", false, 1.0}};
  const app::UncertaintySummary u = app::summarise_uncertainty(plan, variants, criteria, (dir / "report").string());
  const auto band = [&](const std::string& design, const std::string& metric) {
    for (const app::KpiBand& b : u.bands)
      if (b.design == design && b.metric == metric) return b;
    ADD_FAILURE() << design << " " << metric;
    return app::KpiBand{};
  };
  const app::KpiBand flow0 = band("particles[0].positions[0][2]=0.01", "throughput_t_h");
  EXPECT_DOUBLE_EQ(flow0.median, 13.5);
  EXPECT_NEAR(flow0.p05, 10.35, 1e-12);  // 0.05 x 7 = 0.35 between the first two order statistics
  EXPECT_NEAR(flow0.p95, 16.65, 1e-12);
  EXPECT_DOUBLE_EQ(flow0.run_noise, 0.1);
  EXPECT_EQ(flow0.samples, 8);
  for (const app::Beats& b : u.beats) {
    if (b.metric == "throughput_t_h") {
      EXPECT_DOUBLE_EQ(b.probability, b.a == "particles[0].positions[0][2]=0.02" ? 1.0 : 0.0);
    }
    if (b.metric == "spillage_pct") {
      EXPECT_DOUBLE_EQ(b.probability, 0.5);
    }
    EXPECT_EQ(b.pairs, 8);
  }
  EXPECT_EQ(u.beats.size(), 4u);
  EXPECT_TRUE(fs::exists(dir / "report" / "uncertainty.csv"));
  EXPECT_TRUE(fs::exists(dir / "report" / "beats.csv"));
  EXPECT_NE(u.html.find("steel.friction"), std::string::npos) << "the held parameter is named";
}

}  // namespace
}  // namespace dem::test
