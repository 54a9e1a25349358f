// The time step, read as a table of contents: kick, drift, refresh the contact lists when the
// skin is used up, contact and body forces, kick (velocity Verlet, second order, for
// translation and rotation of spheres). advance() runs many steps, most of them fused: the
// kick and drift inside the contact pass, each thread on its own spheres.
#pragma once

#include <cstdint>

#include "model.h"
#include "state.h"
#include "workspace.h"

namespace dem {

/// Builds the contact lists and the forces of the initial state; call once before stepping.
void prepare(const Model& model, State& state, Workspace& work);
/// Advances the state by model.dt.
void step(const Model& model, State& state, Workspace& work);
/// Advances the state by `steps` steps, bitwise as many calls of step() would. Nothing else may
/// change the state during the call, so the closing kick of each step can tell whether the next
/// one's drift will use up the skin: when it will not, the next step moves each thread's spheres
/// inside its contact pass, one parallel region and no barrier between the two (step.cpp).
/// Returns the particle steps done (the owned slots after each step, summed).
std::int64_t advance(const Model& model, State& state, Workspace& work, std::int64_t steps);

}  // namespace dem
