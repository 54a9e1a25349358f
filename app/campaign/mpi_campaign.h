// Campaigns over MPI ranks: the variants of a sweep and the simulations of a calibration or
// diagnosis shared among the ranks of `mpirun -np N demdesign ...`, each rank running whole
// simulations with its own OpenMP threads, the results gathered on rank 0.
//
// MPI is started only when an MPI launcher started this process (OpenMPI's mpirun sets
// OMPI_COMM_WORLD_SIZE, PMIx launchers PMIX_RANK, MPICH's hydra and Slurm PMI_SIZE); a plain
// `demdesign` run never touches MPI, and a build without MPI (-DDEMDESIGN_MPI=OFF) is always
// rank 0 of 1. One case without a sweep is split into slabs over the ranks instead
// (mpi_domain.h).
//
// Sweep variants are handed out one at a time by rank 0 (WorkQueue): a rank with a free slot
// asks, rank 0 answers between looking after its own variants, so a variant that fails at once
// or runs short frees its slot for the next. Rejected: a static share (rank r runs r, r+N, ...),
// which left one rank idle while the other ran two long variants in the test campaign; and an
// MPI window with an atomic counter, which needs the same polling of MPI on rank 0 for progress
// across nodes and is harder to follow. Calibration batches are shared statically and cyclically:
// every rank runs the calibration in lockstep, and a design round's simulations cost alike.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "calibration/calibration.h"

namespace dem::app::mpi {

/// This process's place in an MPI launch.
struct World {
  int rank = 0;
  int size = 1;
  int ranks_on_node = 1;  ///< ranks sharing this machine, and its cores
  bool active() const { return size > 1; }
};

/// MPI for the life of main(): MPI_Init_thread (funneled: OpenMP threads never call MPI) when an
/// MPI launcher started the process, nothing otherwise; MPI_Finalize when it goes out of scope.
class Session {
 public:
  Session(int* argc, char*** argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
};

/// The world of the running Session (rank 0 of 1 without one, without a launcher or without MPI).
const World& world();

/// Ends every rank of the job with `code` (MPI_Abort) after an error on this rank, which the
/// other ranks may not share and would wait for forever; nothing when not under MPI.
void abort(int code);

/// True when an MPI launcher's variables are in the environment.
bool launched_by_mpi();

/// True when this binary was built with MPI.
bool built_with_mpi();

/// Cores this rank may use: the cores OpenMP sees, shared with the other ranks on the machine
/// unless the launcher already bound each rank to its own cores.
int cores_per_rank();

/// Every rank's bytes on rank 0, indexed by rank (collective); other ranks get an empty list.
std::vector<std::string> gather(const std::string& mine);

/// Every rank's bytes on every rank, indexed by rank (collective).
std::vector<std::string> all_gather(const std::string& mine);

/// The environment for a child process: this one's without the MPI launcher's variables, so a
/// child demdesign (a sweep variant) runs as a plain process and never joins the MPI job.
std::vector<std::string> child_environment();

/// The items 0..count-1 of a campaign (sweep variants), handed out one at a time by rank 0 to
/// whichever rank asks (rank 0 serves itself first). Without MPI, a counter. Every rank keeps
/// asking until told there is nothing left, so no message is in flight afterwards.
class WorkQueue {
 public:
  static constexpr long kNone = -1;  ///< nothing left
  static constexpr long kWait = -2;  ///< asked rank 0; the answer is not here yet
  explicit WorkQueue(size_t count);
  ~WorkQueue();
  WorkQueue(const WorkQueue&) = delete;
  WorkQueue& operator=(const WorkQueue&) = delete;
  /// The next item for this rank, kNone or kWait; never blocks.
  long next();
  /// Rank 0: answers the requests that have arrived; true when it answered any.
  bool serve();
  /// Rank 0: true when every other rank has been told there is nothing left (other ranks: true).
  bool all_told() const;

 private:
  size_t count_, next_ = 0;
  int told_ = 0;
  bool asked_ = false;
  long answer_ = kNone;
  void* request_ = nullptr;  ///< the pending MPI_Request of the answer (MPI types stay out of this header)
};

/// Calibration batches shared among the ranks: rank r runs simulations r, r+N, ... (stopping
/// at its first fatal one), and every rank receives every outcome, because every rank runs the
/// calibration in lockstep and has to take the same decisions. Empty (serial) when not active.
materials::BatchRunner calibration_batch_runner();

/// Bytes of the messages: numbers as their bit patterns (results cross ranks bitwise), strings
/// with their length.
class ByteWriter {
 public:
  void u64(std::uint64_t v);
  void f64(double v);
  void str(const std::string& s);
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  explicit ByteReader(const std::string& bytes) : bytes_(bytes) {}
  std::uint64_t u64();
  double f64();
  std::string str();
  bool done() const { return at_ == bytes_.size(); }

 private:
  const std::string& bytes_;
  size_t at_ = 0;
};

/// The outcome of one calibration simulation as bytes, and back.
void write_outcome(ByteWriter& out, const materials::BatchOutcome& outcome);
materials::BatchOutcome read_outcome(ByteReader& in);

}  // namespace dem::app::mpi
