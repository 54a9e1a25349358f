// Design sweeps: reading the `sweep:` section, the variants' cases, errors with file and line;
// the `coarse_grain_check:` that rides with a case (its runs, its refusals, its verdicts).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "case/spec.h"
#include "campaign/bias_check.h"
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

// coarse_grain_check: every design variant runs at the case's coarse_grain and at the finer one,
// the factor set on every particle set and inlet of the case (one F per case), with the check's
// duration; the variants' cases read, and each has the factor it should.
const char* kCoarse = R"(simulation: {duration: 0.4}
materials:
  glass: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}
particles:
  - {material: glass, diameter: 0.004, count: 800, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}, coarse_grain: 2}
inlets:
  - {name: feed, material: glass, diameter: 0.004, mass_rate_tph: 1, region: {min: [0, 0, 0.2], max: [0.1, 0.1, 0.3]}, coarse_grain: 2}
sweep:
  parameters:
    inlets[0].mass_rate_tph: [1, 2, 3]
coarse_grain_check:
  finer: 1.25
  kpis: [throughput_t_h, spillage_kg]
  duration: 0.1
)";

TEST(CoarseGrainCheck, PlanRunsEveryDesignAtTheCasesFactorAndTheFinerOne) {
  const YAML::Node root = YAML::Load(kCoarse);
  const app::SweepPlan plan = app::read_sweep(root, "coarse.yaml");
  ASSERT_EQ(plan.variants.size(), 6u) << "3 designs x 2 runs";
  EXPECT_EQ(plan.check, app::SweepPlan::Check::coarse_grain);
  EXPECT_DOUBLE_EQ(plan.coarse_grain, 2.0);
  EXPECT_DOUBLE_EQ(plan.finer_coarse_grain, 1.25);
  EXPECT_EQ(plan.check_kpis, (std::vector<std::string>{"throughput_t_h", "spillage_kg"}));
  ASSERT_EQ(plan.bias_runs.size(), 2u);
  EXPECT_EQ(plan.bias_runs[1], "coarse_grain 1.25");
  EXPECT_EQ(plan.paths, (std::vector<std::string>{"inlets[0].mass_rate_tph", "particles[0].coarse_grain", "inlets[0].coarse_grain",
                                                   "simulation.duration"}));
  for (size_t k = 0; k < plan.variants.size(); ++k) {
    const CaseSpec spec = parse_case_node(app::variant_case(root, plan, k), "coarse.yaml");
    const double expected = k % 2 == 0 ? 2.0 : 1.25;  // variant k: design k / 2 at run k % 2
    EXPECT_DOUBLE_EQ(spec.particles[0].coarse_grain, expected) << plan.label(k);
    EXPECT_DOUBLE_EQ(spec.inlets[0].coarse_grain, expected) << plan.label(k);
    EXPECT_NEAR(spec.inlets[0].mass_rate, (1.0 + static_cast<double>(k / 2)) / 3.6, 1e-12) << "the design value: " << plan.label(k);
    EXPECT_DOUBLE_EQ(spec.simulation.duration, 0.1) << plan.label(k);
    EXPECT_EQ(plan.design_label(k), fmt::format("inlets[0].mass_rate_tph={}", 1 + k / 2));
  }
}

/// The message of the CaseError reading `text` throws ("" when none is thrown).
std::string refusal(const std::string& text) {
  try {
    app::read_sweep(YAML::Load(text), "coarse.yaml");
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

TEST(CoarseGrainCheck, BadKeysAreRefusedWithFileLineKeyAndWhatIsValid) {
  std::string not_finer = kCoarse;
  not_finer.replace(not_finer.find("finer: 1.25"), 11, "finer: 2");
  std::string message = refusal(not_finer);
  EXPECT_NE(message.find("coarse.yaml:12:"), std::string::npos) << message;
  EXPECT_NE(message.find("coarse_grain_check.finer: 2 is not finer than the case's coarse_grain 2"), std::string::npos) << message;
  EXPECT_NE(message.find("valid: at least 1 and below 2"), std::string::npos) << message;

  std::string below_one = kCoarse;
  below_one.replace(below_one.find("finer: 1.25"), 11, "finer: 0.5");
  message = refusal(below_one);
  EXPECT_NE(message.find("coarse.yaml:12:"), std::string::npos) << message;
  EXPECT_NE(message.find("coarse_grain_check.finer: 0.5"), std::string::npos) << message;
  EXPECT_NE(message.find("is out of range; valid: [1,"), std::string::npos) << message;

  std::string real = kCoarse;  // no coarse_grain anywhere: real particles, nothing to check
  for (size_t at; (at = real.find(", coarse_grain: 2")) != std::string::npos;) real.erase(at, 17);
  message = refusal(real);
  EXPECT_NE(message.find("coarse.yaml:12:"), std::string::npos) << message;
  EXPECT_NE(message.find("coarse_grain_check: the case has no coarse_grain"), std::string::npos) << message;

  std::string typo = kCoarse;
  typo.replace(typo.find("  duration: 0.1"), 15, "  duraton: 0.1");
  message = refusal(typo);
  EXPECT_NE(message.find("coarse.yaml:14:"), std::string::npos) << message;
  EXPECT_NE(message.find("coarse_grain_check.duraton: unknown key (did you mean 'duration'?)"), std::string::npos) << message;

  std::string swept = kCoarse;
  swept.replace(swept.find("inlets[0].mass_rate_tph: [1, 2, 3]"), 34, "inlets[0].coarse_grain: [2, 3]");
  message = refusal(swept);
  EXPECT_NE(message.find("sweep.parameters varies inlets[0].coarse_grain"), std::string::npos) << message;

  std::string both = std::string(kCoarse) + "bias_check: {stiffness_factor: 4}\n";
  EXPECT_NE(refusal(both).find("one check at a time"), std::string::npos) << refusal(both);
}

// The verdicts: each KPI at F against F' in standard errors (batch means, metrics.csv's third
// column). A throughput 1 standard error apart is within noise; a power 10 % and 7 standard errors
// apart is biased; a hold-up 3.5 standard errors but 1 % apart moved within the 5 % tolerance; a
// spillage (a total, no standard error) 20 % apart is biased by the tolerance alone; the run's own
// noise rows are not KPIs.
TEST(CoarseGrainCheck, EachKpiIsJudgedByItsDifferenceInStandardErrors) {
  std::string text = kCoarse;
  text.erase(text.find("sweep:"), text.find("coarse_grain_check:") - text.find("sweep:"));
  text.erase(text.find("  kpis:"), text.find("  duration:") - text.find("  kpis:"));
  const app::SweepPlan plan = app::read_sweep(YAML::Load(text), "coarse.yaml");
  ASSERT_EQ(plan.variants.size(), 2u);
  std::vector<report::SweepVariant> variants(2);
  auto set = [](report::SweepVariant& v, const std::string& name, double value, double std_error) {
    v.metrics.values.emplace_back(name, value);
    if (std_error > 0) v.metrics.std_errors[name] = std_error;
  };
  set(variants[0], "throughput_t_h", 100, 2), set(variants[1], "throughput_t_h", 102.8, 2);
  set(variants[0], "throughput_std_t_h", 7, 0), set(variants[1], "throughput_std_t_h", 9, 0);
  set(variants[0], "power_total_W", 500, 5), set(variants[1], "power_total_W", 550, 5);
  set(variants[0], "holdup_kg", 10.0, 0.02), set(variants[1], "holdup_kg", 10.1, 0.02);
  set(variants[0], "spillage_kg", 1.0, 0), set(variants[1], "spillage_kg", 1.2, 0);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "demdesign_coarse_grain_check_test";
  std::filesystem::remove_all(dir);
  const app::BiasSummary summary = app::summarise_bias_check(plan, variants, dir.string());
  std::map<std::string, const app::KpiShift*> by_metric;
  for (const app::KpiShift& s : summary.shifts) by_metric[s.metric] = &s;
  ASSERT_EQ(by_metric.size(), 4u) << "throughput_std_t_h is a run's noise, not a KPI";
  EXPECT_NEAR(by_metric.at("throughput_t_h")->z, 2.8 / std::hypot(2.0, 2.0), 1e-9);
  EXPECT_FALSE(by_metric.at("throughput_t_h")->sensitive) << by_metric.at("throughput_t_h")->words;
  EXPECT_NE(by_metric.at("throughput_t_h")->words.find("within noise"), std::string::npos) << by_metric.at("throughput_t_h")->words;
  EXPECT_NEAR(by_metric.at("power_total_W")->z, 50 / std::hypot(5.0, 5.0), 1e-9);
  EXPECT_TRUE(by_metric.at("power_total_W")->sensitive);
  EXPECT_NE(by_metric.at("power_total_W")->words.find("moved by +7.1 sigma: coarse graining biases this KPI"), std::string::npos)
      << by_metric.at("power_total_W")->words;
  EXPECT_GT(by_metric.at("holdup_kg")->z, 3.0);
  EXPECT_FALSE(by_metric.at("holdup_kg")->sensitive) << by_metric.at("holdup_kg")->words;
  EXPECT_TRUE(std::isnan(by_metric.at("spillage_kg")->z));
  EXPECT_TRUE(by_metric.at("spillage_kg")->sensitive) << by_metric.at("spillage_kg")->words;
  EXPECT_EQ(summary.flag_word, "BIASED");
  EXPECT_NE(summary.html.find("What coarse graining costs"), std::string::npos);
  // The CSV: a header and one row per KPI, each naming both factors.
  std::ifstream csv(dir / "coarse_grain_check.csv");
  std::vector<std::string> lines;
  for (std::string line; std::getline(csv, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0].rfind("design,metric,coarse_grain,value,std_error,finer_coarse_grain,finer_value,", 0), 0u) << lines[0];
  EXPECT_NE(lines[1].find(",throughput_t_h,2,100,2,1.25,102.8,2,"), std::string::npos) << lines[1];
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
