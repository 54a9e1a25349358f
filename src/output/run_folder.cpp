#include "output/run_folder.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ostream.h>
#include <fnmatch.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <utility>

#include "case/spec.h"
#include "output/run.h"

namespace dem {

namespace {

namespace fs = std::filesystem;

/// A name split into its folder (empty: the run folder itself) and its file name or pattern.
std::pair<std::string, std::string> split_name(const std::string& name) {
  const auto slash = name.rfind('/');
  if (slash == std::string::npos) return {"", name};
  return {name.substr(0, slash), name.substr(slash + 1)};
}

/// Whether `file` is the name `pattern` or one of its temporaries (.part, .tmp).
bool matches(const std::string& pattern, const std::string& file) {
  for (const char* suffix : {"", ".part", ".tmp"})
    if (::fnmatch((pattern + suffix).c_str(), file.c_str(), FNM_PERIOD) == 0) return true;
  return false;
}

bool matches_any(const std::vector<std::string>& names, const std::string& relative) {
  const std::pair<std::string, std::string> file = split_name(relative);
  return std::any_of(names.begin(), names.end(), [&](const std::string& name) {
    const std::pair<std::string, std::string> named = split_name(name);
    return named.first == file.first && matches(named.second, file.second);
  });
}

/// The files in `directory` (paths relative to it, sorted) that bear one of `names`.
std::vector<std::string> files_named(const fs::path& directory, const std::vector<std::string>& names) {
  std::map<std::string, std::vector<std::string>> patterns;  // folder -> file patterns
  for (const std::string& name : names) {
    const auto [folder, pattern] = split_name(name);
    patterns[folder].push_back(pattern);
  }
  std::vector<std::string> found;
  for (const auto& [folder, in_folder] : patterns) {
    std::error_code error;
    const fs::path here = folder.empty() ? directory : directory / folder;
    if (!fs::is_directory(here, error)) continue;
    for (const fs::directory_entry& entry : fs::directory_iterator(here, error)) {
      if (entry.is_directory(error)) continue;
      const std::string file = entry.path().filename().string();
      if (std::any_of(in_folder.begin(), in_folder.end(), [&](const std::string& p) { return matches(p, file); }))
        found.push_back(folder.empty() ? file : folder + "/" + file);
    }
  }
  std::sort(found.begin(), found.end());
  return found;
}

/// "run_info.yaml, scalars.csv, frames/ (21 files)": top-level files by name, folders by count.
std::string describe(const std::vector<std::string>& files) {
  std::vector<std::string> parts;
  std::map<std::string, int> in_folder;
  for (const std::string& f : files) {
    const auto slash = f.find('/');
    if (slash == std::string::npos) parts.push_back(f);
    else ++in_folder[f.substr(0, slash)];
  }
  for (const auto& [folder, count] : in_folder) parts.push_back(fmt::format("{}/ ({} file{})", folder, count, count == 1 ? "" : "s"));
  return fmt::format("{}", fmt::join(parts, ", "));
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

constexpr const char* kClaimedHeader = "# The files demdesign runs write in this folder";

/// A file at one of the folder's own names (run.lock, run_files.txt) that demdesign did not write.
CaseError not_ours(const fs::path& path, const std::string& directory) {
  return CaseError(fmt::format("{}: not written by a demdesign run, and a run into {} keeps a file of that name; nothing was changed. "
                               "Move the file away or choose another --out folder",
                               path.string(), directory));
}

/// The names listed in run_files.txt (lines that are not comments); `listed` says whether it exists.
std::vector<std::string> read_claimed(const fs::path& path, const std::string& directory, bool* listed) {
  std::error_code error;
  *listed = fs::exists(path, error);
  std::vector<std::string> names;
  if (!*listed) return names;
  const std::string text = read_text(path);
  if (text.rfind(kClaimedHeader, 0) != 0) throw not_ours(path, directory);
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') names.push_back(line);
  return names;
}

std::string claimed_text(const std::vector<std::string>& names) {
  std::string text = std::string(kClaimedHeader) +
      " (one name a line; '*' matches any part of a file name;\n"
      "# each name also stands for its temporaries NAME.part and NAME.tmp). `demdesign run --overwrite` removes\n"
      "# the files of these names here and nothing else; a run refuses to replace a file of its names that\n"
      "# is not listed.\n";
  for (const std::string& name : names) text += name + "\n";
  return text;
}

/// The process id written in a lock file: 0 when it is empty, -1 when it holds anything else.
long lock_holder(int descriptor) {
  char text[32] = {};
  const ssize_t got = ::pread(descriptor, text, sizeof text - 1, 0);
  if (got <= 0) return 0;
  char* end = nullptr;
  const long pid = std::strtol(text, &end, 10);
  return end != text && pid > 0 && (*end == '\n' || *end == '\0') ? pid : -1;
}

}  // namespace

RunRecord read_run_record(const std::string& directory) {
  RunRecord record;
  const std::string text = read_text(fs::path(directory) / "run_info.yaml");
  if (text.rfind("software: demdesign", 0) != 0) return record;
  record.exists = true;
  std::istringstream in(text);
  bool in_end = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("case: ", 0) == 0) record.case_path = line.substr(6);
    else if (line.rfind("run_id: ", 0) == 0) record.run_id = std::strtoull(line.c_str() + 8, nullptr, 16);
    else if (line == "end:") in_end = record.ended = true;
    else if (in_end && line.rfind("  completed: ", 0) == 0) record.completed = line.substr(13) == "true";
    else if (in_end && line.rfind("  time_s: ", 0) == 0) record.time = std::strtod(line.c_str() + 10, nullptr);
    else if (in_end && line.rfind("  step: ", 0) == 0) record.step = std::strtoll(line.c_str() + 8, nullptr, 10);
  }
  return record;
}

std::vector<std::string> run_output_names() {
  return {"run_info.yaml",       "scalars.csv",    "events.csv",      "particles.xdmf",       "frames/frame_*.h5",
          "open_in_paraview.py", "walls.h5",       "walls.xdmf",      "checkpoint.bin",       "checkpoint.ranks.bin",
          "checkpoint.ranks/step-*.bin", "stream_profiles.csv"};
}

std::uint64_t new_run_id() {
  // Two draws of the system's random source mixed with the time and the process (splitmix64).
  std::random_device device;
  std::uint64_t x = (static_cast<std::uint64_t>(device()) << 32) ^ device() ^
                    static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count()) ^
                    (static_cast<std::uint64_t>(::getpid()) << 40);
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  x ^= x >> 31;
  return x ? x : 1;
}

RunFolder::RunFolder(std::string directory, FolderUse use, const std::vector<std::string>& names, std::ostream& log)
    : directory_(std::move(directory)) {
  const fs::path folder(directory_);
  std::error_code error;
  if (use == FolderUse::resume && !fs::is_directory(folder, error))
    throw CaseError(fmt::format("{}: no such folder, so there is no run to resume (--resume continues the run in the folder it "
                                "wrote)", directory_));
  fs::create_directories(folder, error);
  if (error) throw std::runtime_error(fmt::format("{}: cannot create the output folder ({})", directory_, error.message()));
  lock(log);
  try {
    // The names runs have written here: run_files.txt; for a folder an earlier version wrote (a
    // demdesign run_info.yaml, no list), the names a run writes, its case.yaml only when that is
    // not the case file the run read.
    bool listed = false;
    std::vector<std::string> claimed = read_claimed(folder / kRunFilesFile, directory_, &listed);
    const RunRecord record = read_run_record(directory_);
    if (!listed && record.exists) {
      const bool case_is_here = fs::equivalent(record.case_path, folder / "case.yaml", error);
      for (const std::string& name : names)
        if (name != "case.yaml" || !case_is_here) claimed.push_back(name);
    }
    std::vector<std::string> all = names;
    all.insert(all.end(), claimed.begin(), claimed.end());
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());

    std::vector<std::string> runs, foreign;
    for (const std::string& file : files_named(folder, all)) (matches_any(claimed, file) ? runs : foreign).push_back(file);
    // A file of the run's names that no run wrote is never replaced.
    if (!foreign.empty())
      throw CaseError(fmt::format("{}: not written by a demdesign run, and a run into {} writes a file of that name; nothing was "
                                  "changed. Move the file away or choose another --out folder (--overwrite replaces only files "
                                  "that runs wrote){}",
                                  (folder / foreign.front()).string(), directory_,
                                  foreign.size() > 1 ? fmt::format("; the same holds for {}", describe(std::vector<std::string>(foreign.begin() + 1, foreign.end())))
                                                     : ""));
    if (!runs.empty() && use == FolderUse::fresh) {
      const bool checkpoint = std::count(runs.begin(), runs.end(), "checkpoint.bin") + std::count(runs.begin(), runs.end(), "checkpoint.ranks.bin") > 0;
      const std::string which = record.exists ? fmt::format("a run of {}", record.case_path) : "another run";
      const std::string how_far = !record.exists    ? ""
                                  : record.completed ? fmt::format(", which ended at t = {:g} s", record.time)
                                  : record.ended     ? fmt::format(", stopped at t = {:g} s", record.time)
                                                     : ", which did not end (killed?)";
      const std::string what = fmt::format("{} holds the results of {}{}: {}", directory_, which, how_far, describe(runs));
      const std::string replace = "add --overwrite to replace them (only the files runs wrote there are removed)";
      if (record.completed) throw CaseError(fmt::format("{}. A new run would replace them: {}, or choose another --out folder", what, replace));
      if (checkpoint)
        throw CaseError(fmt::format("{}. To continue that run add --resume; to start again {}; or choose another --out folder", what, replace));
      throw CaseError(fmt::format("{}. It has no checkpoint to continue from (output.checkpoint_every): {}, or choose another --out folder",
                                  what, replace));
    }
    names_ = std::move(all);
    if (use == FolderUse::overwrite) earlier_ = std::move(runs);
  } catch (...) {
    unlock();
    throw;
  }
}

RunFolder::~RunFolder() { unlock(); }

void RunFolder::begin(std::ostream& log) {
  if (begun_) return;
  begun_ = true;
  const fs::path folder(directory_);
  std::error_code error;
  // Overwrite: the earlier run's files go, then the sub-folders they left empty; nothing else.
  if (!earlier_.empty()) {
    for (const std::string& file : earlier_) {
      fs::remove(folder / file, error);
      if (error) throw std::runtime_error(fmt::format("{}: cannot remove it for --overwrite ({})", (folder / file).string(), error.message()));
    }
    std::vector<std::string> folders;
    for (const std::string& name : names_)
      if (const std::string sub = split_name(name).first; !sub.empty())
        for (auto slash = sub.size(); slash != std::string::npos && slash > 0; slash = sub.rfind('/', slash - 1)) folders.push_back(sub.substr(0, slash));
    std::sort(folders.begin(), folders.end(), [](const std::string& a, const std::string& b) { return a.size() > b.size(); });
    for (const std::string& sub : folders)
      if (fs::is_directory(folder / sub, error) && fs::is_empty(folder / sub, error)) fs::remove(folder / sub, error);
    fmt::print(log, "  --overwrite: removed {} files of the earlier run in {}: {}\n", earlier_.size(), directory_, describe(earlier_));
  }
  write_file_atomically((folder / kRunFilesFile).string(), claimed_text(names_));
}

void RunFolder::lock(std::ostream& log) {
  const std::string path = (fs::path(directory_) / kRunLockFile).string();
  // The lock file may be removed by the run that held it between our open and our flock: then
  // the lock we got is on a file nobody else will see, and we open the path again.
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int descriptor = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (descriptor < 0) throw std::runtime_error(fmt::format("{}: cannot open the folder's lock ({})", path, std::strerror(errno)));
    if (::flock(descriptor, LOCK_EX | LOCK_NB) != 0) {
      const int why = errno;
      if (why != EWOULDBLOCK) {
        // A file system without locks: the run goes on unlocked, and says so.
        ::close(descriptor);
        fmt::print(log, "  WARNING: {}: cannot lock the folder ({}); make sure no other run writes into it\n", path, std::strerror(why));
        return;
      }
      // The holder writes its id just after taking the lock: wait a moment for it.
      long holder = lock_holder(descriptor);
      for (int wait = 0; holder == 0 && wait < 50; ++wait) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        holder = lock_holder(descriptor);
      }
      ::close(descriptor);
      throw CaseError(fmt::format("{} is being written by another run (process {}, {}); wait for it to end or stop it, or choose "
                                  "another --out folder",
                                  directory_, holder > 0 ? std::to_string(holder) : "unknown", path));
    }
    struct stat opened {}, named {};
    if (::fstat(descriptor, &opened) != 0 || ::stat(path.c_str(), &named) != 0 || opened.st_ino != named.st_ino || opened.st_dev != named.st_dev) {
      ::close(descriptor);
      continue;
    }
    // Ours. A process id left in it is a run that ended without releasing it (killed); anything
    // else is not a lock file of demdesign's.
    const long left = lock_holder(descriptor);
    if (left < 0) {
      ::close(descriptor);
      throw not_ours(path, directory_);
    }
    if (left > 0 && left != ::getpid())
      fmt::print(log, "  note: {} was left by process {}, which has ended (killed?); this run takes the folder over\n", path, left);
    const std::string pid = fmt::format("{}\n", ::getpid());
    if (::ftruncate(descriptor, 0) != 0 || ::pwrite(descriptor, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
      ::close(descriptor);
      throw std::runtime_error(fmt::format("{}: cannot write the folder's lock ({})", path, std::strerror(errno)));
    }
    lock_descriptor_ = descriptor;
    return;
  }
  throw std::runtime_error(fmt::format("{}: the lock file keeps disappearing; is another program removing it?", path));
}

void RunFolder::unlock() {
  if (lock_descriptor_ < 0) return;
  // Removed while still held, so a run that opened it meanwhile sees that it is gone (lock()).
  ::unlink((fs::path(directory_) / kRunLockFile).c_str());
  ::close(lock_descriptor_);
  lock_descriptor_ = -1;
}

}  // namespace dem
