// A run's output folder: what a run may replace there and what it leaves alone.
//   - A folder holding an earlier run's results is refused, unless the run continues that run
//     (resume) or replaces its results (overwrite).
//   - A file at a name the run writes that no demdesign run wrote (a user's own case.yaml beside
//     `--out .`) is never replaced, not even with overwrite.
//   - overwrite removes the files runs wrote there and nothing else: run_files.txt lists the names
//     runs have claimed in the folder (frames, renders and report files by their patterns).
//   - One run at a time: the folder is locked (run.lock with the process id, held with flock)
//     while a run writes it; a lock left by a process that died is taken over.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace dem {

/// How a run uses its output folder.
enum class FolderUse {
  fresh,      ///< a new run: the folder must hold no earlier run's results
  resume,     ///< continues the run whose results and checkpoint the folder holds
  overwrite,  ///< a new run that first removes the files earlier runs wrote there
};

/// The lock a run holds on its folder while it writes it (removed when the run ends).
inline constexpr const char* kRunLockFile = "run.lock";
/// The names runs have claimed in a folder, one a line: what overwrite may remove.
inline constexpr const char* kRunFilesFile = "run_files.txt";

/// What a folder's run_info.yaml says of the run that wrote it; `exists` is false (and the rest
/// empty) when there is no run_info.yaml written by demdesign.
struct RunRecord {
  bool exists = false;
  std::string case_path;     ///< `case:`
  std::uint64_t run_id = 0;  ///< `run_id:`; 0 when not recorded (runs of versions before run ids)
  bool ended = false;        ///< its `end:` block was written (a killed run has none)
  bool completed = false;    ///< `end: completed: true`
  double time = 0;           ///< [s] `end: time_s`
  std::int64_t step = 0;     ///< `end: step`
};
RunRecord read_run_record(const std::string& directory);

/// The names of the files the engine's run() writes into its folder, relative to it; a `*` in a
/// file name is a pattern ("frames/frame_*.h5"). Each name also stands for its temporaries
/// (NAME.part, NAME.tmp), which a killed run may leave.
std::vector<std::string> run_output_names();

/// A new run's id (random, never 0): written in run_info.yaml and in every checkpoint, so that a
/// resumed run continues only the rows of the run its checkpoint belongs to.
std::uint64_t new_run_id();

/// A run's claim on its output folder: the folder checked for `use` (above) and locked when
/// created, cleared of an earlier run's files and listed in run_files.txt when the run begins to
/// write; the lock is released when the object is destroyed.
class RunFolder {
 public:
  /// Creates `directory` when needed, locks it and checks what it holds against `use` and the
  /// `names` the run writes (run_output_names() plus the caller's). Throws CaseError naming the
  /// folder and what it holds, the file that no run wrote, or the process that holds the lock;
  /// nothing in the folder is changed then. A note on `log` when a dead process's lock is taken over.
  RunFolder(std::string directory, FolderUse use, const std::vector<std::string>& names, std::ostream& log);
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  /// Called before the run's first write (again: nothing): for overwrite removes the earlier
  /// run's files and the sub-folders that left empty, saying so on `log`; lists the run's names in
  /// run_files.txt. Until then a claimed folder is as it was (a case that fails to compile after
  /// the claim loses nothing). Throws std::runtime_error naming a file it cannot remove.
  void begin(std::ostream& log);

  const std::string& directory() const { return directory_; }

 private:
  void lock(std::ostream& log);
  void unlock();

  std::string directory_;
  int lock_descriptor_ = -1;
  std::vector<std::string> names_;    ///< every name runs write here: this run's and those listed before
  std::vector<std::string> earlier_;  ///< the earlier run's files that overwrite removes (relative paths)
  bool begun_ = false;
};

}  // namespace dem
