// Simplified JKR cohesion (LIGGGHTS `cohesion sjkr`): an attractive normal force proportional
// to the contact area while the bodies overlap,
//   F = -k_c A,   A = pi a^2,
// a the radius of the circle in which the two spheres intersect,
//   a^2 = (d^2 - (R_i - R_j)^2) ((R_i + R_j)^2 - d^2) / (4 d^2),  d = R_i + R_j - delta,
// and for a flat wall a^2 = 2 R delta - delta^2. k_c is a cohesion energy density [J/m^3].
#include <cmath>
#include <numbers>

#include "contact/effects/effects.h"

namespace dem::effects {
namespace {

constexpr ParamSpec kParams[] = {
    {"cohesion_energy_density", "J/m^3", 0.0, 0.0, 1e9, Mixing::geometric, true,
     "cohesion energy density k_c: attractive force per unit contact area"},
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
};

}  // namespace dem::effects
