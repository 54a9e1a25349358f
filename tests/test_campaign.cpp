// Campaigns over MPI ranks (app/campaign/mpi_campaign.h): the tiny sweep of tests/data/campaign_sweep.yaml
// run by the real binary, once alone and once under `mpirun -np 2`. The variants' metrics.csv
// and final state hashes must be bitwise equal, both ranks must have run variants, the variant
// made to fail (a negative feed rate) must be reported in the sweep report while the others
// complete, and the ranking must be the same.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;

const fs::path kScratch = fs::temp_directory_path() / ("demdesign_campaign_" + std::to_string(::getpid()));
const std::string kCase = DEMDESIGN_SOURCE_DIR "/tests/data/campaign_sweep.yaml";

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Finished {
  int status = -1;
  double seconds = 0;
  std::string output;
};

/// Runs `args` (args[0] found on the PATH or given as a path) with stdout and stderr in `log`;
/// no shell. The environment gets the variables OpenMPI's mpirun needs when run as root.
Finished run(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<std::string> environment;
  for (char** e = environ; *e; ++e) environment.emplace_back(*e);
  environment.insert(environment.end(), {"OMPI_ALLOW_RUN_AS_ROOT=1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1", "OMP_NUM_THREADS=1",
                                         "OMP_WAIT_POLICY=passive"});
  std::vector<char*> envp, argv;
  for (auto& e : environment) envp.push_back(e.data());
  envp.push_back(nullptr);
  std::vector<std::string> copy = args;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
  const auto t0 = std::chrono::steady_clock::now();
  pid_t pid = 0;
  Finished f;
  const int err = posix_spawnp(&pid, argv[0], &files, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&files);
  if (err != 0) {
    f.output = "could not start " + args[0];
    return f;
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  f.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  f.output = read_text(log);
  return f;
}

/// The `ranking:` lines a sweep prints at its end.
std::string ranking(const std::string& output) {
  const size_t at = output.find("ranking:\n");
  if (at == std::string::npos) return "";
  std::string out;
  std::istringstream lines(output.substr(at));
  std::getline(lines, out);
  // "  1. v03 (...) score 1.000": ends at the first other line (mpirun's own messages follow).
  for (std::string line; std::getline(lines, line) && line.size() > 3 && line.rfind("  ", 0) == 0 && std::isdigit(line[2]);) out += "\n" + line;
  return out;
}

/// `state_hash: ...` from a run's run_info.yaml.
std::string state_hash(const fs::path& out) {
  const std::string info = read_text(out / "run_info.yaml");
  const size_t at = info.find("state_hash");
  return at == std::string::npos ? "" : info.substr(at, info.find_first_of("}\n", at) - at);
}

TEST(Campaign, SweepUnderMpirunEqualsSerialAndReportsTheFailedVariant) {
  fs::remove_all(kScratch);
  fs::create_directories(kScratch);
  const fs::path serial = kScratch / "serial", shared = kScratch / "mpi";
  const Finished alone = run({DEMDESIGN_BINARY, kCase, "--out", serial.string(), "--quiet"}, kScratch / "serial.log");
  const Finished ranks = run({DEMDESIGN_MPIEXEC, "-np", "2", "--oversubscribe", "--allow-run-as-root", DEMDESIGN_BINARY, kCase, "--out",
                              shared.string(), "--quiet"},
                             kScratch / "mpi.log");
  std::printf("campaign of 4 variants: serial %.1f s, mpirun -np 2 %.1f s\n", alone.seconds, ranks.seconds);
  // A failed variant makes the exit status 1, not a crash or an abort.
  EXPECT_EQ(alone.status, 1) << alone.output;
  EXPECT_EQ(ranks.status, 1) << ranks.output;

  // Both ranks ran variants (handed out by rank 0 as slots free up), each variant exactly once.
  EXPECT_NE(ranks.output.find("over 2 MPI ranks"), std::string::npos) << ranks.output;
  int by_rank[2] = {0, 0};
  for (const std::string v : {"v01", "v02", "v03", "v04"}) {
    int runs = 0;
    for (int r = 0; r < 2; ++r)
      if (ranks.output.find("rank " + std::to_string(r) + ":   " + v + " started") != std::string::npos) ++runs, ++by_rank[r];
    EXPECT_EQ(runs, 1) << v << ":\n" << ranks.output;
  }
  EXPECT_GE(by_rank[0], 1) << ranks.output;
  EXPECT_GE(by_rank[1], 1) << ranks.output;
  EXPECT_EQ(alone.output.find("rank "), std::string::npos) << "a plain run knows nothing of ranks:\n" << alone.output;

  // The completed variants: metrics.csv and the final state bitwise equal.
  for (const std::string v : {"v01", "v02", "v03"}) {
    const fs::path a = serial / "variants" / v, b = shared / "variants" / v;
    const std::string metrics = read_text(a / "report/metrics.csv");
    ASSERT_NE(metrics.find("holdup_kg,"), std::string::npos) << v << " has no metrics:\n" << read_text(a / "log.txt");
    EXPECT_EQ(metrics, read_text(b / "report/metrics.csv")) << v;
    EXPECT_FALSE(state_hash(a).empty()) << v;
    EXPECT_EQ(state_hash(a), state_hash(b)) << v;
  }
  // The variants differ from one another (so equal files mean equal simulations, not empty ones).
  EXPECT_NE(read_text(serial / "variants/v01/report/metrics.csv"), read_text(serial / "variants/v03/report/metrics.csv"));

  // The failed variant: no metrics, its error in the log and in the sweep report of both runs.
  for (const fs::path& out : {serial, shared}) {
    EXPECT_FALSE(fs::exists(out / "variants/v04/report/metrics.csv")) << out;
    EXPECT_NE(read_text(out / "variants/v04/log.txt").find("mass_rate_tph"), std::string::npos) << out;
    const std::string html = read_text(out / "report/sweep.html");
    ASSERT_FALSE(html.empty()) << out << ": no sweep report";
    EXPECT_NE(html.find("mass_rate_tph: -1"), std::string::npos) << out << ": the failure is not in the report";
  }
  // The same ranking, scores included.
  const std::string order = ranking(alone.output);
  EXPECT_NE(order.find("1. v03"), std::string::npos) << alone.output;
  EXPECT_EQ(order, ranking(ranks.output)) << ranks.output;
  if (!HasFailure()) fs::remove_all(kScratch);
}

}  // namespace
