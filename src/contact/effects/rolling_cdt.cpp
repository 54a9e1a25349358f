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

// A candidate beside epsd: the same lever, without the spring. A single contact tells them apart
// (an oblique rebound spins up against a constant torque, not against a spring that stores and
// returns it), so data made with one law may misfit under the other at every mu_r.
constexpr FittedParam kFitted[] = {{"rolling_friction", 0.15, 0.0, 0.5}};
constexpr std::string_view kMoves[] = {"angle_of_repose_cylinder/angle_deg", "rotating_drum/dynamic_angle_deg",
                                       "direct_shear/peak_shear_stress", "direct_shear/steady_shear_stress",
                                       "bulk_density/bulk_density", "drop_rebound/tangential_restitution"};
constexpr CandidateSpec kCandidate{
    .title = "rolling resistance as a constant torque",
    .signature = "heaps and drum beds stand steeper than spheres allow, and an oblique rebound leaves with less spin than "
                 "a rolling spring would return: resistance to rolling without elastic recovery (LIGGGHTS `rolling_friction cdt`)",
    .fitted = kFitted,
    .also_set = {},
    .moves = kMoves,
    .scale = nullptr,
};

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
    .candidate = &kCandidate,
};

}  // namespace dem::effects
