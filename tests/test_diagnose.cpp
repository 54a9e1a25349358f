// diagnose on analytic stand-ins (analytic_lab.h: known answers, no DEM): which hidden effect is
// named, rivals, a wall parameter, the budget plan and progress, and the ledger of versions.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "analytic_lab.h"
#include "calibration/calibration.h"
#include "calibration/calibration_support.h"
#include "report/calibration_report.h"
#include "diagnosis/discrimination.h"
#include "model/material_model.h"
#include "lab/measurements.h"

namespace dem::materials {
namespace {

using namespace analytic;

struct HiddenCase {
  const char* effect;
  MeasurementSet set;
  MaterialModel truth;
};

/// The flow tests of gravel that rolls (mu_r = 0.2, friction 0.5, restitution 0.5), measured by `sim`.
MeasurementSet rolling_gravel(const Simulator& sim) {
  MaterialModel truth = read_material_model(kMaterials + "/gravel.yaml");
  set_parameter(truth, "friction", 0.5), set_parameter(truth, "restitution", 0.5);
  return synthesise(flow_tests(), truth, sim, 11);
}

TEST(Diagnose, AnalyticHiddenRollingResistanceIsNamedFirst) {
  const Analytic sim;
  const MaterialModel start = dry_spheres();
  const MeasurementSet set = rolling_gravel(sim);
  const Diagnosis d = diagnose(start, set, {}, analytic_options(sim));
  EXPECT_GT(d.base.after.chi2_per_n(), 5.0);  // the starting model fails visibly
  ASSERT_FALSE(d.candidates.empty());
  EXPECT_EQ(d.candidates.front().name, "epsd") << d.words.front();
  EXPECT_EQ(d.recommended, "epsd") << d.words.front();
  EXPECT_EQ(d.grade, Verdict::missing) << d.words.front();
  EXPECT_EQ(d.words.front().rfind("Missing: epsd", 0), 0u) << d.words.front();
  EXPECT_LT(d.candidates.front().fit.after.chi2_per_n(), 2.0);
  EXPECT_GT(d.candidates.front().explained, 0.5);
  // The report: self-contained HTML with the diagnosis, contour maps and the ledger.
  const std::string dir = (std::filesystem::temp_directory_path() / "demdesign_calibration_report").string();
  std::filesystem::remove_all(dir);
  report::CalibrationReportInput in;
  in.title = "diagnose gravel";
  in.diagnosis = &d;
  in.ledger = append_ledger(dir + "/ledger.yaml", "gravel", {ledger_entry(start, d.base.before, "start", {"friction"}),
                                                             ledger_entry(d.candidates.front().fit.fitted, d.candidates.front().fit.after, "+ rolling", {"friction"})});
  const std::string html = report::write_calibration_report(in, dir);
  std::ifstream file(html);
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("Missing: epsd"), std::string::npos);
  EXPECT_NE(text.find("Error ledger"), std::string::npos);
  EXPECT_EQ(text.find("http"), std::string::npos);
  // Per experiment, the observable that drives its misfit.
  EXPECT_NE(text.find("what drives its misfit"), std::string::npos);
  const materials::Term* worst = nullptr;
  for (const materials::Term& t : d.base.before.terms)
    if (t.experiment == d.base.before.runs.front().id && (!worst || std::abs(t.residual) > std::abs(worst->residual))) worst = &t;
  ASSERT_NE(worst, nullptr);
  EXPECT_NE(text.find(fmt::format("<td>{}</td><td>{} {:+.2f} &sigma;</td>", worst->experiment, worst->observable, worst->residual)), std::string::npos);
  if (std::filesystem::exists(dir + "/plots/base_contour0.png")) {
    EXPECT_NE(text.find("data:image/png;base64"), std::string::npos);
  }
}

TEST(Diagnose, TheModelsOwnSimulationsArePointsOfEachCandidatesFit) {
  // Every point the model as it is was simulated at is a point of a candidate's parameter space,
  // the candidate's own parameters where it changes nothing (rolling friction 0): its surrogate
  // takes them as data, nothing is simulated again for them.
  const Analytic sim;
  const Diagnosis d = diagnose(dry_spheres(), rolling_gravel(sim), {}, analytic_options(sim));
  ASSERT_FALSE(d.base.points.empty());
  int confirmed = 0;
  for (const CandidateResult& c : d.candidates) {
    if (!c.confirmed || c.kind == "shape") continue;
    ++confirmed;
    for (const SimulatedPoint& own : d.base.points) {
      const auto same = [&](const SimulatedPoint& q) {
        if (q.x.size() != own.x.size() + 1 || q.values != own.values) return false;
        return std::equal(own.x.begin(), own.x.end(), q.x.begin()) && q.x.back() == (c.kind == "parameter" ? q.x.back() : 0.0);
      };
      EXPECT_TRUE(std::any_of(c.fit.points.begin(), c.fit.points.end(), same)) << c.name;
    }
    const std::string said = fmt::format("{} points simulated before", d.base.points.size());
    EXPECT_TRUE(std::any_of(c.fit.words.begin(), c.fit.words.end(), [&](const std::string& w) { return w.find(said) != std::string::npos; }))
        << c.name;
  }
  EXPECT_GE(confirmed, 1);
}

/// The dry spheres with liquid bridges of this liquid content, at friction 0.5.
MaterialModel wet_spheres(double liquid_content) {
  MaterialModel m = dry_spheres();
  for (const EffectCandidate& c : missing_effects(m))
    if (c.name == "liquid_bridge") c.add(m);
  set_parameter(m, "liquid_content", liquid_content), set_parameter(m, "friction", 0.5);
  return m;
}

TEST(Diagnose, AnalyticHiddenLiquidBridgesAreNamedFirst) {
  const Analytic sim;
  const MaterialModel start = dry_spheres(), truth = wet_spheres(0.01);
  MeasurementSet set;
  add(set, "drop", "drop_rebound", {{"drop_height", 0.3}}, "restitution", 0.02);
  add(set, "aor", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 1.0);
  add(set, "density", "bulk_density", {{"cup_diameter", 0.1}}, "bulk_density", 10);
  add(set, "hopper", "hopper_discharge", {{"orifice_diameter", 0.05}}, "mass_flow_rate", 0.02);
  for (double sn : {2000.0, 4000.0, 6000.0}) add(set, fmt::format("shear_{:.0f}", sn), "direct_shear", {{"normal_stress", sn}}, "peak_shear_stress", 50);
  set = synthesise(set, truth, sim, 5);
  const Diagnosis d = diagnose(start, set, {}, analytic_options(sim));
  EXPECT_GT(d.base.after.chi2_per_n(), 5.0);
  EXPECT_EQ(d.recommended, "liquid_bridge") << d.words.front();
  EXPECT_LT(d.candidates.front().fit.after.chi2_per_n(), 2.0);
  bool offset_words = false;
  for (const Pattern& p : d.base.before.patterns) offset_words = offset_words || p.words.find("yield locus") != std::string::npos;
  EXPECT_TRUE(offset_words);
  EXPECT_TRUE(d.rivals.empty()) << "a yield locus at three stresses tells an offset (bridges) from a steeper slope";
}

/// A heap angle and a bulk density of `truth`, measured by `sim`: two numbers that any effect, with
/// friction, fits exactly.
MeasurementSet heap_and_density_of(const MaterialModel& truth, const Simulator& sim) {
  MeasurementSet set;
  add(set, "aor", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 1.0);
  add(set, "density", "bulk_density", {{"cup_diameter", 0.1}}, "bulk_density", 10);
  return synthesise(set, truth, sim, 5);
}

TEST(Diagnose, AnalyticRivalsTheDataCannotTellApartAreNamed) {
  // Truth: liquid bridges. Measured: a heap angle and a bulk density only. Friction cannot move
  // both as the bridges did, but any effect that moves them in another direction, with friction,
  // fits two numbers exactly: the runner-up is as good, and the diagnosis must say so.
  const Analytic sim;
  const MaterialModel start = dry_spheres(), truth = wet_spheres(0.03);
  const MeasurementSet set = heap_and_density_of(truth, sim);
  const Diagnosis d = diagnose(start, set, {}, analytic_options(sim));
  for (const std::string& w : d.words) std::printf("%s\n", w.c_str());
  for (const CandidateResult& c : d.candidates) std::printf("  %s\n", c.words.c_str());
  ASSERT_FALSE(d.recommended.empty()) << d.words.front();
  ASSERT_GE(d.candidates.size(), 2u);
  ASSERT_TRUE(d.candidates[1].confirmed);
  EXPECT_LT(d.candidates[1].bic - d.candidates[0].bic, CalibrationOptions{}.rival_margin);
  ASSERT_EQ(d.rivals.size(), 1u);
  EXPECT_EQ(d.rivals.front(), d.candidates[1].name);
  bool words = false;
  for (const std::string& w : d.words) words = words || w.find("Cannot tell " + d.recommended + " from " + d.rivals.front()) == 0;
  EXPECT_TRUE(words);
  EXPECT_EQ(d.grade, Verdict::cannot_tell);
  // The experiment it names separates them: simulated with the truth (bridges, which neither
  // candidate is), its outcome lies at least 2 sigma nearer one prediction than the other, so the
  // measurement decides between the two (here it also rejects both: the diagnosis is run again
  // with it).
  ASSERT_FALSE(d.separators.at(d.rivals.front()).empty());
  const Separator& best = d.separators.at(d.rivals.front()).front();
  EXPECT_GE(best.separation, 3.0) << best.words;
  bool named = false;
  for (const std::string& w : d.words) named = named || w.find("To tell " + d.recommended + " from " + d.rivals.front() + ", measure " + best.id) == 0;
  EXPECT_TRUE(named);
  TestOptions o;
  o.seed = 4242;
  const double truth_value = sim(truth, best.setup, o).observables.at(best.observable);
  const double off_a = std::abs(truth_value - best.predicted_a) / best.sigma, off_b = std::abs(truth_value - best.predicted_b) / best.sigma;
  std::printf("named: %s; truth %.4g (%.1f and %.1f sigma from the two)\n", best.words.c_str(), truth_value, off_a, off_b);
  EXPECT_GE(std::max(off_a, off_b) - std::min(off_a, off_b), 2.0) << "the measurement decides between the two";
}

// The same two numbers with a budget that confirms only the leader: with as many fitted
// parameters as measured terms any effect fits, so the leader fitting within the noise is no
// evidence against the effects not recalibrated. The grade is "cannot tell", naming those
// effects and the command that confirms them, never "missing" on one fit.
TEST(Diagnose, EffectsNotRecalibratedThatTheDataCannotRuleOutKeepTheGradeFromMissing) {
  const Analytic sim;
  const MeasurementSet set = heap_and_density_of(wet_spheres(0.03), sim);
  CalibrationOptions options = analytic_options(sim);
  options.budget_seconds = 1e-3;
  options.propose_experiments = false;
  const Diagnosis d = diagnose(dry_spheres(), set, {}, options);
  for (const std::string& w : d.words) std::printf("%s\n", w.c_str());
  int confirmed = 0;
  for (const CandidateResult& c : d.candidates) confirmed += c.confirmed ? 1 : 0;
  ASSERT_EQ(confirmed, 1) << "the budget confirms the leader only";
  ASSERT_FALSE(d.recommended.empty());
  EXPECT_EQ(d.grade, Verdict::cannot_tell) << verdict_words(d.grade);
  EXPECT_FALSE(d.unconfirmed_rivals.empty());
  bool words = false;
  for (const std::string& w : d.words) words = words || (w.starts_with("Not ruled out, not recalibrated: ") && w.find("--effects " + d.recommended + ",") != std::string::npos);
  EXPECT_TRUE(words);
}

// Two effects hidden at once (wet gravel that rolls): no one candidate explains the data. The best
// improves the fit and is said to, with what it leaves unexplained; it is not named as missing,
// and a runner-up as good is no tie to separate by experiment (both models misfit).
TEST(Diagnose, AnalyticTwoHiddenEffectsGetImprovesNotMissing) {
  const Analytic sim;
  MaterialModel truth = read_material_model(kMaterials + "/gravel.yaml");
  for (const EffectCandidate& c : missing_effects(truth))
    if (c.name == "liquid_bridge") c.add(truth);
  set_parameter(truth, "liquid_content", 0.03), set_parameter(truth, "rolling_friction", 0.2), set_parameter(truth, "friction", 0.5);
  const MeasurementSet set = synthesise(flow_tests(), truth, sim, 17);
  const Diagnosis d = diagnose(dry_spheres(), set, {}, analytic_options(sim));
  for (const std::string& w : d.words) std::printf("%s\n", w.c_str());
  ASSERT_EQ(d.grade, Verdict::improves) << d.words.front();
  EXPECT_TRUE(d.recommended.empty()) << d.recommended;
  EXPECT_FALSE(d.best.empty());
  EXPECT_EQ(d.words.front().rfind(d.best + " improves the fit but does not explain it", 0), 0u) << d.words.front();
  EXPECT_FALSE(d.unexplained.empty());
  EXPECT_TRUE(d.separators.empty()) << "no experiment sought between two models that misfit";
  for (const std::string& w : d.words) EXPECT_EQ(w.rfind("Cannot tell", 0), std::string::npos) << w;
}

TEST(Discrimination, TheMostPromisingCandidatesAreSimulatedFirstAndAsManyAsPlanned) {
  // Two experiments, the fitted models 2 sigma apart on the density and 0.5 on the heap: the
  // standard set-ups of the tests the file lacks come first, then the density's variants, then
  // the heap's; a plan of 3 simulates the first three and lists the rest as untried.
  const Analytic sim;
  MeasurementSet set;
  add(set, "aor", "angle_of_repose_cylinder", {{"fill_height", 0.1}, {"lift_speed", 0.05}}, "angle_deg", 1.0);
  add(set, "density", "bulk_density", {{"cup_diameter", 0.1}}, "bulk_density", 10);
  set = synthesise(set, dry_spheres(), sim, 5);
  const std::map<std::string, double> apart{{"aor", 0.5}, {"density", 2.0}};
  const std::vector<Experiment> plain = separating_candidates(dry_spheres(), set);
  const std::vector<Experiment> ordered = separating_candidates(dry_spheres(), set, apart);
  ASSERT_EQ(plain.size(), ordered.size());
  const auto kinds = [](const std::vector<Experiment>& list) {
    std::vector<std::string> out;  // "standard", "density", "aor" in their order, runs merged
    for (const Experiment& e : list) {
      const std::string kind = e.id.rfind("density at ", 0) == 0 ? "density" : e.id.rfind("aor at ", 0) == 0 ? "aor" : "standard";
      if (out.empty() || out.back() != kind) out.push_back(kind);
    }
    return out;
  };
  EXPECT_EQ(kinds(ordered), (std::vector<std::string>{"standard", "density", "aor"}));
  EXPECT_EQ(kinds(plain), (std::vector<std::string>{"standard", "aor", "density"})) << "without a plan, the file's order";

  SeparationPlan plan;
  plan.apart = apart, plan.most = 3;
  const SeparationSearch search = separating_experiments(dry_spheres(), "dry", wet_spheres(0.03), "wet", set, analytic_options(sim), plan);
  EXPECT_EQ(search.candidates, static_cast<int>(ordered.size()));
  ASSERT_EQ(search.untried.size(), ordered.size() - 3);
  EXPECT_EQ(search.untried.front(), ordered[3].id);
  for (const Separator& s : search.found)
    EXPECT_TRUE(s.id == ordered[0].id || s.id == ordered[1].id || s.id == ordered[2].id) << s.id;
  EXPECT_FALSE(search.found.empty());
}

TEST(Diagnose, AnalyticControlGetsNoRecommendation) {
  const Analytic sim;
  const MaterialModel start = dry_spheres();
  MaterialModel truth = start;
  set_parameter(truth, "friction", 0.7), set_parameter(truth, "restitution", 0.35);
  const MeasurementSet set = synthesise(flow_tests(), truth, sim, 17);
  const Diagnosis d = diagnose(start, set, {}, analytic_options(sim));
  EXPECT_LT(d.base.after.chi2_per_n(), 1.5);
  EXPECT_EQ(d.recommended, "");
  EXPECT_EQ(d.grade, Verdict::nothing_missing);
  EXPECT_NE(d.words.front().find("No effect recommended"), std::string::npos);
  // A model that fits gets no signature screen: nothing it found could be recommended.
  EXPECT_TRUE(d.candidates.empty());
  EXPECT_NE(d.words.front().find("no candidate was screened"), std::string::npos) << d.words.front();
  // Named candidates are screened all the same.
  CalibrationOptions named = analytic_options(sim);
  named.effects = {"epsd"};
  const Diagnosis screened = diagnose(start, set, {}, named);
  ASSERT_EQ(screened.candidates.size(), 1u);
  EXPECT_EQ(screened.candidates.front().name, "epsd");
  EXPECT_EQ(screened.recommended, "");
}

// A misfit that no candidate could turn into a recommendation (an effect that took up all of
// chi^2 with one parameter more would lower BIC by at most chi^2 - ln n) is not screened.
TEST(Diagnose, NoScreenWhenNoCandidateCouldPassTheMargin) {
  const Analytic sim;
  const MaterialModel start = dry_spheres();
  const MeasurementSet set = rolling_gravel(sim);
  int simulations = 0;
  CalibrationOptions options = analytic_options(sim);
  const Simulator counting = [&](const MaterialModel& m, const TestSetup& s, const TestOptions& o) { return ++simulations, sim(m, s, o); };
  options.simulator = counting;
  const Diagnosis plain = diagnose(start, set, {}, options);
  const int with_screen = simulations;
  ASSERT_GT(plain.base.after.chi2_per_n(), 5.0);
  const double most_gain = plain.base.after.chi2 - std::log(plain.base.after.n);
  options.bic_margin = most_gain + 1;  // just out of reach
  simulations = 0;
  const Diagnosis d = diagnose(start, set, {}, options);
  EXPECT_TRUE(d.candidates.empty());
  EXPECT_EQ(d.recommended, "");
  EXPECT_NE(d.words.front().find(fmt::format("at most {:.1f}", most_gain)), std::string::npos) << d.words.front();
  EXPECT_LT(simulations, with_screen / 2) << "the screen and the confirmations ran";
  options.bic_margin = most_gain - 1;  // within reach: screened
  EXPECT_FALSE(diagnose(start, set, {}, options).candidates.empty());
}

// A drop test misses because the particles' restitution on the steel plate is off, while the
// flow tests fit: the diagnosis finds that the data depend on the guessed wall parameter,
// calibrates it with the others and says so; no missing physics is named.
TEST(Diagnose, AGuessedWallParameterTheDataDependOnIsCalibratedNotNamedAsPhysics) {
  const Simulator sim = [](const MaterialModel& m, const TestSetup& s, const TestOptions& o) {
    std::mt19937_64 random(o.seed * 7919 + std::hash<std::string>{}(s.test));
    std::normal_distribution<double> n(0.0, 1.0);
    const double mu = get_parameter(m, "friction");
    const double mr = m.contact.rolling.model == "none" ? 0.0 : get_parameter(m, "rolling_friction");
    SimulatedOutcome out;
    if (s.test == "drop_rebound") out.observables["restitution"] = get_parameter(m, s.words.at("plate") + ".restitution") + 0.002 * n(random);
    if (s.test == "angle_of_repose_cylinder") out.observables["angle_deg"] = 18 + 20 * mu + 40 * mr + 0.3 * n(random);
    if (s.test == "bulk_density") out.observables["bulk_density"] = 1650 - 150 * mu - 300 * mr + 3 * n(random);
    return out;
  };
  const auto [start, set] = guessed_wall(sim);
  CalibrationOptions options = analytic_options(sim);
  options.walls_first = false;  // (on, the drops settle the restitution first: the next test)
  const Diagnosis d = diagnose(start, set, {{"friction", 0.1, 0.9}}, options);
  for (const std::string& w : d.words) std::cout << w << "\n";
  for (const CandidateResult& c : d.candidates) std::cout << "  " << c.words << "\n";
  EXPECT_EQ(d.grade, Verdict::nothing_missing) << d.words.front();
  EXPECT_EQ(d.recommended, "") << "an effect named to absorb a wall parameter";
  ASSERT_GE(d.words.size(), 2u);
  EXPECT_EQ(d.words[1].rfind("steel.restitution (", 0), 0u) << d.words[1];
  EXPECT_NEAR(get_parameter(d.base.fitted, "steel.restitution"), 0.8, 0.03);
}

// Rolling resistance hidden behind a guessed wall friction: the drum's shell is steel, on which the
// bed slides, nearly level, when the shell is smooth (LIGGGHTS' liner at 0.15, guessed at 0.5). A
// rougher shell than the guess changes nothing, so the wall is probed on both sides of its guess;
// the data depend on it, and it is calibrated from the start. With the wall calibrated the heap
// still asks for a friction beyond its range (and the bulk density for less): rolling resistance
// is missing, and is named.
TEST(Diagnose, AGuessedWallFrictionTheDataDependOnIsCalibratedBeforeTheEffectIsSought) {
  const Simulator sim = [](const MaterialModel& m, const TestSetup& s, const TestOptions& o) {
    std::mt19937_64 random(o.seed * 7919 + std::hash<std::string>{}(s.test + s.id));
    std::normal_distribution<double> n(0.0, 0.3);
    const double mu = get_parameter(m, "friction"), e = get_parameter(m, "restitution"), wall = get_parameter(m, "steel.friction");
    const double mr = m.contact.rolling.model == "epsd" ? get_parameter(m, "rolling_friction") : 0.0;
    SimulatedOutcome out;
    if (s.test == "drop_rebound") out.observables["restitution"] = e + 0.002 * n(random);
    else if (s.test == "angle_of_repose_cylinder") out.observables["angle_deg"] = 18 + 12 * mu + 40 * mr + n(random);
    else if (s.test == "bulk_density") out.observables["bulk_density"] = 1600 - 250 * mu - 100 * mr + 10 * n(random);
    else if (s.test == "rotating_drum") {  // on a shell smoother than about 0.3 the bed slides, nearly level
      const double rides = 1 / (1 + std::exp(-(wall - 0.3) / 0.03));
      out.observables["dynamic_angle_deg"] = rides * (22 + 8 * mu + 35 * mr + (0.15 + 0.5 * mr) * s.numbers.at("rpm")) + (1 - rides) * 5 + n(random);
    }
    return out;
  };
  MaterialModel start = read_material_model(kMaterials + "/gravel.yaml");
  set_parameter(start, "friction", 0.5), set_parameter(start, "rolling_friction", 0.0), set_parameter(start, "steel.friction", 0.5);
  MaterialModel truth = start;
  set_parameter(truth, "friction", 0.4), set_parameter(truth, "rolling_friction", 0.2), set_parameter(truth, "steel.friction", 0.15);
  start.contact.rolling.model = "none";
  start.particle.params.erase("rolling_friction");
  start.tunable.erase("rolling_friction");
  MeasurementSet set;
  add(set, "drop", "drop_rebound", {{"drop_height", 0.3}}, "restitution", 0.02);
  add(set, "aor_1", "angle_of_repose_cylinder", {{"fill_height", 0.1}}, "angle_deg", 1.0);
  add(set, "aor_2", "angle_of_repose_cylinder", {{"fill_height", 0.15}}, "angle_deg", 1.0);
  add(set, "density", "bulk_density", {{"cup_diameter", 0.1}}, "bulk_density", 10);
  for (const int rpm : {5, 10, 20, 30, 40}) add(set, fmt::format("drum_{}", rpm), "rotating_drum", {{"rpm", rpm}}, "dynamic_angle_deg", 1.0);
  set = synthesise(set, truth, sim, 23);
  CalibrationOptions options = analytic_options(sim);
  options.walls_first = false;
  const Diagnosis d = diagnose(start, set, {{"friction", 0.1, 0.9}, {"restitution", 0.1, 0.9}}, options);
  for (const std::string& w : d.words) std::printf("%s\n", w.c_str());
  for (const CandidateResult& c : d.candidates) std::printf("  %s\n", c.words.c_str());
  const auto probed = std::find_if(d.words.begin(), d.words.end(), [](const std::string& w) { return w.rfind("steel.friction (", 0) == 0; });
  ASSERT_NE(probed, d.words.end()) << "the guessed wall friction is not said to be calibrated";
  EXPECT_NE(probed->find("at 0.2 and"), std::string::npos) << "probed below the guess as well as above: " << *probed;
  const auto fitted = [&](const std::string& key) {
    return std::any_of(d.base.parameters.begin(), d.base.parameters.end(), [&](const FitParameter& p) { return p.key == key; });
  };
  EXPECT_TRUE(fitted("steel.friction"));
  EXPECT_FALSE(fitted("rubber.friction")) << "a guess the data do not depend on is left a guess";
  EXPECT_GT(d.base.after.chi2_per_n(), 3.0) << "the plain model should still fail visibly";
  EXPECT_EQ(d.grade, Verdict::missing) << d.words.front();
  EXPECT_EQ(d.recommended, "epsd") << d.words.front();
  const auto epsd = std::find_if(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& c) { return c.name == "epsd"; });
  ASSERT_NE(epsd, d.candidates.end());
  // Every friction at which the bed slides explains the drums alike: below the ride threshold.
  EXPECT_LT(get_parameter(epsd->fit.fitted, "steel.friction"), 0.25);
  EXPECT_NEAR(get_parameter(epsd->fit.fitted, "rolling_friction"), 0.2, 0.06);
  EXPECT_TRUE(std::none_of(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& c) { return c.name == "steel.friction"; }))
      << "a calibrated wall parameter is not screened again";
}

TEST(Budget, PlansTheDiagnosisToFitAndSaysWhatItGaveUp) {
  Comparison first;
  for (int e = 0; e < 7; ++e) {
    ExperimentRun run;
    run.replicas = 3, run.wall_seconds = 3 * 10.0;  // 10 s a simulation: 70 s a pass
    first.runs.push_back(run);
  }
  CalibrationOptions options;
  options.parallel = 2;  // 35 s a pass
  options.budget_seconds = 1e6;
  const BudgetPlan roomy = plan_within_budget(options, first, 2, 4, 4);
  EXPECT_TRUE(roomy.given_up.empty());
  // Defaults, 2 parameters: 2 x 14 + 3 passes for the plain fit; a candidate's passes counted at
  // what they cost against the plain model's, the screen's at 2 (8 candidates x 3) and the
  // confirmations' at 1.2 (2 x (2 x 22 + 3)): 31 + 48 + 112.8 = 191.8 passes.
  EXPECT_NEAR(roomy.seconds, 191.8 * 35.0, 1e-9);
  options.budget_seconds = 3000;
  const BudgetPlan tight = plan_within_budget(options, first, 2, 4, 4);
  EXPECT_LE(tight.seconds, 3000);
  ASSERT_EQ(tight.given_up.size(), 2u);
  EXPECT_EQ(tight.given_up.front().rfind("one surrogate round", 0), 0u);
  EXPECT_EQ(tight.options.rounds, 1);
  // One round (17 + 48 + 1.2 x 2 x (22 + 3) = 125 passes) is not enough; design factor 1 is: 8 + 3
  // passes for the plain fit, 48 for the screen, 1.2 x 2 x (8 + 3) for confirmations that stand
  // beside the plain fit's points (confirmation_design_points): 85.4 passes fit 3000 s.
  EXPECT_EQ(tight.options.design_factor, 1.0);
  EXPECT_EQ(tight.options.signature_replicas, 2);
  EXPECT_NEAR(tight.seconds, 85.4 * 35.0, 1e-9);
  // What the first comparison took comes off the budget: with 100 s spent, 85.4 passes (2989 s)
  // no longer fit the 2900 s left, and the signatures take one packing (8 x 2 x 2 for the screen:
  // 69.4 passes); with 600 s spent, design factor 0.5 goes too (7 + 3 + 32 + 26.4 = 68.4 passes,
  // 2394 s). The wall parameters' screen goes only after the design points and the packings (a
  // guessed wall pair misfits like missing physics): with 1200 s spent, two packings (9 + 32 +
  // 1.2 x 2 x (8 + 2) = 65 passes) are not enough, and the wall screen goes (4 x 2 x 2): 49.
  const BudgetPlan later = plan_within_budget(options, first, 2, 4, 4, 100.0);
  EXPECT_EQ(later.options.signature_replicas, 1);
  EXPECT_EQ(later.options.design_factor, 1.0);
  EXPECT_NEAR(later.seconds, 69.4 * 35.0, 1e-9);
  const BudgetPlan latest = plan_within_budget(options, first, 2, 4, 4, 600.0);
  EXPECT_EQ(latest.options.design_factor, 0.5);
  EXPECT_EQ(latest.options.replicas, 3);
  EXPECT_TRUE(latest.options.wall_candidates);
  EXPECT_NEAR(latest.seconds, 68.4 * 35.0, 1e-9);
  const BudgetPlan last = plan_within_budget(options, first, 2, 4, 4, 1200.0);
  EXPECT_EQ(last.options.replicas, 2);
  EXPECT_FALSE(last.options.wall_candidates);
  EXPECT_EQ(last.options.confirm_candidates, 2);
  EXPECT_NEAR(last.seconds, 49 * 35.0, 1e-9);
  // After the calibration of the model as it is, the screen and the confirmations are planned
  // again at the cost measured so far, a candidate's simulations counted at what they cost
  // against the plain model's (the screen's at 2, the confirmations' at 1.2): at 35 s a pass,
  // 2 x 8 candidates x 3 + 1.2 x 2 x (2 x 22 + 3) = 160.8 passes do not fit 2500 s; one round
  // (1.2 x 2 x (10 + 3)), design factor 1 (1.2 x 2 x (8 + 3)) and signatures with one packing
  // (2 x 8 x 2): 58.4 passes.
  const BudgetPlan rest = plan_screen_within_budget(CalibrationOptions{}, 35.0, 2, 4, 4, 2500, 2500);
  EXPECT_NEAR(plan_screen_within_budget(CalibrationOptions{}, 35.0, 2, 4, 4, 1e6, 1e6).seconds, 160.8 * 35.0, 1e-9);
  EXPECT_EQ(rest.options.rounds, 1);
  EXPECT_EQ(rest.options.signature_replicas, 1);
  EXPECT_TRUE(rest.options.wall_candidates);
  EXPECT_NEAR(rest.seconds, 58.4 * 35.0, 1e-9);
  EXPECT_EQ(rest.given_up.size(), 3u);
  options.budget_seconds = 60;
  const BudgetPlan impossible = plan_within_budget(options, first, 2, 4, 4);
  EXPECT_NE(impossible.given_up.back().find("cannot be met"), std::string::npos);
  EXPECT_EQ(impossible.options.confirm_candidates, 1);
  // A diagnosis with a budget plans after its first comparison and says so first.
  const Simulator costly = [](const MaterialModel& m, const TestSetup& s, const TestOptions& o) {
    SimulatedOutcome out = Analytic{}(m, s, o);
    out.wall_seconds = 10;
    return out;
  };
  CalibrationOptions budgeted = analytic_options(costly);
  budgeted.budget_seconds = 1200;
  const Diagnosis d = diagnose(dry_spheres(), synthesise(flow_tests(), read_material_model(kMaterials + "/gravel.yaml"), costly, 11), {}, budgeted);
  ASSERT_FALSE(d.words.empty());
  EXPECT_EQ(d.words.front().rfind("Planned for the budget of 20 min", 0), 0u) << d.words.front();
  EXPECT_NE(d.words.front().find("given up"), std::string::npos) << d.words.front();
}

// A file that cannot be diagnosed within the budget at full size is diagnosed on the apparatus
// shrunk to half, corrected by what the shrinking does at the start values, and the model named
// is compared at full size. The stand-in's shrunk apparatus packs 60 kg/m^3 looser and heaps 3
// degrees steeper (as a 40 mm cup and cylinder of 6 mm beads do) and costs a twentieth.
TEST(Budget, AShrunkApparatusIsCorrectedToFullSizeAndTheNamedEffectCheckedThere) {
  const Simulator sized = [](const MaterialModel& m, const TestSetup& s, const TestOptions& o) {
    SimulatedOutcome out = Analytic{}(m, s, o);
    const bool shrunk = o.size_factor < 1;
    if (shrunk && out.observables.count("bulk_density")) out.observables["bulk_density"] -= 60;
    if (shrunk && out.observables.count("angle_deg")) out.observables["angle_deg"] += 3;
    out.wall_seconds = shrunk ? 1.0 : 20.0;
    return out;
  };
  const MeasurementSet set = rolling_gravel(sized);
  CalibrationOptions options = analytic_options(sized);
  options.budget_seconds = 3600;  // 8 experiments: 160 s a pass at full size, 8 s shrunk
  const Diagnosis d = diagnose(dry_spheres(), set, {}, options);
  for (const std::string& w : d.words) std::cout << w << "\n";
  ASSERT_EQ(d.size_factor, 0.5);
  EXPECT_NEAR(d.size_shift.at("density/bulk_density").shift, 60, 1e-9);  // the same packings at both sizes: exactly
  EXPECT_NEAR(d.size_shift.at("aor_1/angle_deg").shift, -3, 1e-9);
  EXPECT_NEAR(d.size_shift.at("drop/restitution").shift, 0, 1e-12);
  EXPECT_TRUE(std::any_of(d.words.begin(), d.words.end(), [](const std::string& w) {
    return w.find("shrunk to size factor 0.5") != std::string::npos && w.find("density/bulk_density -60 (-") != std::string::npos;
  }));
  // Corrected, the shrunk runs find what the full-size data hide, and the full-size check holds.
  EXPECT_EQ(d.recommended, "epsd");
  EXPECT_EQ(d.grade, Verdict::missing) << verdict_words(d.grade);
  ASSERT_GT(d.full_size.n, 0);
  const CandidateResult& best = *std::find_if(d.candidates.begin(), d.candidates.end(), [](const CandidateResult& c) { return c.name == "epsd"; });
  EXPECT_LE(d.full_size.chi2_per_n(), noise_line(options, d.full_size.n, best.k));
  EXPECT_TRUE(std::any_of(d.words.begin(), d.words.end(), [](const std::string& w) { return w.rfind("Checked at full size", 0) == 0; }));
  // Without the correction the same shrunk runs misfit the density and the heaps by 6 and 3 sigma:
  // a size effect read as physics.
  CalibrationOptions uncorrected = options;
  uncorrected.size_factor = 0.5, uncorrected.budget_seconds = 0;
  const Comparison raw = compare(best.fit.fitted, set, uncorrected);
  EXPECT_LT(raw.residual("density", "bulk_density"), -4);
}

TEST(Budget, AConfirmationIsCountedAtItsOwnCandidatesCost) {
  // Signature simulations of 20 s of one core each (a drum of clumps) against 5 s (spheres):
  // their confirmations, two simulations at once, are counted at 10 s and 2.5 s of wall time.
  CandidateResult clumps, spheres;
  clumps.cost = 10 * 20.0, clumps.simulations = 10;
  spheres.cost = 10 * 5.0, spheres.simulations = 10;
  EXPECT_DOUBLE_EQ(detail::candidate_seconds_per_simulation(clumps, 2), 10.0);
  EXPECT_DOUBLE_EQ(detail::candidate_seconds_per_simulation(spheres, 2), 2.5);
  EXPECT_DOUBLE_EQ(detail::candidate_seconds_per_simulation(spheres, 0), 5.0);
  // A candidate without signature simulations: 0, the caller's fallback.
  const CandidateResult unscreened;
  EXPECT_EQ(detail::candidate_seconds_per_simulation(unscreened, 2), 0.0);
}

TEST(Budget, CandidatesTheScreenCannotTellApartAreAllConfirmed) {
  // sjkr 73 %, jkr 69 % (within the 10 % margin: tied, although jkr is also among the two leaders
  // confirmed anyway), liquid bridges 57 % (not tied); the budget below may drop only the last.
  std::vector<CandidateResult> ranked(4);
  const char* names[] = {"sjkr", "jkr", "liquid_bridge", "epsd"};
  const double explained[] = {0.73, 0.69, 0.57, 0.19};
  for (size_t k = 0; k < ranked.size(); ++k) ranked[k].name = names[k], ranked[k].explained = explained[k], ranked[k].agreement = 0.9;
  const detail::ConfirmationChoice choice = detail::choose_confirmations(ranked, CalibrationOptions{});
  EXPECT_EQ(choice.confirming, (std::vector<size_t>{0, 1}));
  EXPECT_EQ(choice.undecided, (std::vector<std::string>{"jkr"}));
  EXPECT_TRUE(choice.nonlinear.empty());

  // More tied than may be confirmed (at most 4): the leader, then the stable signatures of its
  // band before the unstable ones, whatever their shares within the band. Wall parameters whose
  // two strengths disagree (their "100 %" a noisy linear recalibration of a few terms) leave the
  // places to the stable shape and liquid bridges.
  std::vector<CandidateResult> crowded(6);
  const char* crowd[] = {"steel.friction", "steel.rolling_friction", "steel.restitution", "clump_shape", "liquid_bridge", "sjkr"};
  const double shares[] = {1.0, 1.0, 1.0, 0.98, 0.96, 0.86};
  const double agreements[] = {-0.01, -0.15, 0.05, 0.80, 0.99, 0.96};
  for (size_t k = 0; k < crowded.size(); ++k)
    crowded[k].name = crowd[k], crowded[k].explained = shares[k], crowded[k].agreement = agreements[k], crowded[k].stable = agreements[k] >= 0.5;
  const detail::ConfirmationChoice crowd_choice = detail::choose_confirmations(crowded, CalibrationOptions{});
  EXPECT_EQ(crowd_choice.confirming, (std::vector<size_t>{0, 1, 3, 4}));
  EXPECT_EQ(crowd_choice.undecided, (std::vector<std::string>{"steel.rolling_friction", "clump_shape", "liquid_bridge"}));
  EXPECT_EQ(crowd_choice.nonlinear, std::vector<std::string>{});

  // 700 s left, 600 s a confirmation: the leader fits; the second is tied with it (the screen
  // cannot tell them apart) and is confirmed beyond the budget; the third is not tied and waits.
  const detail::ConfirmationPlan plan = detail::fit_confirmations({600, 600, 600}, {false, true, false}, 700);
  EXPECT_EQ(plan.kept, (std::vector<size_t>{0, 1}));
  EXPECT_EQ(plan.beyond, (std::vector<size_t>{1}));
  EXPECT_EQ(plan.dropped, (std::vector<size_t>{2}));
  EXPECT_DOUBLE_EQ(plan.left, -500);
  // With room for two, nothing goes beyond; a leader that alone exceeds the budget is kept.
  const detail::ConfirmationPlan roomy = detail::fit_confirmations({600, 600, 600}, {false, false, false}, 1300);
  EXPECT_EQ(roomy.kept, (std::vector<size_t>{0, 1}));
  EXPECT_TRUE(roomy.beyond.empty());
  EXPECT_EQ(detail::fit_confirmations({600}, {false}, 100).kept, (std::vector<size_t>{0}));
  // A tie past the budget falls back on the cheaper confirmations (fewer design points where the
  // plain fit's points stand in): 350 + 350 fit the 700 s; the untied third still waits.
  const double none = std::numeric_limits<double>::quiet_NaN();
  const detail::ConfirmationPlan cheaper = detail::fit_confirmations({600, 600, 600}, {false, true, false}, 700, {350, 350, none});
  EXPECT_TRUE(cheaper.reduced);
  EXPECT_EQ(cheaper.kept, (std::vector<size_t>{0, 1}));
  EXPECT_TRUE(cheaper.beyond.empty());
  EXPECT_EQ(cheaper.dropped, (std::vector<size_t>{2}));
  EXPECT_DOUBLE_EQ(cheaper.left, 0);
  // Without a tie past the budget the full confirmations stay.
  EXPECT_FALSE(detail::fit_confirmations({600, 600}, {false, false}, 1300, {350, 350}).reduced);
  // Fewest design points beside the plain fit's: twice the coefficients that involve the added
  // parameter (3 parameters, one added: 4 of 10), at least k + 2.
  EXPECT_EQ(detail::design_points_beside_known(3, 1), 8);
  EXPECT_EQ(detail::design_points_beside_known(2, 1), 6);
  EXPECT_EQ(detail::design_points_beside_known(1, 1), 4);
  // A confirmation's own design: the design factor on the coefficients the plain fit's points
  // leave open (4 of 10: 2 x 4 + 2 = 10 points at factor 2, against 2 x 10 + 2 = 22 for all of
  // them), never below the fewest, never above the full rule; a zoom round takes the full rule.
  CalibrationOptions o;
  o.rounds = 1, o.design_factor = 2;
  EXPECT_EQ(detail::design_points(o, 3), 22);
  EXPECT_EQ(detail::confirmation_design_points(o, 3, 1), 10);
  EXPECT_EQ(detail::confirmation_passes(o, 2), 10 + std::max(1, o.replicas));
  o.design_factor = 1;
  EXPECT_EQ(detail::confirmation_design_points(o, 3, 1), 8);
  EXPECT_EQ(detail::confirmation_design_points(o, 1, 1), 4);  // the full rule would take 5
  o.design_factor = 2, o.rounds = 2;
  EXPECT_EQ(detail::confirmation_design_points(o, 3, 1), 22);
}

// Progress over the whole command: every line counts one more of the diagnosis' simulations,
// the count planned in all is never below those done, and by the end the plan (made again as the
// diagnosis learns which candidates it confirms) equals what ran.
TEST(Budget, ProgressCountsTheWholeDiagnosis) {
  const Analytic sim;
  const MaterialModel start = dry_spheres();
  MaterialModel truth = read_material_model(kMaterials + "/gravel.yaml");
  set_parameter(truth, "friction", 0.5), set_parameter(truth, "restitution", 0.5);
  CalibrationOptions options = analytic_options(sim);
  std::vector<std::pair<int, int>> counts;  // (done, planned in all)
  options.progress = [&](const std::string& line) {
    const auto at = line.find("; diagnose: simulation ");
    if (at == std::string::npos) return;
    int done = 0, planned = 0;
    ASSERT_EQ(std::sscanf(line.c_str() + at, "; diagnose: simulation %d of about %d", &done, &planned), 2) << line;
    counts.emplace_back(done, planned);
  };
  diagnose(start, synthesise(flow_tests(), truth, sim, 11), {}, options);
  ASSERT_GT(counts.size(), 100u);
  for (size_t k = 0; k < counts.size(); ++k) {
    EXPECT_EQ(counts[k].first, static_cast<int>(k) + 1);
    EXPECT_GE(counts[k].second, counts[k].first);
  }
  EXPECT_EQ(counts.back().first, counts.back().second);
}

TEST(Ledger, AppendsVersions) {
  const std::string path = (std::filesystem::temp_directory_path() / "demdesign_ledger_test" / "ledger.yaml").string();
  std::filesystem::remove_all(std::filesystem::path(path).parent_path());
  const MaterialModel m = dry_spheres();
  Comparison c;
  Term t;
  t.experiment = "aor", t.observable = "angle_deg", t.residual = -3.5;
  c.terms.push_back(t), c.chi2 = 12.25, c.n = 1;
  append_ledger(path, "gravel", {ledger_entry(m, c, "start", {"friction"})});
  c.terms[0].residual = 0.5, c.chi2 = 0.25;
  const auto all = append_ledger(path, "gravel", {ledger_entry(m, c, "+ epsd", {"friction"})});
  ASSERT_EQ(all.size(), 2u);
  const auto read = read_ledger(path);
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[1].version, 2);
  EXPECT_EQ(read[1].label, "+ epsd");
  EXPECT_DOUBLE_EQ(read[0].residuals.at("aor/angle_deg"), -3.5);
  EXPECT_DOUBLE_EQ(read[1].chi2_per_n(), 0.25);
  EXPECT_DOUBLE_EQ(read[0].parameters.at("friction"), 0.65);
}

}  // namespace
}  // namespace dem::materials
