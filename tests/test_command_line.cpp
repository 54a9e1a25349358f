// The command line fuzzed: seeded random argument vectors (commands, options, hostile values:
// nan, inf, -1, 1e300, empty, words) given to the real demdesign binary. Every one gets an
// answer, exit status 0 (help, a listing) or 2 (a usage or input error, said on standard error;
// check-mesh: 1 for a mesh that is not simulable),
// within seconds: never a crash, a hang, or a run started on a value that was not valid. Files
// named in the vectors do not exist, so no vector can start a simulation.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;

/// Runs demdesign with `args` in `cwd`, output discarded; exit status, or 128 + signal; -1 when it
/// did not end within `limit` seconds (then killed).
int run_for(const std::vector<std::string>& args, const fs::path& cwd, double limit) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(cwd.c_str()) != 0) ::_exit(126);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, STDOUT_FILENO), ::dup2(null, STDERR_FILENO);
    std::vector<char*> argv{const_cast<char*>(DEMDESIGN_BINARY)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(DEMDESIGN_BINARY, argv.data());
    ::_exit(127);
  }
  const auto start = std::chrono::steady_clock::now();
  int raw = 0;
  while (::waitpid(pid, &raw, WNOHANG) == 0) {
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > limit) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &raw, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
}

TEST(CommandLineFuzz, RandomArgumentVectorsGetAnAnswerNeverACrash) {
  const fs::path cwd = fs::temp_directory_path() / ("demdesign_cli_fuzz_" + std::to_string(::getpid()));
  fs::create_directories(cwd);
  const std::vector<std::string> commands = {"", "run", "check", "check-mesh", "render", "compare", "calibrate", "diagnose", "test",
                                             "effects", "materials", "keys", "simulate", "chekc", "--help"};
  const std::vector<std::string> files = {"/nonexistent/case.yaml", "/nonexistent/material.yaml", "/nonexistent/lab.yaml",
                                          "/nonexistent/part.stl", "/nonexistent/out", ""};
  const std::vector<std::string> options = {"--duration", "--max-steps", "--threads", "--replicas", "--size-factor", "--budget",
                                            "--seed", "--parallel", "--out", "--resume", "--overwrite", "--quiet", "--no-report",
                                            "--stiffness-scaling", "--rank-grid", "--balance", "--frame", "--effects", "--variant", "-x"};
  const std::vector<std::string> values = {"-1", "nan", "inf", "-inf", "1e300", "0", "-0", "abc", "", "1e-300", "2", "2x2x",
                                           "10000", "30m", "1.5", "0x10", "\xff\xfe", "--", "3 4"};
  std::mt19937 random(20261206);
  const auto pick = [&](const std::vector<std::string>& from) { return from[std::uniform_int_distribution<size_t>(0, from.size() - 1)(random)]; };
  std::map<int, int> statuses;
  constexpr int kVectors = 300;
  for (int k = 0; k < kVectors; ++k) {
    std::vector<std::string> args;
    const std::string command = pick(commands);
    if (!command.empty()) args.push_back(command);
    const int words = std::uniform_int_distribution<int>(0, 6)(random);
    for (int w = 0; w < words; ++w) {
      const int kind = std::uniform_int_distribution<int>(0, 2)(random);
      if (kind == 0) args.push_back(pick(files));
      else if (kind == 1) args.push_back(pick(options)), args.push_back(pick(values));
      else args.push_back(pick(options));
    }
    std::string shown;
    for (const std::string& a : args) shown += " '" + a + "'";
    const int status = run_for(args, cwd, 30.0);
    ++statuses[status];
    // check-mesh answers 1 when a mesh it was given is not simulable (an unreadable file among them).
    const bool answered = status == 0 || status == 2 || (status == 1 && command == "check-mesh");
    EXPECT_TRUE(answered) << "demdesign" << shown << ": " << (status < 0 ? "no answer within 30 s" : "exit status " + std::to_string(status));
  }
  std::printf("%d random command lines:", kVectors);
  for (const auto& [status, count] : statuses) std::printf(" %d exited %d;", count, status);
  std::printf("\n");
  EXPECT_TRUE(fs::is_empty(cwd)) << "a refused command line wrote into the working directory";
  fs::remove_all(cwd);
}

// compare-runs through the real binary: two report folders of the smallest kind give 0 and the
// page; a folder no run wrote gives 2 and writes nothing (tests/test_compare_runs.cpp has the numbers).
TEST(CompareRunsCommand, ComparesTwoRunFoldersAndRefusesAMissingOne) {
  const fs::path dir = fs::temp_directory_path() / ("demdesign_cli_compare_runs_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  for (const char* run : {"a", "b"}) {
    fs::create_directories(dir / run / "report");
    std::FILE* steady = std::fopen((dir / run / "report" / "steady_state.csv").c_str(), "w");
    std::fputs("series,unit,found,t_start_s,t_end_s,mean,std_dev,std_error,trend_per_s,why\n\"outlet bin\",t/h,1,1,4,100,9,3,0,\"\"\n", steady);
    std::fclose(steady);
    std::FILE* metrics = std::fopen((dir / run / "report" / "metrics.csv").c_str(), "w");
    std::fputs("name,value\nsteady,1\nthroughput_t_h,100\n", metrics);
    std::fclose(metrics);
  }
  EXPECT_EQ(run_for({"compare-runs", (dir / "a").string(), (dir / "b").string()}, dir, 30.0), 0);
  EXPECT_TRUE(fs::exists(dir / "compare_a_b" / "compare.html")) << "the default folder lies beside A";
  EXPECT_TRUE(fs::exists(dir / "compare_a_b" / "compare.csv"));
  EXPECT_EQ(run_for({"compare-runs", (dir / "never_run").string(), (dir / "b").string(), "--out", (dir / "refused").string()}, dir, 30.0), 2);
  EXPECT_FALSE(fs::exists(dir / "refused"));
  fs::remove_all(dir);
}

}  // namespace
