#include "pages/video.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

extern char** environ;

namespace dem::app {

bool make_video(const std::string& directory, const std::string& prefix, const std::string& output, double fps,
                std::string* message) {
  const std::string log = output + ".log";
  std::vector<std::string> args = {"ffmpeg", "-y", "-loglevel", "error", "-framerate", fmt::format("{:g}", fps),
                                   "-pattern_type", "glob", "-i", (std::filesystem::path(directory) / (prefix + "*.png")).string(),
                                   // H.264 needs even dimensions; yuv420p plays everywhere.
                                   "-vf", "scale=trunc(iw/2)*2:trunc(ih/2)*2", "-pix_fmt", "yuv420p", "-c:v", "libx264", output};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int error = posix_spawnp(&pid, "ffmpeg", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) {
    std::filesystem::remove(log);
    if (message) *message = fmt::format("ffmpeg not found: install the Debian package ffmpeg to get videos; the PNG frames are in {}", directory);
    return false;
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    std::filesystem::remove(log);
    return true;
  }
  if (message) {
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    *message = fmt::format("ffmpeg failed (see {}): {}", log, text.str().substr(0, 500));
  }
  return false;
}

}  // namespace dem::app
