// Particle contacts with mesh walls: candidate triangles from the BVH at each rebuild of the
// contact lists, then every step the closest features, resolved to one contact per physical
// contact (mesh.h), evaluated by the same effects as every other contact, and recorded per
// triangle (forces, friction work, impacts) and per mesh (force, torque, power).
#pragma once

#include <memory>

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem {

/// Pose and velocity of every mesh at time t (Workspace::mesh_pose...).
void place_meshes(const Model& model, double time, Workspace& work);
/// Candidate triangles within radius + reach of each particle (at the meshes' current pose).
void find_mesh_candidates(const Model& model, State& state, Workspace& work, double reach);
/// Largest displacement of any mesh since the lists were built (for the skin criterion) [m].
double mesh_displacement_since_build(const Model& model, const State& state, double time);
/// Sizes the per-contact results for the candidates of the last rebuild and sets the meshes'
/// loads to zero (before any pass).
void prepare_mesh_contacts(const Model& model, State& state, Workspace& work);

/// One thread's evaluation of mesh contacts, a range of slots at a time. Each slot's contacts
/// are resolved and evaluated, their forces and torques added to its totals (which are complete
/// when run returns), and kept by contact in Workspace::mesh_forces and mesh_slots. Any thread
/// may take any slots, each slot once per step; the records are summed afterwards, range after
/// range in slot order (sum_mesh_records).
class MeshContactPass {
 public:
  MeshContactPass(const Model& model, State& state, Workspace& work);
  ~MeshContactPass();
  MeshContactPass(const MeshContactPass&) = delete;
  MeshContactPass& operator=(const MeshContactPass&) = delete;
  void run(long begin, long end);  ///< slots [begin, end)

 private:
  struct Scratch;
  const Model& model_;
  State& s_;
  Workspace& work_;
  std::unique_ptr<Scratch> scratch_;
};

/// Records per triangle and loads per mesh from the mesh contacts of slots [begin, end) this
/// step, added in slot order (to the loads prepare_mesh_contacts set to zero). Calls for
/// consecutive ranges from 0 to the owned slots give the sums of one call over them all, bitwise.
void sum_mesh_records(const Model& model, State& state, Workspace& work, long begin, long end);

/// Resolves and evaluates the mesh contacts of every particle at the meshes' current pose;
/// forces and torques are added to the particles' totals (state.fx.., tx..) and kept per slot
/// in Workspace::mesh_forces; records and loads go to the state.
void mesh_contact_forces(const Model& model, State& state, Workspace& work);

}  // namespace dem
