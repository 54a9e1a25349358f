// Spatial domain decomposition over MPI ranks: one case split into a 3-D grid of boxes,
// `mpirun -np N demdesign CASE.yaml`. Which grid, where the cuts sit and when they move, which box
// owns a particle and which particles go to a neighbour as ghosts are the engine's
// (src/core/decomposition.h), and what a step asks of the ranks is src/core/domain.h; this is the
// transport between the ranks, kept out of the engine so that the engine builds and is tested
// without MPI.
//
// Exchanges per step: ghost positions and velocities (9 doubles a ghost), ghost loads back (6
// doubles a ghost), one message to or from each neighbour, one logical OR (rebuild?), one sum of
// the plane walls' loads. At a rebuild: one migration of particles with their contact histories
// (to the neighbours; all to all after the cuts moved or when a particle went beyond them), one
// exchange of ghost records, per cut axis one histogram sum for the balance. Meshes are held
// whole by every rank (their triangles are shared, read-only); wear records and loads are summed
// when results are written.
//
// Not decomposed: spheres glued to walls (a shear cell; such a case runs on rank 0 alone). Frames
// are written by every rank together (mpi_frames.h), rows of scalars are sums over the ranks and
// checkpoints are written by every rank (output/checkpoint.h); rank 0 gathers the whole state for
// rendered frames and at the end.
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
/// `balance` is what the cuts balance (src/core/decomposition.h): particles and their contacts,
/// reproducibly, or each rank's measured computing time.
enum class Balance { work, time };
std::unique_ptr<Domain> make_domain(const Model& model, const State& initial, std::string* note, const std::array<int, 3>& grid = {0, 0, 0},
                                    bool neighbour_migration = true, Balance balance = Balance::work);

}  // namespace dem::app::mpi
