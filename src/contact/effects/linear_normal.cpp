// Linear spring normal force F = kn delta (Cundall & Strack 1979).
// With `normal_stiffness: 0` kn follows from the elastic moduli so that a collision at the
// characteristic velocity reaches the Hertz peak overlap, as LIGGGHTS `model hooke` does:
//   kn = 16/15 sqrt(R*) E* (15 m* V^2 / (16 sqrt(R*) E*))^(1/5).
// Tangential stiffness kt = ratio * kn; the default 2/7 makes the tangential and rotational
// oscillation periods of a solid sphere equal (Schaefer, Dippel & Wolf 1996).
#include <algorithm>
#include <cmath>
#include <numbers>

#include "contact/effects/effects.h"

namespace dem::effects {
namespace {

enum Param { kStiffness, kCharacteristicVelocity, kTangentialRatio };

// Coarse graining (core/coarse_grain.h), the last number of each row: a given stiffness x F, so
// that the same stress (force / d^2) gives the same overlap / d; a derived one (0 given) already
// grows as F from the parcel's R* and m* (sqrt(R*) (m*/sqrt(R*))^(1/5) ~ F^(1/2 + 3/5 - 1/10)), and
// 0 x F stays 0. Velocities are the real ones under the law, and a ratio is a ratio.
constexpr ParamSpec kParams[] = {
    {"normal_stiffness", "N/m", 0.0, 0.0, 1e12, Mixing::harmonic, true,
     "contact stiffness; 0 derives it from the Young's modulus and characteristic_velocity", 1},
    {"characteristic_velocity", "m/s", 1.0, 1e-6, 1e3, Mixing::maximum, false,
     "impact speed at which the derived linear stiffness reproduces the Hertz peak overlap", 0},
    {"tangential_stiffness_ratio", "-", 2.0 / 7.0, 0.0, 10.0, Mixing::arithmetic, false,
     "kt / kn", 0},
};

/// The stiffness [N/m]: given, or derived from the moduli at the characteristic velocity.
double stiffness_of(double given, double youngs, double v, double m_eff, double r_eff) {
  if (given > 0.0) return given;
  const double sqrt_r = std::sqrt(r_eff);
  return 16.0 / 15.0 * sqrt_r * youngs * std::pow(15.0 * m_eff * v * v / (16.0 * sqrt_r * youngs), 0.2);
}

void linear_kernel(const EffectContext& ctx, ContactBatch& b) {
  for (int c = 0; c < b.count; ++c) {
    const double stiffness = stiffness_of(ctx.param(b, c, kStiffness), ctx.youngs_eff(b, c), ctx.param(b, c, kCharacteristicVelocity),
                                          b.m_eff[c], b.r_eff[c]);
    const double overlap = std::max(b.overlap[c], 0.0);
    b.kn[c] = stiffness;
    b.kt[c] = stiffness * ctx.param(b, c, kTangentialRatio);
    b.damp_sn[c] = b.kn[c];
    b.damp_st[c] = b.kt[c];
    b.damp_shape[c] = 1.0;
    b.fn_elastic[c] = stiffness * overlap;
    b.fn[c] = b.fn_elastic[c];
  }
}

/// Half the undamped period of the spring the kernel uses.
double linear_time(const double* row, const double* params, double m_eff, double r_eff, double) {
  return std::numbers::pi * std::sqrt(m_eff / stiffness_of(params[kStiffness], row[0], params[kCharacteristicVelocity], m_eff, r_eff));
}

}  // namespace

extern const EffectSpec linear_normal{
    .stage = Stage::normal,
    .name = "linear",
    .summary = "linear spring F = kn delta, kt = ratio kn",
    .citation = "Cundall & Strack (1979); stiffness from LIGGGHTS model hooke; kt/kn = 2/7 Schaefer et al. (1996)",
    .params = kParams,
    .options = {},
    .history = {},
    .kernel = linear_kernel,
    .range = nullptr,
    .derived_count = 0,
    .derive = nullptr,
    .requires_normal = "",
    .contact_time = linear_time,
    .rayleigh_binds = false,
};

}  // namespace dem::effects
