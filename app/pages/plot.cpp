// gnuplot driver: TSV data + script next to the PNG, gnuplot spawned without a shell.
#include "pages/plot.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

extern char** environ;

namespace dem::plot {
namespace {

namespace fs = std::filesystem;

const char* kNotFound = "gnuplot not found: install gnuplot-nox for the plots";

/// Text for a `#` comment line: line breaks would end the comment and start a command.
std::string one_line(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text;
}

std::string number(double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v) : "NaN"; }

std::string read_all(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool has_band(const Series& s) { return !s.lo.empty() && s.lo.size() == s.x.size() && s.hi.size() == s.x.size(); }

/// The script that draws `plot` from `data_name` into `png_name` (both relative to its folder).
std::string script(const Plot& plot, const std::vector<const Series*>& drawn, const std::string& data_name,
                   const std::string& png_name) {
  std::string s = fmt::format(
      "# demdesign plot: {}\n# Redraw: cd into this folder and run `gnuplot {}`.\n"
      "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {{\n"
      "  set terminal pngcairo size {},{} noenhanced font 'DejaVu Sans,10'\n"
      "}} else {{\n"
      "  set terminal png size {},{} noenhanced\n"
      "}}\n"
      "set output {}\n"
      "set datafile separator tab\nset datafile missing 'NaN'\n"
      "set title {} noenhanced\nset xlabel {} noenhanced\nset ylabel {} noenhanced\n"
      "set grid lc rgb '#dddddd'\nset key below noenhanced\nset border 3\nset tics nomirror\n",
      one_line(plot.title), fs::path(png_name).replace_extension(".gp").string(), plot.width, plot.height, plot.width,
      plot.height, gnuplot_string(png_name), gnuplot_string(plot.title), gnuplot_string(plot.x_label),
      gnuplot_string(plot.y_label));
  const char* band_colour = "#d8ecd8";
  if (plot.band)
    s += fmt::format(
        "set object 1 rect from {}, graph 0 to {}, graph 1 behind fillcolor rgb '{}' fillstyle solid 1.0 noborder\n",
        number(plot.band->first), number(plot.band->second), band_colour);
  std::vector<std::string> items;
  // Line k in line type k + 1 (gnuplot's own order), its band, when it has one, in the same colour.
  for (std::size_t k = 0; k < drawn.size(); ++k)
    if (has_band(*drawn[k]))
      items.push_back(fmt::format("{} index {} using 1:3:4 with filledcurves fillstyle transparent solid 0.25 noborder lt {} title {}",
                                  gnuplot_string(data_name), k, k + 1, gnuplot_string(drawn[k]->band_label)));
  for (std::size_t k = 0; k < drawn.size(); ++k)
    items.push_back(fmt::format("{} index {} using 1:2 with lines lw 1.5 lt {} title {}", gnuplot_string(data_name), k, k + 1,
                                gnuplot_string(drawn[k]->label)));
  const char* line_colours[] = {"#222222", "#b2182b", "#2166ac", "#762a83"};
  for (std::size_t k = 0; k < plot.lines.size(); ++k)
    items.push_back(fmt::format("{} with lines dashtype {} lw 1.5 lc rgb '{}' title {}", number(plot.lines[k].y),
                                2 + k % 3, line_colours[k % 4], gnuplot_string(plot.lines[k].label)));
  if (plot.band)
    items.push_back(fmt::format("keyentry with boxes fillcolor rgb '{}' fillstyle solid 1.0 title {}", band_colour,
                                gnuplot_string(plot.band_label)));
  s += "plot ";
  for (std::size_t k = 0; k < items.size(); ++k) s += (k ? ", \\\n     " : "") + items[k];
  s += "\n";
  return s;
}

/// Runs `gnuplot script` in `folder` without a shell; stdout is discarded, stderr goes to
/// `log`. Returns the exit status, or -1 with errno-style `spawn_error` when it did not start.
int run_gnuplot(const fs::path& folder, const fs::path& script_path, const fs::path& log, int* spawn_error) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addchdir_np(&actions, folder.c_str());
  std::string program = "gnuplot", argument = script_path.filename().string();
  char* argv[] = {program.data(), argument.data(), nullptr};
  pid_t pid = 0;
  const int error = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) {
    *spawn_error = error;
    return -1;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      *spawn_error = errno;
      return -1;
    }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

}  // namespace

std::string gnuplot_string(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'')
      out += "''";
    else if (c == '\n' || c == '\r' || c == '\t')
      out += ' ';
    else
      out += c;
  }
  return out + "'";
}

bool draw_plot(const Plot& plot, const std::string& png_path, std::string* message) {
  auto fail = [&](const std::string& why) {
    if (message) *message = why;
    return false;
  };
  try {
    const fs::path png = fs::absolute(png_path);
    const fs::path folder = png.parent_path();
    fs::create_directories(folder);
    const fs::path data = fs::path(png).replace_extension(".tsv"), script_path = fs::path(png).replace_extension(".gp");

    // Data: one block per series (gnuplot `index k`), blocks separated by two blank lines.
    std::vector<const Series*> drawn;
    std::string table;
    for (const Series& s : plot.series) {
      if (s.x.empty() || s.x.size() != s.y.size()) continue;
      if (!drawn.empty()) table += "\n\n";
      table += fmt::format("# {}\n", one_line(s.label));
      for (std::size_t i = 0; i < s.x.size(); ++i)
        table += number(s.x[i]) + "\t" + number(s.y[i]) + (has_band(s) ? "\t" + number(s.lo[i]) + "\t" + number(s.hi[i]) : std::string()) + "\n";
      drawn.push_back(&s);
    }
    if (drawn.empty()) return fail("no data to plot");
    {
      std::ofstream out(data);
      out << table;
      std::ofstream gp(script_path);
      gp << script(plot, drawn, data.filename().string(), png.filename().string());
      if (!out || !gp) return fail(fmt::format("{}: cannot write the plot's data or script", folder.string()));
    }
    return run_gnuplot_script(script_path.string(), png.string(), message);
  } catch (const std::exception& e) {
    return fail(fmt::format("plot {}: {}", png_path, e.what()));
  }
}

bool run_gnuplot_script(const std::string& script, const std::string& png_path, std::string* message) {
  auto fail = [&](const std::string& why) {
    if (message) *message = why;
    return false;
  };
  const fs::path script_path = fs::absolute(script), png = fs::absolute(png_path);
  const fs::path folder = script_path.parent_path(), log = fs::path(png).replace_extension(".log");
  fs::remove(png);
  int spawn_error = 0;
  const int status = run_gnuplot(folder, script_path, log, &spawn_error);
  if (status < 0 || status == 127) fs::remove(log);
  if (status < 0) return fail(spawn_error == ENOENT ? kNotFound : fmt::format("gnuplot could not start: {}", std::strerror(spawn_error)));
  if (status == 127) return fail(kNotFound);
  const std::string errors = read_all(log);
  if (errors.empty()) fs::remove(log);
  if (status != 0 || !fs::exists(png) || fs::file_size(png) == 0)
    return fail(fmt::format("gnuplot failed on {} (exit status {}): {}", script_path.filename().string(), status, errors.substr(0, 600)));
  if (message) message->clear();
  return true;
}

}  // namespace dem::plot
