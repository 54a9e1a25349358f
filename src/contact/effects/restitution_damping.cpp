// Viscous damping chosen so that a binary collision rebounds with the restitution coefficient e:
//   gamma = -2 s beta sqrt(S m*),  beta = ln e / sqrt(ln^2 e + pi^2)
// with S the damping stiffness of the normal law (kn for a linear spring, 2 E* a for Hertz) and
// shape s = 1 (linear, exact) or sqrt(5/6) (Hertz: Tsuji, Tanaka & Ishida 1992 form as written
// by Antypov & Elliott 2011; exact for tension allowed, see validation CO-3).
// The same beta damps the tangential spring (gamma_t from St).
//
// Option `end_of_contact`:
//   tension  (default) the damped force may pull at the end of contact; e is then exact;
//   clip     the normal force is clipped at zero (no tension); e comes out higher
//            (0.2 asks -> 0.325 obtained for Hertz), as LIGGGHTS `limitForce on`.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "contact/effects/effects.h"

namespace dem::effects {
namespace {

enum Param { kRestitution, kBeta /* derived */ };

// Coarse graining (core/coarse_grain.h): e is dimensionless, unchanged (exponent 0); the damping
// coefficient it gives, 2 beta sqrt(S m*), grows as F^2 from the parcel's stiffness and mass.
constexpr ParamSpec kParams[] = {
    {"restitution", "-", 0.5, 1e-4, 1.0, Mixing::arithmetic, true,
     "coefficient of normal restitution of a binary collision", 0, /*wall_candidate=*/true,
     /*plausible=*/std::pair{0.1, 0.95}},
};
constexpr std::string_view kEndOfContact[] = {"tension", "clip"};
constexpr OptionSpec kOptions[] = {
    {"end_of_contact", kEndOfContact,
     "tension: damped force may pull before separation (e exact); clip: force >= 0"},
};

void derive_beta(double* p) {
  const double log_e = std::log(p[kRestitution]);
  p[kBeta] = log_e / std::sqrt(log_e * log_e + std::numbers::pi * std::numbers::pi);
}

DEM_KERNEL void restitution_kernel(const EffectContext& ctx, ContactBatch& b) {
  const bool clip = ctx.options[0] == 1;
  DEM_VECTOR_LOOP
  for (int c = 0; c < b.count; ++c) {
    const double beta = ctx.param(b, c, kBeta);
    const double shape = -2.0 * b.damp_shape[c] * beta;
    b.gamma_n[c] = shape * std::sqrt(b.damp_sn[c] * b.m_eff[c]);
    b.gamma_t[c] = shape * std::sqrt(b.damp_st[c] * b.m_eff[c]);
    const double damping_force = -b.gamma_n[c] * b.vn[c];
    b.energy_dissipated[c] += b.gamma_n[c] * b.vn[c] * b.vn[c] * ctx.dt;
    b.fn[c] += damping_force;
    b.fn[c] = clip ? std::max(b.fn[c], 0.0) : b.fn[c];
  }
}

}  // namespace

extern const EffectSpec restitution_damping{
    .stage = Stage::damping,
    .name = "restitution",
    .summary = "viscous damping that yields the given restitution coefficient (Tsuji form for Hertz)",
    .citation = "Tsuji, Tanaka & Ishida (1992); Antypov & Elliott (2011); LIGGGHTS model hertz",
    .params = kParams,
    .options = kOptions,
    .history = {},
    .kernel = restitution_kernel,
    .range = nullptr,
    .derived_count = 1,
    .derive = derive_beta,
    .requires_normal = "",
};

}  // namespace dem::effects
