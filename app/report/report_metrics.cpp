// metrics.csv: the key numbers of a run as the run report writes them (write_run_report,
// report.cpp) and a sweep reads them back to rank its variants: `name,value` rows, a `steady`
// row (1/0) and a `# steady_text: ...` line.
#include "report/report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "output/run.h"
#include "report/report_internal.h"

namespace dem::report {

std::string key(const std::string& text) {
  std::string out;
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

double RunMetrics::get(const std::string& name) const {
  for (const auto& [n, v] : values)
    if (n == name) return v;
  return kNaN;
}

double RunMetrics::noise(const std::string& metric) const {
  const size_t unit = metric.rfind("_t_h");
  return get(unit != std::string::npos && unit + 4 == metric.size() ? metric.substr(0, unit) + "_std_t_h" : metric + "_std");
}

void write_metrics(const RunMetrics& metrics, const std::string& path) {
  std::string text = "name,value\n";
  text += fmt::format("steady,{}\n", metrics.steady ? 1 : 0);
  std::string steady_text = metrics.steady_text;
  std::replace(steady_text.begin(), steady_text.end(), '\n', ' ');
  text += "# steady_text: " + steady_text + "\n";
  for (const auto& [name, value] : metrics.values) text += fmt::format("{},{:.17g}\n", key(name), value);
  write_file_atomically(path, text);
}

RunMetrics read_metrics(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error(fmt::format("{}: cannot read the metrics file", path));
  std::stringstream text;
  text << file.rdbuf();
  return parse_metrics(text.str(), path);
}

RunMetrics parse_metrics(const std::string& text, const std::string& path) {
  std::istringstream in(text);
  RunMetrics m;
  std::string line;
  const std::string text_tag = "# steady_text: ";
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.rfind(text_tag, 0) == 0) {
      m.steady_text = line.substr(text_tag.size());
      continue;
    }
    if (line.empty() || line[0] == '#' || line == "name,value") continue;
    const std::size_t comma = line.find(',');
    if (comma == std::string::npos) throw std::runtime_error(fmt::format("{}:{}: expected name,value", path, number));
    const std::string name = line.substr(0, comma);
    double value = kNaN;
    try {
      value = std::stod(line.substr(comma + 1));
    } catch (const std::exception&) {
      throw std::runtime_error(fmt::format("{}:{}: '{}' is not a number", path, number, line.substr(comma + 1)));
    }
    if (name == "steady")
      m.steady = value != 0;
    else
      m.values.emplace_back(name, value);
  }
  return m;
}

}  // namespace dem::report
