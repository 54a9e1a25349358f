#include "campaign/sweep.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>
#include <spawn.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <regex>
#include <thread>

#include "campaign/bias_check.h"
#include "case/spec.h"
#include "case/yaml_check.h"
#include "campaign/mpi_campaign.h"
#include "report/report.h"
#include "campaign/uncertainty.h"

namespace dem::app {

namespace {

/// One step of a key path: a map key, or a list index.
struct PathStep {
  std::string key;
  long index = -1;
};

std::vector<PathStep> split_path(const std::string& path) {
  std::vector<PathStep> steps;
  static const std::regex part(R"(([A-Za-z_][A-Za-z0-9_]*)((\[[0-9]+\])*))");
  size_t start = 0;
  while (start <= path.size()) {
    const size_t dot = path.find('.', start);
    const std::string piece = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    std::smatch m;
    if (!std::regex_match(piece, m, part)) return {};
    steps.push_back({m[1].str(), -1});
    std::string rest = m[2].str();
    while (!rest.empty()) {
      const size_t close = rest.find(']');
      steps.push_back({"", std::stol(rest.substr(1, close - 1))});
      rest = rest.substr(close + 1);
    }
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return steps;
}

std::string short_path(const std::string& path) {
  // The last two parts are what a reader recognises: "spoon.radius".
  const size_t last = path.rfind('.');
  if (last == std::string::npos) return path;
  const size_t before = path.rfind('.', last - 1);
  return before == std::string::npos ? path : path.substr(before + 1);
}

std::string format_seconds(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  if (s >= 3600) return fmt::format("{}h{:02}m", s / 3600, (s % 3600) / 60);
  if (s >= 60) return fmt::format("{}m{:02}s", s / 60, s % 60);
  return fmt::format("{}s", s);
}

}  // namespace

std::string SweepPlan::name(size_t k) const { return fmt::format("v{:02}", k + 1); }

std::string SweepPlan::label(size_t k) const {
  std::string out;
  for (size_t p = 0; p < paths.size(); ++p) {
    if (p) out += ", ";
    out += fmt::format("{}={}", short_path(paths[p]), YAML::Dump(variants[k][p]));
  }
  return out;
}

std::string SweepPlan::design_label(size_t k) const {
  std::string out;
  for (size_t p = 0; p < design_paths && p < paths.size(); ++p) {
    if (p) out += ", ";
    out += fmt::format("{}={}", short_path(paths[p]), YAML::Dump(variants[k][p]));
  }
  return out;
}

SweepPlan read_sweep(const YAML::Node& root, const std::string& file) {
  SweepPlan plan = read_design_sweep(root, file);
  plan.design_paths = plan.paths.size();
  if (root.IsMap() && root["bias_check"]) add_bias_check(plan, root, file);
  else if (root.IsMap() && root["coarse_grain_check"]) add_coarse_grain_check(plan, root, file);
  else if (root.IsMap() && root["uncertainty"]) add_uncertainty(plan, root, file);
  return plan;
}

SweepPlan read_design_sweep(const YAML::Node& root, const std::string& file) {
  SweepPlan plan;
  plan.file = file;
  if (!root.IsMap() || !root["sweep"]) return plan;
  MapReader map(root["sweep"], file, "sweep");
  const YAML::Node parameters = map.node("parameters");
  if (!parameters || !parameters.IsMap() || parameters.size() == 0)
    map.fail("parameters", "missing: a map of key paths to value lists, e.g. {equipment.transfer_chute.spoon.radius: [0.6, 0.8]}");
  MapReader params(parameters, file, "sweep.parameters");
  params.keys_are_names("KEY_PATH");
  std::vector<std::vector<YAML::Node>> values;
  for (const std::string& path : params.keys()) {
    if (split_path(path).empty()) params.fail(path, "is not a key path (names separated by dots, list items as [k])");
    if (path.rfind("sweep", 0) == 0) params.fail(path, "a sweep cannot vary itself");
    const YAML::Node list = params.node(path);
    if (!list.IsSequence() || list.size() == 0) params.fail(path, "must be a non-empty list of values");
    plan.paths.push_back(path);
    values.emplace_back(list.begin(), list.end());
  }
  const std::string combine = map.string("combine", "grid", {"grid", "zip"});
  if (combine == "zip") {
    for (size_t p = 1; p < values.size(); ++p)
      if (values[p].size() != values[0].size())
        params.fail(plan.paths[p], fmt::format("has {} values but {} has {}; `combine: zip` needs lists of equal length",
                                               values[p].size(), plan.paths[0], values[0].size()));
    for (size_t k = 0; k < values[0].size(); ++k) {
      std::vector<YAML::Node> row;
      for (const auto& v : values) row.push_back(v[k]);
      plan.variants.push_back(row);
    }
  } else {
    // Sized before it is built: a grid of a few long lists is millions of variants.
    double size = 1;
    std::string sizes;
    for (size_t p = 0; p < values.size(); ++p) size *= static_cast<double>(values[p].size()), sizes += fmt::format("{}{}", p ? " x " : "", values[p].size());
    if (size > kMostSweepVariants)
      map.fail("parameters", fmt::format("makes {:.0f} variants ({} values, combine: grid); at most {}: fewer values, or `combine: zip` to pair "
                                         "the lists item by item", size, sizes, kMostSweepVariants));
    plan.variants = {{}};
    for (const auto& v : values) {
      std::vector<std::vector<YAML::Node>> next;
      for (const auto& row : plan.variants)
        for (const auto& value : v) {
          next.push_back(row);
          next.back().push_back(value);
        }
      plan.variants = std::move(next);
    }
  }
  if (plan.variants.size() > kMostSweepVariants) map.fail("parameters", fmt::format("makes {} variants; at most {}", plan.variants.size(), kMostSweepVariants));
  if (const YAML::Node rank = map.node("rank_by")) {
    if (!rank.IsSequence()) map.fail("rank_by", "must be a list of {metric, goal: minimize|maximize, weight}");
    for (size_t k = 0; k < rank.size(); ++k) {
      MapReader c(rank[k], file, fmt::format("sweep.rank_by[{}]", k));
      SweepCriterion criterion;
      criterion.metric = c.required_string("metric", "a metric of the run report's metrics.csv");
      criterion.minimize = c.string("goal", "minimize", {"minimize", "maximize"}) == "minimize";
      criterion.weight = c.number("weight", 1.0, 0.0, 1e6);
      c.finish();
      plan.criteria.push_back(criterion);
    }
  }
  plan.parallel = static_cast<int>(map.integer("parallel", 0, 0, 256));
  map.finish();
  return plan;
}

YAML::Node variant_case(const YAML::Node& root, const SweepPlan& plan, size_t k) {
  YAML::Node copy = YAML::Clone(root);
  copy.remove("sweep");
  copy.remove("uncertainty");
  copy.remove("bias_check");
  copy.remove("coarse_grain_check");
  for (size_t p = 0; p < plan.paths.size(); ++p) {
    const std::vector<PathStep> steps = split_path(plan.paths[p]);
    // yaml-cpp nodes are handles: walking with operator[] on a non-const node creates missing
    // map entries, which is what lets a sweep set a parameter the case leaves at its default.
    std::vector<YAML::Node> chain = {copy};
    for (size_t s = 0; s < steps.size(); ++s) {
      YAML::Node here = chain.back();
      const bool last = s + 1 == steps.size();
      if (steps[s].index >= 0) {
        if (!here.IsSequence() || steps[s].index >= static_cast<long>(here.size()))
          throw CaseError(fmt::format("{}: sweep.parameters: {}: there is no list item [{}] there", plan.file, plan.paths[p], steps[s].index));
        if (last) here[steps[s].index] = plan.variants[k][p];
        else chain.push_back(here[steps[s].index]);
      } else {
        if (here.IsDefined() && !here.IsMap() && !here.IsNull())
          throw CaseError(fmt::format("{}: sweep.parameters: {}: '{}' is inside a value that is not a map", plan.file, plan.paths[p], steps[s].key));
        if (last) here[steps[s].key] = plan.variants[k][p];
        else chain.push_back(here[steps[s].key]);
      }
    }
  }
  return copy;
}

namespace {

namespace fs = std::filesystem;

// ---- the phases of run_sweep ------------------------------------------------------------------

/// How this rank runs the sweep: the plan, the options, where progress is told, and the sizes
/// taken once at the start.
struct SweepRank {
  const SweepPlan& plan;
  const SweepOptions& options;
  std::ostream& log;
  const mpi::World& world;
  size_t n;         ///< variants of the sweep
  int threads;      ///< per variant
  int parallel;     ///< variants at once on this rank
  std::string who;  ///< "rank 1: " under MPI, "" otherwise
  std::vector<double> durations;  ///< [s] per variant, the simulated time it runs to (0: not known)
};

/// What a variant's child process is started with: this program, and this process's environment
/// without the MPI launcher's variables.
struct ChildProgram {
  std::string self;
  std::vector<std::string> environment;
  std::vector<char*> envp;  ///< into environment, then nullptr
};

/// A variant's child process while it runs.
struct RunningVariant {
  pid_t pid;
  size_t variant;
  std::chrono::steady_clock::time_point started;
};

/// This rank's variants as they run, and once they have.
struct RankRuns {
  std::vector<RunningVariant> running;
  std::vector<int> status;   ///< per variant of the sweep: exit status (127: not started or lost), -1 until known
  std::vector<size_t> mine;  ///< the variants this rank ran, in the order it started them
  size_t done = 0;
  double busy_seconds = 0;
};

/// Every variant's result on rank 0, as the ranks that ran them reported it.
struct VariantResults {
  std::vector<std::string> metrics_text, messages, images;  ///< per variant
};

/// [s] the simulated time each variant runs to (--duration, else its case's simulation.duration,
/// which a check may set); 0 where the case cannot be read again (the time left is then the mean
/// of the variants done).
std::vector<double> variant_durations(const SweepPlan& plan, const SweepOptions& options) {
  std::vector<double> out(plan.variants.size(), options.duration >= 0 ? options.duration : 0.0);
  if (options.duration >= 0) return out;
  try {
    const YAML::Node root = YAML::LoadFile(options.case_path);
    for (size_t k = 0; k < out.size(); ++k) {
      const YAML::Node duration = variant_case(root, plan, k)["simulation"]["duration"];
      if (duration && duration.IsScalar()) out[k] = duration.as<double>();
    }
  } catch (const std::exception&) {
    std::fill(out.begin(), out.end(), 0.0);
  }
  return out;
}

/// [s] simulated so far by the run in `dir`: the time of the last whole row of its scalars.csv
/// (0 while it has none).
double simulated_so_far(const std::string& dir) {
  std::ifstream in(dir + "/scalars.csv", std::ios::binary);
  if (!in) return 0;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(std::max<std::streamoff>(0, size - 8192));
  const std::string tail((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t end = tail.find_last_of('\n');
  if (end == std::string::npos || end == 0) return 0;
  const size_t start = tail.find_last_of('\n', end - 1);
  const std::string row = tail.substr(start == std::string::npos ? 0 : start + 1, end - (start == std::string::npos ? 0 : start + 1));
  char* stop = nullptr;
  const double t = std::strtod(row.c_str(), &stop);
  return stop != row.c_str() && std::isfinite(t) ? t : 0.0;
}

/// This rank's share of the variants, the threads of each and how many run at once.
SweepRank size_this_rank(const SweepPlan& plan, const SweepOptions& options, std::ostream& log) {
  const mpi::World& world = mpi::world();
  const size_t n = plan.variants.size();
  // Under MPI rank 0 hands the variants out one at a time to whichever rank has a free slot; a
  // rank's threads and slots are sized for its expected share.
  const size_t share = (n + static_cast<size_t>(world.size) - 1) / static_cast<size_t>(world.size);
  const int cores = mpi::cores_per_rank();
  const int threads = options.threads > 0 ? options.threads : (static_cast<int>(share) >= cores ? 1 : cores);
  const int parallel = plan.parallel > 0 ? plan.parallel : std::max(1, cores / threads);
  const std::string who = world.active() ? fmt::format("rank {}: ", world.rank) : "";
  return {plan, options, log, world, n, threads, parallel, who, variant_durations(plan, options)};
}

/// Makes the variants' folder and says how the sweep runs.
void announce(const SweepRank& sweep) {
  const SweepOptions& options = sweep.options;
  const mpi::World& world = sweep.world;
  std::ostream& log = sweep.log;
  const size_t n = sweep.n;
  const int threads = sweep.threads, parallel = sweep.parallel;
  fs::create_directories(options.out + "/variants");
  if (!world.active())
    log << fmt::format("sweep: {} variants of {}, {} at a time with {} thread(s) each\n", n, options.case_path, parallel, threads);
  else {
    if (world.rank == 0) log << fmt::format("sweep: {} variants of {} over {} MPI ranks\n", n, options.case_path, world.size);
    log << fmt::format("{}{} at a time with {} thread(s) each\n", sweep.who, parallel, threads) << std::flush;
  }
}

/// This program and the environment its children run with.
void find_child_program(ChildProgram& child) {
  child.self = fs::read_symlink("/proc/self/exe").string();
  // The children are plain processes: without the launcher's variables they never join the MPI job.
  child.environment = mpi::child_environment();
  for (auto& e : child.environment) child.envp.push_back(e.data());
  child.envp.push_back(nullptr);
}

/// Starts variant k as `demdesign run CASE --variant k` in its folder. The sweep owns its variants'
/// folders: a sweep run again replaces what its variants wrote there (--overwrite).
void start_variant(const SweepRank& sweep, const ChildProgram& child, RankRuns& runs, size_t k) {
  const SweepPlan& plan = sweep.plan;
  const SweepOptions& options = sweep.options;
  const std::string dir = fmt::format("{}/variants/{}", options.out, plan.name(k));
  fs::create_directories(dir);
  std::vector<std::string> args = {child.self, "run", options.case_path, "--variant", std::to_string(k), "--out", dir,
                                   "--threads", std::to_string(sweep.threads), "--quiet", "--overwrite"};
  if (options.duration >= 0) args.insert(args.end(), {"--duration", fmt::format("{:.17g}", options.duration)});
  if (options.max_steps >= 0) args.insert(args.end(), {"--max-steps", std::to_string(options.max_steps)});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  // The child's output goes to its log file; no shell is involved.
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  const std::string log_path = dir + "/log.txt";
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, child.self.c_str(), &files, nullptr, argv.data(), child.envp.data());
  posix_spawn_file_actions_destroy(&files);
  runs.mine.push_back(k);
  if (err != 0) {
    sweep.log << fmt::format("{}  {} could not be started: {}\n", sweep.who, plan.name(k), std::strerror(err));
    runs.status[k] = 127;
    ++runs.done;
  } else {
    sweep.log << fmt::format("{}  {} started: {}\n", sweep.who, plan.name(k), plan.label(k)) << std::flush;
    runs.running.push_back({pid, k, std::chrono::steady_clock::now()});
  }
}

/// Free slots take the next variants; true when one was started. `exhausted` becomes true when
/// the queue has none left.
bool fill_free_slots(const SweepRank& sweep, const ChildProgram& child, mpi::WorkQueue& queue, bool& exhausted, RankRuns& runs) {
  bool progressed = false;
  while (!exhausted && static_cast<int>(runs.running.size()) < sweep.parallel) {
    const long item = queue.next();
    if (item == mpi::WorkQueue::kWait) break;
    if (item == mpi::WorkQueue::kNone) {
      exhausted = true;
      break;
    }
    start_variant(sweep, child, runs, static_cast<size_t>(item));
    progressed = true;
  }
  return progressed;
}

/// [s] of wall time the rest of this rank's variants will take: each running variant at its own
/// pace so far (its simulated time against its duration), those not yet started at the mean of
/// the ones done, over the parallel slots. Rejected: the mean of the ones done for every variant,
/// which a coarse-grain check's finer run (three times the case's cost) makes a third of the truth.
double seconds_left(const SweepRank& sweep, const RankRuns& runs) {
  const auto now = std::chrono::steady_clock::now();
  const double per_done = runs.done > 0 ? runs.busy_seconds / static_cast<double>(runs.done) : 0.0;
  double sum = 0, longest = 0;
  for (const RunningVariant& r : runs.running) {
    const double elapsed = std::chrono::duration<double>(now - r.started).count();
    const double duration = sweep.durations[r.variant];
    const double simulated = simulated_so_far(sweep.options.out + "/variants/" + sweep.plan.name(r.variant));
    const double rest = duration > 0 && simulated > 0.02 * duration ? elapsed * std::max(0.0, duration - simulated) / simulated
                                                                    : std::max(0.0, per_done - elapsed);
    sum += rest, longest = std::max(longest, rest);
  }
  const size_t started = runs.done + runs.running.size();
  const size_t waiting = sweep.world.active() || started >= sweep.n ? 0 : sweep.n - started;
  sum += static_cast<double>(waiting) * per_done;
  return std::max(longest, sum / std::max(1, sweep.parallel));
}

/// Takes the child `pid` that ended with `wstatus` off the running variants and tells how far
/// the sweep is; nothing when it is not one of them.
void variant_finished(const SweepRank& sweep, pid_t pid, int wstatus, RankRuns& runs) {
  const SweepPlan& plan = sweep.plan;
  std::vector<RunningVariant>& running = runs.running;
  std::vector<int>& status = runs.status;
  const auto it = std::find_if(running.begin(), running.end(), [&](const RunningVariant& r) { return r.pid == pid; });
  if (it == running.end()) return;
  const size_t v = it->variant;
  status[v] = WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : 128 + WTERMSIG(wstatus);
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - it->started).count();
  runs.busy_seconds += took;
  running.erase(it);
  ++runs.done;
  const size_t done = runs.done, n = sweep.n;
  const std::string count = sweep.world.active() ? fmt::format("{} done on this rank", done)
                                                 : fmt::format("{}/{} done, about {} left", done, n, format_seconds(seconds_left(sweep, runs)));
  sweep.log << fmt::format("{}  {} {} in {} ({}){}\n", sweep.who, plan.name(v), status[v] == 0 ? "finished" : "FAILED", format_seconds(took), count,
                           status[v] == 0 ? "" : fmt::format(": see {}/variants/{}/log.txt", sweep.options.out, plan.name(v)))
            << std::flush;
}

/// Runs the variants this rank is handed, `parallel` at a time, until none is left (and, on
/// rank 0, every other rank has been told so).
RankRuns run_variants(const SweepRank& sweep, const ChildProgram& child) {
  RankRuns runs;
  runs.status.assign(sweep.n, -1);
  mpi::WorkQueue queue(sweep.n);
  bool exhausted = false;
  for (;;) {
    bool progressed = fill_free_slots(sweep, child, queue, exhausted, runs);
    progressed = queue.serve() || progressed;  // rank 0 answers the other ranks
    if (exhausted && runs.running.empty() && queue.all_told()) break;
    // Without MPI wait for a variant to finish; under MPI look, and keep asking and answering.
    int wstatus = 0;
    const pid_t pid = runs.running.empty() ? 0 : waitpid(-1, &wstatus, sweep.world.active() ? WNOHANG : 0);
    if (pid < 0 && errno == EINTR) continue;
    if (pid < 0) {
      // No child to wait for (cannot happen with variants running): count them as failed.
      for (const RunningVariant& r : runs.running) runs.status[r.variant] = 127, ++runs.done;
      runs.running.clear();
      continue;
    }
    if (pid == 0) {
      if (!progressed) std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    variant_finished(sweep, pid, wstatus, runs);
  }
  return runs;
}

/// Every rank's record of the variants it ran, on rank 0 (collective; other ranks get none).
std::vector<std::string> gather_results(const SweepRank& sweep, const RankRuns& runs) {
  const SweepPlan& plan = sweep.plan;
  const std::vector<int>& status = runs.status;
  // What rank 0 needs of each variant this rank ran: exit status, metrics.csv as text, why it
  // failed (the last lines of its log) and its last flow image; gathered over MPI, so rank 0
  // ranks the variants even when the other ranks' folders are not on its file system.
  mpi::ByteWriter record;
  for (const size_t k : runs.mine) {
    const std::string dir = fmt::format("{}/variants/{}", sweep.options.out, plan.name(k));
    std::string metrics, message, image;
    if (status[k] == 0) {
      std::ifstream in(dir + "/report/metrics.csv");
      if (in) metrics.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
      else message = fmt::format("{}/report/metrics.csv: cannot read the metrics file", dir);
      if (fs::is_directory(dir + "/renders"))
        for (const auto& entry : fs::directory_iterator(dir + "/renders"))
          if (entry.path().extension() == ".png" && entry.path().filename().string().rfind("frame_", 0) == 0)
            image = std::max(image, entry.path().string());
    } else {
      // The last lines of the variant's log say why it failed.
      std::ifstream in(dir + "/log.txt");
      std::vector<std::string> lines;
      for (std::string line; std::getline(in, line);) lines.push_back(line);
      for (size_t l = lines.size() > 3 ? lines.size() - 3 : 0; l < lines.size(); ++l) message += lines[l] + " ";
      if (message.empty()) message = fmt::format("exit status {}", status[k]);
    }
    record.u64(k), record.u64(static_cast<std::uint64_t>(status[k])), record.str(metrics), record.str(message), record.str(image);
  }
  return mpi::gather(record.bytes());
}

/// Rank 0: every variant's result from the ranks' records, its exit status into `status`.
VariantResults read_results(const std::vector<std::string>& records, size_t n, std::vector<int>& status) {
  VariantResults results{std::vector<std::string>(n), std::vector<std::string>(n), std::vector<std::string>(n)};
  std::vector<std::string>& metrics_text = results.metrics_text;
  std::vector<std::string>& messages = results.messages;
  std::vector<std::string>& images = results.images;
  for (const std::string& bytes : records) {
    mpi::ByteReader in(bytes);
    while (!in.done()) {
      const size_t k = in.u64();
      if (k >= n) throw std::runtime_error(fmt::format("sweep: a rank reported variant {} of {}", k, n));
      status[k] = static_cast<int>(in.u64());
      metrics_text[k] = in.str(), messages[k] = in.str(), images[k] = in.str();
    }
  }
  return results;
}

/// The comparison: each variant's metrics (from its report) and its last flow image.
report::SweepReportInput comparison_input(const SweepRank& sweep, const std::vector<int>& status, const VariantResults& results) {
  const SweepPlan& plan = sweep.plan;
  const SweepOptions& options = sweep.options;
  const std::vector<std::string>& metrics_text = results.metrics_text;
  const std::vector<std::string>& messages = results.messages;
  const std::vector<std::string>& images = results.images;
  report::SweepReportInput input;
  input.case_path = options.case_path, input.version = DEMDESIGN_VERSION;
  input.title = fmt::format("Design sweep: {}", fs::path(options.case_path).filename().string());
  for (const SweepCriterion& c : plan.criteria) input.criteria.push_back({c.metric, !c.minimize, c.weight});
  for (size_t k = 0; k < sweep.n; ++k) {
    const std::string dir = fmt::format("{}/variants/{}", options.out, plan.name(k));
    report::SweepVariant v;
    v.name = plan.name(k);
    for (size_t p = 0; p < plan.paths.size(); ++p) v.parameters.emplace_back(plan.paths[p], YAML::Dump(plan.variants[k][p]));
    v.report_path = fmt::format("variants/{}/report/report.html", plan.name(k));
    v.ok = status[k] == 0 && messages[k].empty();
    v.message = messages[k];
    if (v.ok) {
      try {
        v.metrics = report::parse_metrics(metrics_text[k], dir + "/report/metrics.csv");
      } catch (const std::exception& e) {
        v.ok = false, v.message = e.what();
      }
      // Shown when rank 0 can read it (a shared file system, as clusters have).
      if (fs::exists(images[k])) v.image_path = images[k];
    }
    input.variants.push_back(std::move(v));
  }
  return input;
}

/// A criterion no variant reports is a typo in the case, not a tie: say so.
void warn_of_unknown_criteria(const SweepRank& sweep, const report::SweepReportInput& input) {
  for (const SweepCriterion& c : sweep.plan.criteria) {
    const bool known = std::any_of(input.variants.begin(), input.variants.end(), [&](const report::SweepVariant& v) {
      return std::any_of(v.metrics.values.begin(), v.metrics.values.end(), [&](const auto& kv) { return kv.first == c.metric; });
    });
    if (known) continue;
    std::string names;
    for (const auto& v : input.variants)
      if (v.ok) {
        for (const auto& kv : v.metrics.values) names += (names.empty() ? "" : ", ") + kv.first;
        break;
      }
    sweep.log << fmt::format("warning: sweep.rank_by metric '{}' is not in any variant's metrics.csv (it scores 0 everywhere); "
                             "metrics: {}\n", c.metric, names);
  }
}

/// With `uncertainty:`: each KPI's band over the parameter sets, on the page and in the log.
void report_uncertainty(const SweepRank& sweep, report::SweepReportInput& input) {
  const SweepPlan& plan = sweep.plan;
  std::ostream& log = sweep.log;
  const UncertaintySummary summary = summarise_uncertainty(plan, input.variants, input.criteria, sweep.options.out + "/report");
  input.extra_html = summary.html;
  input.title = fmt::format("Design runs with calibration uncertainty: {}", fs::path(sweep.options.case_path).filename().string());
  log << fmt::format("calibration uncertainty ({} parameter sets per design): median [90 % band]\n", plan.samples);
  for (const std::string& note : plan.held) log << "  " << note << "\n";
  for (const KpiBand& b : summary.bands)
    if (b.p95 != b.p05 || b.median != 0)
      log << fmt::format("  {}{:<34} {:.4g} [{:.4g}, {:.4g}]{}\n", b.design.empty() ? "" : b.design + ": ", b.metric, b.median, b.p05, b.p95,
                         std::isfinite(b.run_noise) ? fmt::format("  (run noise {:.2g})", b.run_noise) : "");
  for (const Beats& x : summary.beats)
    if (x.probability > 0.5) log << fmt::format("  P({} beats {} on {}) = {:.2f} over {} parameter sets\n", x.a, x.b, x.metric, x.probability, x.pairs);
}

/// With `bias_check:` or `coarse_grain_check:`: how each KPI moves under the checks, on the page
/// and in the log.
void report_bias_check(const SweepRank& sweep, report::SweepReportInput& input) {
  std::ostream& log = sweep.log;
  const BiasSummary summary = summarise_bias_check(sweep.plan, input.variants, sweep.options.out + "/report");
  input.extra_html = summary.html;
  input.title = fmt::format("{}: {}", summary.title, fs::path(sweep.options.case_path).filename().string());
  log << summary.log_heading << "\n";
  for (const std::string& line : summary.log_lines) log << "  " << line << "\n";
  for (const KpiShift& s : summary.shifts)
    log << fmt::format("  {}{}{}\n", s.design.empty() ? "" : s.design + ": ", s.sensitive ? summary.flag_word + ": " : "", s.words);
}

/// Writes the comparison report into OUT/report and tells the ranking.
void write_and_rank(const SweepRank& sweep, const report::SweepReportInput& input) {
  report::write_sweep_report(input, sweep.options.out + "/report");
  const auto ranked = report::rank_variants(input);
  sweep.log << fmt::format("sweep report: {}/report/sweep.html\nranking:\n", sweep.options.out);
  for (size_t r = 0; r < ranked.size(); ++r)
    sweep.log << fmt::format("  {}. {} ({}) score {:.3f}\n", r + 1, input.variants[ranked[r].variant].name, sweep.plan.label(ranked[r].variant),
                             ranked[r].score);
}

}  // namespace

int run_sweep(const SweepPlan& plan, const SweepOptions& options, std::ostream& log) {
  const SweepRank sweep = size_this_rank(plan, options, log);
  announce(sweep);
  ChildProgram child;
  find_child_program(child);
  RankRuns runs = run_variants(sweep, child);
  const std::vector<std::string> records = gather_results(sweep, runs);
  if (sweep.world.rank != 0) return 0;  // rank 0 reports the campaign and gives its exit status
  const VariantResults results = read_results(records, sweep.n, runs.status);
  report::SweepReportInput input = comparison_input(sweep, runs.status, results);
  warn_of_unknown_criteria(sweep, input);
  if (plan.samples > 0) report_uncertainty(sweep, input);
  if (!plan.bias_runs.empty()) report_bias_check(sweep, input);
  write_and_rank(sweep, input);
  return std::all_of(runs.status.begin(), runs.status.end(), [](int s) { return s == 0; }) ? 0 : 1;
}

}  // namespace dem::app
