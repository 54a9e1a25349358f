// Campaigns over MPI ranks (rules in mpi_campaign.h).
#include "campaign/mpi_campaign.h"

#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <stdexcept>
#include <thread>

#ifdef DEMDESIGN_WITH_MPI
#include <mpi.h>
#endif

extern char** environ;

namespace dem::app::mpi {

namespace {

World the_world;
bool initialised = false;

/// Variables an MPI launcher puts into the environment of the processes it starts.
constexpr const char* kLauncherPrefixes[] = {"OMPI_", "PMIX_", "PMI_"};

#ifdef DEMDESIGN_WITH_MPI
void check(int code, const char* what) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  throw std::runtime_error(fmt::format("MPI: {} failed: {}", what, std::string(text, static_cast<size_t>(length))));
}

/// Waits for every rank without spinning: a rank whose share is done would otherwise busy-poll
/// in a blocking collective and take a core from the simulations still running.
void quiet_barrier() {
  MPI_Request request;
  check(MPI_Ibarrier(MPI_COMM_WORLD, &request), "MPI_Ibarrier");
  for (int arrived = 0;;) {
    check(MPI_Test(&request, &arrived, MPI_STATUS_IGNORE), "MPI_Test");
    if (arrived) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

/// Lengths of every rank's bytes, then the bytes (MPI_Gatherv / MPI_Allgatherv).
std::vector<std::string> collect(const std::string& mine, bool everyone) {
  quiet_barrier();
  const int n = the_world.size;
  const int length = static_cast<int>(mine.size());
  if (mine.size() > static_cast<size_t>(std::numeric_limits<int>::max() / 2))
    throw std::runtime_error(fmt::format("MPI: a message of {} bytes is too large", mine.size()));
  std::vector<int> lengths(static_cast<size_t>(n)), offsets(static_cast<size_t>(n));
  if (everyone) check(MPI_Allgather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
  else check(MPI_Gather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  long long total = 0;
  for (int r = 0; r < n; ++r) offsets[r] = static_cast<int>(total), total += lengths[r];
  if (total > std::numeric_limits<int>::max()) throw std::runtime_error(fmt::format("MPI: {} bytes in one gather are too many", total));
  const bool receives = everyone || the_world.rank == 0;
  std::string all(receives ? static_cast<size_t>(total) : 0, '\0');
  if (everyone)
    check(MPI_Allgatherv(mine.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR, MPI_COMM_WORLD), "MPI_Allgatherv");
  else
    check(MPI_Gatherv(mine.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR, 0, MPI_COMM_WORLD), "MPI_Gatherv");
  std::vector<std::string> out;
  if (receives)
    for (int r = 0; r < n; ++r) out.push_back(all.substr(static_cast<size_t>(offsets[r]), static_cast<size_t>(lengths[r])));
  return out;
}
#endif

}  // namespace

bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"})
    if (std::getenv(name)) return true;
  return false;
}

bool built_with_mpi() {
#ifdef DEMDESIGN_WITH_MPI
  return true;
#else
  return false;
#endif
}

Session::Session(int* argc, char*** argv) {
#ifdef DEMDESIGN_WITH_MPI
  if (!launched_by_mpi()) return;
  int provided = 0;
  check(MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  initialised = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &the_world.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &the_world.size);
  // Ranks on this machine: the communicator of ranks that can share memory.
  MPI_Comm node;
  check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, the_world.rank, MPI_INFO_NULL, &node), "MPI_Comm_split_type");
  MPI_Comm_size(node, &the_world.ranks_on_node);
  MPI_Comm_free(&node);
#else
  (void)argc, (void)argv;
#endif
}

Session::~Session() {
#ifdef DEMDESIGN_WITH_MPI
  // Ranks with nothing (more) to do wait here, asleep, for the others.
  if (initialised) {
    try {
      quiet_barrier();
    } catch (const std::exception&) {
    }
    MPI_Finalize();
  }
  initialised = false;
  the_world = World{};
#endif
}

const World& world() { return the_world; }

void abort(int code) {
#ifdef DEMDESIGN_WITH_MPI
  if (initialised && the_world.active()) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  (void)code;
}

int cores_per_rank() {
  const int seen = std::max(1, omp_get_num_procs());  // the cores of this process's affinity mask
  const int machine = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  // A launcher that binds ranks has already given each its own cores; otherwise share them.
  if (the_world.ranks_on_node > 1 && seen >= machine) return std::max(1, seen / the_world.ranks_on_node);
  return seen;
}

std::vector<std::string> gather(const std::string& mine) {
#ifdef DEMDESIGN_WITH_MPI
  if (the_world.active()) return collect(mine, false);
#endif
  return {mine};
}

std::vector<std::string> all_gather(const std::string& mine) {
#ifdef DEMDESIGN_WITH_MPI
  if (the_world.active()) return collect(mine, true);
#endif
  return {mine};
}

std::vector<std::string> child_environment() {
  std::vector<std::string> out;
  for (char** e = environ; *e; ++e) {
    const std::string entry = *e;
    const bool launcher = std::any_of(std::begin(kLauncherPrefixes), std::end(kLauncherPrefixes),
                                      [&](const char* prefix) { return entry.rfind(prefix, 0) == 0; });
    if (!launcher) out.push_back(entry);
  }
  return out;
}

// ---- bytes ----------------------------------------------------------------------------------

void ByteWriter::u64(std::uint64_t v) { bytes_.append(reinterpret_cast<const char*>(&v), sizeof v); }

void ByteWriter::f64(double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  u64(bits);
}

void ByteWriter::str(const std::string& s) {
  u64(s.size());
  bytes_ += s;
}

std::uint64_t ByteReader::u64() {
  if (bytes_.size() - at_ < sizeof(std::uint64_t)) throw std::runtime_error("MPI: a message ended early (ranks running different builds?)");
  std::uint64_t v = 0;
  std::memcpy(&v, bytes_.data() + at_, sizeof v);
  at_ += sizeof v;
  return v;
}

double ByteReader::f64() {
  const std::uint64_t bits = u64();
  double v = 0;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

std::string ByteReader::str() {
  const std::uint64_t n = u64();
  if (bytes_.size() - at_ < n) throw std::runtime_error("MPI: a message ended early (ranks running different builds?)");
  std::string s = bytes_.substr(at_, n);
  at_ += n;
  return s;
}

void write_outcome(ByteWriter& out, const materials::BatchOutcome& b) {
  out.u64(static_cast<std::uint64_t>(b.error));
  out.str(b.message);
  const materials::SimulatedOutcome& o = b.outcome;
  out.u64(o.observables.size());
  for (const auto& [key, value] : o.observables) out.str(key), out.f64(value);
  out.u64(o.flags.size());
  for (const std::string& f : o.flags) out.str(f);
  out.u64(static_cast<std::uint64_t>(o.particles));
  out.f64(o.simulated_seconds), out.f64(o.wall_seconds);
  out.u64(o.notes.size());
  for (const std::string& n : o.notes) out.str(n);
}

materials::BatchOutcome read_outcome(ByteReader& in) {
  materials::BatchOutcome b;
  b.error = static_cast<materials::BatchOutcome::Error>(in.u64());
  b.message = in.str();
  materials::SimulatedOutcome& o = b.outcome;
  for (std::uint64_t k = 0, n = in.u64(); k < n; ++k) {
    std::string key = in.str();
    o.observables[key] = in.f64();
  }
  for (std::uint64_t k = 0, n = in.u64(); k < n; ++k) o.flags.push_back(in.str());
  o.particles = static_cast<std::int64_t>(in.u64());
  o.simulated_seconds = in.f64(), o.wall_seconds = in.f64();
  for (std::uint64_t k = 0, n = in.u64(); k < n; ++k) o.notes.push_back(in.str());
  return b;
}

// ---- sweep variants --------------------------------------------------------------------------

namespace {
constexpr int kAskTag = 701, kAnswerTag = 702;  // message tags of the work queue
}

WorkQueue::WorkQueue(size_t count) : count_(count) {}

WorkQueue::~WorkQueue() {
#ifdef DEMDESIGN_WITH_MPI
  delete static_cast<MPI_Request*>(request_);
#endif
}

long WorkQueue::next() {
#ifdef DEMDESIGN_WITH_MPI
  if (the_world.active() && the_world.rank != 0) {
    // Ask rank 0 and wait for the answer without blocking (the rank looks after its variants meanwhile).
    auto* request = static_cast<MPI_Request*>(request_);
    if (!asked_) {
      const int ask = 1;
      check(MPI_Send(&ask, 1, MPI_INT, 0, kAskTag, MPI_COMM_WORLD), "MPI_Send");
      if (!request) request_ = request = new MPI_Request;
      check(MPI_Irecv(&answer_, 1, MPI_LONG, 0, kAnswerTag, MPI_COMM_WORLD, request), "MPI_Irecv");
      asked_ = true;
    }
    int arrived = 0;
    check(MPI_Test(request, &arrived, MPI_STATUS_IGNORE), "MPI_Test");
    if (!arrived) return kWait;
    asked_ = false;
    return answer_;
  }
#endif
  return next_ < count_ ? static_cast<long>(next_++) : kNone;
}

bool WorkQueue::serve() {
  bool answered = false;
#ifdef DEMDESIGN_WITH_MPI
  if (!the_world.active() || the_world.rank != 0) return false;
  for (;;) {
    int waiting = 0;
    MPI_Status status;
    check(MPI_Iprobe(MPI_ANY_SOURCE, kAskTag, MPI_COMM_WORLD, &waiting, &status), "MPI_Iprobe");
    if (!waiting) break;
    int ask = 0;
    check(MPI_Recv(&ask, 1, MPI_INT, status.MPI_SOURCE, kAskTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "MPI_Recv");
    const long item = next_ < count_ ? static_cast<long>(next_++) : kNone;
    if (item == kNone) ++told_;
    check(MPI_Send(&item, 1, MPI_LONG, status.MPI_SOURCE, kAnswerTag, MPI_COMM_WORLD), "MPI_Send");
    answered = true;
  }
#endif
  return answered;
}

bool WorkQueue::all_told() const { return the_world.rank != 0 || told_ >= the_world.size - 1; }

// ---- calibration batches ----------------------------------------------------------------------

materials::BatchRunner calibration_batch_runner() {
  if (!the_world.active()) return {};
  return [](size_t count, const std::function<materials::BatchOutcome(size_t)>& simulate,
            const std::function<void(size_t, const materials::BatchOutcome&)>& done,
            const std::function<bool(const materials::BatchOutcome&)>& fatal) {
    const size_t rank = static_cast<size_t>(the_world.rank), size = static_cast<size_t>(the_world.size);
    std::vector<materials::BatchOutcome> out(count);
    // This rank's share, in order, up to its first fatal outcome.
    ByteWriter mine;
    for (size_t k = rank; k < count; k += size) {
      out[k] = simulate(k);
      done(k, out[k]);
      mine.u64(k);
      write_outcome(mine, out[k]);
      if (fatal(out[k])) break;
    }
    // Everyone's outcomes, on every rank.
    const std::vector<std::string> all = all_gather(mine.bytes());
    for (size_t r = 0; r < all.size(); ++r) {
      if (r == rank) continue;
      ByteReader in(all[r]);
      while (!in.done()) {
        const std::uint64_t k = in.u64();
        if (k >= count || k % size != r) throw std::runtime_error(fmt::format("MPI: rank {} sent an outcome for simulation {} of {}", r, k, count));
        out[k] = read_outcome(in);
        done(k, out[k]);
      }
    }
    return out;
  };
}

}  // namespace dem::app::mpi
