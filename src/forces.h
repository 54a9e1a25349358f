// Contact forces: geometry of each listed contact, the effects in stage order over batches of
// contacts, a per-particle sum in a fixed order plus gravity, and optionally the closing half
// kick of the step in the same pass.
#pragma once

#include "model.h"
#include "state.h"
#include "workspace.h"

namespace dem {

/// Fills state.fx.. and state.tx.. (and the bodies' totals) for the current positions and
/// velocities. With kick = h != 0 [s], free spheres and bodies then take the half kick
/// v += h F/m, w += h T/I (bodies: L += h T) in the same pass.
void compute_forces(const Model& model, State& state, Workspace& work, double kick = 0.0);

/// Runs the model's effects over a filled batch (outputs zeroed first). Exposed for kernel tests.
void evaluate_effects(const Model& model, ContactBatch& batch);

}  // namespace dem
