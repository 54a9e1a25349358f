// The stress tensor of a granular sample from its contact forces, the source paper's Eq. 5:
//   sigma_ij = 1/(2V) sum_c (d_i F_j + d_j F_i)
// with d the branch vector from the second body to the first (minimum image across periodic
// boundaries; for a wall contact, from the contact point to the sphere centre) and F the
// contact force on the first body. Compression is positive. Christoffersen, Mehrabadi &
// Nemat-Nasser (1981); Love-Weber formula.
#pragma once

#include <Eigen/Core>

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem {

/// Contact stress [Pa] of all contacts (particle pairs and, if `with_walls`, wall contacts),
/// over the sample volume `volume` [m^3]. Uses the forces of the last evaluation, which keeps
/// them only when Workspace::keep_pair_forces was set before it (else std::logic_error).
Eigen::Matrix3d contact_stress(const Model& model, const State& state, const Workspace& work, double volume,
                               bool with_walls = true);

}  // namespace dem
