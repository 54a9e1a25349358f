// A run loses nothing and explains itself: a real `demdesign` process killed with SIGKILL at
// seeded random moments resumes with --resume to the same final state (state_hash in
// run_info.yaml) as an uninterrupted run; SIGTERM writes a checkpoint and exits cleanly; a write
// that fails (file size limit standing in for a full disk) gives a clear error and keeps the
// earlier results readable. Numerical trouble (NaN, overlap, energy rising without a source,
// particles leaving the domain) is reported with the particle and the likely cause. A soak run
// with continuous insertion and removal keeps its memory flat.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <cstdio>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "core/step.h"
#include "output/run.h"
#include "statistics/diagnostics.h"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const fs::path kScratch = fs::temp_directory_path() / ("demdesign_crash_" + std::to_string(::getpid()));

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// inlet_outlet.yaml with a checkpoint every 0.02 s of simulated time.
fs::path checkpoint_case() {
  fs::create_directories(kScratch);
  std::string text = read_text(fs::path(DEMDESIGN_SOURCE_DIR) / "cases/inlet_outlet.yaml");
  const std::string from = "output: {directory: out/inlet_outlet}";
  text.replace(text.find(from), from.size(), "output: {directory: out/crash_test, checkpoint_every: 0.02}");
  const fs::path path = kScratch / "case.yaml";
  std::ofstream(path) << text;
  return path;
}

/// Starts the demdesign binary with `args`, output to `log`; optional file size limit [bytes].
pid_t start(const std::vector<std::string>& args, const fs::path& log, rlim_t file_limit = 0) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, STDOUT_FILENO), ::dup2(fd, STDERR_FILENO);
    if (file_limit) {
      ::signal(SIGXFSZ, SIG_IGN);  // writes past the limit fail with EFBIG, as on a full disk
      const rlimit limit{file_limit, file_limit};
      ::setrlimit(RLIMIT_FSIZE, &limit);
    }
    std::vector<char*> argv{const_cast<char*>(DEMDESIGN_BINARY)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
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

std::string end_hash(const fs::path& out) {
  const std::string info = read_text(out / "run_info.yaml");
  const auto at = info.find("state_hash: ");
  return at == std::string::npos ? "" : info.substr(at + 12, 16);
}

std::vector<std::string> run_args(const fs::path& c, const fs::path& out) {
  return {c.string(), "--out", out.string(), "--threads", "1", "--quiet", "--no-report"};
}

TEST(KillAndResume, SigkillAtRandomMomentsThenResumeReachesTheSameState) {
  const fs::path c = checkpoint_case();
  const fs::path reference = kScratch / "reference";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(wait_exit(start(run_args(c, reference), kScratch / "reference.log")), 0) << read_text(kScratch / "reference.log");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string expected = end_hash(reference);
  ASSERT_EQ(expected.size(), 16u);
  // The run writes 30 checkpoints (0.6 s, one every 0.02 s). Each trial waits for a seeded random
  // number of them, then a seeded random part of one checkpoint interval, and kills: the moment is
  // random but always inside the run, however fast or slow the machine is at that moment.
  std::mt19937 random(20240901);
  int trials = 0, killed_mid_run = 0;
  for (int trial = 0; trial < 4; ++trial) {
    const fs::path out = kScratch / ("trial" + std::to_string(trial));
    const int checkpoints_before_kill = std::uniform_int_distribution<int>(1, 20)(random);
    const double part_of_interval = std::uniform_real_distribution<double>(0.0, 0.9)(random);
    const pid_t pid = start(run_args(c, out), kScratch / "trial.log");
    int seen = 0;
    ino_t last = 0;
    auto last_seen = std::chrono::steady_clock::now();
    double interval = 0.0;  // wall seconds between the last two checkpoints
    while (seen < checkpoints_before_kill && ::waitpid(pid, nullptr, WNOHANG) == 0) {
      struct stat info {};
      if (::stat((out / "checkpoint.bin").c_str(), &info) == 0 && info.st_ino != last) {
        last = info.st_ino;  // written atomically (a new file renamed over the old): a new inode
        const auto now = std::chrono::steady_clock::now();
        if (seen > 0) interval = std::chrono::duration<double>(now - last_seen).count();
        last_seen = now, ++seen;
      }
      std::this_thread::sleep_for(1ms);
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(part_of_interval * interval));
    const bool running = ::kill(pid, SIGKILL) == 0;
    const int status = wait_exit(pid);
    killed_mid_run += running && status == 128 + SIGKILL;
    auto args = run_args(c, out);
    args.push_back("--resume");
    ASSERT_EQ(wait_exit(start(args, kScratch / "resume.log")), 0) << read_text(kScratch / "resume.log");
    EXPECT_EQ(end_hash(out), expected) << "trial " << trial << ": " << read_text(kScratch / "resume.log");
    ++trials;
  }
  std::cout << trials << " kill-and-resume trials (" << killed_mid_run << " killed mid-run), uninterrupted run " << seconds
            << " s; every resumed run ended with state_hash " << expected << "\n";
  EXPECT_EQ(killed_mid_run, trials);
}

/// A soft 5 mm bead (short runs) and a measurement file of two drops and a poured cup.
fs::path calibration_files() {
  const fs::path dir = kScratch / "calibration";
  fs::create_directories(dir);
  std::ofstream(dir / "soft_beads.yaml") << R"(name: soft_beads
description: soft 5 mm beads for the calibration crash test
contact: {normal: hertz, damping: restitution, tangential: mindlin}
properties: {density: 2500, youngs_modulus: 1.0e6, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5}
size: 0.005
walls:
  steel: {friction: 0.5, restitution: 0.5}
tunable:
  friction: [0.2, 0.8]
)";
  std::ofstream(dir / "measurements.yaml") << R"(material: soft beads
particles: {diameter: 0.005, density: 2500}
walls:
  steel: {youngs_modulus: 2.0e11, poisson_ratio: 0.3, density: 7800}
experiments:
  - {id: drop_low, test: drop_rebound, setup: {drop_height: 0.02, plate: steel}, observed: {restitution: {value: 0.5, sigma: 0.02}}}
  - {id: drop_high, test: drop_rebound, setup: {drop_height: 0.1, plate: steel}, observed: {restitution: {value: 0.5, sigma: 0.02}}}
  - id: cup
    test: bulk_density
    setup: {cup_diameter: 0.05, cup_height: 0.04, pour_height: 0.02, base: steel}
    observed: {bulk_density: {value: 1500, sigma: 30}}
)";
  return dir;
}

/// The compared terms a `compare` printed (measured, simulated with its sigma, residual).
std::vector<std::string> term_lines(const fs::path& log) {
  std::vector<std::string> out;
  std::istringstream in(read_text(log));
  for (std::string line; std::getline(in, line);)
    if (line.find(" measured ") != std::string::npos && line.find(" residual ") != std::string::npos) out.push_back(line);
  return out;
}

// A compare killed with SIGKILL at seeded random moments and started again with the same command
// ends with the same numbers as an uninterrupted one, taking every simulation that finished
// before the kill from OUT/simulations/ instead of running it again.
TEST(KillAndResume, CalibrationCompareKilledThenRerunEndsWithTheSameNumbers) {
  const fs::path dir = calibration_files();
  auto args = [&](const fs::path& out) {
    return std::vector<std::string>{"compare", (dir / "soft_beads.yaml").string(), (dir / "measurements.yaml").string(), "--replicas", "2",
                                    "--out", out.string(), "--no-renders", "--quiet"};
  };
  const fs::path reference = kScratch / "compare_reference";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(wait_exit(start(args(reference), kScratch / "compare_reference.log")), 0) << read_text(kScratch / "compare_reference.log");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::vector<std::string> expected = term_lines(kScratch / "compare_reference.log");
  ASSERT_EQ(expected.size(), 3u) << read_text(kScratch / "compare_reference.log");
  EXPECT_EQ(std::distance(fs::directory_iterator(reference / "simulations"), fs::directory_iterator{}), 6) << "3 experiments x 2 replicas kept";
  std::mt19937 random(20261203);
  int killed_mid_run = 0, reused = 0;
  for (int trial = 0; trial < 3; ++trial) {
    const fs::path out = kScratch / ("compare_trial" + std::to_string(trial));
    // Kill once a seeded random number (1 to 4) of the 6 simulations is kept, a seeded random
    // few milliseconds later: inside the run however loaded the machine is.
    const int kept_before_kill = std::uniform_int_distribution<int>(1, 4)(random);
    const auto extra = std::chrono::milliseconds(std::uniform_int_distribution<int>(0, 50)(random));
    const pid_t pid = start(args(out), kScratch / "compare_trial.log");
    const auto kept_now = [&] {
      std::error_code ec;
      long n = 0;  // kept simulations, not the .part files being written
      for (const auto& f : fs::directory_iterator(out / "simulations", ec)) n += f.path().extension() != ".part";
      return n;
    };
    while (kept_now() < kept_before_kill && ::waitpid(pid, nullptr, WNOHANG) == 0) std::this_thread::sleep_for(1ms);
    std::this_thread::sleep_for(extra);
    const bool running = ::kill(pid, SIGKILL) == 0;
    killed_mid_run += running && wait_exit(pid) == 128 + SIGKILL;
    const auto kept = fs::exists(out / "simulations") ? std::distance(fs::directory_iterator(out / "simulations"), fs::directory_iterator{}) : 0;
    reused += kept > 0;
    ASSERT_EQ(wait_exit(start(args(out), kScratch / "compare_rerun.log")), 0) << read_text(kScratch / "compare_rerun.log");
    EXPECT_EQ(term_lines(kScratch / "compare_rerun.log"), expected) << "trial " << trial << ", " << kept << " simulations kept before the kill";
  }
  std::cout << killed_mid_run << " of 3 compares killed mid-run, " << reused << " reran with kept simulations; uninterrupted " << seconds << " s\n";
  EXPECT_EQ(killed_mid_run, 3);
  EXPECT_EQ(reused, 3);
  // A second compare in a folder that holds every simulation runs none of them again (no kept
  // file is written anew).
  std::map<std::string, fs::file_time_type> written;
  for (const auto& f : fs::directory_iterator(reference / "simulations")) written[f.path().string()] = f.last_write_time();
  ASSERT_EQ(wait_exit(start(args(reference), kScratch / "compare_again.log")), 0);
  EXPECT_EQ(term_lines(kScratch / "compare_again.log"), expected);
  for (const auto& f : fs::directory_iterator(reference / "simulations")) EXPECT_EQ(written.at(f.path().string()), f.last_write_time()) << f.path();
}

/// ledger.yaml without its `time:` lines (when each version was written).
std::string ledger_without_times(const fs::path& path) {
  std::istringstream in(read_text(path));
  std::string out;
  for (std::string line; std::getline(in, line);)
    if (line.find("time: ") == std::string::npos) out += line + "\n";
  return out;
}

/// Names and write times of the kept simulations in `folder` (not the .part files being written).
std::map<std::string, fs::file_time_type> kept_simulations(const fs::path& folder) {
  std::map<std::string, fs::file_time_type> kept;
  std::error_code ec;
  for (const auto& f : fs::directory_iterator(folder, ec))
    if (f.path().extension() != ".part") kept[f.path().filename().string()] = f.last_write_time();
  return kept;
}

// A diagnosis of the shipped wet glass beads measurements (cases/calibration/), with few
// design points so that it takes minutes, killed with SIGKILL after a seeded random number of
// kept simulations and started again with the same command, writes the same ledger as an
// uninterrupted one (every version, parameter and residual; only the times differ) and runs
// none of the kept simulations again. Label long (a few minutes on 2 cores):
// `ctest --test-dir build -L long -R Diagnose`.
TEST(KillAndResumeLong, DiagnoseOfAShippedFileKilledThenRerunWritesTheSameLedger) {
  const fs::path source(DEMDESIGN_SOURCE_DIR);
  auto args = [&](const fs::path& out) {
    return std::vector<std::string>{"diagnose", (source / "materials/glass_beads.yaml").string(),
                                    (source / "cases/calibration/wet_glass_beads_measurements.yaml").string(),
                                    "--params", "friction", "--stiffness-scaling", "1e-5", "--replicas", "1", "--rounds", "1",
                                    "--design-factor", "0.5", "--confirm", "1", "--effects", "liquid_bridge,jkr",
                                    "--parallel", "2", "--no-renders", "--out", out.string()};
  };
  const fs::path reference = kScratch / "diagnose_reference";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(wait_exit(start(args(reference), kScratch / "diagnose_reference.log")), 0) << read_text(kScratch / "diagnose_reference.log");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string expected = ledger_without_times(reference / "ledger.yaml");
  ASSERT_NE(expected.find("version: 3"), std::string::npos) << "start, calibrated and at least one candidate:\n" << expected;
  const auto all = kept_simulations(reference / "simulations");
  ASSERT_GE(all.size(), 20u);

  std::mt19937 random(20261203);
  const fs::path out = kScratch / "diagnose_trial";
  const auto kept_before_kill = std::uniform_int_distribution<size_t>(all.size() / 4, 3 * all.size() / 4)(random);
  const pid_t pid = start(args(out), kScratch / "diagnose_trial.log");
  while (kept_simulations(out / "simulations").size() < kept_before_kill && ::waitpid(pid, nullptr, WNOHANG) == 0) std::this_thread::sleep_for(5ms);
  ASSERT_EQ(::kill(pid, SIGKILL), 0);
  ASSERT_EQ(wait_exit(pid), 128 + SIGKILL) << "killed mid-run";
  EXPECT_FALSE(fs::exists(out / "ledger.yaml")) << "the ledger is written at the end";
  const auto before = kept_simulations(out / "simulations");

  const auto t1 = std::chrono::steady_clock::now();
  ASSERT_EQ(wait_exit(start(args(out), kScratch / "diagnose_rerun.log")), 0) << read_text(kScratch / "diagnose_rerun.log");
  const double rerun_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  EXPECT_EQ(ledger_without_times(out / "ledger.yaml"), expected);
  const auto after = kept_simulations(out / "simulations");
  for (const auto& [name, time] : before) {
    ASSERT_TRUE(after.count(name)) << name;
    EXPECT_EQ(after.at(name), time) << name << ": a kept simulation was run and written again";
  }
  EXPECT_EQ(after.size(), all.size());
  // The rerun says so: one "stored" progress line per kept simulation it took.
  std::istringstream log(read_text(kScratch / "diagnose_rerun.log"));
  size_t stored_lines = 0;
  for (std::string line; std::getline(log, line);) stored_lines += line.find(" done (") != std::string::npos && line.find(", stored") != std::string::npos;
  EXPECT_GE(stored_lines, before.size());
  std::cout << "diagnose: uninterrupted " << seconds << " s, " << all.size() << " simulations; killed after " << before.size()
            << " kept; the rerun took " << stored_lines << " from the store and ran the other " << after.size() - before.size() << " in "
            << rerun_seconds << " s; same ledger\n";
}

#ifdef DEMDESIGN_MPIEXEC
/// Starts `mpirun -np ranks demdesign args` in a process group of its own (killing the group
/// kills every rank at once, as a node failure would), output to `log`.
pid_t start_ranks(int ranks, const std::vector<std::string>& args, const fs::path& log) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setpgid(0, 0);
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, STDOUT_FILENO), ::dup2(fd, STDERR_FILENO);
    for (const char* v : {"OMPI_ALLOW_RUN_AS_ROOT", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM"}) ::setenv(v, "1", 1);
    ::setenv("OMP_NUM_THREADS", "1", 1), ::setenv("OMP_WAIT_POLICY", "passive", 1);
    std::vector<std::string> all{DEMDESIGN_MPIEXEC, "-np", std::to_string(ranks), "--oversubscribe", DEMDESIGN_BINARY};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(DEMDESIGN_MPIEXEC, argv.data());
    ::_exit(127);
  }
  ::setpgid(pid, pid);
  return pid;
}

/// Kills a job started by start_ranks() as a batch system or the OOM killer would: mpirun's
/// process group and every rank it started (Open MPI puts its ranks in process groups of their
/// own, so they outlive a killed mpirun and go on writing OUT). Returns whether mpirun was running.
bool kill_job(pid_t pid, const fs::path& out) {
  const bool running = ::kill(-pid, SIGKILL) == 0;
  std::vector<pid_t> ranks;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "cmdline", std::ios::binary);
    std::vector<std::string> argv;
    for (std::string arg; std::getline(in, arg, '\0');) argv.push_back(arg);
    if (!argv.empty() && argv[0] == DEMDESIGN_BINARY && std::find(argv.begin(), argv.end(), out.string()) != argv.end())
      ranks.push_back(static_cast<pid_t>(std::stol(name)));
  }
  for (const pid_t rank : ranks) ::kill(rank, SIGKILL);
  // A killed process closes its files (and so releases its lock on OUT) before it disappears.
  for (const pid_t rank : ranks)
    for (int i = 0; i < 1000 && ::kill(rank, 0) == 0; ++i) {
      std::ifstream status("/proc/" + std::to_string(rank) + "/status");
      std::string line;
      bool zombie = false;
      while (std::getline(status, line))
        if (line.rfind("State:", 0) == 0) zombie = line.find('Z') != std::string::npos;
      if (zombie) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  return running;
}

/// The last row of OUT/scalars.csv by column name.
std::map<std::string, double> last_scalars(const fs::path& out) {
  std::istringstream in(read_text(out / "scalars.csv"));
  std::string header, line, last;
  std::getline(in, header);
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  std::map<std::string, double> row;
  std::istringstream names(header), values(last);
  for (std::string name, value; std::getline(names, name, ',') && std::getline(values, value, ',');) row[name] = std::stod(value);
  return row;
}

std::string end_line(const fs::path& out, const std::string& key) {
  const std::string info = read_text(out / "run_info.yaml");
  const auto at = info.find("  " + key + ": ", info.find("end:"));
  return at == std::string::npos ? "" : info.substr(at, info.find('\n', at) - at);
}

// A run split over 4 ranks is killed with SIGKILL (every rank at once) at a seeded random moment
// after a seeded number of per-rank checkpoints, and resumed on 4 ranks and on 2. The resumed run
// cuts its boxes again from the particles it reads, so its forces are summed in another order
// than the uninterrupted run's: the two agree to round-off at the checkpoint, and the flow off
// the plate then scatters them as two runs of one case on different rank counts scatter. The
// resumed run ends at the uninterrupted run's step and time; the mass inserted (the inlet's
// random stream is part of the checkpoint) agrees within 1 %, the mass the outlet removed and the
// particles left on the plate within 10 %.
TEST(KillAndResume, SplitRunKilledOnFourRanksResumesOnFourAndOnTwo) {
  const fs::path c = checkpoint_case();
  const fs::path reference = kScratch / "split_reference";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(wait_exit(start_ranks(4, run_args(c, reference), kScratch / "split_reference.log")), 0) << read_text(kScratch / "split_reference.log");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(fs::exists(reference / "checkpoint.ranks.bin"));
  EXPECT_FALSE(fs::exists(reference / "checkpoint.bin")) << "no rank gathers the state for a checkpoint";
  const std::map<std::string, double> expected = last_scalars(reference);
  std::mt19937 random(20261205);
  for (const int resume_on : {4, 2}) {
    const fs::path out = kScratch / ("split_trial" + std::to_string(resume_on));
    const int checkpoints_before_kill = std::uniform_int_distribution<int>(2, 20)(random);
    const double part_of_interval = std::uniform_real_distribution<double>(0.0, 0.9)(random);
    const pid_t pid = start_ranks(4, run_args(c, out), kScratch / "split_trial.log");
    int seen = 0;
    ino_t last = 0;
    auto last_seen = std::chrono::steady_clock::now();
    double interval = 0.0;
    while (seen < checkpoints_before_kill && ::waitpid(pid, nullptr, WNOHANG) == 0) {
      struct stat info {};
      if (::stat((out / "checkpoint.ranks.bin").c_str(), &info) == 0 && info.st_ino != last) {
        last = info.st_ino;
        const auto now = std::chrono::steady_clock::now();
        if (seen > 0) interval = std::chrono::duration<double>(now - last_seen).count();
        last_seen = now, ++seen;
      }
      std::this_thread::sleep_for(1ms);
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(part_of_interval * interval));
    const bool running = kill_job(pid, out);
    const int status = wait_exit(pid);
    EXPECT_TRUE(running && status == 128 + SIGKILL) << "the run ended before the kill: " << read_text(kScratch / "split_trial.log");
    auto args = run_args(c, out);
    args.push_back("--resume");
    const fs::path log = kScratch / ("split_resume" + std::to_string(resume_on) + ".log");
    ASSERT_EQ(wait_exit(start_ranks(resume_on, args, log)), 0) << read_text(log);
    EXPECT_NE(read_text(log).find("and the shares of 4 ranks"), std::string::npos) << read_text(log);
    for (const std::string key : {"completed", "step", "time_s"}) EXPECT_EQ(end_line(out, key), end_line(reference, key)) << key;
    const std::map<std::string, double> got = last_scalars(out);
    std::printf("killed after %d checkpoints, resumed on %d ranks: particles %.0f (uninterrupted %.0f), inserted %.6g kg (%.6g), "
                "removed %.6g kg (%.6g), kinetic %.4g J (%.4g)\n",
                checkpoints_before_kill, resume_on, got.at("particles"), expected.at("particles"), got.at("inserted_mass_kg"),
                expected.at("inserted_mass_kg"), got.at("removed_mass_kg"), expected.at("removed_mass_kg"), got.at("kinetic_translation_J"),
                expected.at("kinetic_translation_J"));
    EXPECT_NEAR(got.at("inserted_mass_kg"), expected.at("inserted_mass_kg"), 0.01 * expected.at("inserted_mass_kg"));
    EXPECT_NEAR(got.at("removed_mass_kg"), expected.at("removed_mass_kg"), 0.1 * expected.at("removed_mass_kg"));
    EXPECT_NEAR(got.at("particles"), expected.at("particles"), 0.1 * expected.at("particles"));
  }
  std::printf("uninterrupted run on 4 ranks: %.1f s\n", seconds);
}
#endif

TEST(KillAndResume, SigtermWritesACheckpointAndExitsCleanly) {
  const fs::path c = checkpoint_case();
  const fs::path out = kScratch / "sigterm";
  const pid_t pid = start(run_args(c, out), kScratch / "sigterm.log");
  while (!fs::exists(out / "checkpoint.bin") && ::waitpid(pid, nullptr, WNOHANG) == 0) std::this_thread::sleep_for(2ms);
  std::this_thread::sleep_for(100ms);
  ::kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(pid), 0);
  const std::string log = read_text(kScratch / "sigterm.log");
  if (log.find("stopped by signal 15") == std::string::npos) GTEST_SKIP() << "the run ended before the signal";
  EXPECT_NE(read_text(out / "run_info.yaml").find("completed: false"), std::string::npos);
  EXPECT_NE(read_text(out / "scalars.csv").find("time_s,step"), std::string::npos);
  auto args = run_args(c, out);
  args.push_back("--resume");
  ASSERT_EQ(wait_exit(start(args, kScratch / "sigterm_resume.log")), 0) << read_text(kScratch / "sigterm_resume.log");
  EXPECT_NE(read_text(out / "run_info.yaml").find("completed: true"), std::string::npos);
}

// A default run (no checkpoint_every) killed with SIGKILL keeps its rows: scalars.csv is saved
// whole every output.rows_seconds (5 s) of wall time, so the rows on disk are the run's own rows,
// exactly, up to a save at most rows_seconds before the kill. The reference run to the last
// saved row's time gives the same rows bit for bit (one thread: deterministic).
TEST(KillKeepsRows, SigkillOfADefaultRunKeepsItsRowsUpToTheLastSave) {
  fs::create_directories(kScratch);
  std::string text = read_text(fs::path(DEMDESIGN_SOURCE_DIR) / "cases/inlet_outlet.yaml");
  const std::string from = "output: {directory: out/inlet_outlet}";
  text.replace(text.find(from), from.size(), "output: {directory: out/rows_test, scalars_every: 200}");
  const fs::path c = kScratch / "rows_case.yaml";
  std::ofstream(c) << text;
  const fs::path out = kScratch / "rows_killed";
  auto args = run_args(c, out);
  args.insert(args.end(), {"--duration", "60"});
  const pid_t pid = start(args, kScratch / "rows_killed.log");
  // The first save comes after 5 s of wall time; then a seeded random moment within the next save interval.
  while (!fs::exists(out / "scalars.csv") && ::waitpid(pid, nullptr, WNOHANG) == 0) std::this_thread::sleep_for(5ms);
  std::mt19937 random(20261206);
  std::this_thread::sleep_for(std::chrono::duration<double>(std::uniform_real_distribution<double>(0.2, 6.0)(random)));
  const auto saved = fs::last_write_time(out / "scalars.csv");
  const bool running = ::kill(pid, SIGKILL) == 0;
  const auto killed = fs::file_time_type::clock::now();
  ASSERT_TRUE(running && wait_exit(pid) == 128 + SIGKILL) << "the run ended before the kill: " << read_text(kScratch / "rows_killed.log");
  const double since_save = std::chrono::duration<double>(killed - std::max(saved, fs::last_write_time(out / "scalars.csv"))).count();
  const std::string kept = read_text(out / "scalars.csv");
  ASSERT_EQ(kept.rfind("time_s,step", 0), 0u) << kept.substr(0, 200);
  ASSERT_EQ(kept.back(), '\n') << "a torn row";
  std::vector<std::string> rows;
  std::istringstream lines(kept);
  for (std::string line; std::getline(lines, line);) rows.push_back(line);
  ASSERT_GE(rows.size(), 3u) << "the header and at least two rows";
  const std::string last_time = rows.back().substr(0, rows.back().find(','));
  // The same run to the last kept row's time: the same rows.
  const fs::path reference = kScratch / "rows_reference";
  auto reference_args = run_args(c, reference);
  reference_args.insert(reference_args.end(), {"--duration", last_time});
  ASSERT_EQ(wait_exit(start(reference_args, kScratch / "rows_reference.log")), 0) << read_text(kScratch / "rows_reference.log");
  std::istringstream expected(read_text(reference / "scalars.csv"));
  size_t same = 0;
  for (std::string line; std::getline(expected, line) && same < rows.size() && line == rows[same];) ++same;
  EXPECT_GE(same + 1, rows.size()) << "row " << same << " differs: " << rows[std::min(same, rows.size() - 1)];
  std::printf("killed %.2f s after the last save of scalars.csv (rows_seconds 5): %zu rows kept, to t = %s s, equal to the reference's\n",
              since_save, rows.size() - 1, last_time.c_str());
  EXPECT_LE(since_save, 5.0 + 1.5) << "the rows were saved less often than output.rows_seconds";
}

// Without checkpoint_every, checkpoints come on the wall clock (output.checkpoint_seconds, 600 s
// by default; here an eighth of the run): a run killed after one continues with --resume to the
// uninterrupted run's final state, bit for bit.
TEST(KillAndResume, WallClockCheckpointsLetAKilledRunWithoutCheckpointEveryResume) {
  fs::create_directories(kScratch);
  const std::string text = read_text(fs::path(DEMDESIGN_SOURCE_DIR) / "cases/inlet_outlet.yaml");
  const std::string from = "output: {directory: out/inlet_outlet}";
  const auto write_case = [&](const fs::path& path, double seconds) {
    std::string t = text;
    t.replace(t.find(from), from.size(), "output: {directory: out/wall_clock, checkpoint_seconds: " + std::to_string(seconds) + "}");
    std::ofstream(path) << t;
  };
  const fs::path c = kScratch / "wall_clock.yaml";
  write_case(c, 0);
  const fs::path reference = kScratch / "wall_clock_reference";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(wait_exit(start(run_args(c, reference), kScratch / "wall_clock_reference.log")), 0) << read_text(kScratch / "wall_clock_reference.log");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_FALSE(fs::exists(reference / "checkpoint.bin")) << "checkpoint_seconds: 0 writes none";
  write_case(c, std::max(0.02, seconds / 8));
  const fs::path out = kScratch / "wall_clock_trial";
  const pid_t pid = start(run_args(c, out), kScratch / "wall_clock_trial.log");
  while (!fs::exists(out / "checkpoint.bin") && ::waitpid(pid, nullptr, WNOHANG) == 0) std::this_thread::sleep_for(1ms);
  const bool running = ::kill(pid, SIGKILL) == 0;
  ASSERT_TRUE(running && wait_exit(pid) == 128 + SIGKILL) << "the run ended before its first checkpoint: " << read_text(kScratch / "wall_clock_trial.log");
  auto args = run_args(c, out);
  args.push_back("--resume");
  ASSERT_EQ(wait_exit(start(args, kScratch / "wall_clock_resume.log")), 0) << read_text(kScratch / "wall_clock_resume.log");
  EXPECT_EQ(end_hash(out), end_hash(reference)) << read_text(kScratch / "wall_clock_resume.log");
}

TEST(FullDisk, AFailedWriteIsAClearErrorAndEarlierResultsStayReadable) {
  // Every row of scalars (about 9000 steps a second); scalars.csv outgrows 256 kB mid-run, like a disk filling up.
  std::string text = read_text(checkpoint_case());
  text.replace(text.find("checkpoint_every: 0.02}"), 23, "checkpoint_every: 0.02, scalars_every: 1}");
  const fs::path c = kScratch / "full_disk.yaml";
  std::ofstream(c) << text;
  const fs::path out = kScratch / "full_disk";
  const int status = wait_exit(start(run_args(c, out), kScratch / "full_disk.log", 256 * 1024));
  const std::string log = read_text(kScratch / "full_disk.log");
  EXPECT_EQ(status, 1) << log;
  EXPECT_NE(log.find("cannot write"), std::string::npos) << log;
  EXPECT_NE(log.find("is kept"), std::string::npos) << log;
  // What was written before is whole: the last scalars.csv and checkpoint, no half-written files.
  const std::string csv = read_text(out / "scalars.csv");
  EXPECT_EQ(csv.rfind("time_s,step", 0), 0u);
  EXPECT_EQ(csv.back(), '\n');
  EXPECT_TRUE(fs::exists(out / "checkpoint.bin"));
  for (const auto& entry : fs::recursive_directory_iterator(out)) EXPECT_NE(entry.path().extension(), ".part") << entry.path();
}

// ---- numerical trouble, in process ----

std::string base_case(const std::string& particles, const std::string& simulation_extra = "") {
  return "simulation: {duration: 0.02, gravity: [0, 0, 0]" + simulation_extra + "}\n"
         "materials:\n  glass: {density: 2500, youngs_modulus: 5.0e7, restitution: 0.9, friction: 0.3}\n"
         "particles:\n" + particles;
}

std::string run_and_catch(const std::string& text, std::string* log_out = nullptr) {
  const dem::Model model = dem::compile(dem::parse_case_text(text));
  dem::State state = dem::initial_state(model);
  dem::Workspace work;
  dem::RunOptions options;
  options.write_files = false;
  options.progress = false;
  std::ostringstream log;
  try {
    dem::run(model, state, work, options, log);
  } catch (const dem::NumericalError& e) {
    if (log_out) *log_out = log.str();
    return e.what();
  }
  if (log_out) *log_out = log.str();
  return "";
}

TEST(NumericalTrouble, OverlapBeyondTheLimitNamesBothParticles) {
  // 60 % of the radius at the start: beyond the 50 % limit.
  const std::string e = run_and_catch(base_case("  - {material: glass, diameter: 0.01, positions: [[0, 0, 0], [0.007, 0, 0]]}\n"));
  EXPECT_NE(e.find("particles 0 and 1 overlap by 60 %"), std::string::npos) << e;
  EXPECT_NE(e.find("Likely causes"), std::string::npos) << e;
}

TEST(NumericalTrouble, EnergyRisingWithoutASourceIsCaught) {
  // 30 % overlap (within the overlap limit) at rest: the contact pushes them apart, from nothing.
  const std::string e = run_and_catch(base_case("  - {material: glass, diameter: 0.01, positions: [[0, 0, 0], [0.0085, 0, 0]]}\n"));
  EXPECT_NE(e.find("the energy (kinetic + gravitational) rose"), std::string::npos) << e;
  EXPECT_NE(e.find("fastest particle is"), std::string::npos) << e;
  EXPECT_NE(e.find("time step"), std::string::npos) << e;
  // With `numerical_trouble: warn` the run goes on and says so.
  std::string log;
  EXPECT_EQ(run_and_catch(base_case("  - {material: glass, diameter: 0.01, positions: [[0, 0, 0], [0.0085, 0, 0]]}\n",
                                    ", numerical_trouble: warn"),
                          &log),
            "");
  EXPECT_NE(log.find("WARNING (numerical_trouble: warn"), std::string::npos) << log;
  // A clean elastic collision is not flagged (elastic energy is given back on rebound).
  EXPECT_EQ(run_and_catch(base_case("  - {material: glass, diameter: 0.01, positions: [[0, 0, 0]], velocity: [1, 0, 0]}\n"
                                    "  - {material: glass, diameter: 0.01, positions: [[0.0105, 0, 0]], velocity: [-1, 0, 0]}\n")),
            "");
}

// A run stopped by numerical trouble keeps what it computed and says why: the rows so far, and a
// run record whose end block says it did not complete and why (the report's banner reads it).
TEST(NumericalTrouble, AStoppedRunKeepsItsRowsAndItsRecordSaysWhy) {
  const dem::Model model = dem::compile(
      dem::parse_case_text(base_case("  - {material: glass, diameter: 0.01, positions: [[0, 0, 0], [0.0085, 0, 0]]}\n")));
  dem::State state = dem::initial_state(model);
  dem::Workspace work;
  dem::RunOptions options;
  options.output_directory = (kScratch / "stopped").string();
  options.progress = false;
  std::ostringstream log;
  try {
    dem::run(model, state, work, options, log);
    FAIL() << "the energy rise should stop the run";
  } catch (const dem::RunStopped& e) {
    EXPECT_NE(e.summary.stopped.find("numerical trouble: "), std::string::npos) << e.summary.stopped;
    EXPECT_NE(e.summary.stopped.find("the energy (kinetic + gravitational) rose"), std::string::npos) << e.summary.stopped;
    EXPECT_FALSE(e.summary.scalars.empty());
  }
  const std::string info = read_text(kScratch / "stopped" / "run_info.yaml");
  EXPECT_NE(info.find("completed: false"), std::string::npos) << info;
  EXPECT_NE(info.find("stopped: \"numerical trouble: "), std::string::npos) << info;
  EXPECT_EQ(read_text(kScratch / "stopped" / "scalars.csv").rfind("time_s,step", 0), 0u);
}

// The same through the program: the report of what was computed, under a banner that says why.
TEST(NumericalTrouble, AStoppedRunsReportSaysWhy) {
  fs::create_directories(kScratch);
  const fs::path c = kScratch / "stopped_case.yaml";
  std::ofstream(c) << base_case("  - {material: glass, diameter: 0.01, positions: [[0, 0, 0], [0.0085, 0, 0]]}\n");
  const fs::path out = kScratch / "stopped_binary";
  const int status = wait_exit(start({c.string(), "--out", out.string(), "--threads", "1", "--quiet"}, kScratch / "stopped_binary.log"));
  const std::string log = read_text(kScratch / "stopped_binary.log");
  EXPECT_NE(status, 0) << log;
  EXPECT_NE(log.find("the energy (kinetic + gravitational) rose"), std::string::npos) << log;
  const std::string html = read_text(out / "report" / "report.html");
  EXPECT_NE(html.find("The run stopped before its end"), std::string::npos) << log;
  EXPECT_NE(html.find("numerical trouble: "), std::string::npos);
}

TEST(NumericalTrouble, BlowUpFromATooLargeTimeStepIsCaughtWithTheCause) {
  const std::string e = run_and_catch(
      base_case("  - {material: glass, diameter: 0.01, count: 100, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}, velocity: [0, 0, -2]}\n",
                ", time_step: 1.0e-3, unsafe_time_step: warn, domain: {min: [-1, -1, -1], max: [1, 1, 1]}") +
      "walls:\n  - {name: floor, material: glass, plane: {point: [0, 0, -0.001], normal: [0, 0, 1]}}\n");
  EXPECT_FALSE(e.empty());
  EXPECT_NE(e.find("Likely cause"), std::string::npos) << e;
  EXPECT_NE(e.find("time step"), std::string::npos) << e;
}

TEST(NumericalTrouble, ParticlesLeavingTheDomainAreNamed) {
  std::string log;
  EXPECT_EQ(run_and_catch(base_case("  - {material: glass, diameter: 0.01, positions: [[0, 0, 0]], velocity: [10, 0, 0]}\n",
                                    ", domain: {min: [-0.1, -0.1, -0.1], max: [0.1, 0.1, 0.1]}"),
                          &log),
            "");
  EXPECT_NE(log.find("1 particles have left the domain"), std::string::npos) << log;
  EXPECT_NE(log.find("particle 0, at [0.1"), std::string::npos) << log;
}

// ---- soak: continuous insertion and removal, memory flat ----

long rss_kb() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  statm >> size >> resident;
  return resident * (::sysconf(_SC_PAGESIZE) / 1024);
}

TEST(Soak, InletAndOutletForManyStepsKeepMemoryFlat) {
  // The inlet_outlet case with a wider outlet: feeds at 1.8 t/h and removes what reaches x > 0.12.
  std::string text = read_text(fs::path(DEMDESIGN_SOURCE_DIR) / "cases/inlet_outlet.yaml");
  text.replace(text.find("{min: [0.3, -0.1, -0.3]"), 23, "{min: [0.12, -0.1, -0.3]");
  const dem::Model model = dem::compile(dem::parse_case_text(text, (fs::path(DEMDESIGN_SOURCE_DIR) / "cases/x.yaml").string()));
  dem::State state = dem::initial_state(model);
  dem::Workspace work;
  dem::prepare(model, state, work);
  const double seconds = std::getenv("DEMDESIGN_SOAK_SECONDS") ? std::atof(std::getenv("DEMDESIGN_SOAK_SECONDS")) : 4.0;
  const std::int64_t steps = static_cast<std::int64_t>(seconds / model.dt);
  long warm = 0, peak = 0;
  size_t particles_min = SIZE_MAX, particles_max = 0;
  for (std::int64_t k = 1; k <= steps; ++k) {
    dem::step(model, state, work);
    if (k % 2000 == 0) {
      const long rss = rss_kb();
      if (k >= steps / 4) {
        if (!warm) warm = rss;
        peak = std::max(peak, rss);
        particles_min = std::min(particles_min, state.size()), particles_max = std::max(particles_max, state.size());
      }
    }
  }
  const auto& in = state.inlets[0];
  const auto& out = state.outlets[0];
  std::cout << "soak: " << steps << " steps (" << seconds << " s simulated), " << in.inserted << " particles inserted, "
            << out.removed << " removed, " << particles_min << "-" << particles_max << " alive after the first quarter; RSS "
            << warm << " kB after the first quarter, peak " << peak << " kB later (drift " << peak - warm << " kB)\n";
  EXPECT_GT(out.removed, 1000);
  EXPECT_LT(peak - warm, 4096) << "memory grows with insertions and removals";
}

}  // namespace
