// Contact forces: geometry of each listed contact, the effects in stage order over batches of
// contacts, a per-particle sum in a fixed order plus gravity, and optionally the closing half
// kick of the step in the same pass.
#pragma once

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem {

/// Fills state.fx.. and state.tx.. (and the bodies' totals) for the current positions and
/// velocities. With kick = h != 0 [s], free spheres and bodies then take the half kick
/// v += h F/m, w += h T/I (bodies: L += h T) in the same pass.
void compute_forces(const Model& model, State& state, Workspace& work, double kick = 0.0);

/// What a contact pass does besides the contacts (step.cpp).
struct ForcePass {
  double kick = 0.0;  ///< [s] closing half kick h (0: none), as compute_forces' `kick`
  /// With a kick: each sphere's closing kick is followed by the next step's opening kick (the
  /// same h) and drift (Model::dt), in the same pass (drift ahead); Workspace::drifted_ahead
  /// gets their Moved flags. Only without bodies, glued spheres or ghosts, and only when the
  /// next step follows at once (advance(): no one else reads or changes the state in between).
  bool drift_ahead = false;
};

/// compute_forces as `pass` says.
void compute_forces(const Model& model, State& state, Workspace& work, const ForcePass& pass);

/// Runs the model's effects over a filled batch (outputs zeroed first). Exposed for kernel tests.
void evaluate_effects(const Model& model, ContactBatch& batch);

}  // namespace dem
