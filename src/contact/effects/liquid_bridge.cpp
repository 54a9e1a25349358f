// Pendular liquid bridge (capillary force), Willett, Adams, Johnson & Seville (2000), eq. 12:
//   F = 2 pi R gamma cos(theta) / (1 + 2.1 S+ + 10 S+^2),  S+ = (S/2) sqrt(R / V),
//   R = 2 R_i R_j / (R_i + R_j) (= 2 R*; 2 R_i against a flat wall), S the surface separation.
// The bridge forms when the bodies touch, holds while they separate, and ruptures at the
// Lian, Thornton & Adams (1993) distance S_c = (1 + theta/2) V^(1/3).
// Bridge volume from the liquid content w (liquid volume per solid volume) shared by the
// bridges of each particle: V = w (V_i + V_j) / n_b; a wall brings no liquid (V = w V_i / n_b).
// Total liquid is conserved when each particle holds n_b bridges.
//
// Why this form and not the source paper's toroidal F = pi gamma R2 (R2/R1 + 1): the toroidal
// radii R1, R2 must be solved from volume and separation at every step; Willett's closed form is
// fitted to exact Young-Laplace solutions, keeps the contact limit 2 pi R gamma cos(theta) and
// is continuous up to rupture, where it is small (no jump that would inject energy).
#include <cmath>
#include <numbers>

#include "contact/effects/effects.h"

namespace dem::effects {
namespace {

constexpr double kPi = std::numbers::pi;
enum Param { kLiquidContent, kSurfaceTension, kContactAngle, kBridgesPerParticle, kCosAngle, kReachCubed /* derived */ };

// Coarse graining (core/coarse_grain.h), the last number of each row: gamma x F, so that the
// bridge force 2 pi R gamma cos(theta) ~ F^2 keeps its stress. The liquid content is a volume
// fraction: unchanged, it makes the bridge volume w (V_i + V_j) / n_b grow as F^3 with the
// parcels' volume, so S+ = (S/2) sqrt(R/V) at the same S / d and the rupture distance
// (1 + theta/2) V^(1/3) / d are the real ones. An angle and a count of bridges are unchanged.
constexpr ParamSpec kParams[] = {
    {"liquid_content", "-", 0.0, 0.0, 0.5, Mixing::arithmetic, true,
     "liquid volume per solid volume of the particles", 0},
    {"surface_tension", "N/m", 0.072, 0.0, 1.0, Mixing::arithmetic, false,
     "surface tension of the liquid (water: 0.072)", 1},
    {"contact_angle_deg", "deg", 0.0, 0.0, 89.0, Mixing::arithmetic, true,
     "wetting angle of the liquid on the solid", 0},
    {"bridges_per_particle", "-", 6.0, 1.0, 14.0, Mixing::arithmetic, false,
     "bridges that share one particle's liquid", 0},
};
constexpr HistorySpec kHistory[] = {{"bridge_formed", 1}};

/// cos(theta) and (S_c / V^(1/3))^3 = (1 + theta/2)^3 of a pair row, so that the kernel calls no
/// libm function and vectorises.
void derive_angle_terms(double* p) {
  const double theta = p[kContactAngle] * kPi / 180.0;
  const double reach = 1.0 + 0.5 * theta;
  p[kCosAngle] = std::cos(theta);
  p[kReachCubed] = reach * reach * reach;
}

[[gnu::always_inline]] inline double bridge_volume(double liquid, double bridges, double ri, double rj) {
  const double vi = 4.0 / 3.0 * kPi * ri * ri * ri;
  const double vj = 4.0 / 3.0 * kPi * rj * rj * rj;
  return liquid * (vi + vj) / bridges;
}

/// Without branches, so that it vectorises: the rupture test compares cubes (S^3 > S_c^3, no
/// cube root), the bridge state and the force are chosen, not jumped to.
DEM_KERNEL void bridge_kernel(const EffectContext& ctx, ContactBatch& b) {
  double* formed = ctx.hist(b, 0);  // 1 while a bridge joins the pair, else 0
  DEM_VECTOR_LOOP
  for (int c = 0; c < b.count; ++c) {
    const double liquid = ctx.param(b, c, kLiquidContent);
    const bool wet = liquid > 0.0;
    const double separation = -b.overlap[c];  // [m]
    const double volume = bridge_volume(liquid, ctx.param(b, c, kBridgesPerParticle), b.radius_i[c], b.radius_j[c]);
    const bool ruptured = separation * separation * separation > ctx.param(b, c, kReachCubed) * volume;
    const bool was_formed = formed[c] != 0.0;
    const bool holds = wet & ((separation <= 0.0) | was_formed) & !ruptured;
    const double radius = 2.0 * b.r_eff[c];
    const double sqrt_ratio = std::sqrt(radius / (wet ? volume : 1.0));
    const double s_plus = separation > 0.0 ? 0.5 * separation * sqrt_ratio : 0.0;
    const double force = 2.0 * kPi * radius * ctx.param(b, c, kSurfaceTension) * ctx.param(b, c, kCosAngle) /
                         (1.0 + 2.1 * s_plus + 10.0 * s_plus * s_plus);
    b.fn[c] -= holds ? force : 0.0;
    formed[c] = static_cast<double>(holds | (!wet & was_formed));  // dry pairs keep their state
  }
}

double bridge_range(const double* row, const double* p, double radius_max) {
  if (p[kLiquidContent] <= 0.0) return 0.0;
  const double theta = p[kContactAngle] * kPi / 180.0;
  const double volume = bridge_volume(p[kLiquidContent], p[kBridgesPerParticle], radius_max, radius_max);
  return (1.0 + 0.5 * theta) * std::cbrt(volume);
}

constexpr FittedParam kFitted[] = {{"liquid_content", 0.01, 0.0, 0.05}};
constexpr StartValue kAlsoSet[] = {{"contact_angle_deg", 20.0}};
constexpr std::string_view kMoves[] = {"angle_of_repose_cylinder/angle_deg", "rotating_drum/dynamic_angle_deg",
                                       "bulk_density/bulk_density", "hopper_discharge/mass_flow_rate",
                                       "direct_shear/peak_shear_stress", "direct_shear/steady_shear_stress"};
constexpr CandidateSpec kCandidate{
    .title = "liquid bridges",
    .signature = "strength that does not come from the load (steeper heaps, looser packing, slower or blocked discharge, "
                 "a yield locus offset by a constant): cohesion from moisture, capillary bridges",
    .fitted = kFitted,
    .also_set = kAlsoSet,
    .moves = kMoves,
    .scale = nullptr,
};

}  // namespace

extern const EffectSpec liquid_bridge{
    .stage = Stage::extra,
    .name = "liquid_bridge",
    .summary = "capillary bridge force (Willett 2000 eq. 12), rupture at the Lian distance",
    .citation = "Willett et al. (2000) Langmuir 16:9396 eq. 12; Lian, Thornton & Adams (1993) J. Colloid Interface Sci. 161:138",
    .params = kParams,
    .options = {},
    .history = kHistory,
    .kernel = bridge_kernel,
    .range = bridge_range,
    .derived_count = 2,
    .derive = derive_angle_terms,
    .requires_normal = "",
    .candidate = &kCandidate,
};

}  // namespace dem::effects
