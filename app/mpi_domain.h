// Spatial domain decomposition over MPI ranks (the engine's side is src/core/domain.h): one case
// split into slabs along one axis, `mpirun -np N demdesign CASE.yaml`.
//
// Slabs: along the axis on which the particles spread furthest (a periodic axis counts with its
// period, the axis of gravity at half its extent: particles travel along it). The cuts between slabs sit at quantiles of the particle count (load balance by
// particle count), recomputed at a rebuild when the largest rank holds more than 10 % above the
// mean; every slab stays at least one ghost reach wide, so a rank's ghosts come from the next rank
// up only. The outer slabs of a non-periodic axis reach to infinity; along a periodic axis the top
// rank's upper neighbour is rank 0, whose particles it sees shifted by one period.
//
// Exchanges per step: ghost positions and velocities down (9 doubles a ghost), ghost loads back
// up (6 doubles a ghost), one logical OR (rebuild?), one sum of the plane walls' loads. At a
// rebuild: one all-to-all of migrating particles with their contact histories, one exchange of
// ghost records, one histogram sum for the balance. Meshes are held whole by every rank (their
// triangles are shared, read-only); wear records and loads are summed when results are written.
//
// Clumps belong to the rank of their centre and move with all their spheres; the ghost layer and
// the narrowest slab are deeper by how far a clump's spheres stick out. Not decomposed: spheres
// glued to walls (a shear cell; such a case runs on rank 0 alone). Rank 0 gathers the whole
// state for every row of scalars, frame and checkpoint.
#pragma once

#include <memory>

#include "core/domain.h"

namespace dem::app::mpi {

/// The domain over all ranks of the running MPI session for `model`, whose initial particles are
/// `initial` (the same on every rank); `note` tells how it was cut. Null without MPI, on one
/// rank, and when the case cannot be split (clumps, glued spheres, a slab axis too short for the
/// ranks): then `note` says why, and the case runs on rank 0 alone.
std::unique_ptr<Domain> make_domain(const Model& model, const State& initial, std::string* note);

}  // namespace dem::app::mpi
