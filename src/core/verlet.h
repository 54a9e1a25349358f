// The velocity Verlet's passes over the slots (step.cpp, forces.cpp): the opening half kick with
// the drift, and gravity with the closing half kick. Loops over the columns that the compiler
// vectorises (DEM_KERNEL); spheres of bodies and glued spheres keep their values (their body or
// wall moves them).
#pragma once

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem {

/// What the drift found: a free sphere used up its share of the skin since the lists were built
/// (kRebuild, DriftLimits), or moved more than half the near margin since the last full scan of
/// the pair list (kRescan), or more than half the margin from where the lists' common drift
/// carried it since that scan (kRescanDrift). The near pairs hold every pair that can touch
/// unless both kRescan and kRescanDrift are set: a pair's gap shrinks by at most |e_i - c| +
/// |e_j - c| for any one vector c (e: displacement since the scan), c = 0 or the drift.
enum Moved : int { kRebuild = 1, kRescan = 2, kRescanDrift = 4 };

/// What the drift measures a free sphere's new position against. A flag whose positions are
/// missing (null) is always set.
///
/// The lists hold every pair whose gap was under the skin at the build, and every wall within a
/// skin of a sphere. A pair's gap has since shrunk by at most |d_i - d_j| (d: displacement since
/// the build), which is at most |d_i - c| + |d_j - c| for any vector c: so the pairs stay
/// complete while every sphere is within skin/2 of its build position carried along by c, the
/// common drift (c = 0 gives the usual test, |d| <= skin/2). A wall's gap shrinks by at most
/// |d_i| plus the wall's own motion: a sphere may move a whole skin from static walls, half of
/// it where walls move (these take the other half). Where the lists follow the drift
/// (neighbors.h, lists_follow_drift), c moves at the middle of the spheres' velocities at the
/// build, and a stream in a chute is rebuilt much less often
/// (bench/results/design_measurements.csv).
struct DriftLimits {
  const double *x_built = nullptr, *y_built = nullptr, *z_built = nullptr;  ///< [m] at the last build (State)
  const float *x_near = nullptr, *y_near = nullptr, *z_near = nullptr;      ///< [m] at the last full scan, from x_built (Workspace::near)
  double skin2 = 0.0;             ///< [m^2] (skin/2)^2: how far from the build position carried along by c
  double cx = 0, cy = 0, cz = 0;  ///< [m] c, the common drift since the build
  double wall2 = 0.0;             ///< [m^2] how far from the build position itself: skin^2 with static walls, a domain or outlets ((8 skin)^2 without any), else (skin/2)^2
  double near2 = 0.0;             ///< [m^2] (near margin/2)^2
  double scan_cx = 0, scan_cy = 0, scan_cz = 0;  ///< [m] the common drift since the last full scan (0 where the lists do not follow it)
};

/// Whether the sphere in slot p, at (x, y, z), has left what the lists cover for it.
[[gnu::always_inline]] inline bool outside_skin(const DriftLimits& l, long p, double x, double y, double z) {
  const double dx = x - l.x_built[p], dy = y - l.y_built[p], dz = z - l.z_built[p];
  const double ex = dx - l.cx, ey = dy - l.cy, ez = dz - l.cz;
  return (ex * ex + ey * ey + ez * ez > l.skin2) | (dx * dx + dy * dy + dz * dz > l.wall2);
}

/// The Moved flags a drift with these limits sets without testing.
int untested(const DriftLimits& limits);

/// The limits of a drift over the n owned slots that brings the spheres to `time` [s]: the
/// build positions when the lists are those of the current slots, the scan positions when also
/// the near pairs are (`near_valid`).
DriftLimits drift_limits(const Model& model, const State& s, const Workspace& work, bool near_valid, double time);

/// Slots [begin, end): v += h F/m, w += h T/I, x += dt v for free spheres, and F and T set to
/// zero once used (the contact pass sums anew: Workspace::loads_cleared). Returns the Moved
/// flags of those spheres.
int kick_drift_range(State& s, const DriftLimits& limits, long begin, long end, double h, double dt);

/// Slots [begin, end): gravity added to the free spheres' forces, then the closing half kick
/// v += h F/m, w += h T/I (none when h = 0). With `ahead` (and h != 0), then also the next step's
/// opening half kick and drift (drift ahead), by the same operations as kick_drift_range, so
/// bitwise what it would give, F and T set to zero, and returns their Moved flags; else 0.
int gravity_kick_range(const double* gravity, State& s, long begin, long end, double h, const DriftLimits* ahead, double dt);

}  // namespace dem
