// Particle contacts with mesh walls: candidate triangles from the BVH at each rebuild of the
// contact lists, then every step the closest features, resolved to one contact per physical
// contact (mesh.h), evaluated by the same effects as every other contact, and recorded per
// triangle (forces, friction work, impacts) and per mesh (force, torque, power).
#pragma once

#include "model.h"
#include "state.h"
#include "workspace.h"

namespace dem {

/// Pose and velocity of every mesh at time t (Workspace::mesh_pose...).
void place_meshes(const Model& model, double time, Workspace& work);
/// Candidate triangles within radius + reach of each particle (at the meshes' current pose).
void find_mesh_candidates(const Model& model, State& state, Workspace& work, double reach);
/// Largest displacement of any mesh since the lists were built (for the skin criterion) [m].
double mesh_displacement_since_build(const Model& model, const State& state, double time);
/// Resolves and evaluates the mesh contacts of every particle at the meshes' current pose;
/// forces and torques are added to the particles' totals (state.fx.., tx..) and kept per slot
/// in Workspace::mesh_forces; records and loads go to the state.
void mesh_contact_forces(const Model& model, State& state, Workspace& work);

}  // namespace dem
