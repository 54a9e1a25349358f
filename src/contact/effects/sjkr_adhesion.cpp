// Simplified JKR cohesion (LIGGGHTS `cohesion sjkr`): an attractive normal force proportional
// to the contact area while the bodies overlap,
//   F = -k_c A,   A = pi a^2,
// a the radius of the circle in which the two spheres intersect,
//   a^2 = (d^2 - (R_i - R_j)^2) ((R_i + R_j)^2 - d^2) / (4 d^2),  d = R_i + R_j - delta,
// and for a flat wall a^2 = 2 R delta - delta^2. k_c is a cohesion energy density [J/m^3].
#include <algorithm>
#include <cmath>
#include <numbers>

#include "contact/effects/effects.h"

namespace dem::effects {
namespace {

// Coarse graining (core/coarse_grain.h): k_c unchanged (exponent 0). It is already a stress (force
// per contact area), and the parcels' contact area at the same delta / d is F^2 the real one.
constexpr ParamSpec kParams[] = {
    {"cohesion_energy_density", "J/m^3", 0.0, 0.0, 1e9, Mixing::geometric, true,
     "cohesion energy density k_c: attractive force per unit contact area", 0},
};

DEM_KERNEL void sjkr_kernel(const EffectContext& ctx, ContactBatch& b) {
  DEM_VECTOR_LOOP
  for (int c = 0; c < b.count; ++c) {
    const double overlap = b.overlap[c];
    const double ri = b.radius_i[c], rj = b.radius_j[c];
    const double d = ri + rj - overlap;
    const double a2_wall = 2.0 * ri * overlap - overlap * overlap;
    const double a2_pair = (d * d - (ri - rj) * (ri - rj)) * ((ri + rj) * (ri + rj) - d * d) / (4.0 * d * d);
    const double a2 = rj == 0.0 ? a2_wall : a2_pair;
    const double pull = ctx.param(b, c, 0) * std::numbers::pi * std::max(a2, 0.0);
    b.fn[c] -= overlap > 0.0 ? pull : 0.0;
  }
}

/// Cohesion energy density [J/m^3] that pulls two particles of the typical size together with
/// one particle weight W = rho g pi d^3/6 at the contact that one weight presses (Hertz:
/// delta = (3 W / (4 E* sqrt(R*)))^(2/3), E* = E / (2 (1 - nu^2)), R* = d/4; the area of the
/// spheres' intersection circle is pi a^2 with a^2 = 2 R* delta): k_c = W / (2 pi R* delta). The
/// fit starts at 3 and searches up to 30 such units, as jkr's surface energy does.
double one_weight_area_bond(const ParticleScale& s) {
  const double weight = s.density * 9.81 * std::numbers::pi * s.diameter * s.diameter * s.diameter / 6.0;
  const double r_eff = 0.25 * s.diameter, youngs = s.youngs_modulus / (2.0 * (1.0 - s.poisson_ratio * s.poisson_ratio));
  const double overlap = std::pow(3.0 * weight / (4.0 * youngs * std::sqrt(r_eff)), 2.0 / 3.0);
  return weight / (2.0 * std::numbers::pi * r_eff * overlap);
}

constexpr FittedParam kFitted[] = {{"cohesion_energy_density", 3.0, 0.0, 30.0}};
constexpr std::string_view kMoves[] = {"angle_of_repose_cylinder/angle_deg", "rotating_drum/dynamic_angle_deg",
                                       "bulk_density/bulk_density", "hopper_discharge/mass_flow_rate",
                                       "direct_shear/peak_shear_stress", "direct_shear/steady_shear_stress"};
constexpr CandidateSpec kCandidate{
    .title = "cohesion growing with the contact area (simplified JKR)",
    .signature = "strength beyond friction that grows with the load, while single rebounds fit: an attraction over the "
                 "contact area, as LIGGGHTS `cohesion sjkr` models fine or moist particles",
    .fitted = kFitted,
    .also_set = {},
    .moves = kMoves,
    .scale = one_weight_area_bond,
};

}  // namespace

extern const EffectSpec sjkr_adhesion{
    .stage = Stage::adhesion,
    .name = "sjkr",
    .summary = "simplified JKR: attractive force = cohesion energy density x contact area",
    .citation = "LIGGGHTS cohesion sjkr (Gilabert et al. 2007 style area law)",
    .params = kParams,
    .options = {},
    .history = {},
    .kernel = sjkr_kernel,
    .range = nullptr,
    .derived_count = 0,
    .derive = nullptr,
    .requires_normal = "",
    .candidate = &kCandidate,
};

}  // namespace dem::effects
