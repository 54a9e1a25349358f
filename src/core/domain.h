// Spatial domain decomposition, the engine's side: what a step asks of the ranks that share one
// simulation. The engine knows no MPI; app/mpi/mpi_domain.* implements this over MPI, with the
// grid, cuts, owners and ghost sets of decomposition.h.
//
// Each rank owns the particles in its box of the domain (decomposition.h) and holds, after its
// own particles, ghost copies of the particles of its upper neighbours (the boxes across a face,
// edge or corner that lie above it, z first) that lie within one pair reach (interaction range +
// skin + the largest diameter) of the faces, edges or corner they share (State::ghosts). A pair
// across ranks is thus listed on exactly one rank, which evaluates it once and returns the force
// on the ghost to its owner (Newton's third law holds exactly, as in one process). Ghost-ghost
// pairs are not listed.
//
// The step with a domain (step.cpp, neighbors.cpp, forces.cpp):
//   kick + drift of owned particles
//   rebuild decided together (any rank's skin used up rebuilds every rank), and then, in
//   rebuild_contacts: ghosts dropped, lost particles removed, migrate() (owned particles that
//   left the box move to their new owner with every contact history they had), owned slots
//   sorted, make_ghosts(), lists built, histories carried by particle id;
//   otherwise refresh_ghosts() (positions and velocities of the ghosts from their owners)
//   contact forces, then return_ghost_loads(), sum_wall_loads(), gravity and the closing kick.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem {

/// The non-zero histories of a contact list keyed by particle ids (wall contacts: b is the wall).
HistoryRows histories_by_id(const ContactList& list, const State& state, int width, bool walls);
/// The same into `out`, whose blocks are reused.
void histories_by_id(const ContactList& list, const State& state, int width, bool walls, HistoryRows& out);

class Domain {
 public:
  virtual ~Domain() = default;
  /// True on every rank when `mine` is true on any (collective).
  virtual bool any(bool mine) = 0;
  /// Whether a point lies in this rank's box (new particles of an inlet are kept by the owner).
  virtual bool owns(double x, double y, double z) const = 0;
  /// Centres and radii (x, y, z, r) of every rank's owned particles inside the box [lo, hi], for
  /// an inlet's overlap checks (collective).
  virtual std::vector<std::array<double, 4>> particles_in(const State& state, const double lo[3], const double hi[3]) = 0;
  /// Sends owned particles that left this rank's box to their owners with their contact
  /// histories (taken from `pairs` and `walls`) and appends the particles and histories other
  /// ranks sent (collective). Ghosts have been dropped.
  virtual void migrate(const Model& model, State& state, HistoryRows& pairs, HistoryRows& walls) = 0;
  /// Appends the ghosts after the owned, sorted slots and sets state.ghosts (collective).
  virtual void make_ghosts(const Model& model, State& state) = 0;
  /// Positions and velocities of the ghosts from their owners (collective).
  virtual void refresh_ghosts(State& state) = 0;
  /// Adds the forces and torques the ghosts received to their owners' (collective).
  virtual void return_ghost_loads(State& state) = 0;
  /// Sums the plane walls' loads over the ranks (collective), so servo walls see the whole.
  virtual void sum_wall_loads(State& state) = 0;

  // The run's side (run.cpp).
  /// The model the ranks step: the case's, with the periodic axes the grid cuts no longer
  /// periodic (the ranks carry the period across their faces).
  virtual const Model& local_model() const = 0;
  /// Whether this rank writes the results (rank 0).
  virtual bool root() const = 0;
  /// This rank's number (the root's is 0) and how many ranks share the run (per-rank checkpoints).
  virtual int rank() const = 0;
  virtual int ranks() const = 0;
  /// Keeps this rank's share of a whole state (the same on every rank: the initial state or a
  /// checkpoint); its contact histories are kept for the first rebuild.
  virtual void distribute(State& state) = 0;
  /// The whole state on the root, as one process would hold it (lists rebuilt, histories
  /// carried, records and counters summed); an empty state elsewhere (collective).
  virtual State gather(const State& state) = 0;
  /// Sums per-rank counts (particle steps) over the ranks (collective).
  virtual double sum(double mine) = 0;
  /// Sums each element over the ranks, in place on every rank (collective): the parts of a row
  /// of scalars (statistics/diagnostics.h).
  virtual void sum(std::vector<double>& values) = 0;
  /// The largest of the ranks' values (collective).
  virtual double max(double mine) = 0;
  /// What the decomposition cost this rank so far (time in communication, bytes, migrations),
  /// one line for the run's log.
  virtual std::string statistics() const = 0;
};

/// Removes the ghost slots (they are rebuilt from their owners).
void drop_ghosts(State& state);

/// One rank's share of a whole state as numbers: its counters (lost particles, outlets), its
/// part of the mesh records, its owned bodies and particles and the histories of the contacts
/// it lists, keyed by particle id. What gather() sends to the root and a per-rank checkpoint holds.
std::vector<double> pack_share(const State& state, int history_width);
/// The whole state from every rank's share: `like` gives what the ranks hold alike (time, step,
/// walls, inlets, meshes); its particles, lists and counters are replaced by the shares'
/// (counters and records summed, particles appended in share order, lists by slot).
State merge_shares(const State& like, const std::vector<std::vector<double>>& shares, int history_width);
/// `like` without its particles, bodies, lists and run totals: what merge_shares keeps of it.
State shared_part(const State& like);

/// A whole state gathered on the root, made ready for results: `state` with its lists rebuilt
/// and histories carried (frames, checkpoints), `evaluated` a copy with this instant's contact
/// forces (scalars, wall loads), `work` the lists of both.
struct WholeState {
  State state, evaluated;
  Workspace work;
};
WholeState ready_for_results(const Model& model, State gathered);

}  // namespace dem
