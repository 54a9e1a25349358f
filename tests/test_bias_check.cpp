// What reduced stiffness costs: the `bias_check:` section of a case, run by the real binary. A
// soft packing's density near the floor depends on the particle stiffness (Hertz overlap under
// the bed's weight, about 10 % of a diameter at the bottom of a 20-layer column of E = 0.1 MPa
// beads, 2 % when ten times stiffer): flagged. A dense silo's discharge rate does not (Beverloo:
// the flow is set by the orifice, gravity and the bulk density, not by the contact stiffness):
// not flagged. A calibrated material run at another stiffness than it was calibrated at is named.
// `compare --stiffness-check` says the same of a calibration's observables.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "binary_runs.h"
#include "case/spec.h"
#include "core/model.h"

namespace {

namespace fs = std::filesystem;
using namespace dem::test;

const fs::path kScratch = fs::temp_directory_path() / "demdesign_bias_check_test";

/// bias_check.csv of a run: metric -> (shift [%], sensitive).
std::map<std::string, std::pair<double, bool>> shifts(const fs::path& out) {
  std::map<std::string, std::pair<double, bool>> m;
  // design,check,metric,as_case,checked,shift_pct,noise_pct,sensitive
  for (const auto& cells : csv_rows(out / "report/bias_check.csv"))
    if (cells.size() == 8) m[cells[2]] = {std::atof(cells[5].c_str()), cells[7] == "1"};
  return m;
}

TEST(BiasCheck, ASoftPackingsDensityIsFlaggedADenseSilosFlowIsNot) {
  fs::remove_all(kScratch);
  fs::create_directories(kScratch);
  // 20 layers of 7 x 7 beads (4 mm, lattice 4.2 mm, jittered by at most 0.1 mm) settling in a
  // 30 mm square column; the box sensor holds the lowest 20 mm.
  std::string positions;
  std::uint32_t state = 3;
  auto jitter = [&] {
    state = state * 1664525u + 1013904223u;
    return 1e-4 * (2.0 * (state >> 8) / double(1u << 24) - 1.0);
  };
  for (int k = 0; k < 20; ++k)
    for (int i = 0; i < 7; ++i)
      for (int j = 0; j < 7; ++j)
        positions += (positions.empty() ? "" : ", ") + std::string("[") + std::to_string(-0.0126 + 0.0042 * i + jitter()) + ", " +
                     std::to_string(-0.0126 + 0.0042 * j + jitter()) + ", " + std::to_string(0.0021 + 0.0042 * k) + "]";
  std::ofstream(kScratch / "soft.yaml") << R"(title: soft packing under its own weight
simulation: {duration: 0.6, gravity: [0, 0, -9.81], seed: 4}
materials:
  soft: {density: 2500, youngs_modulus: 1.0e5, poisson_ratio: 0.25, restitution: 0.3, friction: 0.3}
  steel: {density: 7800, youngs_modulus: 2.0e11, poisson_ratio: 0.3, restitution: 0.3, friction: 0.3}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
walls:
  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: steel}
  - {name: x0, plane: {point: [-0.015, 0, 0], normal: [1, 0, 0]}, material: steel}
  - {name: x1, plane: {point: [0.015, 0, 0], normal: [-1, 0, 0]}, material: steel}
  - {name: y0, plane: {point: [0, -0.015, 0], normal: [0, 1, 0]}, material: steel}
  - {name: y1, plane: {point: [0, 0.015, 0], normal: [0, -1, 0]}, material: steel}
particles:
  - {material: soft, diameter: 0.004, positions: [)" << positions << R"(]}
sensors:
  - {name: bottom, box: {min: [-0.015, -0.015, -0.001], max: [0.015, 0.015, 0.02]}}
output: {directory: out/soft, records_from: 0.4}
bias_check: {stiffness_factor: 10}
)";
  std::ofstream(kScratch / "silo.yaml") << R"(title: dense silo discharge
simulation: {duration: 0.9, gravity: [0, 0, -9.81], seed: 3}
materials:
  beads: {density: 2500, youngs_modulus: 5.0e6, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5, rolling_friction: 0.1}
  steel: {density: 7800, youngs_modulus: 2.0e11, poisson_ratio: 0.3, restitution: 0.5, friction: 0.5, rolling_friction: 0.1}
contact: {normal: hertz, damping: restitution, tangential: mindlin, rolling: epsd}
equipment:
  silo: {diameter: 0.09, height: 0.16, orifice_diameter: 0.035, open_at: 0.4}
particles:
  - material: beads
    diameter: {distribution: uniform, min: 0.0055, max: 0.0065}
    count: 2500
    region: {min: [-0.03, -0.03, 0.005], max: [0.03, 0.03, 0.40]}
output: {directory: out/silo, records_from: 0.45}
bias_check: {stiffness_factor: 4}
)";
  ASSERT_EQ(run_case(kScratch / "soft.yaml", kScratch / "soft"), 0) << read_text(kScratch / "soft.log");
  const auto soft = shifts(kScratch / "soft");
  ASSERT_TRUE(soft.count("mass_in_bottom_kg")) << read_text(kScratch / "soft.log");
  EXPECT_TRUE(soft.at("mass_in_bottom_kg").second) << "shift " << soft.at("mass_in_bottom_kg").first << " %";
  EXPECT_LT(soft.at("mass_in_bottom_kg").first, -5.0) << "stiffer beads overlap less: fewer fit in the lowest 20 mm";
  EXPECT_NE(read_text(kScratch / "soft.log").find("SENSITIVE: mass_in_bottom_kg"), std::string::npos) << read_text(kScratch / "soft.log");

  ASSERT_EQ(run_case(kScratch / "silo.yaml", kScratch / "silo"), 0) << read_text(kScratch / "silo.log");
  const auto silo = shifts(kScratch / "silo");
  ASSERT_TRUE(silo.count("throughput_t_h")) << read_text(kScratch / "silo.log");
  EXPECT_FALSE(silo.at("throughput_t_h").second) << "shift " << silo.at("throughput_t_h").first << " %";
  EXPECT_LT(std::abs(silo.at("throughput_t_h").first), 5.0) << "Beverloo: the orifice sets the flow";
  std::cout << "mass in the lowest 20 mm of the soft packing: " << soft.at("mass_in_bottom_kg").first
            << " % with 10x stiffer beads; silo discharge: " << silo.at("throughput_t_h").first << " % with 4x stiffer beads\n";
}

TEST(BiasCheck, ACalibratedMaterialAtAnotherStiffnessIsNamed) {
  fs::create_directories(kScratch);
  fs::copy_file(fs::path(DEMDESIGN_SOURCE_DIR) / "tests/data/beads_calibrated.yaml", kScratch / "beads_calibrated.yaml",
                fs::copy_options::overwrite_existing);
  auto notes = [&](double scaling) {
    std::ofstream(kScratch / "calibrated.yaml") << "simulation: {duration: 0.01, stiffness_scaling: " << scaling << R"(}
materials:
  beads: {library: beads_calibrated}
particles:
  - {material: beads, diameter: 0.006, positions: [[0, 0, 0.01]]}
)";
    std::string all;
    for (const std::string& n : dem::compile(dem::parse_case_file((kScratch / "calibrated.yaml").string())).notes) all += n + "\n";
    return all;
  };
  EXPECT_EQ(notes(1.0).find("was calibrated with"), std::string::npos) << "calibrated at stiffness x 1, run at x 1";
  const std::string other = notes(0.1);
  EXPECT_NE(other.find("beads was calibrated with its Young's modulus x 1"), std::string::npos) << other;
  EXPECT_NE(other.find("bias_check"), std::string::npos) << other;
}

// compare --stiffness-check: a drop's restitution does not depend on the stiffness (restitution
// damping gives the asked coefficient at any stiffness: good enough); a poured cup of soft beads
// packs denser the softer they are, by more than a tight measurement sigma: sensitive.
TEST(BiasCheck, CompareSaysWhichObservablesTheStiffnessMoves) {
  fs::create_directories(kScratch);
  std::ofstream(kScratch / "soft_beads.yaml") << R"(name: soft_beads
description: soft 5 mm beads
contact: {normal: hertz, damping: restitution, tangential: mindlin}
properties: {density: 2500, youngs_modulus: 2.0e5, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5}
size: 0.005
walls:
  steel: {friction: 0.5, restitution: 0.5}
tunable:
  friction: [0.2, 0.8]
)";
  std::ofstream(kScratch / "measurements.yaml") << R"(material: soft beads
particles: {diameter: 0.005, density: 2500}
walls:
  steel: {youngs_modulus: 2.0e11, poisson_ratio: 0.3, density: 7800}
experiments:
  - {id: drop, test: drop_rebound, setup: {drop_height: 0.05, plate: steel}, observed: {restitution: {value: 0.5, sigma: 0.02}}}
  - id: cup
    test: bulk_density
    setup: {cup_diameter: 0.05, cup_height: 0.05, pour_height: 0.02, base: steel}
    observed: {bulk_density: {value: 1500, sigma: 3}}
)";
  const fs::path out = kScratch / "compare";
  fs::remove_all(out);  // no simulations kept from an earlier run
  ASSERT_EQ(run_binary({"compare", (kScratch / "soft_beads.yaml").string(), (kScratch / "measurements.yaml").string(), "--replicas", "2",
                        "--stiffness-check", "10", "--no-renders", "--quiet", "--out", out.string()},
                       out.string() + ".log"),
            0)
      << read_text(out.string() + ".log");
  std::map<std::string, std::pair<double, bool>> rows;  // observable -> (shift in measurement sigma, sensitive)
  // observable,simulated,simulated_stiffer,shift,shift_in_measurement_sigma,noise,sensitive
  for (const auto& cells : csv_rows(out / "stiffness_check.csv"))
    if (cells.size() == 7) rows[cells[0]] = {std::atof(cells[4].c_str()), cells[6] == "1"};
  ASSERT_TRUE(rows.count("drop/restitution") && rows.count("cup/bulk_density")) << read_text(out.string() + ".log");
  EXPECT_FALSE(rows.at("drop/restitution").second) << rows.at("drop/restitution").first << " sigma";
  EXPECT_LT(std::abs(rows.at("drop/restitution").first), 1.0);
  EXPECT_TRUE(rows.at("cup/bulk_density").second) << rows.at("cup/bulk_density").first << " sigma\n" << read_text(out.string() + ".log");
  EXPECT_LT(rows.at("cup/bulk_density").first, -1.0) << "stiffer beads pack less densely";
  std::cout << "stiffness x 10: drop restitution " << rows.at("drop/restitution").first << " sigma, poured density "
            << rows.at("cup/bulk_density").first << " sigma\n";
}

}  // namespace
