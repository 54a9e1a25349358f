// What the engine can rebuild from Model and State at any time: cell grid, contact-list
// indexing, per-contact force buffers. Never part of a checkpoint.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace dem {

/// Forces of each listed wall or mesh contact from the last evaluation (by contact index). The
/// force and torque on the particle were added to its totals as the contact was evaluated.
/// Per contact: 3 doubles + 1 byte.
struct ContactForces {
  std::vector<double> fx, fy, fz;     // [N] on the particle
  std::vector<std::uint8_t> active;   // 1 when the contact exerted a force this step
  void resize(std::size_t n);
};

/// Particle pairs. The force and torque on body i were added to i's totals by the thread that
/// owns i, in list order; what body j receives is kept here in j's incoming order (slot q =
/// slot[k] of pair k; j's incoming pairs are contiguous and in pair order), so the per-particle
/// sum afterwards streams through them and does not depend on the thread count. A pair that is
/// not acting has zeros in its slot. Per pair: 6 doubles + 4 bytes + 1 byte = 53 bytes.
struct PairForces {
  std::vector<std::uint8_t> active;   ///< by pair k: 1 when the contact exerted a force this step
  std::vector<std::int32_t> slot;     ///< by pair k: its incoming slot q
  std::vector<double> fx, fy, fz;     // [N] by slot q: force on body i (body j receives minus this)
  std::vector<double> tjx, tjy, tjz;  // [N m] by slot q: torque on body j
  /// Force on body i of pair k [N].
  double force(std::size_t k, int axis) const {
    const std::size_t q = static_cast<std::size_t>(slot[k]);
    return axis == 0 ? fx[q] : axis == 1 ? fy[q] : fz[q];
  }
};

/// Per mesh-contact slot, what the records of triangles and meshes need from the evaluation.
struct MeshSlotResults {
  std::vector<double> fn;             // [N] normal force
  std::vector<double> shear_power;    // [W] |Ft . v_slip|
  std::vector<double> cx, cy, cz;     // [m] contact point, world
  std::vector<double> vx, vy, vz;     // [m/s] wall velocity at the contact
  std::vector<double> impact_energy;  // [J] 1/2 m* vn^2 when the contact started this step, else -1
  void resize(std::size_t n) {
    for (auto* c : {&fn, &shear_power, &cx, &cy, &cz, &vx, &vy, &vz}) c->assign(n, 0.0);
    impact_energy.assign(n, -1.0);
  }
};

struct Workspace {
  bool valid = false;  ///< false: the next step rebuilds the lists
  std::int64_t rebuilds = 0;

  // Contact-list indexing (n + 1 entries each): pairs owned by slot p are
  // [pair_begin[p], pair_begin[p+1]); the incoming slots of pairs where p is j are
  // [incoming_begin[p], incoming_begin[p+1]) (PairForces::slot).
  std::vector<std::int32_t> pair_begin, incoming_begin, wall_begin;

  PairForces pair_forces;
  ContactForces wall_forces;

  // Meshes where they are at the time forces are evaluated: x_world = R x_local + T, and the
  // rigid velocity field. (n_meshes)
  double mesh_time = -1;  // [s]
  std::vector<std::array<double, 9>> mesh_rotation;  // row-major R
  std::vector<std::array<double, 3>> mesh_translation, mesh_linear, mesh_angular, mesh_origin;
  ContactForces mesh_forces;  ///< per particle slot (n x MeshContacts::kSlots)
  MeshSlotResults mesh_slots;

  // Spheres of each body: body_members[body_begin[b] ... body_begin[b+1]).
  std::vector<std::int32_t> body_begin, body_members;

  // Cell grid scratch.
  std::vector<std::int32_t> cell_of, cell_start, order;
};

}  // namespace dem
