// Contact forces: geometry of each listed contact, the effects in stage order over batches of
// contacts, a per-particle sum in a fixed order plus gravity, and optionally the closing half
// kick of the step in the same pass.
#pragma once

#include "model.h"
#include "state.h"
#include "verlet.h"
#include "workspace.h"

namespace dem {

/// Fills state.fx.. and state.tx.. (and the bodies' totals) for the current positions and
/// velocities. With kick = h != 0 [s], free spheres and bodies then take the half kick
/// v += h F/m, w += h T/I (bodies: L += h T) in the same pass.
void compute_forces(const Model& model, State& state, Workspace& work, double kick = 0.0);

/// What a contact pass does besides the contacts (step.cpp).
struct ForcePass {
  double kick = 0.0;  ///< [s] closing half kick h (0: none), as compute_forces' `kick`
  /// [s] when not 0: the step's opening half kick (this h) and drift (Model::dt) come first, each
  /// thread's spheres right before their contacts, with no barrier between the two (a fused
  /// step: no bodies, glued spheres or ghosts, and the lists need no rebuild). Zeroes the owned
  /// slots' loads (Workspace::loads_cleared must be set).
  double drift_kick = 0.0;
  DriftLimits drift;     ///< what that drift tests (drift_limits before the pass)
  bool predict = false;  ///< with a kick: Workspace::next_moved, the flags of the next step's drift
};

/// compute_forces as `pass` says. Returns the Moved flags of its drift (0 without).
int compute_forces(const Model& model, State& state, Workspace& work, const ForcePass& pass);

/// Runs the model's effects over a filled batch (outputs zeroed first). Exposed for kernel tests.
void evaluate_effects(const Model& model, ContactBatch& batch);

}  // namespace dem
