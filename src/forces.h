// Contact forces: geometry of each listed contact, the effects in stage order over batches of
// contacts, then a per-particle sum in a fixed order plus gravity.
#pragma once

#include "model.h"
#include "state.h"
#include "workspace.h"

namespace dem {

/// Fills state.fx.. and state.tx.. for the current positions and velocities.
void compute_forces(const Model& model, State& state, Workspace& work);

/// Runs the model's effects over a filled batch (outputs zeroed first). Exposed for kernel tests.
void evaluate_effects(const Model& model, ContactBatch& batch);

}  // namespace dem
