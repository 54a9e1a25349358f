// A run folder is never overwritten or spliced silently (src/output/run_folder.h): a folder holding
// another run's results is refused unless the run resumes it or is told to overwrite it; no run
// replaces a file that no run wrote (a user's own case.yaml beside `--out .`), not even with
// --overwrite; --overwrite removes the earlier run's files and nothing else; a folder is locked
// while a run writes it (a second run fails at once naming the first one's process, a lock left
// by a killed run is taken over); --resume continues only a checkpoint of the run whose rows lie
// beside it, and says a complete run is complete instead of rewinding it. Each rule is tried
// through the engine's run() and through the real demdesign binary.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "output/run.h"
#include "output/run_folder.h"

namespace dem::test {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const fs::path kScratch = fs::temp_directory_path() / ("demdesign_run_folder_" + std::to_string(::getpid()));

/// The scratch folder goes when every test passed (kept to look at otherwise).
class RemoveScratch : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    if (::testing::UnitTest::GetInstance()->Passed()) fs::remove_all(kScratch, ignored);
  }
};
[[maybe_unused]] ::testing::Environment* const kRemoveScratch = ::testing::AddGlobalTestEnvironment(new RemoveScratch);

/// Two soft beads dropped on a floor: 5000 steps in a blink, a frame and a checkpoint every 1000.
constexpr const char* kCase = R"(simulation: {duration: 0.05, time_step: 1.0e-5, gravity: [0, 0, -9.81]}
materials:
  glass: {density: 2500, youngs_modulus: 5.0e7, poisson_ratio: 0.25, restitution: 0.9, friction: 0.3}
walls:
  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: glass}
particles:
  - {material: glass, diameter: 0.01, positions: [[0, 0, 0.02], [0.03, 0, 0.03]]}
output: {directory: out/run_folder_test, checkpoint_every: 0.01, frames_every: 0.01}
)";

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// A fresh, empty folder under the scratch folder.
fs::path folder(const std::string& name) {
  const fs::path dir = kScratch / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// The files below `dir`, relative to it.
std::set<std::string> files_in(const fs::path& dir) {
  std::set<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file()) files.insert(fs::relative(entry.path(), dir).string());
  return files;
}

const Model& tiny_model() {
  static const Model model = compile(parse_case_text(kCase, "run_folder.yaml"));
  return model;
}

/// What one call of run() did: the refusal's message (empty when it ran) and its log.
struct Attempt {
  std::string error;
  std::string log;
  bool already_complete = false;
};

Attempt attempt(const fs::path& out, RunOptions options = {}) {
  options.output_directory = out.string();
  options.progress = false;
  State state = initial_state(tiny_model());
  Workspace work;
  std::ostringstream log;
  Attempt a;
  try {
    a.already_complete = run(tiny_model(), state, work, options, log).already_complete;
  } catch (const CaseError& e) {
    a.error = e.what();
  }
  a.log = log.str();
  return a;
}

RunOptions with(bool resume, bool overwrite, double duration = -1, std::int64_t max_steps = -1) {
  RunOptions options;
  options.resume = resume, options.overwrite = overwrite, options.duration = duration, options.max_steps = max_steps;
  return options;
}

/// run_info.yaml as a run killed mid-way leaves it: without its `end:` block.
void as_killed(const fs::path& out) {
  const std::string info = read_text(out / "run_info.yaml");
  std::ofstream(out / "run_info.yaml") << info.substr(0, info.find("end:\n"));
}

// ---- through the engine's run() ----

TEST(RunFolderRules, AFreshRunRefusesAFolderHoldingAnotherRunAndChangesNothing) {
  const fs::path out = folder("holds");
  ASSERT_EQ(attempt(out).error, "");
  const std::string scalars = read_text(out / "scalars.csv"), info = read_text(out / "run_info.yaml");
  const std::set<std::string> before = files_in(out);
  // A run that ended: replace it with --overwrite, or go elsewhere.
  Attempt again = attempt(out);
  EXPECT_NE(again.error.find(out.string() + " holds the results of a run of run_folder.yaml, which ended at t = 0.05 s: "),
            std::string::npos) << again.error;
  EXPECT_NE(again.error.find("run_info.yaml"), std::string::npos) << again.error;
  EXPECT_NE(again.error.find("checkpoint.bin"), std::string::npos) << again.error;
  EXPECT_NE(again.error.find("frames/ (6 files)"), std::string::npos) << again.error;
  EXPECT_NE(again.error.find("add --overwrite to replace them (only the files runs wrote there are removed), or choose another --out folder"),
            std::string::npos) << again.error;
  EXPECT_EQ(read_text(out / "scalars.csv"), scalars);
  EXPECT_EQ(read_text(out / "run_info.yaml"), info);
  EXPECT_EQ(files_in(out), before);
  // A run that did not end, with a checkpoint: --resume continues it.
  as_killed(out);
  again = attempt(out);
  EXPECT_NE(again.error.find("which did not end (killed?)"), std::string::npos) << again.error;
  EXPECT_NE(again.error.find("To continue that run add --resume; to start again add --overwrite"), std::string::npos) << again.error;
  // Without a checkpoint there is nothing to continue: the message says how to get one.
  fs::remove(out / "checkpoint.bin");
  again = attempt(out);
  EXPECT_NE(again.error.find("It has no checkpoint to continue from (output.checkpoint_every): add --overwrite"), std::string::npos)
      << again.error;
}

TEST(RunFolderRules, OverwriteRemovesTheEarlierRunsFilesAndNothingElse) {
  const fs::path out = folder("overwrite");
  ASSERT_EQ(attempt(out).error, "");  // 0.05 s: frames at steps 0 to 5000
  ASSERT_TRUE(fs::exists(out / "frames/frame_005000.h5"));
  ASSERT_TRUE(fs::exists(out / "checkpoint.bin"));
  // The user's own files, beside the results and among the frames.
  std::ofstream(out / "notes.txt") << "my notes\n";
  std::ofstream(out / "frames/README") << "my frames\n";
  std::ofstream(out / "scalars.csv.bak") << "my copy\n";
  // A shorter run, without checkpoints, replacing the earlier one.
  RunOptions options = with(false, true, 0.02);
  const Attempt a = attempt(out, options);
  ASSERT_EQ(a.error, "") << a.log;
  EXPECT_NE(a.log.find("--overwrite: removed "), std::string::npos) << a.log;
  EXPECT_EQ(read_text(out / "notes.txt"), "my notes\n");
  EXPECT_EQ(read_text(out / "frames/README"), "my frames\n");
  EXPECT_EQ(read_text(out / "scalars.csv.bak"), "my copy\n");
  // Only the new run's frames: none of the earlier run's later frames is left among them.
  std::set<std::string> frames;
  for (const auto& f : fs::directory_iterator(out / "frames")) frames.insert(f.path().filename().string());
  EXPECT_EQ(frames, (std::set<std::string>{"README", "frame_000000.h5", "frame_001000.h5", "frame_002000.h5"}));
  const RunRecord record = read_run_record(out.string());
  EXPECT_TRUE(record.completed);
  EXPECT_NEAR(record.time, 0.02, 1e-9);
}

TEST(RunFolderRules, AFreshRunLeavesNoOldCheckpointBehind) {
  const fs::path out = folder("old_checkpoint");
  ASSERT_EQ(attempt(out, with(false, false, -1, 2500)).error, "");
  ASSERT_TRUE(fs::exists(out / "checkpoint.bin"));
  CaseSpec spec = parse_case_text(kCase, "run_folder.yaml");
  spec.output.checkpoint_every = 0;
  const Model without_checkpoints = compile(spec);
  RunOptions options = with(false, true, -1, 3000);  // stopped short of the end: --resume would look for a checkpoint
  options.output_directory = out.string();
  options.progress = false;
  State state = initial_state(without_checkpoints);
  Workspace work;
  std::ostringstream log;
  run(without_checkpoints, state, work, options, log);
  EXPECT_FALSE(fs::exists(out / "checkpoint.bin")) << "a checkpoint of the earlier run would be resumed beside the new rows";
  // And --resume has nothing to splice: no checkpoint to resume from.
  EXPECT_THROW(attempt(out, with(true, false)), std::runtime_error);
}

TEST(RunFolderRules, NoRunReplacesAFileThatNoRunWroteNotEvenWithOverwrite) {
  const fs::path out = folder("foreign");
  const std::string mine = "# my own case file\nsimulation: {duration: 1}\n";
  std::ofstream(out / "case.yaml") << mine;
  RunOptions options;
  options.caller_outputs = {"case.yaml"};  // as the demdesign program writes OUT/case.yaml
  for (const bool overwrite : {false, true}) {
    options.overwrite = overwrite;
    const Attempt a = attempt(out, options);
    EXPECT_EQ(a.error.rfind((out / "case.yaml").string() + ": not written by a demdesign run, and a run into " + out.string() +
                                " writes a file of that name; nothing was changed. Move the file away or choose another --out folder "
                                "(--overwrite replaces only files that runs wrote)",
                            0),
              0u)
        << a.error;
    EXPECT_EQ(read_text(out / "case.yaml"), mine);
    EXPECT_EQ(files_in(out), std::set<std::string>{"case.yaml"}) << "nothing written, no lock left";
  }
  // An engine output name too: a scalars.csv of the user's own.
  fs::remove(out / "case.yaml");
  std::ofstream(out / "scalars.csv") << "x,y\n1,2\n";
  const Attempt a = attempt(out, with(false, true));
  EXPECT_NE(a.error.find((out / "scalars.csv").string() + ": not written by a demdesign run"), std::string::npos) << a.error;
  EXPECT_EQ(read_text(out / "scalars.csv"), "x,y\n1,2\n");
}

TEST(RunFolderRules, ASecondRunIntoALockedFolderFailsAtOnceNamingTheFirst) {
  const fs::path out = folder("locked");
  std::ostringstream log;
  {
    const RunFolder first(out.string(), FolderUse::fresh, run_output_names(), log);
    EXPECT_EQ(read_text(out / kRunLockFile), std::to_string(::getpid()) + "\n");
    const auto begun = std::chrono::steady_clock::now();
    for (const bool overwrite : {false, true}) {
      const Attempt second = attempt(out, with(false, overwrite));
      EXPECT_EQ(second.error, fmt::format("{} is being written by another run (process {}, {}); wait for it to end or stop it, or choose "
                                          "another --out folder",
                                          out.string(), ::getpid(), (out / kRunLockFile).string()));
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - begun).count(), 5.0) << "at once, not after waiting";
  }
  EXPECT_FALSE(fs::exists(out / kRunLockFile)) << "released when the run lets go";
  EXPECT_EQ(attempt(out).error, "");
  EXPECT_FALSE(fs::exists(out / kRunLockFile));
}

TEST(RunFolderRules, ALockLeftByAProcessThatDiedIsTakenOver) {
  const fs::path out = folder("stale_lock");
  const pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  std::ofstream(out / kRunLockFile) << dead << "\n";
  const Attempt a = attempt(out);
  ASSERT_EQ(a.error, "");
  EXPECT_NE(a.log.find(fmt::format("{} was left by process {}, which has ended (killed?); this run takes the folder over",
                                   (out / kRunLockFile).string(), dead)),
            std::string::npos)
      << a.log;
  EXPECT_FALSE(fs::exists(out / kRunLockFile));
}

TEST(RunFolderRules, ResumeRefusesACheckpointThatIsNotTheRowsRun) {
  // Two runs stopped part-way, each with its checkpoint; the first's checkpoint put beside the
  // second's rows would splice the two.
  const fs::path a = folder("resume_a"), b = folder("resume_b");
  ASSERT_EQ(attempt(a, with(false, false, -1, 2500)).error, "");
  ASSERT_EQ(attempt(b, with(false, false, -1, 1500)).error, "");
  const RunRecord record_a = read_run_record(a.string()), record_b = read_run_record(b.string());
  ASSERT_NE(record_a.run_id, 0u);
  ASSERT_NE(record_a.run_id, record_b.run_id);
  fs::copy_file(a / "checkpoint.bin", b / "checkpoint.bin", fs::copy_options::overwrite_existing);
  const std::string rows = read_text(b / "scalars.csv");
  const Attempt spliced = attempt(b, with(true, false));
  EXPECT_EQ(spliced.error, fmt::format("{}: the checkpoint belongs to another run (run id {:016x}) than the results beside it "
                                       "({}/run_info.yaml: run id {:016x}); resuming would splice the two runs' rows: add --overwrite "
                                       "instead of --resume to start the run again, or resume in the folder the checkpoint was written in",
                                       (b / "checkpoint.bin").string(), record_a.run_id, b.string(), record_b.run_id));
  EXPECT_EQ(read_text(b / "scalars.csv"), rows);
  // A checkpoint with no run record beside it cannot be told to belong to the rows.
  fs::remove(b / "run_info.yaml");
  EXPECT_NE(attempt(b, with(true, false)).error.find("no run_info.yaml beside it"), std::string::npos);
  // Its own checkpoint resumes.
  const Attempt own = attempt(a, with(true, false));
  EXPECT_EQ(own.error, "") << own.log;
  EXPECT_NE(own.log.find("resumed from"), std::string::npos) << own.log;
  EXPECT_EQ(read_run_record(a.string()).run_id, record_a.run_id) << "a resumed run keeps its id";
}

TEST(RunFolderRules, ResumingACompleteRunSaysSoAndChangesNothing) {
  const fs::path out = folder("complete");
  ASSERT_EQ(attempt(out).error, "");
  const std::string scalars = read_text(out / "scalars.csv"), info = read_text(out / "run_info.yaml");
  const Attempt again = attempt(out, with(true, false));
  EXPECT_EQ(again.error, "");
  EXPECT_TRUE(again.already_complete);
  EXPECT_NE(again.log.find(fmt::format("{}: the run is complete (t = 0.05 s, step 5000; run_info.yaml): nothing to resume. To run it again "
                                       "from the start, use --overwrite instead of --resume",
                                       out.string())),
            std::string::npos)
      << again.log;
  EXPECT_EQ(read_text(out / "scalars.csv"), scalars) << "not rewound to the last checkpoint";
  EXPECT_EQ(read_text(out / "run_info.yaml"), info);
}

// ---- through the demdesign binary ----

/// Starts `demdesign args` in `cwd`, its output to `log`.
pid_t start(const std::vector<std::string>& args, const fs::path& log, const fs::path& cwd = fs::current_path()) {
  std::vector<char*> argv{const_cast<char*>(DEMDESIGN_BINARY)};
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(cwd.c_str()) != 0) ::_exit(126);
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, STDOUT_FILENO), ::dup2(fd, STDERR_FILENO);
    ::execv(DEMDESIGN_BINARY, argv.data());
    ::_exit(127);
  }
  return pid;
}

int wait_exit(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// `demdesign args` in `cwd` to its end: exit status and output.
std::pair<int, std::string> demdesign(const std::vector<std::string>& args, const fs::path& cwd = fs::current_path()) {
  const fs::path log = kScratch / "demdesign.log";
  const int status = wait_exit(start(args, log, cwd));
  return {status, read_text(log)};
}

fs::path case_file() {
  fs::create_directories(kScratch);
  const fs::path path = kScratch / "beads.yaml";
  std::ofstream(path) << kCase;
  return path;
}

TEST(RunFolderRulesBinary, OutDotNeverReplacesTheUsersCaseFile) {
  const fs::path here = folder("dot");
  std::ofstream(here / "case.yaml") << kCase;
  for (const std::vector<std::string>& extra : {std::vector<std::string>{}, std::vector<std::string>{"--overwrite"}}) {
    std::vector<std::string> args = {"case.yaml", "--out", ".", "--quiet", "--no-report"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto [status, log] = demdesign(args, here);
    EXPECT_EQ(status, 2) << log;
    EXPECT_NE(log.find("error: ./case.yaml: not written by a demdesign run, and a run into . writes a file of that name; nothing was changed"),
              std::string::npos)
        << log;
    EXPECT_EQ(read_text(here / "case.yaml"), kCase);
    EXPECT_EQ(files_in(here), std::set<std::string>{"case.yaml"});
  }
}

TEST(RunFolderRulesBinary, RunAgainOverwriteResumeAndBothTogether) {
  const fs::path c = case_file(), out = kScratch / "binary_out";
  fs::remove_all(out);
  const std::vector<std::string> base = {c.string(), "--out", out.string(), "--quiet", "--no-report", "--threads", "1"};
  const auto with_flag = [&](const std::string& flag) {
    std::vector<std::string> args = base;
    args.push_back(flag);
    return args;
  };
  auto [status, log] = demdesign(base);
  ASSERT_EQ(status, 0) << log;
  EXPECT_NE(read_text(out / kRunFilesFile).find("\ncase.yaml\n"), std::string::npos) << "the program's own outputs are listed";
  const std::string rows = read_text(out / "scalars.csv");
  std::tie(status, log) = demdesign(base);
  EXPECT_EQ(status, 2) << log;
  EXPECT_NE(log.find("error: " + out.string() + " holds the results of a run of " + c.string() + ", which ended at t = 0.05 s"),
            std::string::npos) << log;
  EXPECT_EQ(read_text(out / "scalars.csv"), rows);
  std::tie(status, log) = demdesign(with_flag("--resume"));
  EXPECT_EQ(status, 0) << log;
  EXPECT_NE(log.find("the run is complete (t = 0.05 s, step 5000; run_info.yaml): nothing to resume"), std::string::npos) << log;
  EXPECT_EQ(read_text(out / "scalars.csv"), rows);
  std::tie(status, log) = demdesign(with_flag("--overwrite"));
  EXPECT_EQ(status, 0) << log;
  EXPECT_NE(log.find("--overwrite: removed "), std::string::npos) << log;
  std::vector<std::string> both = with_flag("--resume");
  both.push_back("--overwrite");
  std::tie(status, log) = demdesign(both);
  EXPECT_EQ(status, 2) << log;
  EXPECT_NE(log.find("excludes"), std::string::npos) << log;
}

TEST(RunFolderRulesBinary, ASecondRunFailsWhileTheFirstWritesAndAKilledRunsLockIsTakenOver) {
  const fs::path c = case_file(), out = kScratch / "binary_lock";
  fs::remove_all(out);
  const std::vector<std::string> base = {c.string(), "--out", out.string(), "--quiet", "--no-report", "--threads", "1"};
  // A first run long enough to be caught writing (it is killed).
  std::vector<std::string> long_run = base;
  long_run.insert(long_run.end(), {"--duration", "1000"});
  const pid_t first = start(long_run, kScratch / "first.log");
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!fs::exists(out / "checkpoint.bin") && ::waitpid(first, nullptr, WNOHANG) == 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(2ms);
  ASSERT_TRUE(fs::exists(out / "checkpoint.bin")) << read_text(kScratch / "first.log");
  for (const std::string flag : {"--resume", "--overwrite"}) {
    std::vector<std::string> args = base;
    args.push_back(flag);
    const auto begun = std::chrono::steady_clock::now();
    const auto [status, log] = demdesign(args);
    EXPECT_EQ(status, 2) << log;
    EXPECT_NE(log.find(fmt::format("error: {} is being written by another run (process {}, {}/run.lock)", out.string(), first, out.string())),
              std::string::npos)
        << log;
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - begun).count(), 30.0);
  }
  ASSERT_EQ(::kill(first, SIGKILL), 0);
  ASSERT_EQ(wait_exit(first), 128 + SIGKILL);
  ASSERT_TRUE(fs::exists(out / "run.lock")) << "a killed run leaves its lock file";
  // The next run takes the dead run's lock over; a fresh one is told the folder holds a run it
  // can resume, and --overwrite replaces it.
  auto [status, log] = demdesign(base);
  EXPECT_EQ(status, 2) << log;
  EXPECT_NE(log.find(fmt::format("{}/run.lock was left by process {}, which has ended (killed?); this run takes the folder over",
                                 out.string(), first)),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("which did not end (killed?)"), std::string::npos) << log;
  EXPECT_NE(log.find("To continue that run add --resume"), std::string::npos) << log;
  std::vector<std::string> overwrite = base;
  overwrite.push_back("--overwrite");
  std::tie(status, log) = demdesign(overwrite);
  EXPECT_EQ(status, 0) << log;
  EXPECT_NE(log.find("--overwrite: removed "), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out / "run.lock"));
  EXPECT_TRUE(read_run_record(out.string()).completed);
}

}  // namespace
}  // namespace dem::test
