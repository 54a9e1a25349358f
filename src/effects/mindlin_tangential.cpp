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

DEM_KERNEL void mindlin_kernel(const EffectContext& ctx, ContactBatch& b) {
  const double dt = ctx.dt;
  double* sx = ctx.hist(b, 0);  // [m] spring xi, by component
  double* sy = ctx.hist(b, 1);
  double* sz = ctx.hist(b, 2);
  DEM_VECTOR_LOOP
  for (int c = 0; c < b.count; ++c) {
    const bool acting = (b.overlap[c] > 0.0) & (b.kt[c] > 0.0);  // else the spring is forgotten
    const double nx = b.nx[c], ny = b.ny[c], nz = b.nz[c];
    double x = sx[c], y = sy[c], z = sz[c];
    keep_in_contact_plane(x, y, z, nx, ny, nz);
    x += b.vtx[c] * dt;
    y += b.vty[c] * dt;
    z += b.vtz[c] * dt;

    const double kt = b.kt[c], gt = b.gamma_t[c];
    double fx = -kt * x - gt * b.vtx[c];
    double fy = -kt * y - gt * b.vty[c];
    double fz = -kt * z - gt * b.vtz[c];
    const double limit = ctx.param(b, c, kFriction) * b.load[c];
    const double magnitude2 = fx * fx + fy * fy + fz * fz;
    const bool slides = magnitude2 > limit * limit;
    const double scale = cap_to_limit(magnitude2, limit);
    fx *= scale, fy *= scale, fz *= scale;
    const double inv_kt = 1.0 / kt;
    x = slides ? -fx * inv_kt : x;
    y = slides ? -fy * inv_kt : y;
    z = slides ? -fz * inv_kt : z;
    sx[c] = acting ? x : 0.0, sy[c] = acting ? y : 0.0, sz[c] = acting ? z : 0.0;
    fx = acting ? fx : 0.0, fy = acting ? fy : 0.0, fz = acting ? fz : 0.0;
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
