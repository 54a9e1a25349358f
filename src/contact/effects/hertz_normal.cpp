// Hertz normal force between elastic spheres:
//   F = 4/3 E* sqrt(R*) delta^(3/2)            (Hertz 1882; Johnson, Contact Mechanics, eq. 4.22)
// and the linearisation that damping and friction use (Di Renzo & Di Maio 2004, as in LIGGGHTS
// `model hertz`): kn = 4/3 E* a, Sn = 2 E* a, kt = St = 8 G* a (Mindlin 1949), a = sqrt(R* delta).
#include <algorithm>
#include <cmath>

#include "contact/effects/effects.h"

namespace dem::effects {
namespace {

DEM_KERNEL void hertz_kernel(const EffectContext& ctx, ContactBatch& b) {
  const double tsuji_shape = std::sqrt(5.0 / 6.0);
  DEM_VECTOR_LOOP
  for (int c = 0; c < b.count; ++c) {
    const double overlap = std::max(b.overlap[c], 0.0);
    const double contact_radius = std::sqrt(b.r_eff[c] * overlap);  // [m]
    const double youngs = ctx.youngs_eff(b, c);
    const double shear = ctx.shear_eff(b, c);
    b.kn[c] = 4.0 / 3.0 * youngs * contact_radius;
    b.kt[c] = 8.0 * shear * contact_radius;
    b.damp_sn[c] = 2.0 * youngs * contact_radius;
    b.damp_st[c] = b.kt[c];
    b.damp_shape[c] = tsuji_shape;
    b.fn_elastic[c] = b.kn[c] * overlap;
    b.fn[c] = b.fn_elastic[c];
  }
}

double hertz_time(const double* row, const double*, double m_eff, double r_eff, double speed) {
  return hertz_contact_time(m_eff, r_eff, row[0], speed);
}

}  // namespace

extern const EffectSpec hertz_normal{
    .stage = Stage::normal,
    .name = "hertz",
    .summary = "Hertz elastic sphere contact, F = 4/3 E* sqrt(R*) delta^1.5, Mindlin tangential stiffness",
    .citation = "Hertz (1882); Johnson (1985) eq. 4.22; Mindlin (1949); Di Renzo & Di Maio (2004)",
    .params = {},
    .options = {},
    .history = {},
    .kernel = hertz_kernel,
    .range = nullptr,
    .derived_count = 0,
    .derive = nullptr,
    .requires_normal = "",
    .contact_time = hertz_time,
    .rayleigh_binds = true,
};

}  // namespace dem::effects

double dem::hertz_contact_time(double m_eff, double r_eff, double youngs_eff, double speed) {
  return 2.8683 * std::pow(m_eff * m_eff / (r_eff * youngs_eff * youngs_eff * speed), 0.2);
}
