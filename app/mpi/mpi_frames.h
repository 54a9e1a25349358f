// Frames of a split run written by every rank together into one HDF5 file (parallel HDF5, the
// MPI-IO driver, collective writes): each rank writes its own particles as one block of rows, in
// rank order, and no rank gathers the particles for a frame (output/results_hdf5.h, FrameShare).
// The file and the XDMF are those one process writes; only the order of the rows differs.
#pragma once

#include <cstddef>
#include <functional>

#include "output/results_hdf5.h"

namespace dem::app::mpi {

/// Where this rank's `owned` particles go in the next frame (collective: every rank of the
/// running MPI session calls it with its own count). Empty when this build cannot write frames
/// together (no MPI, or a serial HDF5): the run then gathers each frame on rank 0. The HDF5
/// property lists it holds are released when the last copy goes, before MPI ends.
std::function<FrameShare(std::size_t owned)> collective_frames();

}  // namespace dem::app::mpi
