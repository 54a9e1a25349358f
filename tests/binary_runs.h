// Helpers of the tests that run the real demdesign binary on case files they write: read a file,
// run the binary, read a CSV the run wrote.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace dem::test {

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// `demdesign ARGS` (each argument quoted), output to `log`; the exit status as std::system gives it.
inline int run_binary(const std::vector<std::string>& args, const std::filesystem::path& log) {
  std::string command = std::string("'") + DEMDESIGN_BINARY + "'";
  for (const std::string& a : args) command += " '" + a + "'";
  command += " > '" + log.string() + "' 2>&1";
  return std::system(command.c_str());
}

/// `demdesign CASE --out OUT`, output to OUT.log.
inline int run_case(const std::filesystem::path& case_file, const std::filesystem::path& out) {
  return run_binary({case_file.string(), "--out", out.string()}, out.string() + ".log");
}

/// The rows of a CSV file after its header; cells split at commas outside double quotes.
inline std::vector<std::vector<std::string>> csv_rows(const std::filesystem::path& path) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(read_text(path));
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    bool quoted = false;
    for (char c : line) {
      if (c == '"') quoted = !quoted;
      else if (c == ',' && !quoted) cells.push_back(cell), cell.clear();
      else cell += c;
    }
    cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

}  // namespace dem::test
