// The time step, read as a table of contents: kick, drift, refresh the contact lists when the
// skin is used up, contact and body forces, kick (velocity Verlet, second order, for
// translation and rotation of spheres). advance() runs many steps, each closing kick followed
// at once by the next step's opening kick and drift.
#pragma once

#include <cstdint>

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem {

/// Builds the contact lists and the forces of the initial state; call once before stepping.
void prepare(const Model& model, State& state, Workspace& work);
/// Advances the state by model.dt.
void step(const Model& model, State& state, Workspace& work);
/// Advances the state by `steps` steps, bitwise as many calls of step() would. Between its steps
/// no one reads or changes the state, so each step's closing kick also gives the next one's
/// opening kick and drift, in the same pass over the spheres (step.cpp). Returns the particle
/// steps done (the owned slots after each step, summed).
std::int64_t advance(const Model& model, State& state, Workspace& work, std::int64_t steps);

}  // namespace dem
