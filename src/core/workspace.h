// What the engine can rebuild from Model and State at any time: cell grid, contact-list
// indexing, per-contact force buffers. Never part of a checkpoint.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "base/allocator.h"
#include "core/state.h"

namespace dem {

class Domain;

/// Forces of each listed wall or mesh contact from the last evaluation (by contact index). The
/// force and torque on the particle were added to its totals as the contact was evaluated.
/// Per contact: 3 doubles + 1 byte.
struct ContactForces {
  std::vector<double> fx, fy, fz;     // [N] on the particle
  std::vector<std::uint8_t> active;   // 1 when the contact exerted a force this step
  void resize(std::size_t n);
};

/// Particle pairs, by pair k: whether the contact acted at the last evaluation and its force on
/// body i (body j received minus this). The forces are kept only where asked for
/// (Workspace::keep_pair_forces): 1 byte per listed pair, else 25.
struct PairForces {
  std::vector<std::uint8_t> active;  ///< 1 when the contact exerted a force this step
  std::vector<double> fx, fy, fz;    // [N] on body i
  /// Force on body i of pair k [N].
  double force(std::size_t k, int axis) const { return axis == 0 ? fx[k] : axis == 1 ? fy[k] : fz[k]; }
};

/// Per mesh contact (indexed as Workspace::mesh_forces), what the records of triangles and
/// meshes need from the evaluation.
struct MeshSlotResults {
  std::vector<double> fn;             // [N] normal force
  std::vector<double> shear_power;    // [W] |Ft . v_slip|
  std::vector<double> cx, cy, cz;     // [m] contact point, world
  std::vector<double> wall_power;     // [W] F . v_wall, F the force on the particle, v_wall the wall's velocity at the contact
  std::vector<double> impact_energy;  // [J] 1/2 m* vn^2 when the contact started this step, else -1
  /// A slot is written before it is read (slots beyond a particle's count never are), so the
  /// columns are not filled.
  void resize(std::size_t n) {
    for (auto* c : {&fn, &shear_power, &cx, &cy, &cz, &wall_power, &impact_energy}) resize_discarding(*c, n);
  }
};

/// Contact histories keyed by particle ids, seen from particle `a` (`b` is the other particle's
/// id, or the wall index for a plane-wall contact), `width` doubles each.
struct HistoryRows {
  std::vector<std::int64_t> a, b;
  std::vector<double> rows;
  std::size_t size() const { return a.size(); }
  void add(std::int64_t id_a, std::int64_t id_b, const double* row, int width) {
    a.push_back(id_a), b.push_back(id_b);
    rows.insert(rows.end(), row, row + width);
  }
  void append(const HistoryRows& more) {
    a.insert(a.end(), more.a.begin(), more.a.end());
    b.insert(b.end(), more.b.begin(), more.b.end());
    rows.insert(rows.end(), more.rows.begin(), more.rows.end());
  }
  /// Row q as doubles (a, b, history) at the end of `out`, for a message between ranks.
  void pack(std::size_t q, int width, std::vector<double>& out) const {
    out.push_back(static_cast<double>(a[q])), out.push_back(static_cast<double>(b[q]));
    out.insert(out.end(), rows.begin() + static_cast<std::ptrdiff_t>(q * width), rows.begin() + static_cast<std::ptrdiff_t>((q + 1) * width));
  }
  /// Appends `count` packed rows from `in`; returns the position after them.
  const double* unpack(const double* in, std::size_t count, int width) {
    for (std::size_t k = 0; k < count; ++k, in += 2 + width) add(static_cast<std::int64_t>(in[0]), static_cast<std::int64_t>(in[1]), in + 2, width);
    return in;
  }
};

struct Workspace {
  /// The ranks sharing this simulation (domain.h); null in a single process. Not owned.
  Domain* domain = nullptr;
  bool valid = false;  ///< false: the next step rebuilds the lists
  std::int64_t rebuilds = 0;

  // Contact-list indexing (n + 1 entries each): pairs owned by slot p are
  // [pair_begin[p], pair_begin[p+1]); wall contacts likewise.
  std::vector<std::int32_t> pair_begin, wall_begin;
  /// Owned slots with mesh candidates or mesh contacts when the lists were indexed, ascending:
  /// the others cannot touch a mesh before the next build (mesh_contacts.cpp).
  std::vector<std::int32_t> mesh_rows;
  /// [m] Where each plane wall's point was when the lists were built (State::walls), for the
  /// rebuild test of moving walls. Empty (a state restored from a checkpoint before its first
  /// rebuild): not tested.
  std::vector<std::array<double, 3>> plane_built;
  /// [m] Per mesh candidate (State::mesh_candidates): the distance from the sphere's centre to
  /// the triangle when the lists were built. A candidate whose distance then exceeds the sphere's
  /// reach by more than the sphere and the meshes have moved since cannot touch, and the contact
  /// pass skips it without reading the triangle. Empty (a state restored from a checkpoint
  /// before its first rebuild): every candidate is tested.
  std::vector<double> mesh_gap;
  /// Slots per block of the force evaluation: every pair (i, j) has j in i's block or the next
  /// (forces.cpp).
  std::int32_t block = 64;
  /// Per block (balance.h): its work (seconds of its passes per step, averaged; pairs listed
  /// until first measured), the time its passes took this step, the running sum of the work
  /// over the blocks, and the number of the last contact pass that summed its contacts.
  std::vector<double> block_work, block_time, block_prefix;
  std::vector<std::uint32_t> block_done;
  std::uint32_t pass_epoch = 0;
  std::uint32_t records_turn = 0;  ///< the thread whose turn it is to sum its mesh records (forces.cpp)
  bool block_timed = false;  ///< block_work holds measured seconds
  /// Owned slots with a ghost partner, ascending (domain.h; empty without ghosts).
  std::vector<std::int32_t> ghost_owners;
  /// Per thread of the ghost pass, the loads on the ghosts of each contact in pass order: slot j,
  /// force on j [N] (3), torque on j [N m] (3). Added to the ghosts after the pass (forces.cpp).
  std::vector<std::vector<double>> ghost_loads;
  /// Owned spheres with ghost partners from which the ghost pass runs on all threads.
  long ghost_pass_parallel_min = 256;

  /// The pairs of the list that can act before the spheres move another margin/2: those whose
  /// gap was under `margin` when the list was last scanned in full (plus every pair with a
  /// sphere of a body or a glued one, whose motion the drift does not check). Stored block by
  /// block (Workspace::block), one run per block from the pair list's start of the block's first
  /// slot, in list order, with their owners i and partners j. A contact pass reads a block's run
  /// in one loop (no loop per slot, whose end, after one to three pairs, the branch predictor
  /// misses), and forms the same batches in the same order as one over the whole list, for a
  /// fraction of the distance tests (forces.cpp).
  struct NearPairs {
    std::vector<std::int32_t> k, i, j;  ///< pair index, owner and partner
    /// End of each block's run of near pairs (a run starts where the block's pairs do).
    std::vector<std::int32_t> end;
    /// [m] positions at the last full scan less the build positions (State::x_built): single
    /// precision is plenty for an offset of at most 8 skins (verlet.cpp)
    std::vector<float> x, y, z;
    double margin = 0.0;             ///< [m] gap below which a pair is kept (0.05-0.5 Model::skin, adapted: forces.cpp)
    double time = 0.0;               ///< [s] time of the positions at the last full scan
    int age = 0;                     ///< contact passes over the near pairs since the last full scan
    bool valid = false;              ///< rows and positions are those of the current list
    bool trusted = false;            ///< set by step() unless a free sphere moved margin/2 since, with and without the common drift (verlet.h, Moved)
  } near;
  std::int64_t near_refreshes = 0;   ///< full scans of the pair list
  /// The Moved flags (verlet.h) of the next step's opening kick and drift when the closing kick of
  /// this one gave them already (ForcePass::drift_ahead); -1 when it did not.
  int drifted_ahead = -1;
  std::int64_t drifts_ahead = 0;  ///< steps whose opening kick and drift the step before gave
  /// Set by step() when the kick-drift pass zeroed the owned slots' forces and torques after
  /// using them and no rebuild moved or added slots since: compute_forces then clears only the
  /// ghosts' (one pass over 6 columns less per step). Cleared by compute_forces.
  bool loads_cleared = false;

  /// The histories a rebuild carries from the old lists to the new ones (rebuild_contacts). Kept
  /// between rebuilds: blocks of MiB, mapped anew at each rebuild, cost their page faults every
  /// time, a large part of a rebuild (bench/results/design_measurements.csv); the peak memory is
  /// the same.
  HistoryRows old_pairs, old_walls;
  PairForces pair_forces;
  /// Keep each pair's force (pair_forces.fx, fy, fz; for contact_stress): 24 bytes per listed
  /// pair, most of them idle pairs of the skin, and written every step; off unless asked for.
  bool keep_pair_forces = false;
  ContactForces wall_forces;

  // Meshes where they are at the time forces are evaluated: x_world = R x_local + T, and the
  // rigid velocity field. (n_meshes)
  double mesh_time = -1;  // [s]
  std::vector<std::array<double, 9>> mesh_rotation;  // row-major R
  std::vector<std::array<double, 3>> mesh_translation, mesh_linear, mesh_angular, mesh_origin;
  ContactForces mesh_forces;  ///< contact k of particle p at State::candidate_begin[p] + k (mesh_contacts.cpp)
  MeshSlotResults mesh_slots;

  // Spheres of each body: body_members[body_begin[b] ... body_begin[b+1]).
  std::vector<std::int32_t> body_begin, body_members;

  // Cell grid scratch; members: slots by cell (only with ghosts, which are not sorted).
  std::vector<std::int32_t> cell_of, cell_start, order, members;
  std::vector<std::uint8_t> keep;  ///< slots kept at a rebuild (0: left the domain or entered an outlet)
  /// Partners and mesh candidates found by each thread while the lists are built, and the
  /// buffers the particle sort gathers into (kept: a rebuild allocates nothing once grown).
  std::vector<std::vector<std::int32_t>> partner_scratch;
  std::vector<std::vector<std::array<std::int32_t, 2>>> candidate_scratch;
  PermuteScratch permute_scratch;
};

}  // namespace dem
