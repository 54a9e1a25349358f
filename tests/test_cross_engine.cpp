// Diagnosis on measurements this engine did not make: the cross-engine sets of
// tests/data/cross_engine/ were simulated by LIGGGHTS 3.8 (calibration/liggghts/) with one effect
// switched on in each, and are diagnosed from the same starting material (plain Hertz-Coulomb
// 6 mm beads, friction and restitution guessed) with the command's defaults and a budget of 30
// minutes, as a user runs `demdesign diagnose MATERIAL SET --budget 30m`. ctest label `long`.
//
// DEMDESIGN_CROSS_ENGINE_STORE=DIR keeps the simulations in DIR/SET/ (the simulation store), so a
// second run of a test replays the first one's simulations; without it each run starts afresh.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "calibration/calibration.h"
#include "model/material_model.h"
#include "lab/measurements.h"

namespace dem::materials {
namespace {

namespace fs = std::filesystem;

struct CrossEngineRun {
  Diagnosis diagnosis;
  double seconds = 0;
};

/// Diagnoses `set` from the starting material `start` (a file of tests/data/cross_engine/).
CrossEngineRun diagnose_set(const std::string& set, const std::string& start = "glass_beads_6mm") {
  const std::string dir = std::string(DEMDESIGN_SOURCE_DIR) + "/tests/data/cross_engine/";
  MaterialModel model = read_material_model(dir + start + ".yaml");
  const MeasurementSet measured = read_measurements(dir + set + ".yaml");
  apply_measured(model, measured);
  CalibrationOptions options;  // the command's defaults
  options.parallel = std::max(1, omp_get_num_procs());
  options.budget_seconds = 30 * 60;
  const char* keep = std::getenv("DEMDESIGN_CROSS_ENGINE_STORE");
  const fs::path store = keep ? fs::path(keep) / set : fs::temp_directory_path() / ("demdesign_cross_engine_" + set);
  if (!keep) fs::remove_all(store);
  options.store = (store / "simulations").string();
  options.progress = [](const std::string& line) { std::printf("%s\n", line.c_str()), std::fflush(stdout); };
  const auto t0 = std::chrono::steady_clock::now();
  CrossEngineRun run;
  run.diagnosis = diagnose(model, measured, {}, options);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Diagnosis& d = run.diagnosis;
  std::printf("%s: %.0f s; plain model chi^2/n %.2f before, %.2f calibrated\n", set.c_str(), run.seconds, d.base.before.chi2_per_n(),
              d.base.after.chi2_per_n());
  for (const std::string& w : d.words) std::printf("  %s\n", w.c_str());
  const auto fitted = [](const CalibrationResult& r) {
    std::string out;
    for (size_t k = 0; k < r.parameters.size(); ++k) out += fmt::format("{}{} {:.4g} +- {:.2g}", k ? ", " : "", r.parameters[k].key, r.value[k], r.sigma[k]);
    return out;
  };
  std::printf("  plain model fitted: %s\n", fitted(d.base).c_str());
  for (const CandidateResult& c : d.candidates)
    std::printf("  %-16s explained %3.0f %%%s\n", c.name.c_str(), 100 * c.explained,
                c.confirmed ? fmt::format(", confirmed: chi^2/n {:.2f}, delta BIC {:+.1f}; {}", c.fit.after.chi2_per_n(), c.delta_bic, fitted(c.fit)).c_str()
                            : "");
  if (!keep) fs::remove_all(store);
  return run;
}

const CandidateResult* candidate(const Diagnosis& d, const std::string& name) {
  const auto c = std::find_if(d.candidates.begin(), d.candidates.end(), [&](const CandidateResult& r) { return r.name == name; });
  return c == d.candidates.end() ? nullptr : &*c;
}

/// The effect LIGGGHTS had switched on is recommended, or it is a rival the data cannot rule out
/// and the diagnosis names an experiment whose two predictions lie at least 3 sigma apart; and,
/// recalibrated with it, the model fits within the noise (chi^2/n at most 1.5); never a
/// confident wrong name (the grade missing or cannot tell only for the right effect).
void expect_effect_found(const CrossEngineRun& run, const std::string& effect) {
  const Diagnosis& d = run.diagnosis;
  EXPECT_GT(d.base.after.chi2_per_n(), 3.0) << "the plain model should fail visibly on these data";
  if (d.recommended != effect) {
    ASSERT_NE(std::find(d.rivals.begin(), d.rivals.end(), effect), d.rivals.end())
        << effect << " is neither recommended nor named as a rival; recommended: '" << d.recommended << "'";
    ASSERT_TRUE(d.separators.count(effect) && !d.separators.at(effect).empty()) << "no experiment proposed to tell " << effect << " from " << d.recommended;
    EXPECT_GE(d.separators.at(effect).front().separation, 3.0) << d.separators.at(effect).front().words;
  }
  const CandidateResult* c = candidate(d, effect);
  ASSERT_NE(c, nullptr);
  ASSERT_TRUE(c->confirmed);
  EXPECT_LE(c->fit.after.chi2_per_n(), 1.5) << effect << " recalibrated";
  EXPECT_TRUE(d.grade == Verdict::missing || d.grade == Verdict::cannot_tell) << verdict_words(d.grade);
}

// Plain Hertz-Mindlin in LIGGGHTS: no effect is missing. A wall parameter may be named (the
// starting material guesses the steel's friction and restitution), an effect must not be.
TEST(CrossEngine, ControlGetsNoEffect) {
  const CrossEngineRun run = diagnose_set("control");
  const Diagnosis& d = run.diagnosis;
  const CandidateResult* named = candidate(d, d.recommended);
  EXPECT_TRUE(d.recommended.empty() || (named && named->kind == "parameter")) << "recommended: " << d.recommended;
  const double chi2 = named ? named->fit.after.chi2_per_n() : d.base.after.chi2_per_n();
  EXPECT_LE(chi2, 1.5);
}

// The control with the traits a diagnosis must not read as missing physics (control_traits.yaml):
// plain Hertz-Mindlin beads on a liner as soft as they are (E 5e6 Pa), whose friction against
// them (0.15) is not theirs (0.4), so the drum's bed slides on its shell and the heap spreads; a
// silo orifice of 4.5 d50 near arching. No effect may be named, a wall parameter may.
TEST(CrossEngine, ControlWithTraitsGetsNoEffect) {
  const CrossEngineRun run = diagnose_set("control_traits", "glass_beads_6mm_liner");
  const Diagnosis& d = run.diagnosis;
  const CandidateResult* named = candidate(d, d.recommended);
  EXPECT_TRUE(d.recommended.empty() || (named && named->kind == "parameter")) << "recommended: " << d.recommended;
  EXPECT_TRUE(d.grade == Verdict::nothing_missing || d.grade == Verdict::parameter) << verdict_words(d.grade);
  const double chi2 = named ? named->fit.after.chi2_per_n() : d.base.after.chi2_per_n();
  EXPECT_LE(chi2, 1.5);
}

/// What must hold on a set whose effect the diagnosis may not yet find: no confident wrong name.
/// "Missing" names one of `right`; "cannot tell" names one of them among the effect and its rivals.
void expect_never_confidently_wrong(const CrossEngineRun& run, const std::vector<std::string>& right) {
  const Diagnosis& d = run.diagnosis;
  EXPECT_GT(d.base.after.chi2_per_n(), 3.0) << "the plain model should fail visibly on these data";
  EXPECT_NE(d.grade, Verdict::nothing_missing);
  const auto is_right = [&](const std::string& name) { return std::find(right.begin(), right.end(), name) != right.end(); };
  if (d.grade == Verdict::missing) {
    EXPECT_TRUE(is_right(d.recommended)) << "Missing: " << d.recommended;
  }
  if (d.grade == Verdict::cannot_tell) {
    EXPECT_TRUE(is_right(d.recommended) || std::any_of(d.rivals.begin(), d.rivals.end(), is_right) ||
                std::any_of(d.unconfirmed_rivals.begin(), d.unconfirmed_rivals.end(), is_right))
        << "cannot tell, recommended " << d.recommended;
  }
}

// The sets with traits and an effect (glass_beads_6mm_traits_experiments.json): the beads on a liner as soft
// as they are, particle-liner friction 0.15 against 0.4 between beads, a 27 mm (4.5 d50) silo
// orifice, a drum whose bed slides on its shell, from the liner starting material. With LIGGGHTS
// epsd2 rolling friction (mu_r 0.25) the cylinder leaves a low heap (5-13 deg) where the plain
// beads leave none, and the 27 mm orifice arches in every packing where the plain beads flow.
// demdesign with LIGGGHTS' values (epsd, mu_r 0.25, liner friction 0.15) fits these data at
// chi^2/n 0.89. From the liner starting material, whose liner friction is a guess of 0.5, the
// diagnosis finds that the data depend on that guess, calibrates it with the others, and names
// rolling resistance (2026-12-07: "Missing: epsd", chi^2/n 7.68 to 0.93, rolling friction 0.24,
// liner friction 0.145; 1594 s on 2 cores).
TEST(CrossEngine, RollingFrictionWithTraitsIsFound) {
  const CrossEngineRun run = diagnose_set("rolling_epsd2_traits", "glass_beads_6mm_liner");
  expect_never_confidently_wrong(run, {"epsd", "cdt"});
  expect_effect_found(run, "epsd");
}

// LIGGGHTS sjkr cohesion (1e5 J/m^3 between beads and on the liner) with the same traits: on the
// soft liner a drop rebounds at 0.24 where the dry beads' restitution is 0.45, the cohesive bed
// rides level on the drum's shell, and the lifted cylinder leaves beads on its wall. demdesign
// with LIGGGHTS' values fits at chi^2/n 1.30.
TEST(CrossEngine, CohesionWithTraitsIsNeverConfidentlyWrong) {
  expect_never_confidently_wrong(diagnose_set("cohesion_sjkr_traits", "glass_beads_6mm_liner"), {"sjkr"});
}

// LIGGGHTS epsd2 rolling friction (mu_r 0.25): demdesign's rolling resistance (epsd).
TEST(CrossEngine, RollingFrictionEpsd2IsFound) { expect_effect_found(diagnose_set("rolling_epsd2"), "epsd"); }

// LIGGGHTS cdt rolling friction (mu_r 0.25, a constant torque without a spring): the same law
// (cdt). epsd, the spring-dashpot law, moves the heaps and the drum the same way but returns the
// spin of an oblique rebound: recalibrated on these data it stayed at chi^2/n 34.78 (2026-12-04).
TEST(CrossEngine, RollingFrictionCdtIsFound) { expect_effect_found(diagnose_set("rolling_cdt"), "cdt"); }

// LIGGGHTS sjkr cohesion (cohesion energy density 1.5e5 J/m^3, a force on the contact area):
// the same law (sjkr), which the diagnosis offers beside JKR's pull-off.
TEST(CrossEngine, CohesionSjkrIsFound) { expect_effect_found(diagnose_set("cohesion_sjkr"), "sjkr"); }

// The benchmark laboratory file (lab_rolling.yaml): seven experiments as an ordinary lab writes
// them, at full size (drop, bulk density in an 80 mm cup, 80 mm lifted cylinder, 160 mm drum at 10
// and 30 rpm, 120 mm silo with 30 and 40 mm orifices), E 1e7 Pa, LIGGGHTS epsd2 rolling friction
// (mu_r 0.2) hidden in them; its 30 mm silo arched in two of three packings. Rolling resistance
// must be named, as missing or as a tie of demdesign's two rolling laws (epsd, cdt: LIGGGHTS'
// epsd2 is neither exactly), never another effect, and the model with it must fit.
TEST(CrossEngine, LabFileRollingResistanceIsFound) {
  const CrossEngineRun run = diagnose_set("lab_rolling");
  const Diagnosis& d = run.diagnosis;
  EXPECT_GT(d.base.after.chi2_per_n(), 3.0) << "the plain model should fail visibly on these data";
  ASSERT_TRUE(d.grade == Verdict::missing || d.grade == Verdict::cannot_tell) << verdict_words(d.grade) << ", best " << d.best;
  EXPECT_TRUE(d.recommended == "epsd" || d.recommended == "cdt") << "recommended: " << d.recommended;
  for (const std::string& rival : d.rivals) EXPECT_TRUE(rival == "epsd" || rival == "cdt") << "rival: " << rival;
  const CandidateResult* c = candidate(d, d.recommended);
  ASSERT_NE(c, nullptr);
  EXPECT_LE(c->fit.after.chi2_per_n(), noise_line({}, c->fit.after.n, c->k));
}

// LIGGGHTS two-sphere clumps of aspect ratio 1.5 (shape_multisphere.yaml), no rolling friction,
// no cohesion, with a shear series after one pre-shear (a yield locus): a heap of 14-17 deg where
// the spheres leave none, the drum at 37 deg against 23, peaks of the locus about 1.6 times the
// spheres'. The diagnosis names the shape (clump_shape), or says that rolling resistance explains
// the data as well and names an experiment whose two predictions lie at least 3 sigma apart;
// never another effect with the grade missing, and the model named fits. 2026-12-08 (24b7a22,
// 2354 s): "Missing: clump_shape", chi^2/n 8.81 to 0.19, aspect ratio 1.53 +- 0.08; before a
// clump's mass was counted once and its drop averaged over orientations, cdt "improved" it.
TEST(CrossEngine, ShapeIsNamedOrTiedWithRollingResistance) {
  const CrossEngineRun run = diagnose_set("shape_multisphere");
  const Diagnosis& d = run.diagnosis;
  EXPECT_GT(d.base.after.chi2_per_n(), 3.0) << "the plain model should fail visibly on these data";
  ASSERT_TRUE(d.grade == Verdict::missing || d.grade == Verdict::cannot_tell) << verdict_words(d.grade) << ", best " << d.best;
  const CandidateResult* c = candidate(d, d.recommended);
  ASSERT_NE(c, nullptr);
  EXPECT_LE(c->fit.after.chi2_per_n(), noise_line({}, c->fit.after.n, c->k));
  if (d.recommended == "clump_shape") return;
  ASSERT_TRUE(d.recommended == "epsd" || d.recommended == "cdt") << "recommended: " << d.recommended;
  ASSERT_EQ(d.grade, Verdict::cannot_tell) << "rolling resistance named as missing on clump data: shape not even a rival";
  ASSERT_NE(std::find(d.rivals.begin(), d.rivals.end(), "clump_shape"), d.rivals.end()) << "shape is not named as a rival";
  ASSERT_TRUE(d.separators.count("clump_shape") && !d.separators.at("clump_shape").empty());
  EXPECT_GE(d.separators.at("clump_shape").front().separation, 3.0) << d.separators.at("clump_shape").front().words;
}

// LIGGGHTS liquid bridges (capillary_easo.yaml): easo/capillary, each bead wetted with 2.5 % of
// its volume of water (surface tension 0.072 N/m, contact angle 20 deg), no viscous force, with
// the shear series at 250, 500 and 750 Pa after a pre-shear at 1000 Pa: peaks of the locus
// 90-132 Pa, 185-218 Pa and 290-307 Pa, an intercept of about 40 Pa the dry beads do not have
// (at 1000-3000 Pa it was within the noise: the dry model fitted at chi^2/n 1.49, 2026-12-08). Between equal spheres
// LIGGGHTS' liquid content 0.025 fills the bridge of demdesign's liquid_content 0.01
// (calibration/liggghts/README.md: w = 0.40 c at 6 bridges a particle); the force laws differ
// (Soulie against Willett, 12 % at contact). The diagnosis names the liquid bridge, or a rival it
// cannot rule out with an experiment that separates them; never another effect as missing; the
// recalibrated liquid content within a factor 3 of 0.01. Not met (2026-12-08, 24b7a22, 826 s):
// the dry model recalibrated fits these data at chi^2/n 0.91 ("nothing missing"): the bridges of
// 6 mm beads (a force of half a bead's weight) are within the tests' noise.
TEST(CrossEngine, LiquidBridgesAreFound) {
  const CrossEngineRun run = diagnose_set("capillary_easo");
  expect_never_confidently_wrong(run, {"liquid_bridge"});
  expect_effect_found(run, "liquid_bridge");
  const CandidateResult* c = candidate(run.diagnosis, "liquid_bridge");
  ASSERT_NE(c, nullptr);
  const double w = get_parameter(c->fit.fitted, "liquid_content");
  EXPECT_GT(w, 0.01 / 3);
  EXPECT_LT(w, 0.01 * 3);
}

}  // namespace
}  // namespace dem::materials
