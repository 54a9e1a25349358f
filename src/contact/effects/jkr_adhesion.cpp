// JKR adhesion (Johnson, Kendall & Roberts 1971), added to the Hertz normal law. With work of
// adhesion W = 2 gamma (gamma: surface energy of each surface; unlike materials: geometric mean)
// the contact radius a follows from the overlap
//   delta = a^2/R* - sqrt(2 pi W a / E*)
// and the normal force is
//   F = 4 E* a^3 / (3 R*) - sqrt(8 pi W E* a^3).
// The force reaches its most tensile value -3/2 pi W R* (the pull-off force), and the neck
// breaks at delta_c = a_c^2/R* - sqrt(2 pi W a_c/E*), a_c^3 = pi W R*^2 / (8 E*), where
// d delta/da = 0. A contact forms when the bodies touch and then holds until delta_c (hysteresis).
// This effect replaces the Hertz elastic force by the JKR force; friction keeps using the
// repulsive load of the normal law.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "contact/effects/effects.h"

namespace dem::effects {
namespace {

constexpr double kPi = std::numbers::pi;
// Coarse graining (core/coarse_grain.h): gamma x F (exponent 1). The pull-off force 3/2 pi W R*
// then grows as F^2, its stress (force / d^2) is the real one, and with E* unchanged the whole JKR
// curve is the real one in force / d^2 against delta / d (a ~ F, a^3/R* ~ F^2, sqrt(W E* a^3) ~ F^2),
// the breaking overlap delta_c ~ F included.
constexpr ParamSpec kParams[] = {
    {"surface_energy", "J/m^2", 0.0, 0.0, 10.0, Mixing::geometric, true,
     "surface energy gamma of each surface; work of adhesion W = 2 gamma", 1},
};
constexpr HistorySpec kHistory[] = {{"jkr_neck", 1}};  // the neck's contact radius a [m]; 0: no neck

/// Overlap at which the neck breaks [m] (negative), k = sqrt(2 pi W / E*): the least overlap of
/// the stable branch, delta_c = min over s of s^4/R* - k s = -3/4 k s_c with s_c^3 = k R*/4
/// (that is, a_c^3 = pi W R*^2 / (8 E*)), where d delta/da = 0.
double breaking_overlap(double k, double r_eff) { return -0.75 * k * std::cbrt(0.25 * k * r_eff); }

/// Square root of the contact radius, s = sqrt(a), on the stable branch (a >= a_c) for an
/// overlap: the root of g(s) = s^4/R* - k s - delta, k = sqrt(2 pi W / E*), which is convex and
/// increasing there, so Newton converges monotonically from the right of the root, and a step
/// from its left lands on its right. It starts from the radius of the step before (`previous`,
/// 0 for a new neck), which the overlap has hardly moved: one or two iterations. Convergence is
/// quadratic, so after a step of 1e-8 s the root is exact to about 1e-16 s.
double root_radius(double overlap, double k, double r_eff, double previous) {
  const double first = previous > 0.0 ? previous : std::max(std::pow(2.0 * k * r_eff, 2.0 / 3.0), std::sqrt(2.0 * r_eff * std::max(overlap, 0.0)));
  double s = std::sqrt(first);
  const double inv_r = 1.0 / r_eff;
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double s3 = s * s * s;
    const double step = (s3 * s * inv_r - k * s - overlap) / (4.0 * s3 * inv_r - k);
    s -= step;
    if (std::abs(step) <= 1e-8 * s) break;
  }
  return s;
}

void jkr_kernel(const EffectContext& ctx, ContactBatch& b) {
  double* neck_column = ctx.hist(b, 0);  // the neck's contact radius [m] while one joins the pair, else 0
  for (int c = 0; c < b.count; ++c) {
    double& neck = neck_column[c];
    const double work = 2.0 * ctx.param(b, c, 0);
    if (work <= 0.0) continue;
    const double youngs = ctx.youngs_eff(b, c), r_eff = b.r_eff[c], overlap = b.overlap[c];
    if (neck == 0.0 && !(overlap > 0.0)) continue;
    const double k = std::sqrt(2.0 * kPi * work / youngs);
    if (overlap < 0.0 && overlap < breaking_overlap(k, r_eff)) {
      neck = 0.0;
      continue;
    }
    const double s = root_radius(overlap, k, r_eff, neck), a = s * s;
    neck = a;
    // F = 4 E* a^3 / (3 R*) - sqrt(8 pi W E* a^3), with sqrt(8 pi W E*) = 2 E* k
    const double force = 4.0 * youngs * a * a * a / (3.0 * r_eff) - 2.0 * youngs * k * a * s;
    b.fn[c] += force - b.fn_elastic[c];
  }
}

double jkr_range(const double* row, const double* params, double radius_max) {
  // |delta_c| grows as R*^(1/3): the largest particle bounds every pair.
  const double work = 2.0 * params[0];
  return work > 0.0 ? -breaking_overlap(std::sqrt(2.0 * kPi * work / row[0]), radius_max) : 0.0;
}

/// Surface energy [J/m^2] that gives a pull-off force of one particle weight between two
/// particles: F = 3/2 pi W R*, W = 2 gamma, R* = d/4, weight = rho pi d^3 g / 6, so
/// gamma = rho g d^2 / 9. The fit starts at 3 weights and searches up to 30 (bond numbers of
/// fine cohesive powders).
double one_weight_bond(const ParticleScale& s) { return s.density * 9.81 * s.diameter * s.diameter / 9.0; }

constexpr FittedParam kFitted[] = {{"surface_energy", 3.0, 0.0, 30.0}};
constexpr std::string_view kMoves[] = {"angle_of_repose_cylinder/angle_deg", "rotating_drum/dynamic_angle_deg",
                                       "bulk_density/bulk_density", "hopper_discharge/mass_flow_rate",
                                       "drop_rebound/restitution", "direct_shear/peak_shear_stress"};
constexpr CandidateSpec kCandidate{
    .title = "van der Waals cohesion (JKR)",
    .signature = "strength that does not come from the load, growing with the contact area: cohesion of fine dry "
                 "particles (van der Waals, JKR adhesion)",
    .fitted = kFitted,
    .also_set = {},
    .moves = kMoves,
    .scale = one_weight_bond,
};

}  // namespace

extern const EffectSpec jkr_adhesion{
    .stage = Stage::adhesion,
    .name = "jkr",
    .summary = "JKR adhesion from a surface energy: pull-off 3/2 pi W R*, neck breaks at delta_c",
    .citation = "Johnson, Kendall & Roberts (1971) Proc. R. Soc. A 324:301",
    .params = kParams,
    .options = {},
    .history = kHistory,
    .kernel = jkr_kernel,
    .range = jkr_range,
    .derived_count = 0,
    .derive = nullptr,
    .requires_normal = "hertz",
    .candidate = &kCandidate,
};

}  // namespace dem::effects
