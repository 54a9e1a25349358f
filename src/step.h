// The time step, read as a table of contents: kick, drift, refresh the contact lists when the
// skin is used up, contact and body forces, kick (velocity Verlet, second order, for
// translation and rotation of spheres).
#pragma once

#include "model.h"
#include "state.h"
#include "workspace.h"

namespace dem {

/// Builds the contact lists and the forces of the initial state; call once before stepping.
void prepare(const Model& model, State& state, Workspace& work);
/// Advances the state by model.dt.
void step(const Model& model, State& state, Workspace& work);

}  // namespace dem
