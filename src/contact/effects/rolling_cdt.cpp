// Rolling resistance, constant directional torque (Ai, Chen, Rotter & Ooi 2011, model A; the
// lever mu_r R* of the source paper's Fig. 4):
//   M_r = -mu_r R* Fn w_r / |w_r|,   w_r = (w_i - w_j) projected on the contact plane,
// Fn the elastic normal force (as LIGGGHTS `rolling_friction cdt`).
// Model A flips sign every step once the relative rolling has stopped (the oscillation at rest
// that Ai et al. criticise); the torque is therefore limited to the one that stops the relative
// rolling within this step, |M_r| <= I* |w_r| / dt, so a ball stops and stays.
#include <algorithm>
#include <cmath>

#include "contact/effects/effects.h"

namespace dem::effects {
namespace {

constexpr ParamSpec kParams[] = {kRollingFrictionParam};

DEM_KERNEL void cdt_kernel(const EffectContext& ctx, ContactBatch& b) {
  DEM_VECTOR_LOOP
  for (int c = 0; c < b.count; ++c) {
    const double nx = b.nx[c], ny = b.ny[c], nz = b.nz[c];
    const double w_n = b.wx[c] * nx + b.wy[c] * ny + b.wz[c] * nz;
    const double rx = b.wx[c] - w_n * nx, ry = b.wy[c] - w_n * ny, rz = b.wz[c] - w_n * nz;
    const double w_roll = std::sqrt(rx * rx + ry * ry + rz * rz);  // [rad/s]
    const bool acting = (b.overlap[c] > 0.0) & (w_roll > 0.0);
    const double limit = ctx.param(b, c, 0) * b.r_eff[c] * std::max(b.fn_elastic[c], 0.0);
    const double stopping = b.inertia_eff[c] * w_roll / ctx.dt;
    const double torque = acting ? std::min(limit, stopping) : 0.0;
    const double mx = torque * rx / w_roll, my = torque * ry / w_roll, mz = torque * rz / w_roll;  // (0/0 when not acting: not used)
    b.mx[c] -= acting ? mx : 0.0;
    b.my[c] -= acting ? my : 0.0;
    b.mz[c] -= acting ? mz : 0.0;
    b.energy_dissipated[c] += torque * w_roll * ctx.dt;
  }
}

}  // namespace

extern const EffectSpec rolling_cdt{
    .stage = Stage::rolling,
    .name = "cdt",
    .summary = "constant directional rolling torque mu_r R* Fn (Ai et al. model A)",
    .citation = "Ai, Chen, Rotter & Ooi (2011) Powder Technol. 206:269, model A; LIGGGHTS rolling_friction cdt",
    .params = kParams,
    .options = {},
    .history = {},
    .kernel = cdt_kernel,
    .range = nullptr,
    .derived_count = 0,
    .derive = nullptr,
    .requires_normal = "",
    .reads_spin = true,
};

}  // namespace dem::effects
