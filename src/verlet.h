// The velocity Verlet's passes over the slots (step.cpp, forces.cpp): the opening half kick with
// the drift, and gravity with the closing half kick. Loops over the columns that the compiler
// vectorises (DEM_KERNEL); spheres of bodies and glued spheres keep their values (their body or
// wall moves them).
#pragma once

#include "model.h"
#include "state.h"
#include "workspace.h"

namespace dem {

/// What the drift found: a free sphere moved more than half the skin since the lists were built
/// (kRebuild), or more than half the near margin since the last full scan of the pair list
/// (kRescan).
enum Moved : int { kRebuild = 1, kRescan = 2 };

/// What the drift measures a free sphere's new position against. A flag whose positions are
/// missing (null) is always set.
struct DriftLimits {
  const double *x_built = nullptr, *y_built = nullptr, *z_built = nullptr;  ///< [m] at the last build (State)
  const float *x_near = nullptr, *y_near = nullptr, *z_near = nullptr;      ///< [m] at the last full scan, from x_built (Workspace::near)
  double skin2 = 0.0;  ///< [m^2] (skin/2)^2
  double near2 = 0.0;  ///< [m^2] (near margin/2)^2
};

/// The Moved flags a drift with these limits sets without testing.
int untested(const DriftLimits& limits);

/// The limits of the next drift over the n owned slots: the build positions when the lists are
/// those of the current slots, the scan positions when also the near pairs are (`near_valid`).
DriftLimits drift_limits(const Model& model, const State& s, const Workspace& work, bool near_valid);

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
