// Running a compiled case from its initial state to its end time: progress with time left,
// per-step scalars to CSV (written atomically), numerical checks.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"
#include "output/results_hdf5.h"
#include "output/run_folder.h"
#include "statistics/diagnostics.h"
#include "statistics/events.h"

namespace dem {

class Domain;

struct RunOptions {
  double duration = -1;           ///< [s] overrides the case's when >= 0
  std::int64_t max_steps = -1;    ///< stop after this many steps when >= 0 (shortened runs)
  std::string output_directory;   ///< overrides the case's when not empty
  bool write_files = true;
  bool progress = true;
  bool resume = false;            ///< continue from OUT's checkpoint (load_resumable, checkpoint.h)
  /// Replace the results of an earlier run in OUT (only the files runs wrote there, run_folder.h);
  /// without it (or resume) a folder holding another run's results is refused.
  bool overwrite = false;
  /// Names the caller writes into OUT after the run (run_output_names() has the engine's): they
  /// are guarded, listed and removed for overwrite as the run's own.
  std::vector<std::string> caller_outputs;
  /// OUT claimed by the caller (on the root): run() then claims nothing itself. A program claims
  /// the folder before it compiles the case, so that a refusal comes before any work.
  std::shared_ptr<RunFolder> folder;
  std::string command_line;       ///< the command that started the run, kept in run_info.yaml
  /// Called after a particle frame is written, with the whole state: after every
  /// model.output.render_every-th frame of the run and after the last (the app renders images
  /// here; the engine knows nothing of rendering). `last` is true for the final frame.
  std::function<void(const Model&, const State&, const Workspace&, const std::string& out, bool last)> on_frame;
  /// The ranks sharing this simulation (domain decomposition, domain.h), or null. Every rank
  /// calls run() with the whole initial state and the same options; the root (rank 0) writes
  /// the results and returns with the whole final state, the others with their share.
  Domain* domain = nullptr;
  /// With a domain: where this rank's particles go in a frame every rank writes together
  /// (FrameShare; app/mpi/mpi_frames.h). Empty: the root gathers the whole state for each frame.
  /// The whole state is still gathered once at the end, and for a frame on_frame is called with.
  std::function<FrameShare(std::size_t owned)> share_frame;
};

struct RunSummary {
  std::int64_t steps = 0;
  double wall_seconds = 0;
  double particle_steps_per_second = 0;
  std::vector<Scalars> scalars;
  std::vector<RunEvent> events;  ///< first arrivals at outlets and plane sensors, first loss (events.h)
  std::string output_directory;
  /// The output folder claimed for the run (locked, run_folder.h) while the summary or a copy of
  /// this pointer lives: the caller writes its own files into it (caller_outputs) before letting go.
  std::shared_ptr<RunFolder> folder;
  /// A resumed run that had already reached its end: nothing was run, the state is as given.
  bool already_complete = false;
  /// Why the run stopped before its end (a signal, numerical trouble); "" when it reached it.
  std::string stopped;
};

/// Thrown by run() when numerical trouble stops it (simulation.numerical_trouble: stop), after the
/// rows, events and run_info.yaml so far are written: what the run computed up to then, for the
/// caller's report. The message is the trouble's.
class RunStopped : public NumericalError {
 public:
  RunStopped(const NumericalError& cause, RunSummary so_far) : NumericalError(cause.what()), summary(std::move(so_far)) {}
  RunSummary summary;
};

/// Prints the model's set-up (effects, time-step advice, notes) to `log`.
void print_setup(const Model& model, const State& state, std::ostream& log);
/// Warnings for particles placed wholly behind a one-sided plane wall and for inlets whose region
/// lies wholly behind one (print_setup says them): such particles fall through the wall.
std::vector<std::string> particles_behind_walls(const Model& model, const State& state);

/// Runs from the state as it is (prepare() is called here) to the model's end time. Writing files,
/// it first claims OUT (RunFolder: refused when it holds another run's results unless resume or
/// overwrite, or a file of the run's names that no run wrote; locked while the run writes). With
/// options.resume the state is replaced by OUT's checkpoint (checkpoint.bin, or under domain
/// decomposition every rank's share, checkpoint.h), which must belong to the run whose results
/// lie beside it (the run id in the checkpoint and in run_info.yaml); a run that had reached its
/// end is not run again (already_complete). `log` gets the set-up, progress
/// and summary lines. SIGINT and SIGTERM stop the run after the current step with a checkpoint.
RunSummary run(const Model& model, State& state, Workspace& work, const RunOptions& options, std::ostream& log);

/// Writes the state's particles (a split run's rank: its own, without the ghosts) as a frame with
/// their bodies' orientations: by this process, or with `share` by every rank together.
void write_frame(FrameWriter& writer, const State& state, const FrameShare* share = nullptr);

/// Writes `content` to `path` through a temporary file and a rename, so a reader never sees a
/// half-written file. Creates the parent directory.
void write_file_atomically(const std::string& path, const std::string& content);

}  // namespace dem
