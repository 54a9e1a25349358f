// A contributor's effect (tests/effects/viscous_dashpot.cpp: one file, one registration line,
// no edit anywhere else) reaches every tool: the effect table and `demdesign effects`, a case's
// contact model, the diagnosis (which proposes it on data made with it) and the calibration
// (which finds its strength again).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "calibration/calibration.h"
#include "case/spec.h"
#include "contact/effect.h"
#include "core/model.h"
#include "model/material_model.h"

namespace dem::materials {
namespace {

constexpr double kTrueDashpot = 0.03;  // [N s/m]

/// Soft 3 mm spheres dropped on steel (E = 0.5 MPa: a time step of about 1e-5 s, so a drop takes
/// a few tens of milliseconds); the restitution of the sphere-steel pair is what the plain model
/// calibrates.
MaterialModel soft_spheres() {
  MaterialModel m;
  m.name = m.particle.name = "soft_spheres";
  m.particle.density = 2500, m.particle.youngs_modulus = 5e5, m.particle.poisson_ratio = 0.25;
  m.particle.params = {{"restitution", 0.8}, {"friction", 0.4}};
  m.diameter.kind = SizeDistributionSpec::Kind::fixed;
  m.diameter.value = 0.003;
  MaterialSpec steel;
  steel.name = "steel", steel.density = 7800, steel.youngs_modulus = 2e11, steel.poisson_ratio = 0.3;
  m.walls.push_back(steel);
  InteractionSpec pair;
  pair.material_a = m.name, pair.material_b = "steel";
  pair.params = {{"restitution", 0.8}, {"friction", 0.4}};
  m.wall_pairs.push_back(pair);
  return m;
}

/// Drops from 2 mm to 500 mm, restitution measured to +-0.005 (no noise added: the data are
/// the truth's own simulation).
MeasurementSet drops_made_with(const MaterialModel& truth) {
  MeasurementSet set;
  for (const double h : {0.002, 0.01, 0.05, 0.2, 0.5}) {
    Experiment e;
    e.id = fmt::format("drop_{:.0f}mm", h * 1000);
    e.setup.test = "drop_rebound";
    e.setup.numbers = {{"drop_height", h}};
    e.setup.words = {{"plate", "steel"}};
    TestOptions o;
    o.threads = 1;
    e.observed["restitution"] = Observation{run_virtual_test(truth, e.setup, o).observables.at("restitution"), 0.005, {}};
    set.experiments.push_back(e);
  }
  return set;
}

TEST(ContributorEffect, OneFileReachesTheTableTheDocsAndACase) {
  const EffectSpec* e = find_effect(Stage::extra, "viscous_dashpot");
  ASSERT_NE(e, nullptr);
  ASSERT_NE(find_param("dashpot_coefficient"), nullptr);
  const std::string listing = describe_effects();  // what `demdesign effects` prints
  EXPECT_NE(listing.find("contact.extra: viscous_dashpot"), std::string::npos);
  EXPECT_NE(listing.find("diagnosis candidate (viscous normal dashpot)"), std::string::npos);
  // A case switches it on with one key and sets its parameter like any other.
  const CaseSpec spec = parse_case_text(R"(simulation: {duration: 0.01}
contact: {normal: hertz, damping: restitution, extra: [viscous_dashpot]}
materials:
  beads: {density: 2500, youngs_modulus: 5e5, restitution: 0.8, dashpot_coefficient: 0.01}
particles:
  - {material: beads, diameter: 0.003, positions: [[0, 0, 0.1]]}
)");
  const Model model = compile(spec, {});
  EXPECT_DOUBLE_EQ(model.pair_param(0, 0, "dashpot_coefficient"), 0.01);
  // A second registration of the same name is refused.
  EXPECT_THROW(register_effect(e), std::invalid_argument);
  // A normal law that does not say how long its contacts last is refused: the time step could not
  // resolve them. The shipped laws say it: Hertz's impact time (Johnson 1985) and the linear
  // spring's half period.
  static const EffectSpec silent_normal{.stage = Stage::normal, .name = "silent_normal", .kernel = e->kernel};
  try {
    register_effect(&silent_normal);
    ADD_FAILURE() << "a normal law without contact_time was registered";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("must give its contact_time"), std::string::npos) << error.what();
  }
  for (const EffectSpec* table_row : effect_table())
    if (table_row->stage == Stage::normal) EXPECT_NE(table_row->contact_time, nullptr) << table_row->name;
  const EffectSpec* hertz = find_effect(Stage::normal, "hertz");
  const EffectSpec* linear = find_effect(Stage::normal, "linear");
  ASSERT_TRUE(hertz && hertz->contact_time && linear && linear->contact_time);
  const double row[1] = {1e7}, spring[3] = {1000.0, 1.0, 2.0 / 7.0};
  EXPECT_DOUBLE_EQ(hertz->contact_time(row, nullptr, 1e-3, 1e-3, 1.0), hertz_contact_time(1e-3, 1e-3, 1e7, 1.0));
  EXPECT_NEAR(linear->contact_time(row, spring, 1e-3, 1e-3, 1.0), 3.14159265 * std::sqrt(1e-3 / 1000.0), 1e-9);
  EXPECT_TRUE(hertz->rayleigh_binds);
  EXPECT_FALSE(linear->rayleigh_binds);
}

TEST(ContributorEffect, DiagnoseProposesItAndCalibrationFindsItsStrength) {
  const MaterialModel start = soft_spheres();
  MaterialModel truth = start;
  std::vector<EffectCandidate> candidates = missing_effects(start);
  const auto it = std::find_if(candidates.begin(), candidates.end(), [](const EffectCandidate& c) { return c.name == "viscous_dashpot"; });
  ASSERT_NE(it, candidates.end()) << "the effect's CandidateSpec makes it a candidate";
  it->add(truth);
  set_parameter(truth, "dashpot_coefficient", kTrueDashpot);
  const MeasurementSet measured = drops_made_with(truth);

  CalibrationOptions options;
  options.replicas = 1;  // one sphere: every replica is the same
  options.threads = 1;
  options.confirm_candidates = static_cast<int>(candidates.size());
  const Diagnosis d = diagnose(start, measured, {{"steel.restitution", 0.5, 0.98}}, options);
  ASSERT_FALSE(d.words.empty());
  EXPECT_GT(d.base.after.chi2_per_n(), 5.0) << "a constant restitution cannot follow the speed dependence";
  EXPECT_EQ(d.recommended, "viscous_dashpot") << fmt::format("{}", fmt::join(d.words, "\n"));
  const auto found = std::find_if(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& c) { return c.name == "viscous_dashpot"; });
  ASSERT_NE(found, d.candidates.end());
  ASSERT_TRUE(found->confirmed);
  EXPECT_LE(found->fit.after.chi2_per_n(), 1.5);
  // The fitted strength: the particle's c (the steel pair mixes it with steel's 0 as the truth did).
  const double fitted = get_parameter(found->fit.fitted, "dashpot_coefficient");
  EXPECT_NEAR(fitted, kTrueDashpot, 0.2 * kTrueDashpot);
  EXPECT_NE(d.words.front().find("viscous normal dashpot"), std::string::npos) << d.words.front();
}

}  // namespace
}  // namespace dem::materials
