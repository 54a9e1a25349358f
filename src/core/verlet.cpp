#include "core/verlet.h"

#include "base/parallel.h"
#include "core/neighbors.h"

namespace dem {

namespace {

/// Whether every sphere of slots [begin, end) is free (neither in a body nor glued to a wall):
/// then the loops below need not test each one, and vectorise over doubles alone (mixed with
/// the two int columns, GCC took 16 slots an iteration and ran out of registers).
[[gnu::always_inline]] inline bool all_free(const State& s, long begin, long end) {
  const std::int32_t *body = s.body.data(), *attached = s.attached.data();
  std::int32_t any = 0;
  for (long p = begin; p < end; ++p) any |= ~body[p] | ~attached[p];  // ~(-1) = 0; ~b != 0 for b >= 0
  return any == 0;
}

/// The Moved flags of a free sphere at (x, y, z) in slot p: kRebuild checked when kCheck,
/// kRescan when kNear (the caller sets the flags it does not check).
template <bool kCheck, bool kNear>
[[gnu::always_inline]] inline int moved(const DriftLimits& l, long p, bool free, double x, double y, double z) {
  int flags = 0;
  if constexpr (kCheck) flags |= (free & outside_skin(l, p, x, y, z)) * kRebuild;
  if constexpr (kNear) {
    const double ex = (x - l.x_built[p]) - l.x_near[p], ey = (y - l.y_built[p]) - l.y_near[p], ez = (z - l.z_built[p]) - l.z_near[p];
    const double fx = ex - l.scan_cx, fy = ey - l.scan_cy, fz = ez - l.scan_cz;
    flags |= (free & (ex * ex + ey * ey + ez * ez > l.near2)) * kRescan;
    flags |= (free & (fx * fx + fy * fy + fz * fz > l.near2)) * kRescanDrift;
  }
  return flags;
}

/// kAllFree: every sphere of the range is free (all_free), so none is tested or left in place.
template <bool kAllFree, bool kCheck, bool kNear>
[[gnu::always_inline]] inline int kick_drift_loop(State& s, const DriftLimits& limits, long begin, long end, double h, double dt) {
  const std::int32_t *body = s.body.data(), *attached = s.attached.data();
  const double *inv_mass = s.inv_mass.data(), *inv_inertia = s.inv_inertia.data();
  double *fx = s.fx.data(), *fy = s.fy.data(), *fz = s.fz.data();
  double *tx = s.tx.data(), *ty = s.ty.data(), *tz = s.tz.data();
  double *vx = s.vx.data(), *vy = s.vy.data(), *vz = s.vz.data();
  double *wx = s.wx.data(), *wy = s.wy.data(), *wz = s.wz.data();
  double *x = s.x.data(), *y = s.y.data(), *z = s.z.data();
  int flags = 0;
  DEM_VECTOR_LOOP
  for (long p = begin; p < end; ++p) {
    const bool free = kAllFree || ((body[p] < 0) & (attached[p] < 0));
    const double a = h * inv_mass[p], b = h * inv_inertia[p];
    const double nvx = vx[p] + a * fx[p], nvy = vy[p] + a * fy[p], nvz = vz[p] + a * fz[p];
    const double nx = x[p] + dt * nvx, ny = y[p] + dt * nvy, nz = z[p] + dt * nvz;
    flags |= moved<kCheck, kNear>(limits, p, free, nx, ny, nz);
    const double nwx = wx[p] + b * tx[p], nwy = wy[p] + b * ty[p], nwz = wz[p] + b * tz[p];
    wx[p] = free ? nwx : wx[p], wy[p] = free ? nwy : wy[p], wz[p] = free ? nwz : wz[p];
    vx[p] = free ? nvx : vx[p], vy[p] = free ? nvy : vy[p], vz[p] = free ? nvz : vz[p];
    x[p] = free ? nx : x[p], y[p] = free ? ny : y[p], z[p] = free ? nz : z[p];
    fx[p] = fy[p] = fz[p] = tx[p] = ty[p] = tz[p] = 0.0;  // used: the contact pass sums anew
  }
  return flags;
}

/// kAhead: then the next step's opening kick and drift (kick_drift_loop<kAllFree, kCheck, kNear>).
template <bool kAllFree, bool kAhead, bool kCheck, bool kNear>
[[gnu::always_inline]] inline int gravity_kick_loop(const double* gravity, State& s, const DriftLimits& limits, long begin, long end,
                                                    double h, double dt) {
  const double gx = gravity[0], gy = gravity[1], gz = gravity[2];
  const std::int32_t *body = s.body.data(), *attached = s.attached.data();
  const double *inv_mass = s.inv_mass.data(), *inv_inertia = s.inv_inertia.data();
  double *fx = s.fx.data(), *fy = s.fy.data(), *fz = s.fz.data();
  double *tx = s.tx.data(), *ty = s.ty.data(), *tz = s.tz.data();
  double *vx = s.vx.data(), *vy = s.vy.data(), *vz = s.vz.data();
  double *wx = s.wx.data(), *wy = s.wy.data(), *wz = s.wz.data();
  double *x = s.x.data(), *y = s.y.data(), *z = s.z.data();
  const bool kicks = h != 0.0;
  int flags = 0;
  DEM_VECTOR_LOOP
  for (long p = begin; p < end; ++p) {
    const bool free = kAllFree || ((body[p] < 0) & (attached[p] < 0));
    const double weight = 1.0 / inv_mass[p];
    const double mass = free ? weight : 0.0;
    const double nfx = fx[p] + mass * gx, nfy = fy[p] + mass * gy, nfz = fz[p] + mass * gz;
    const bool kicked = free & kicks;
    const double a = h * inv_mass[p], b = h * inv_inertia[p];
    const double nvx = vx[p] + a * nfx, nvy = vy[p] + a * nfy, nvz = vz[p] + a * nfz;
    const double nwx = wx[p] + b * tx[p], nwy = wy[p] + b * ty[p], nwz = wz[p] + b * tz[p];
    const double kvx = kicked ? nvx : vx[p], kvy = kicked ? nvy : vy[p], kvz = kicked ? nvz : vz[p];
    const double kwx = kicked ? nwx : wx[p], kwy = kicked ? nwy : wy[p], kwz = kicked ? nwz : wz[p];
    if constexpr (kAhead) {
      // The next step's opening kick and drift, as kick_drift_loop computes them.
      const double ovx = kvx + a * nfx, ovy = kvy + a * nfy, ovz = kvz + a * nfz;
      const double owx = kwx + b * tx[p], owy = kwy + b * ty[p], owz = kwz + b * tz[p];
      const double nx = x[p] + dt * ovx, ny = y[p] + dt * ovy, nz = z[p] + dt * ovz;
      flags |= moved<kCheck, kNear>(limits, p, free, nx, ny, nz);
      vx[p] = free ? ovx : kvx, vy[p] = free ? ovy : kvy, vz[p] = free ? ovz : kvz;
      wx[p] = free ? owx : kwx, wy[p] = free ? owy : kwy, wz[p] = free ? owz : kwz;
      x[p] = free ? nx : x[p], y[p] = free ? ny : y[p], z[p] = free ? nz : z[p];
      fx[p] = fy[p] = fz[p] = tx[p] = ty[p] = tz[p] = 0.0;  // used: the next contact pass sums anew
    } else {
      fx[p] = nfx, fy[p] = nfy, fz[p] = nfz;
      vx[p] = kvx, vy[p] = kvy, vz[p] = kvz;
      wx[p] = kwx, wy[p] = kwy, wz[p] = kwz;
    }
  }
  return flags;
}

}  // namespace

int untested(const DriftLimits& limits) { return (limits.x_built ? 0 : kRebuild) | (limits.x_near ? 0 : kRescan | kRescanDrift); }

DriftLimits drift_limits(const Model& model, const State& s, const Workspace& work, bool near_valid, double time) {
  DriftLimits limits;
  const size_t n = s.owned();
  if (s.x_built.size() != s.size()) return limits;
  limits.x_built = s.x_built.data(), limits.y_built = s.y_built.data(), limits.z_built = s.z_built.data();
  limits.skin2 = 0.25 * model.skin * model.skin;
  limits.wall2 = limits.skin2;
  if (lists_follow_drift(model, work)) {
    const double since = time - s.lists_built_time;  // [s]
    limits.cx = s.lists_drift_velocity[0] * since, limits.cy = s.lists_drift_velocity[1] * since, limits.cz = s.lists_drift_velocity[2] * since;
    // Spheres that leave the domain or enter an outlet are found at a rebuild: as promptly as
    // before, a skin of travel, as if these were walls. Without any, 8 skins, so that the scan
    // offsets below stay short enough for single precision.
    const bool bounds = !model.planes.empty() || !model.meshes.empty() || model.has_domain || !model.outlets.empty();
    limits.wall2 = (bounds ? 1.0 : 64.0) * model.skin * model.skin;
  }
  if (!near_valid || work.near.x.size() != n) return limits;
  limits.x_near = work.near.x.data(), limits.y_near = work.near.y.data(), limits.z_near = work.near.z.data();
  // The scan positions are kept as single-precision offsets from the build positions, at most
  // 8 skins long for a free sphere (else the list is rebuilt): their rounding, under 5e-7 of
  // the skin, is taken off the margin, so that the test stays on the safe side.
  const double half_margin = 0.5 * work.near.margin - 1e-6 * model.skin;
  limits.near2 = half_margin * half_margin;
  const double since_scan = time - work.near.time;  // [s] (the drift velocity is 0 where the lists do not follow it)
  limits.scan_cx = s.lists_drift_velocity[0] * since_scan, limits.scan_cy = s.lists_drift_velocity[1] * since_scan;
  limits.scan_cz = s.lists_drift_velocity[2] * since_scan;
  return limits;
}

namespace {

// The loop for the limits at hand. Called, not chosen through a pointer: the loops are inlined
// here and these into each clone of the kernels below; a pointer to a loop would be compiled
// once, for the baseline instruction set.
template <bool kAllFree>
[[gnu::always_inline]] inline int kick_drift_for(State& s, const DriftLimits& limits, long begin, long end, double h, double dt) {
  if (!limits.x_built) return kick_drift_loop<kAllFree, false, false>(s, limits, begin, end, h, dt);
  if (!limits.x_near) return kick_drift_loop<kAllFree, true, false>(s, limits, begin, end, h, dt);
  return kick_drift_loop<kAllFree, true, true>(s, limits, begin, end, h, dt);
}

template <bool kAllFree>
[[gnu::always_inline]] inline int gravity_kick_for(const double* gravity, State& s, long begin, long end, double h, const DriftLimits* ahead,
                                                   double dt) {
  if (!ahead || h == 0.0) return gravity_kick_loop<kAllFree, false, false, false>(gravity, s, DriftLimits{}, begin, end, h, dt);
  const int flags = untested(*ahead);
  if (!ahead->x_built) return flags | gravity_kick_loop<kAllFree, true, false, false>(gravity, s, *ahead, begin, end, h, dt);
  if (!ahead->x_near) return flags | gravity_kick_loop<kAllFree, true, true, false>(gravity, s, *ahead, begin, end, h, dt);
  return flags | gravity_kick_loop<kAllFree, true, true, true>(gravity, s, *ahead, begin, end, h, dt);
}

}  // namespace

DEM_KERNEL int kick_drift_range(State& s, const DriftLimits& limits, long begin, long end, double h, double dt) {
  const int flags = untested(limits);
  if (all_free(s, begin, end)) return flags | kick_drift_for<true>(s, limits, begin, end, h, dt);
  return flags | kick_drift_for<false>(s, limits, begin, end, h, dt);
}

DEM_KERNEL int gravity_kick_range(const double* gravity, State& s, long begin, long end, double h, const DriftLimits* ahead, double dt) {
  if (all_free(s, begin, end)) return gravity_kick_for<true>(gravity, s, begin, end, h, ahead, dt);
  return gravity_kick_for<false>(gravity, s, begin, end, h, ahead, dt);
}

}  // namespace dem
