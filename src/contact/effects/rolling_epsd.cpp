// Rolling resistance, elastic-plastic spring-dashpot (Ai, Chen, Rotter & Ooi 2011, model C; as
// LIGGGHTS `rolling_friction epsd`):
//   M_k += -k_r w_r dt,  k_r = 2.25 kn mu_r^2 R*^2,  |M_k| <= M_m = mu_r R* Fn
//   M_d  = -eta_r 2 sqrt(I_r k_r) w_r   while |M_k| < M_m (switched off at full mobilisation)
// I_r is the reduced moment of inertia about the contact point (7/5 m R^2 for a sphere).
// The spring holds a heap at rest under a torque below M_m without the sign flips of model A.
#include <algorithm>
#include <cmath>

#include "contact/effects/effects.h"

namespace dem::effects {
namespace {

enum Param { kRollingFriction, kRollingDamping };

// Coarse graining (core/coarse_grain.h): both unchanged (exponent 0), dimensionless; k_r and the
// damping follow from the parcel's kn, R* and inertia.
constexpr ParamSpec kParams[] = {
    kRollingFrictionParam,
    {"rolling_damping", "-", 0.3, 0.0, 2.0, Mixing::arithmetic, false,
     "viscous damping ratio eta_r of the rolling spring (Ai et al. use 0.3)", 0},
};
constexpr HistorySpec kHistory[] = {{"rolling_spring_torque", 3, /*odd=*/true}};

DEM_KERNEL void epsd_kernel(const EffectContext& ctx, ContactBatch& b) {
  const double dt = ctx.dt;
  double* sx = ctx.hist(b, 0);  // [N m] spring torque, by component
  double* sy = ctx.hist(b, 1);
  double* sz = ctx.hist(b, 2);
  DEM_VECTOR_LOOP
  for (int c = 0; c < b.count; ++c) {
    const bool acting = b.overlap[c] > 0.0;  // else the spring is forgotten
    const double mu_r = ctx.param(b, c, kRollingFriction);
    const double nx = b.nx[c], ny = b.ny[c], nz = b.nz[c];
    const double w_n = b.wx[c] * nx + b.wy[c] * ny + b.wz[c] * nz;
    const double rx = b.wx[c] - w_n * nx, ry = b.wy[c] - w_n * ny, rz = b.wz[c] - w_n * nz;
    // Keep the spring torque in the contact plane at constant magnitude.
    double x = sx[c], y = sy[c], z = sz[c];
    keep_in_contact_plane(x, y, z, nx, ny, nz);
    const double r_eff = b.r_eff[c];
    const double k_roll = 2.25 * b.kn[c] * mu_r * mu_r * r_eff * r_eff;  // [N m/rad]
    x -= k_roll * rx * dt;
    y -= k_roll * ry * dt;
    z -= k_roll * rz * dt;
    const double limit = mu_r * r_eff * std::max(b.fn_elastic[c], 0.0);
    const double magnitude2 = x * x + y * y + z * z;
    const bool full = magnitude2 > limit * limit;  // fully mobilised: capped, no damping
    const double scale = cap_to_limit(magnitude2, limit);
    x *= scale, y *= scale, z *= scale;
    const double damping_on = ctx.param(b, c, kRollingDamping) * 2.0 * std::sqrt(b.inertia_eff[c] * k_roll);
    // A product, not a choice: GCC 12 did not vectorise the loop with `full | !acting ? 0 :
    // damping_on` (the main job's rolling friction ran scalar). damping_on is finite: the
    // normal stage's kn and the inertia are.
    const double damping = damping_on * static_cast<double>(!full & acting);
    x = acting ? x : 0.0, y = acting ? y : 0.0, z = acting ? z : 0.0;
    sx[c] = x, sy[c] = y, sz[c] = z;
    b.mx[c] += x - damping * rx;
    b.my[c] += y - damping * ry;
    b.mz[c] += z - damping * rz;
    b.energy_dissipated[c] += damping * (rx * rx + ry * ry + rz * rz) * dt;
  }
}

constexpr FittedParam kFitted[] = {{"rolling_friction", 0.15, 0.0, 0.5}};
constexpr std::string_view kMoves[] = {"angle_of_repose_cylinder/angle_deg", "rotating_drum/dynamic_angle_deg",
                                       "direct_shear/peak_shear_stress", "direct_shear/steady_shear_stress",
                                       "bulk_density/bulk_density"};
constexpr CandidateSpec kCandidate{
    .title = "rolling resistance",
    .signature = "heaps and drum beds stand steeper than spheres allow while single contacts fit: resistance to rolling, "
                 "standing in for particle shape and surface roughness",
    .fitted = kFitted,
    .also_set = {},
    .moves = kMoves,
    .scale = nullptr,
};

}  // namespace

extern const EffectSpec rolling_epsd{
    .stage = Stage::rolling,
    .name = "epsd",
    .summary = "elastic-plastic spring-dashpot rolling torque, capped at mu_r R* Fn (Ai et al. model C)",
    .citation = "Ai, Chen, Rotter & Ooi (2011) Powder Technol. 206:269, model C; LIGGGHTS rolling_friction epsd",
    .params = kParams,
    .options = {},
    .history = kHistory,
    .kernel = epsd_kernel,
    .range = nullptr,
    .derived_count = 0,
    .derive = nullptr,
    .requires_normal = "",
    .reads_spin = true,
    .candidate = &kCandidate,
};

}  // namespace dem::effects
