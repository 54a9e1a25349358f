// What the engine can rebuild from Model and State at any time: cell grid, contact-list
// indexing, per-contact force buffers. Never part of a checkpoint.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace dem {

/// Forces of each listed contact from the last evaluation. The force and torque on body i are
/// added to i's totals as the contact is evaluated (by the thread that owns i); what body j
/// receives is kept here and summed per particle afterwards, in list order, so results do not
/// depend on the thread count. Per contact: 6 doubles + 1 byte = 49 bytes (3 + 1 = 25 without
/// reaction torques: wall and mesh contacts).
struct ContactForces {
  std::vector<double> fx, fy, fz;     // [N] on body i
  std::vector<double> tjx, tjy, tjz;  // [N m] on body j (particle pairs only, else empty)
  std::vector<std::uint8_t> active;   // 1 when the contact exerted a force this step
  void resize(std::size_t n, bool reaction_torques);
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
  // [pair_begin[p], pair_begin[p+1]); pairs where p is j are incoming[incoming_begin[p] ...].
  std::vector<std::int32_t> pair_begin, incoming_begin, incoming, wall_begin;

  ContactForces pair_forces, wall_forces;

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
