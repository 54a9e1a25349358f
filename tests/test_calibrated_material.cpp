// A calibrated material as a library file: written by calibrate/diagnose, read back by the
// material library and by a case, refused when edited after its fit, and sampled for design runs;
// the coarse_grain it was fitted at, named to a case that runs it at another.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "calibration/calibrated_material.h"
#include "case/calibration_record.h"
#include "core/model.h"
#include "model/library.h"
#include "model/material_model.h"

namespace dem::materials {
namespace {

namespace fs = std::filesystem;
const std::string kMaterials = DEMDESIGN_SOURCE_DIR "/materials";

/// A fit of gravel's friction and rolling friction (made by hand: the file is what is tested).
CalibrationResult gravel_fit() {
  CalibrationResult r;
  r.fitted = read_material_model(kMaterials + "/gravel.yaml");
  r.parameters = {{"friction", 0.1, 0.9}, {"rolling_friction", 0.0, 0.5}, {"steel.friction", 0.1, 0.9}};
  r.value = {0.537, 0.214, 0.41};
  r.sigma = {0.021, 0.013, 0.05};
  r.correlation = {{1, -0.62, 0.1}, {-0.62, 1, 0}, {0.1, 0, 1}};
  for (size_t k = 0; k < r.parameters.size(); ++k) set_parameter(r.fitted, r.parameters[k].key, r.value[k]);
  r.after.chi2 = 6.3, r.after.n = 7;
  return r;
}

/// A folder of the running test's own: ctest runs tests in parallel processes, and two tests
/// sharing one folder would remove each other's files.
fs::path scratch() {
  const fs::path dir = fs::temp_directory_path() /
                       (std::string("demdesign_calibrated_material_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(CalibratedMaterial, RoundTripsThroughTheLibraryAndACase) {
  const fs::path dir = scratch();
  const CalibrationResult fit = gravel_fit();
  write_calibrated_material((dir / "gravel_calibrated.yaml").string(), fit, {"diagnose", "lab/gravel.yaml", "2026-12-03", "with epsd"});
  const MaterialModel back = read_material_model((dir / "gravel_calibrated.yaml").string());
  for (size_t k = 0; k < fit.parameters.size(); ++k)
    EXPECT_NEAR(get_parameter(back, fit.parameters[k].key), fit.value[k], 1e-9) << fit.parameters[k].key;
  EXPECT_EQ(back.contact.rolling.model, fit.fitted.contact.rolling.model);
  EXPECT_EQ(back.tunable, fit.fitted.tunable);
  ASSERT_TRUE(back.particle.calibration.has_value());
  const CalibrationRecord& r = *back.particle.calibration;
  EXPECT_EQ(r.command, "diagnose");
  EXPECT_EQ(r.measurements, "lab/gravel.yaml");
  EXPECT_EQ(r.parameters, (std::vector<std::string>{"friction", "rolling_friction", "steel.friction"}));
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(r.value[i], fit.value[i], 1e-12);
    EXPECT_NEAR(r.sigma[i], fit.sigma[i], 1e-12);
    for (size_t j = 0; j < 3; ++j) EXPECT_NEAR(r.correlation[i][j], fit.correlation[i][j], 1e-12);
  }
  EXPECT_NEAR(r.chi2_per_n, 0.9, 1e-12);
  EXPECT_NE(std::find(r.effects.begin(), r.effects.end(), "epsd"), r.effects.end());
  // A case names it from its own folder and gets the fitted values with their record (steel from
  // the material library).
  const CaseSpec spec = parse_case_text(
      "simulation: {duration: 0.001}\nmaterials:\n  g: {library: gravel_calibrated}\n  steel: {library: steel}\n"
      "particles:\n  - {material: g, diameter: 0.01, positions: [[0, 0, 0]]}\n",
      (dir / "case.yaml").string(), library_lookup());
  const auto g = std::find_if(spec.materials.begin(), spec.materials.end(), [](const MaterialSpec& m) { return m.name == "g"; });
  ASSERT_NE(g, spec.materials.end());
  ASSERT_TRUE(g->calibration.has_value());
  EXPECT_NEAR(g->params.at("friction"), 0.537, 1e-12);
}

// A material of sphere clumps: the file keeps the fitted shape under `shape:`, the material
// library reads it back as the model's shape, and a case's particle set and inlet of the material
// are its clumps (a template named after the material) unless they name a clump of their own.
TEST(CalibratedMaterial, AShapeOfClumpsRoundTripsAndACaseUsesIt) {
  const fs::path dir = scratch();
  CalibrationResult fit = gravel_fit();
  ClumpTemplateSpec three;
  three.centres = {Vec3(0, 0, 0), Vec3(0.7, 0, 0), Vec3(0.35, 0.6, 0)};
  three.radii = {0.5, 0.5, 0.4};
  fit.fitted.shape = {three};
  write_calibrated_material((dir / "ore.yaml").string(), fit, {"calibrate", "lab/ore.yaml", "2026-12-07", ""});
  const MaterialModel back = read_material_model((dir / "ore.yaml").string());
  ASSERT_EQ(back.shape.size(), 1u);
  ASSERT_EQ(back.shape[0].radii.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(back.shape[0].radii[k], three.radii[k], 1e-12);
    EXPECT_NEAR((back.shape[0].centres[k] - three.centres[k]).norm(), 0.0, 1e-12);
  }
  EXPECT_FALSE(back.particle.shape.has_value());  // the model's, not the material's
  const CaseSpec spec = parse_case_text(
      "simulation: {duration: 0.001}\nmaterials:\n  rock: {library: ore}\n  steel: {library: steel}\n"
      "clumps:\n  pair: {spheres: [{centre: [0, 0, 0], diameter: 1}, {centre: [0.5, 0, 0], diameter: 1}]}\n"
      "particles:\n  - {material: rock, diameter: 0.01, positions: [[0, 0, 0.05]]}\n"
      "  - {material: rock, clump: pair, diameter: 0.01, positions: [[0.05, 0, 0.05]]}\n"
      "  - {material: steel, diameter: 0.01, positions: [[0.1, 0, 0.05]]}\n"
      "inlets:\n  - {material: rock, diameter: 0.01, mass_rate_kgs: 1, region: {min: [0, 0, 0.2], max: [0.1, 0.1, 0.3]}}\n",
      (dir / "case.yaml").string(), library_lookup());
  const Model model = compile(spec);
  ASSERT_EQ(model.clumps.size(), 2u);
  ASSERT_EQ(model.sources.size(), 3u);
  EXPECT_EQ(model.clumps[model.sources[0].clump].name, "rock");
  EXPECT_EQ(model.clumps[model.sources[0].clump].radii.size(), 3u);
  EXPECT_EQ(model.clumps[model.sources[1].clump].name, "pair");
  EXPECT_EQ(model.sources[2].clump, -1);
  ASSERT_EQ(model.inlets.size(), 1u);
  EXPECT_EQ(model.clumps[model.inlets[0].clump].name, "rock");
  std::string notes;
  for (const std::string& n : model.notes) notes += n + "\n";
  EXPECT_NE(notes.find("particles[0]: clumps of 3 spheres, the shape material 'rock' gives"), std::string::npos) << notes;
  EXPECT_NE(notes.find("inlets[0]: clumps of 3 spheres"), std::string::npos) << notes;
  EXPECT_EQ(notes.find("particles[1]: clumps"), std::string::npos) << notes;
  // The message a case of the shaped material is refused with ("" when it compiles).
  const auto refusal = [&](const std::string& rest) {
    try {
      (void)compile(parse_case_text("simulation: {duration: 0.001}\nmaterials:\n  rock: {library: ore}\n  steel: {library: steel}\n" + rest,
                                    (dir / "case.yaml").string(), library_lookup()));
    } catch (const CaseError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // Glued particles are spheres: a set of the shaped material cannot be glued, and is told why.
  const std::string glued = refusal(
      "walls:\n  - {name: plate, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: steel}\n"
      "particles:\n  - {material: rock, diameter: 0.01, positions: [[0, 0, 0.005]], attach_to: plate}\n");
  EXPECT_NE(glued.find("material 'rock' gives clumps: glue spheres of a material without a `shape:`"), std::string::npos) << glued;
  // A case template of the material's name would be ambiguous.
  const std::string named = refusal(
      "clumps:\n  rock: {spheres: [{centre: [0, 0, 0], diameter: 1}]}\n"
      "particles:\n  - {material: rock, diameter: 0.01, positions: [[0, 0, 0.05]]}\n");
  EXPECT_NE(named.find("clumps.rock: the material 'rock' gives its particles' shape"), std::string::npos) << named;
}

// A fit at the parcel size (--coarse-grain 2): the file records the coarse_grain its virtual tests
// ran at, and a case that runs the material at another coarse_grain (real particles, or 3) is
// told in its set-up notes, with the comparison that would check it; at 2 nothing is said.
TEST(CalibratedMaterial, RecordsItsCoarseGrainAndACaseAtAnotherIsTold) {
  const fs::path dir = scratch();
  CalibrationResult fit = gravel_fit();
  fit.fitted.coarse_grain = 2;
  write_calibrated_material((dir / "gravel_calibrated.yaml").string(), fit, {"calibrate", "lab/gravel.yaml", "2026-12-03", ""});
  EXPECT_NE(read_text(dir / "gravel_calibrated.yaml").find("\n  coarse_grain: 2\n"), std::string::npos);
  const MaterialModel back = read_material_model((dir / "gravel_calibrated.yaml").string());
  ASSERT_TRUE(back.particle.calibration.has_value());
  EXPECT_DOUBLE_EQ(back.particle.calibration->coarse_grain, 2.0);
  const auto notes = [&](const std::string& coarse_grain) {
    const CaseSpec spec = parse_case_text(
        "simulation: {duration: 0.001}\nmaterials:\n  g: {library: gravel_calibrated}\n  steel: {library: steel}\n"
        "particles:\n  - {material: g, diameter: 0.01, positions: [[0, 0, 0.05]]" + coarse_grain + "}\n",
        (dir / "case.yaml").string(), library_lookup());
    std::string all;
    for (const std::string& n : compile(spec).notes) all += n + "\n";
    return all;
  };
  const std::string same = notes(", coarse_grain: 2"), real = notes(""), coarser = notes(", coarse_grain: 3");
  EXPECT_EQ(same.find("was calibrated at coarse_grain"), std::string::npos) << same;
  EXPECT_NE(real.find("was calibrated at coarse_grain 2 and is used here at coarse_grain 1: the scaling law carries it"), std::string::npos)
      << real;
  EXPECT_NE(real.find("compare at 1 to check (demdesign compare"), std::string::npos) << real;
  EXPECT_NE(real.find("lab/gravel.yaml --coarse-grain 1"), std::string::npos) << real;
  EXPECT_NE(coarser.find("was calibrated at coarse_grain 2 and is used here at coarse_grain 3"), std::string::npos) << coarser;
}

TEST(CalibratedMaterial, AFileEditedAfterItsFitOrWithABadCorrelationIsRefused) {
  const fs::path dir = scratch();
  const fs::path file = dir / "gravel_calibrated.yaml";
  write_calibrated_material(file.string(), gravel_fit(), {"calibrate", "lab/gravel.yaml", "2026-12-03", ""});
  const std::string text = read_text(file);
  // Friction edited by hand: the record no longer describes the file.
  std::string edited = text;
  edited.replace(edited.find("  friction: 0.537"), 17, "  friction: 0.600");
  std::ofstream(file) << edited;
  try {
    read_material_model(file.string());
    FAIL() << "an edited calibrated material was accepted";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("edited after its calibration"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("gravel_calibrated.yaml:"), std::string::npos) << e.what();
  }
  // A correlation that no three real parameters can have (pairwise 0.9, 0.9 and -0.9).
  std::string bad = text;
  const size_t at = bad.find("  correlation:");
  const size_t end = bad.find("  chi2_per_n");
  bad.replace(at, end - at, "  correlation:\n    - [1, 0.9, 0.9]\n    - [0.9, 1, -0.9]\n    - [0.9, -0.9, 1]\n");
  std::ofstream(file) << bad;
  try {
    read_material_model(file.string());
    FAIL() << "a correlation that is not positive semi-definite was accepted";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("calibration.correlation"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("positive semi-definite"), std::string::npos) << e.what();
  }
}

// Draws from the record: sample means, standard deviations and correlation match the record
// within their sampling error (2000 draws: 3 standard errors on the mean, 6 % on sigma, 0.05 on
// the correlation); each parameter's Latin-hypercube strata are filled once when uncorrelated;
// clipping keeps every draw in range.
TEST(CalibratedMaterial, PosteriorSamplesFollowTheRecord) {
  CalibrationRecord r;
  r.parameters = {"friction", "restitution"};
  r.value = {0.5, 0.4};
  r.sigma = {0.1, 0.02};
  r.correlation = {{1, 0.8}, {0.8, 1}};
  const int n = 2000;
  const auto draws = posterior_samples(r, n, 7);
  ASSERT_EQ(draws.size(), static_cast<size_t>(n));
  double m[2] = {}, s[2] = {}, c = 0;
  for (const auto& d : draws) m[0] += d[0] / n, m[1] += d[1] / n;
  for (const auto& d : draws) {
    s[0] += (d[0] - m[0]) * (d[0] - m[0]) / (n - 1), s[1] += (d[1] - m[1]) * (d[1] - m[1]) / (n - 1);
    c += (d[0] - m[0]) * (d[1] - m[1]) / (n - 1);
  }
  for (int j = 0; j < 2; ++j) {
    EXPECT_NEAR(m[j], r.value[j], 3 * r.sigma[j] / std::sqrt(n));
    EXPECT_NEAR(std::sqrt(s[j]), r.sigma[j], 0.06 * r.sigma[j]);
  }
  EXPECT_NEAR(c / std::sqrt(s[0] * s[1]), 0.8, 0.05);
  // Uncorrelated: 16 draws put exactly one in each sixteenth of each marginal.
  r.correlation = {{1, 0}, {0, 1}};
  const auto lhs = posterior_samples(r, 16, 3);
  for (int j = 0; j < 2; ++j) {
    std::vector<int> filled(16, 0);
    for (const auto& d : lhs) {
      const double p = 0.5 * std::erfc(-(d[j] - r.value[j]) / r.sigma[j] / std::sqrt(2.0));
      ++filled[std::min(15, static_cast<int>(p * 16))];
    }
    for (int k = 0; k < 16; ++k) EXPECT_EQ(filled[k], 1) << "parameter " << j << " stratum " << k;
  }
  for (const auto& d : posterior_samples(r, 200, 5, {{0.45, 0.55}, {0.0, 1.0}})) {
    EXPECT_GE(d[0], 0.45);
    EXPECT_LE(d[0], 0.55);
  }
}

}  // namespace
}  // namespace dem::materials
