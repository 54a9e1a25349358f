// Tangential spring with history, capped by Coulomb friction (Cundall & Strack 1979; stiffness
// from the normal law, 8 G* a for Hertz = Mindlin 1949 no-slip):
//   xi   += vt dt                      elastic tangential displacement, kept in the contact plane
//   Ft    = -kt xi - gamma_t vt
//   |Ft| <= mu * load                  load = repulsive normal force (elastic + damping)
// When the cap is reached the contact slides: Ft = mu load t (exactly Coulomb), and the spring is
// reset to carry that force alone, xi = -Ft/kt (as LIGGGHTS `tangential history`).
// Rejected alternative: Luding (2008) eq. 13, xi = -(Ft + gamma_t vt)/kt. While the stiffness
// grows with the overlap at the start of an impact, the stored damping share is amplified at the
// next step and can turn the friction force along the slip (seen in Chung & Ooi test 6).
// The spring is rotated with the contact plane at constant length, and forgotten when the bodies
// separate.
#include <cmath>

#include "effects/effects.h"

namespace dem::effects {
namespace {

enum Param { kFriction };

constexpr ParamSpec kParams[] = {
    {"friction", "-", 0.5, 0.0, 10.0, Mixing::arithmetic, true, "Coulomb sliding friction coefficient"},
};
constexpr HistorySpec kHistory[] = {{"tangential_spring", 3, /*odd=*/true}};

void mindlin_kernel(const EffectContext& ctx, ContactBatch& b) {
  const double dt = ctx.dt;
  for (int c = 0; c < b.count; ++c) {
    double* xi = ctx.hist(b, c);  // [m] (3)
    if (b.overlap[c] <= 0.0 || b.kt[c] <= 0.0) {
      xi[0] = xi[1] = xi[2] = 0.0;
      continue;
    }
    const double nx = b.nx[c], ny = b.ny[c], nz = b.nz[c];
    // Keep the spring in the current contact plane, at constant length.
    const double old_len2 = xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2];
    if (old_len2 > 0.0) {
      const double along_n = xi[0] * nx + xi[1] * ny + xi[2] * nz;
      xi[0] -= along_n * nx;
      xi[1] -= along_n * ny;
      xi[2] -= along_n * nz;
      const double new_len2 = xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2];
      if (new_len2 > 0.0) {
        const double scale = std::sqrt(old_len2 / new_len2);
        xi[0] *= scale;
        xi[1] *= scale;
        xi[2] *= scale;
      }
    }
    xi[0] += b.vtx[c] * dt;
    xi[1] += b.vty[c] * dt;
    xi[2] += b.vtz[c] * dt;

    const double kt = b.kt[c], gt = b.gamma_t[c];
    double fx = -kt * xi[0] - gt * b.vtx[c];
    double fy = -kt * xi[1] - gt * b.vty[c];
    double fz = -kt * xi[2] - gt * b.vtz[c];
    const double limit = ctx.param(b, c, kFriction) * b.load[c];
    const double magnitude2 = fx * fx + fy * fy + fz * fz;
    if (magnitude2 > limit * limit) {
      const double scale = magnitude2 > 0.0 ? limit / std::sqrt(magnitude2) : 0.0;
      fx *= scale;
      fy *= scale;
      fz *= scale;
      const double inv_kt = 1.0 / kt;
      xi[0] = -fx * inv_kt;
      xi[1] = -fy * inv_kt;
      xi[2] = -fz * inv_kt;
    }
    b.ftx[c] += fx;
    b.fty[c] += fy;
    b.ftz[c] += fz;
    b.energy_dissipated[c] -= (fx * b.vtx[c] + fy * b.vty[c] + fz * b.vtz[c]) * dt;
  }
}

}  // namespace

extern const EffectSpec mindlin_tangential{
    .stage = Stage::tangential,
    .name = "mindlin",
    .summary = "tangential spring-dashpot with history, Coulomb cap mu * Fn",
    .citation = "Cundall & Strack (1979); Mindlin (1949); spring reset as LIGGGHTS tangential history",
    .params = kParams,
    .options = {},
    .history = kHistory,
    .kernel = mindlin_kernel,
    .range = nullptr,
    .derived_count = 0,
    .derive = nullptr,
    .requires_normal = "",
};

}  // namespace dem::effects
