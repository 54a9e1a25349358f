// Design sweeps: reading the `sweep:` section, the variants' cases, errors with file and line.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "case/spec.h"
#include "campaign/sweep.h"

namespace dem::test {
namespace {

const char* kSweep = R"(simulation: {duration: 0.1}
materials:
  glass: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}
equipment:
  transfer_chute: {spoon: {radius: 0.8}}
inlets:
  - {port: feed_belt, material: glass, diameter: 0.004, mass_rate_tph: 1}
sweep:
  parameters:
    equipment.transfer_chute.spoon.radius: [0.6, 0.8, 1.0]
    inlets[0].mass_rate_tph: [10, 20]
  rank_by:
    - {metric: spillage_pct, goal: minimize, weight: 2}
)";

TEST(Sweep, GridMakesEveryCombinationAndSetsEachPath) {
  const YAML::Node root = YAML::Load(kSweep);
  const app::SweepPlan plan = app::read_sweep(root, "sweep.yaml");
  ASSERT_EQ(plan.variants.size(), 6u);
  ASSERT_EQ(plan.criteria.size(), 1u);
  EXPECT_TRUE(plan.criteria[0].minimize);
  EXPECT_DOUBLE_EQ(plan.criteria[0].weight, 2);
  EXPECT_EQ(plan.name(4), "v05");
  EXPECT_EQ(plan.label(4), "spoon.radius=1.0, inlets[0].mass_rate_tph=10");
  const YAML::Node variant = app::variant_case(root, plan, 4);
  EXPECT_FALSE(variant["sweep"]) << "a variant's case has no sweep";
  EXPECT_DOUBLE_EQ(variant["equipment"]["transfer_chute"]["spoon"]["radius"].as<double>(), 1.0);
  EXPECT_DOUBLE_EQ(variant["inlets"][0]["mass_rate_tph"].as<double>(), 10);
  EXPECT_DOUBLE_EQ(root["equipment"]["transfer_chute"]["spoon"]["radius"].as<double>(), 0.8) << "the sweep case is untouched";
  // A parameter the case leaves at its default is created where the path says.
  YAML::Node defaults = YAML::Load(kSweep);
  defaults["equipment"]["transfer_chute"].remove("spoon");
  const YAML::Node created = app::variant_case(defaults, app::read_sweep(defaults, "sweep.yaml"), 0);
  EXPECT_DOUBLE_EQ(created["equipment"]["transfer_chute"]["spoon"]["radius"].as<double>(), 0.6);
  // The variant is a valid case.
  EXPECT_NO_THROW(parse_case_node(variant, "sweep.yaml"));
}

TEST(Sweep, ZipNeedsEqualListsAndBadPathsAreNamed) {
  std::string text = kSweep;
  text.replace(text.find("  rank_by:"), 0, "  combine: zip\n");
  try {
    app::read_sweep(YAML::Load(text), "sweep.yaml");
    FAIL() << "zip of lists of 3 and 2 values must be refused";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("sweep.yaml:11"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("equal length"), std::string::npos) << e.what();
  }
  std::string index = kSweep;
  index.replace(index.find("inlets[0]"), 9, "inlets[3]");
  const YAML::Node root = YAML::Load(index);
  EXPECT_THROW(app::variant_case(root, app::read_sweep(root, "sweep.yaml"), 0), CaseError);
  std::string metric = kSweep;
  metric.replace(metric.find("goal: minimize"), 14, "goal: smallest");
  EXPECT_THROW(app::read_sweep(YAML::Load(metric), "sweep.yaml"), CaseError);
}

// A grid is sized before it is built: four keys of 50 values (6.25 million variants, gigabytes of
// YAML copies) are refused at once, with the sizes and the way out.
TEST(Sweep, AGridTooLargeIsRefusedBeforeItIsBuilt) {
  std::string values;
  for (int k = 0; k < 50; ++k) values += fmt::format("{}{}", k ? ", " : "", 0.5 + 0.01 * k);
  std::string text = kSweep;
  text.replace(text.find("    equipment.transfer_chute.spoon.radius"), 0,
               fmt::format("    a.b: [{0}]\n    a.c: [{0}]\n    a.d: [{0}]\n    a.e: [{0}]\n", values));
  try {
    app::read_sweep(YAML::Load(text), "sweep.yaml");
    FAIL() << "a grid of 37.5 million variants must be refused";
  } catch (const CaseError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("sweep.yaml:"), std::string::npos) << m;
    EXPECT_NE(m.find("makes 37500000 variants (50 x 50 x 50 x 50 x 3 x 2 values"), std::string::npos) << m;
    EXPECT_NE(m.find("at most 1000"), std::string::npos) << m;
    EXPECT_NE(m.find("combine: zip"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace dem::test

#include <cstdlib>
#include <filesystem>

#include "pages/video.h"

namespace dem::test {
namespace {

// Videos are optional: without ffmpeg on the PATH the call says so (and what to install) instead
// of failing the run; the frames stay where they are.
TEST(Video, MissingFfmpegIsSaidClearly) {
  const std::filesystem::path empty = std::filesystem::temp_directory_path() / "demdesign_video_test_path";
  std::filesystem::create_directories(empty);
  const std::string saved = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", empty.c_str(), 1);
  std::string message;
  const bool made = app::make_video(empty.string(), "frame_", (empty / "flow.mp4").string(), 10, &message);
  setenv("PATH", saved.c_str(), 1);
  EXPECT_FALSE(made);
  EXPECT_NE(message.find("ffmpeg not found: install the Debian package ffmpeg"), std::string::npos) << message;
  EXPECT_FALSE(std::filesystem::exists(empty / "flow.mp4"));
}

}  // namespace
}  // namespace dem::test

#include <numbers>

#include "case/yaml_check.h"
#include "equipment.h"

namespace dem::test {
namespace {

// The shipped angled-transfer sweep (cases/angled_transfer_sweep.yaml): every variant is a case
// that reads and expands, and its chute has the variant's plan angle and rock box ledge.
TEST(Sweep, ShippedAngledTransferSweepVariesPlanAngleAndLedge) {
  const std::string path = std::string(DEMDESIGN_SOURCE_DIR) + "/cases/angled_transfer_sweep.yaml";
  const YAML::Node root = read_yaml_file(path, "the case file");
  const app::SweepPlan plan = app::read_sweep(root, path);
  ASSERT_EQ(plan.paths, (std::vector<std::string>{"equipment.transfer_chute.plan_angle_deg", "equipment.transfer_chute.rock_box.ledge_depth"}));
  ASSERT_EQ(plan.variants.size(), 3u);
  for (size_t k = 0; k < plan.variants.size(); ++k) {
    SCOPED_TRACE(plan.label(k));
    CaseSpec spec = parse_case_node(app::variant_case(root, plan, k), path);
    equipment::expand_equipment(spec);
    const equipment::TransferChuteLayout c = equipment::transfer_chute_layout(*spec.equipment);
    EXPECT_NEAR(c.plan_angle * 180 / std::numbers::pi, plan.variants[k][0].as<double>(), 1e-9);
    EXPECT_NEAR(c.ledge_depth, plan.variants[k][1].as<double>(), 1e-12);
    EXPECT_TRUE(c.rock_box);
    EXPECT_FALSE(c.spoon_profile.empty()) << "the sweep's spoon is drawn as a profile";
  }
}

}  // namespace
}  // namespace dem::test
