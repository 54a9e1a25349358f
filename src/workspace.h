// What the engine can rebuild from Model and State at any time: cell grid, contact-list
// indexing, per-contact force buffers. Never part of a checkpoint.
#pragma once

#include <cstdint>
#include <vector>

namespace dem {

/// Forces of each listed contact from the last evaluation, written by the contact loop and
/// summed per particle in a fixed order (so results do not depend on the thread count).
/// Per contact: 9 doubles + 1 byte = 73 bytes.
struct ContactForces {
  std::vector<double> fx, fy, fz;     // [N] on body i
  std::vector<double> tix, tiy, tiz;  // [N m] on body i
  std::vector<double> tjx, tjy, tjz;  // [N m] on body j (particle pairs only)
  std::vector<std::uint8_t> active;   // 1 when the contact exerted a force this step
  void resize(std::size_t n);
};

struct Workspace {
  bool valid = false;  ///< false: the next step rebuilds the lists
  std::int64_t rebuilds = 0;

  // Contact-list indexing (n + 1 entries each): pairs owned by slot p are
  // [pair_begin[p], pair_begin[p+1]); pairs where p is j are incoming[incoming_begin[p] ...].
  std::vector<std::int32_t> pair_begin, incoming_begin, incoming, wall_begin;

  ContactForces pair_forces, wall_forces;

  // Spheres of each body: body_members[body_begin[b] ... body_begin[b+1]).
  std::vector<std::int32_t> body_begin, body_members;

  // Cell grid scratch.
  std::vector<std::int32_t> cell_of, cell_start, order;
};

}  // namespace dem
