// Coarse graining (src/core/coarse_grain.h): the reader's checks, parcels from real counts and
// sizes, the pair parameters scaled by their declared exponents and nothing else, and the law's
// promise checked on single contacts: a parcel falls and rebounds as the real particle does, and
// its cohesive forces over (F d)^2 are the real ones over d^2. Each case is built here from YAML.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "core/coarse_grain.h"
#include "sim.h"
#include "validation/validation.h"

namespace dem::test {
namespace {

constexpr double kPi = std::numbers::pi;

std::string replace_all(std::string text, const std::string& from, const std::string& to) {
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) text.replace(at, from.size(), to);
  return text;
}

/// `text` with "@F@" replaced by the coarse_grain entry of a flow-style map (nothing for 1, so that
/// F = 1 is the case without the key) and "@D@" by `factor` times `unit` [m].
std::string with_factor(const std::string& text, double factor, double unit = 0) {
  const std::string key = factor == 1.0 ? std::string() : ", coarse_grain: " + fmt::format("{:.17g}", factor);
  return replace_all(replace_all(text, "@F@", key), "@D@", fmt::format("{:.17g}", factor * unit));
}

Model compile_text(const std::string& text) { return compile(parse_case_text(text, "case.yaml")); }

/// The message of the CaseError that reading and compiling `text` throws ("" when none).
std::string error_of(const std::string& text) {
  try {
    compile_text(text);
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ---- (a) the reader -------------------------------------------------------------------------

TEST(CoarseGrain, AFactorBelowOneOrInfiniteIsRefusedWithFileLineAndKey) {
  const std::string below = R"(simulation: {duration: 0.1}
materials:
  ore: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}
particles:
  - {material: ore, diameter: 0.004, positions: [[0, 0, 0.01]], coarse_grain: 0.5}
)";
  const std::string e = error_of(below);
  EXPECT_TRUE(contains(e, "case.yaml:5:")) << e;
  EXPECT_TRUE(contains(e, "particles[0].coarse_grain")) << e;
  EXPECT_TRUE(contains(e, "0.5 is out of range; valid: [1, 1000]")) << e;
  const std::string infinite = error_of(replace_all(below, "coarse_grain: 0.5", "coarse_grain: .inf"));
  EXPECT_TRUE(contains(infinite, "case.yaml:5:")) << infinite;
  EXPECT_TRUE(contains(infinite, "inf is out of range")) << infinite;
}

TEST(CoarseGrain, DifferentFactorsInOneCaseAreRefusedAsOutOfScope) {
  const std::string e = error_of(R"(simulation: {duration: 0.1}
materials:
  ore: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}
particles:
  - {material: ore, diameter: 0.004, positions: [[0, 0, 0.01]], coarse_grain: 2}
inlets:
  - {name: feed, material: ore, diameter: 0.004, mass_rate_kgs: 0.01, region: {min: [0, 0, 0.5], max: [0.1, 0.1, 0.6]}, coarse_grain: 3}
)");
  EXPECT_TRUE(contains(e, "case.yaml:7:")) << e;
  EXPECT_TRUE(contains(e, "inlets[0].coarse_grain: 3 differs from particles[0].coarse_grain 2")) << e;
  EXPECT_TRUE(contains(e, "mixed coarse graining is out of scope")) << e;
}

// ---- (b) parcels ------------------------------------------------------------------------------

TEST(CoarseGrain, AParticleSetOf8000RealParticlesAtFactorTwoIs1000ParcelsOfTwiceTheDiameter) {
  const std::string text = R"(simulation: {duration: 0.1, gravity: [0, 0, 0]}
materials:
  ore: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}
particles:
  - {material: ore, diameter: 0.004, count: 8000, region: {min: [0, 0, 0], max: [0.2, 0.2, 0.1]}@F@}
)";
  const Model model = compile_text(with_factor(text, 2.0));
  EXPECT_EQ(model.coarse_grain, 2.0);
  EXPECT_EQ(model.sources[0].spec.count, 1000);
  EXPECT_DOUBLE_EQ(model.radius_max, 0.004);
  const State state = initial_state(model);
  ASSERT_EQ(state.size(), 1000u);
  double mass = 0;
  for (size_t p = 0; p < state.size(); ++p) {
    EXPECT_DOUBLE_EQ(state.radius[p], 0.004) << p;
    mass += 1.0 / state.inv_mass[p];
  }
  // The same solid as 8000 real particles of 4 mm.
  const double real_mass = 8000 * 2500 * kPi / 6 * std::pow(0.004, 3);
  EXPECT_NEAR(mass, real_mass, 1e-12 * real_mass);
}

TEST(CoarseGrain, ParcelCountsRoundAndKeepOneAndDistributionsScaleWhole) {
  EXPECT_EQ(parcel_count(8000, 2.0), 1000);
  EXPECT_EQ(parcel_count(20, 2.0), 3);  // 2.5 rounds away from zero
  EXPECT_EQ(parcel_count(3, 2.0), 1);   // 0.375: at least one parcel
  EXPECT_EQ(parcel_count(1000, 10.0), 1);
  SizeDistributionSpec sieve;
  sieve.kind = SizeDistributionSpec::Kind::discrete;
  sieve.values = {0.002, 0.005, 0.010};
  sieve.mass_fractions = {0.2, 0.5, 0.3};
  const SizeDistributionSpec parcels = parcel_diameters(sieve, 3.0);
  ASSERT_EQ(parcels.values.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(parcels.values[k], 3.0 * sieve.values[k]);
    EXPECT_EQ(parcels.mass_fractions[k], sieve.mass_fractions[k]);
  }
  SizeDistributionSpec normal;
  normal.kind = SizeDistributionSpec::Kind::normal;
  normal.mean = 0.004, normal.std_dev = 0.001, normal.min = 0.002, normal.max = 0.007;
  const SizeDistributionSpec n3 = parcel_diameters(normal, 3.0);
  EXPECT_DOUBLE_EQ(n3.mean, 0.012);
  EXPECT_DOUBLE_EQ(n3.std_dev, 0.003);
  EXPECT_DOUBLE_EQ(n3.smallest(), 0.006);
  EXPECT_DOUBLE_EQ(n3.largest(), 0.021);
}

// ---- (c) the compiled pair parameters ------------------------------------------------------

const char* kEveryCohesion = R"(simulation: {duration: 0.1}
contact: {normal: hertz, adhesion: [jkr, sjkr], rolling: epsd, extra: [liquid_bridge]}
materials:
  ore: {density: 2500, youngs_modulus: 5e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.6, rolling_friction: 0.1, surface_energy: 0.05, cohesion_energy_density: 2e4, liquid_content: 0.01, contact_angle_deg: 20}
  steel: {density: 7800, youngs_modulus: 2e11, poisson_ratio: 0.3, restitution: 0.8, friction: 0.3, surface_tension: 0.05}
interactions:
  - {materials: [ore, steel], surface_energy: 0.02}
walls:
  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: steel}
particles:
  - {material: ore, diameter: 0.004, positions: [[0, 0, 0.01]]@F@}
)";

/// Every column of every pair row of `scaled` against `real`: the columns of the keys in
/// `factor` multiplied by it, every other one (E*, G*, each other parameter, derived values)
/// the same bit for bit.
void expect_pair_table(const Model& real, const Model& scaled, const std::map<std::string, double>& factor) {
  ASSERT_EQ(real.pair_stride, scaled.pair_stride);
  ASSERT_EQ(real.pair_table.size(), scaled.pair_table.size());
  std::map<int, std::string> key_of_column;
  for (const ActiveEffect& e : real.effects)
    for (size_t k = 0; k < e.spec->params.size(); ++k)
      key_of_column[e.param_offset + static_cast<int>(k)] = std::string(e.spec->params[k].key);
  int checked_scaled = 0;
  for (int t = 0; t < real.n_materials() * real.n_materials(); ++t)
    for (int c = 0; c < real.pair_stride; ++c) {
      const double a = real.pair_row(t)[c], b = scaled.pair_row(t)[c];
      const auto key = key_of_column.find(c);
      const auto f = key == key_of_column.end() ? factor.end() : factor.find(key->second);
      if (f == factor.end()) {
        EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "pair row " << t << ", column " << c << ": " << a << " != " << b;
      } else {
        EXPECT_DOUBLE_EQ(b, f->second * a) << key->second << ", pair row " << t;
        checked_scaled += a != 0.0;
      }
    }
  EXPECT_GT(checked_scaled, 0);
}

TEST(CoarseGrain, CohesionParametersScaleByTheirExponentsAndEverythingElseStaysBitForBit) {
  const Model real = compile_text(with_factor(kEveryCohesion, 1.0));
  const Model parcels = compile_text(with_factor(kEveryCohesion, 2.0));
  // JKR surface energy and the liquid's surface tension x F; the sjkr energy density, the liquid
  // content, friction, rolling friction, restitution, the moduli: unchanged.
  expect_pair_table(real, parcels, {{"surface_energy", 2.0}, {"surface_tension", 2.0}});
  EXPECT_DOUBLE_EQ(parcels.pair_param(0, 1, "surface_energy"), 2.0 * 0.02);  // the interaction's value, scaled
  // The bridge volume w (V_i + V_j)/n_b grows as F^3 with the parcels: its rupture distance
  // (1 + theta/2) V^(1/3), the case's interaction range, is F times the real one.
  const double theta = 20 * kPi / 180, radius = 2.0 * 0.002;
  const double volume = 0.01 * 2 * (4.0 / 3.0 * kPi * radius * radius * radius) / 6;
  EXPECT_NEAR(parcels.interaction_range, (1 + theta / 2) * std::cbrt(volume), 1e-12 * parcels.interaction_range);
  EXPECT_NEAR(parcels.interaction_range, 2.0 * real.interaction_range, 1e-12 * parcels.interaction_range);
  // F = 1 is the case without the key: the same model, hash and all.
  const Model explicit_one = compile_text(replace_all(kEveryCohesion, "@F@", ", coarse_grain: 1"));
  EXPECT_EQ(explicit_one.hash, real.hash);
  EXPECT_TRUE(explicit_one.coarse_grain_report.empty());
  EXPECT_NE(parcels.hash, real.hash);
}

TEST(CoarseGrain, ALinearSpringsStiffnessScalesByFAndItsOtherParametersDoNot) {
  const std::string text = R"(simulation: {duration: 0.1}
contact: {normal: linear}
materials:
  ore: {density: 2500, youngs_modulus: 5e7, restitution: 0.5, normal_stiffness: 2e4, characteristic_velocity: 2, tangential_stiffness_ratio: 0.4}
particles:
  - {material: ore, diameter: 0.004, positions: [[0, 0, 0.01]]@F@}
)";
  const Model real = compile_text(with_factor(text, 1.0));
  const Model parcels = compile_text(with_factor(text, 3.0));
  expect_pair_table(real, parcels, {{"normal_stiffness", 3.0}});
  EXPECT_DOUBLE_EQ(parcels.pair_param(0, 0, "normal_stiffness"), 6e4);
}

TEST(CoarseGrain, TheSetUpSaysWhatWasScaledAndWarnsOfANarrowOrifice) {
  const std::string text = R"(simulation: {duration: 0.1}
contact: {adhesion: [jkr]}
materials:
  ore: {density: 2500, youngs_modulus: 5e7, restitution: 0.5, surface_energy: 0.05}
walls:
  - {name: orifice, disc: {point: [0, 0, 0], normal: [0, 0, 1], radius: 0.1, hole_radius: HOLE}, material: ore}
particles:
  - {material: ore, diameter: 0.004, count: 8000, region: {min: [-0.1, -0.1, 0.01], max: [0.1, 0.1, 0.11]}@F@}
)";
  const Model narrow = compile_text(with_factor(replace_all(text, "HOLE", "0.02"), 2.0));
  std::string said;
  for (const std::string& line : narrow.coarse_grain_report) said += line + "\n";
  EXPECT_TRUE(contains(said, "F = 2: each particle is a parcel standing for 8 real particles")) << said;
  EXPECT_TRUE(contains(said, "8000 real particles as 1000 parcels; parcel diameters 0.008 m (real 0.004 m)")) << said;
  EXPECT_TRUE(contains(said, "surface_energy [J/m^2] x 2 (F^1)")) << said;
  EXPECT_TRUE(contains(said, "mass flow, drive power, wall pressure and wear")) << said;
  // The hole is 0.04 m across: 5 parcel diameters of 8 mm, 10 real ones.
  EXPECT_TRUE(contains(said, "WARNING: the hole of wall 'orifice' (an orifice) is 0.04 m across, 5 parcel diameters")) << said;
  const Model wide = compile_text(with_factor(replace_all(text, "HOLE", "0.03"), 2.0));
  for (const std::string& line : wide.coarse_grain_report) EXPECT_FALSE(contains(line, "WARNING")) << line;
  EXPECT_TRUE(compile_text(with_factor(replace_all(text, "HOLE", "0.02"), 1.0)).coarse_grain_report.empty());
}

// ---- (d) a parcel falls and rebounds as the real particle -----------------------------------

TEST(CoarseGrain, AParcelFallsAsTheRealParticle) {
  // A given step, the same for both (the auto step would grow with the parcel); 6000 steps.
  const std::string text = R"(simulation: {duration: 1, time_step: 5e-5}
materials:
  ore: {density: 2500, youngs_modulus: 5e7, poisson_ratio: 0.25, restitution: 0.5}
particles:
  - {material: ore, diameter: 0.02, positions: [[0, 0, 1]], velocity: [0.5, 0, 1]@F@}
)";
  Sim real(parse_case_text(with_factor(text, 1.0), "case.yaml"));
  Sim parcel(parse_case_text(with_factor(text, 4.0), "case.yaml"));
  ASSERT_DOUBLE_EQ(parcel.state.radius[0], 4.0 * real.state.radius[0]);
  const auto never = [](const State&) { return false; };
  real.advance_until(never, 0.3);
  parcel.advance_until(never, 0.3);
  ASSERT_EQ(real.state.time, parcel.state.time);
  const double t = real.state.time, z = 1 + t - 0.5 * 9.81 * t * t;
  EXPECT_NEAR(parcel.state.z[0], real.state.z[0], 1e-9 * std::abs(real.state.z[0]));
  EXPECT_NEAR(parcel.state.x[0], real.state.x[0], 1e-9 * std::abs(real.state.x[0]));
  EXPECT_NEAR(real.state.z[0], z, 1e-9 * std::abs(z));  // velocity Verlet is exact under constant gravity
  EXPECT_NEAR(parcel.state.x[0], 0.5 * t, 1e-9 * 0.5 * t);
}

TEST(CoarseGrain, AParcelDroppedOnAPlaneReboundsWithTheRealRestitution) {
  // Hertz with restitution damping at 1 m/s onto a rigid plane, starting 10 um x F above it.
  const std::string text = R"(simulation: {duration: 0.01, rayleigh_fraction: 0.01, gravity: [0, 0, 0]}
materials:
  ore: {density: 2500, youngs_modulus: 5e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5}
  rigid: {density: 1, youngs_modulus: rigid, poisson_ratio: 0.0, restitution: 0.5, friction: 0.5}
walls:
  - {name: plane, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: rigid}
particles:
  - {material: ore, diameter: 0.004, positions: [[0, 0, @D@]], velocity: [0, 0, -1]@F@}
)";
  const double factor = 3.0;
  const validation::ImpactRecord real = validation::record_impact(parse_case_text(with_factor(text, 1.0, 0.00201)), 0.01);
  const validation::ImpactRecord parcel = validation::record_impact(parse_case_text(with_factor(text, factor, 0.00201)), 0.01);
  EXPECT_NEAR(real.rebound_speed, 0.5, 0.01 * 0.5);  // the restitution asked for
  EXPECT_NEAR(parcel.rebound_speed, real.rebound_speed, 0.01 * real.rebound_speed);
  // The same impact F times as large: peak overlap and contact time x F.
  EXPECT_NEAR(parcel.max_overlap, factor * real.max_overlap, 0.01 * factor * real.max_overlap);
  EXPECT_NEAR(parcel.contact_time, factor * real.contact_time, 0.01 * factor * real.contact_time);
}

// ---- (e) cohesive forces over d^2 -----------------------------------------------------------

const char* kCohesivePair = R"(simulation: {duration: 0.01}
contact: CONTACT
materials:
  ore: {density: 2500, youngs_modulus: 5e7, poisson_ratio: 0.25, restitution: 0.5, PARAMS}
particles:
  - {material: ore, diameter: 0.004, positions: [[0, 0, 0.01]]@F@}
)";

/// The model of two 4 mm particles (F x 4 mm parcels) with this contact law and parameters.
Model cohesive_model(const std::string& contact, const std::string& params, double factor) {
  return compile_text(with_factor(replace_all(replace_all(kCohesivePair, "CONTACT", contact), "PARAMS", params), factor));
}

/// The most tensile normal force [N] between two spheres of radius 2 mm x F over the overlaps
/// F x `overlaps` [m] in that order (a neck or bridge formed at one holds at the next), divided
/// by the parcel diameter squared: a stress [Pa].
double most_tensile_stress(const Model& model, double factor, const std::vector<double>& overlaps) {
  const double radius = 0.002 * factor, mass = 2500 * 4.0 / 3.0 * kPi * radius * radius * radius;
  OneContact pair(model, radius, radius, 0.5 * mass);
  double least = 0;
  for (double overlap : overlaps) least = std::min(least, pair.force_at(model, factor * overlap));
  return least / (4 * radius * radius);
}

/// n overlaps from `from` down to `to` [m].
std::vector<double> sweep(double from, double to, int n) {
  std::vector<double> out;
  for (int k = 0; k <= n; ++k) out.push_back(from + (to - from) * k / n);
  return out;
}

TEST(CoarseGrain, LiquidBridgePullOffOverDiameterSquaredIsTheRealOne) {
  const std::string contact = "{extra: [liquid_bridge]}", params = "liquid_content: 0.01, contact_angle_deg: 20";
  // Touch (the bridge forms), then pull apart to 200 um x F, within the 566 um x F rupture distance.
  const std::vector<double> path = sweep(1e-7, -200e-6, 400);
  const double real = most_tensile_stress(cohesive_model(contact, params, 1.0), 1.0, path);
  const double parcel = most_tensile_stress(cohesive_model(contact, params, 3.0), 3.0, path);
  // 2 pi R gamma cos(theta) / d^2 at touching, R = 2 R* = 2 mm, d = 4 mm.
  const double expected = -2 * kPi * 0.002 * 0.072 * std::cos(20 * kPi / 180) / (0.004 * 0.004);
  EXPECT_NEAR(real, expected, 0.01 * std::abs(expected));
  EXPECT_NEAR(parcel, real, 0.01 * std::abs(real));
  // Past the real bridge's rupture distance times F, the parcels' bridge has ruptured too.
  const Model model = cohesive_model(contact, params, 3.0);
  OneContact pair(model, 0.006, 0.006, 1e-3);
  pair.force_at(model, 3e-7);
  EXPECT_LT(pair.force_at(model, -3.0 * 550e-6), 0.0);
  EXPECT_EQ(pair.force_at(model, -3.0 * 580e-6), 0.0);
}

TEST(CoarseGrain, SjkrPullOffOverDiameterSquaredIsTheRealOne) {
  const std::string contact = "{adhesion: [sjkr]}", params = "cohesion_energy_density: 2e5";
  // Hertz repulsion against the area law: the most tensile net force lies at a small overlap.
  const std::vector<double> path = sweep(0, 2e-6, 2000);
  const double real = most_tensile_stress(cohesive_model(contact, params, 1.0), 1.0, path);
  const double parcel = most_tensile_stress(cohesive_model(contact, params, 2.0), 2.0, path);
  ASSERT_LT(real, 0.0);
  EXPECT_NEAR(parcel, real, 0.01 * std::abs(real));
}

TEST(CoarseGrain, JkrPullOffOverDiameterSquaredIsTheRealOne) {
  const std::string contact = "{adhesion: [jkr]}", params = "surface_energy: 0.05";
  const Model real_model = cohesive_model(contact, params, 1.0);
  // The neck breaks at delta_c = -3/4 k (k R*/4)^(1/3), k = sqrt(2 pi W / E*) (jkr_adhesion.cpp).
  const double work = 2 * 0.05, r_eff = 0.001, youngs = real_model.pair_row(0)[0];
  const double k = std::sqrt(2 * kPi * work / youngs), breaking = -0.75 * k * std::cbrt(0.25 * k * r_eff);
  const std::vector<double> path = sweep(-2 * breaking, 1.1 * breaking, 4000);
  const double real = most_tensile_stress(real_model, 1.0, path);
  const double parcel = most_tensile_stress(cohesive_model(contact, params, 2.0), 2.0, path);
  // Pull-off 3/2 pi W R* over d^2.
  const double expected = -1.5 * kPi * work * r_eff / (0.004 * 0.004);
  EXPECT_NEAR(real, expected, 0.01 * std::abs(expected));
  EXPECT_NEAR(parcel, real, 0.01 * std::abs(real));
}

}  // namespace
}  // namespace dem::test
