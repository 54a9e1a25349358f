// Collective frame files over MPI-IO; see mpi_frames.h.
#include "mpi/mpi_frames.h"

#include <hdf5.h>

#include <memory>
#include <stdexcept>

#if defined(DEMDESIGN_WITH_MPI) && defined(H5_HAVE_PARALLEL)
#include <mpi.h>
#endif

namespace dem::app::mpi {

#if defined(DEMDESIGN_WITH_MPI) && defined(H5_HAVE_PARALLEL)
namespace {

// The two property lists every frame of the run shares: files opened through MPI-IO on
// MPI_COMM_WORLD, datasets written collectively (one aggregated write, not a write per rank).
class FrameLists {
 public:
  FrameLists() {
    access_ = H5Pcreate(H5P_FILE_ACCESS);
    transfer_ = H5Pcreate(H5P_DATASET_XFER);
    if (access_ < 0 || transfer_ < 0 || H5Pset_fapl_mpio(access_, MPI_COMM_WORLD, MPI_INFO_NULL) < 0 ||
        H5Pset_dxpl_mpio(transfer_, H5FD_MPIO_COLLECTIVE) < 0) {
      release();
      throw std::runtime_error("parallel HDF5: cannot set up the MPI-IO file access for collective frames");
    }
  }
  ~FrameLists() { release(); }
  FrameLists(const FrameLists&) = delete;
  FrameLists& operator=(const FrameLists&) = delete;
  hid_t access() const { return access_; }
  hid_t transfer() const { return transfer_; }

 private:
  void release() {
    if (access_ >= 0) H5Pclose(access_);
    if (transfer_ >= 0) H5Pclose(transfer_);
    access_ = transfer_ = -1;
  }
  hid_t access_ = -1, transfer_ = -1;
};

}  // namespace

std::function<FrameShare(std::size_t)> collective_frames() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) return {};
  auto lists = std::make_shared<FrameLists>();
  return [lists](std::size_t owned) {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    unsigned long long mine = owned, before = 0, total = 0;
    MPI_Exscan(&mine, &before, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
    MPI_Allreduce(&mine, &total, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
    FrameShare share;
    share.offset = rank == 0 ? 0 : before;  // MPI_Exscan leaves rank 0's result undefined
    share.total = total;
    share.root = rank == 0;
    share.file_access = lists->access();
    share.transfer = lists->transfer();
    share.all = [](bool ok) {
      int mine_ok = ok ? 1 : 0, every = 0;
      MPI_Allreduce(&mine_ok, &every, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
      return every != 0;
    };
    return share;
  };
}

#else

std::function<FrameShare(std::size_t)> collective_frames() { return {}; }

#endif

}  // namespace dem::app::mpi
