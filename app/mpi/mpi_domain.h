// Spatial domain decomposition over MPI ranks (the engine's side is src/core/domain.h): one case
// split into a 3-D grid of boxes, `mpirun -np N demdesign CASE.yaml`.
//
// The grid: of the factorisations nx x ny x nz of the rank count, the one whose boxes share the
// least face area with their neighbours, over the extent the particles and the domain box span
// (a periodic axis counts with its period, the axis of gravity at half its extent: particles
// travel along it), with every box at least one ghost reach wide along each axis it is cut across.
// The cuts along each axis sit at quantiles of the work (a particle weighs one plus its
// contacts; or, with Balance::time, each rank's measured computing time since the last rebuild,
// shared among its particles by that weight), recomputed at a rebuild when the most loaded rank
// carries more than 10 % above the mean and the ranks have, since the last rebalance, waited for
// the most loaded one 20 steps' worth of the mean rank's work (a flow that keeps moving, an inlet
// feeding one rank, would otherwise move the cuts at nearly every rebuild). Time-balanced cuts depend on the machine's timing, so
// such runs are not reproducible bit for bit; the default is reproducible. The outer boxes of a non-periodic axis reach to infinity; along a periodic axis the last
// box's upper neighbour is the first, seen one period on.
//
// Ghosts: of its up to 26 neighbours, a rank receives the particles of the 13 that lie above it
// (z first, then y, then x), within one reach of the faces, edges or corner they share, and lists
// the pairs with them; the forces on those ghosts go back to their owners. A pair across ranks is
// thus listed once. Exchanges per step: ghost positions and velocities (9 doubles a ghost), ghost
// loads back (6 doubles a ghost), one message to or from each neighbour, one logical OR
// (rebuild?), one sum of the plane walls' loads. At a rebuild: one all-to-all of migrating
// particles with their contact histories, one exchange of ghost records, per cut axis one
// histogram sum for the balance. Meshes are held whole by every rank (their triangles are shared,
// read-only); wear records and loads are summed when results are written.
//
// Clumps belong to the rank of their centre and move with all their spheres; the ghost layer and
// the narrowest box are deeper by how far a clump's spheres stick out. Not decomposed: spheres
// glued to walls (a shear cell; such a case runs on rank 0 alone). Frames are written by
// every rank together (mpi_frames.h), rows of scalars are sums over the ranks and checkpoints are
// written by every rank (output/checkpoint.h); rank 0 gathers the whole state for rendered
// frames and at the end.
#pragma once

#include <array>
#include <memory>

#include "core/domain.h"

namespace dem::app::mpi {

/// The domain over all ranks of the running MPI session for `model`, whose initial particles are
/// `initial` (the same on every rank); `note` tells how it was cut. Null without MPI, on one
/// rank, and when the case cannot be split (glued spheres, a domain too small for the ranks' boxes):
/// then `note` says why, and the case runs on rank 0 alone. `grid` (nx, ny, nz; zeros: chosen)
/// asks for a rank grid, whose boxes must have the ranks' count and one reach's width.
/// `neighbour_migration` false sends every migration all to all (for tests: the state is the same).
/// `balance` is what the cuts balance (the header above).
enum class Balance { work, time };
std::unique_ptr<Domain> make_domain(const Model& model, const State& initial, std::string* note, const std::array<int, 3>& grid = {0, 0, 0},
                                    bool neighbour_migration = true, Balance balance = Balance::work);

}  // namespace dem::app::mpi
