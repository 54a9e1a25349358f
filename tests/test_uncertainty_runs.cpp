// Design numbers with error bars, run by the real binary: a small silo discharging beads whose
// friction is known from a calibration as 0.5 +- 0.1 (normal), three orifices. The band of the
// flow the `uncertainty:` section reports equals the band of a plain sweep over the same friction
// values (the same runs, whichever way they are asked for); the wider orifice (40 against 30 mm:
// Beverloo's (D0 - 1.5 d)^2.5 gives 2.3 times the flow) beats the narrower at every parameter set,
// while two orifices 0.2 mm apart (Beverloo: 2 % more flow, inside the run-to-run scatter) are not
// told apart with certainty. The flow over time is drawn as a band per design.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "binary_runs.h"

namespace {

namespace fs = std::filesystem;
using namespace dem::test;

const fs::path kScratch = fs::temp_directory_path() / "demdesign_uncertainty_runs_test";

/// The q-quantile of sorted values, linear between order statistics (as the report computes it).
double quantile(const std::vector<double>& sorted, double q) {
  const double at = q * static_cast<double>(sorted.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(at)), hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (at - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

/// The folder of sweep variant k (1-based): "v01".
std::string variant(int k) { return (k < 10 ? "v0" : "v") + std::to_string(k); }

double metric(const fs::path& metrics_csv, const std::string& name) {
  for (const auto& row : csv_rows(metrics_csv))
    if (row.size() >= 2 && row[0] == name) return std::atof(row[1].c_str());  // name,value,std_error
  return std::nan("");
}

const char* kMaterial = R"(name: beads_calibrated
description: 6 mm beads whose friction a calibration knows to +-0.1
contact: {normal: hertz, damping: restitution, tangential: mindlin, rolling: epsd}
properties: {density: 2500, youngs_modulus: 5.0e6, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5, rolling_friction: 0.1}
size: 0.006
tunable:
  friction: [0.1, 0.9]
calibration:
  command: calibrate
  measurements: "lab.yaml"
  parameters: [friction]
  value: [0.5]
  sigma: [0.1]
  correlation:
    - [1]
  chi2_per_n: 1.0
)";

std::string silo_case(const std::string& sections) {
  return R"(title: small silo, friction uncertain
simulation: {duration: 0.75, gravity: [0, 0, -9.81], seed: 3}
materials:
  beads: {library: beads_calibrated}
  steel: {density: 7800, youngs_modulus: 2.0e11, poisson_ratio: 0.3, restitution: 0.5, friction: 0.5, rolling_friction: 0.1}
contact: {normal: hertz, damping: restitution, tangential: mindlin, rolling: epsd}
equipment:
  silo: {diameter: 0.07, height: 0.12, orifice_diameter: 0.03, open_at: 0.3}
particles:
  - material: beads
    diameter: {distribution: uniform, min: 0.0055, max: 0.0065}
    count: 1200
    region: {min: [-0.022, -0.022, 0.005], max: [0.022, 0.022, 0.30]}
output: {directory: out/silo, records_from: 0.35}
)" + sections;
}

TEST(UncertaintyRuns, SiloFlowBandEqualsADirectSweepAndTheRankingKnowsWhatItCannotTell) {
  fs::remove_all(kScratch);
  fs::create_directories(kScratch);
  std::ofstream(kScratch / "beads_calibrated.yaml") << kMaterial;
  const int samples = 6;
  std::ofstream(kScratch / "uncertain.yaml") << silo_case(R"(sweep:
  parameters:
    equipment.silo.orifice_diameter: [0.03, 0.0302, 0.04]
  rank_by:
    - {metric: throughput_t_h, goal: maximize}
uncertainty: {samples: 6, seed: 2}
)");
  ASSERT_EQ(run_case(kScratch / "uncertain.yaml", kScratch / "uncertain"), 0) << read_text(kScratch / "uncertain.log");

  // The friction of each run of the 30 mm design (variants v01..v06), as its case.yaml says.
  std::vector<double> friction;
  for (int s = 1; s <= samples; ++s) {
    const YAML::Node c = YAML::LoadFile((kScratch / "uncertain" / "variants" / variant(s) / "case.yaml").string());
    friction.push_back(c["materials"]["beads"]["friction"].as<double>());
  }
  std::vector<double> sorted = friction;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_LT(sorted.front(), 0.45) << "a space-filling draw from N(0.5, 0.1) spans the distribution";
  EXPECT_GT(sorted.back(), 0.55);

  // A plain sweep over the same friction values, as a user would run it by hand.
  std::string values;
  for (double f : friction) {
    std::ostringstream v;
    v.precision(17);
    v << f;
    values += (values.empty() ? "" : ", ") + v.str();
  }
  std::ofstream(kScratch / "direct.yaml") << silo_case("sweep:\n  parameters:\n    materials.beads.friction: [" + values + "]\n");
  ASSERT_EQ(run_case(kScratch / "direct.yaml", kScratch / "direct"), 0) << read_text(kScratch / "direct.log");
  std::vector<double> direct;
  for (int s = 1; s <= samples; ++s)
    direct.push_back(metric(kScratch / "direct" / "variants" / variant(s) / "report" / "metrics.csv", "throughput_t_h"));
  std::sort(direct.begin(), direct.end());

  std::map<std::string, std::vector<double>> band;  // design -> median, p05, p95 of the flow
  for (const auto& row : csv_rows(kScratch / "uncertain" / "report" / "uncertainty.csv"))
    if (row.size() == 7 && row[1] == "throughput_t_h") band[row[0]] = {std::atof(row[2].c_str()), std::atof(row[3].c_str()), std::atof(row[4].c_str())};
  ASSERT_TRUE(band.count("silo.orifice_diameter=0.03")) << read_text(kScratch / "uncertain" / "report" / "uncertainty.csv");
  const auto& b = band.at("silo.orifice_diameter=0.03");
  EXPECT_NEAR(b[0], quantile(direct, 0.5), 1e-6 * b[0]);
  EXPECT_NEAR(b[1], quantile(direct, 0.05), 1e-6 * b[0]);
  EXPECT_NEAR(b[2], quantile(direct, 0.95), 1e-6 * b[0]);
  EXPECT_GT(b[2], b[1]) << "friction moves the flow: the band has a width";

  std::map<std::pair<std::string, std::string>, double> beats;
  for (const auto& row : csv_rows(kScratch / "uncertain" / "report" / "beats.csv"))
    if (row.size() == 5 && row[0] == "throughput_t_h") beats[{row[1], row[2]}] = std::atof(row[3].c_str());
  const double wide = beats.at({"silo.orifice_diameter=0.04", "silo.orifice_diameter=0.03"});
  const double near = beats.at({"silo.orifice_diameter=0.0302", "silo.orifice_diameter=0.03"});
  EXPECT_EQ(wide, 1.0) << "40 mm against 30 mm: 2.3 times the flow at every friction";
  EXPECT_GT(near, 0.0) << "0.2 mm apart: not certain";
  EXPECT_LT(near, 1.0) << "0.2 mm apart: not certain";
  EXPECT_NE(read_text(kScratch / "uncertain" / "report" / "sweep.html").find("Which design wins"), std::string::npos);
  // The flow over time as a band per design: the median line and the 5-95 % band of each design.
  const std::string bands = read_text(kScratch / "uncertain" / "report" / "plots" / "band_outlet_flow.tsv");
  EXPECT_NE(bands.find("# silo.orifice_diameter=0.04: outlet discharge"), std::string::npos) << bands.substr(0, 300);
  EXPECT_TRUE(fs::exists(kScratch / "uncertain" / "report" / "plots" / "band_outlet_flow.png"));
  EXPECT_NE(read_text(kScratch / "uncertain" / "report" / "sweep.html").find("KPIs over time"), std::string::npos);
  std::cout << "flow of the 30 mm orifice: median " << b[0] << " t/h, 90 % band [" << b[1] << ", " << b[2] << "] (direct sweep: "
            << quantile(direct, 0.5) << " [" << quantile(direct, 0.05) << ", " << quantile(direct, 0.95) << "]); P(40 mm beats 30 mm) = "
            << wide << ", P(30.2 mm beats 30 mm) = " << near << "\n";
}

}  // namespace
