// metrics.csv: the key numbers of a run as the run report writes them (write_run_report,
// report.cpp) and a sweep reads them back to rank its variants: `name,value,std_error` rows, a
// `steady` row (1/0) and a `# steady_text: ...` line. The standard error is a third column, empty
// where a metric has none, rather than a row of its own (`METRIC_se`): a row would be a metric the
// sweep ranks, the uncertainty study bands and the bias check shifts.
#include "report/report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
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

double RunMetrics::std_error(const std::string& metric) const {
  const auto it = std_errors.find(metric);
  return it == std_errors.end() ? kNaN : it->second;
}

double RunMetrics::noise(const std::string& metric) const {
  const size_t unit = metric.rfind("_t_h");
  return get(unit != std::string::npos && unit + 4 == metric.size() ? metric.substr(0, unit) + "_std_t_h" : metric + "_std");
}

void write_metrics(const RunMetrics& metrics, const std::string& path) {
  std::string text = "name,value,std_error\n";
  text += fmt::format("steady,{}\n", metrics.steady ? 1 : 0);
  std::string steady_text = metrics.steady_text;
  std::replace(steady_text.begin(), steady_text.end(), '\n', ' ');
  text += "# steady_text: " + steady_text + "\n";
  for (const auto& [name, value] : metrics.values) {
    const double error = metrics.std_error(name);
    text += fmt::format("{},{:.17g},{}\n", key(name), value, std::isnan(error) ? std::string() : fmt::format("{:.17g}", error));
  }
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
    if (line.empty() || line[0] == '#' || line == "name,value" || line == "name,value,std_error") continue;
    const std::size_t comma = line.find(',');
    if (comma == std::string::npos) throw std::runtime_error(fmt::format("{}:{}: expected name,value,std_error", path, number));
    const std::string name = line.substr(0, comma);
    const std::size_t second = line.find(',', comma + 1);
    const std::string value_text = line.substr(comma + 1, second == std::string::npos ? std::string::npos : second - comma - 1);
    const std::string error_text = second == std::string::npos ? std::string() : line.substr(second + 1);
    const auto number_of = [&](const std::string& cell) {
      try {
        return std::stod(cell);
      } catch (const std::exception&) {
        throw std::runtime_error(fmt::format("{}:{}: '{}' is not a number", path, number, cell));
      }
    };
    const double value = number_of(value_text);
    if (name == "steady")
      m.steady = value != 0;
    else
      m.values.emplace_back(name, value);
    if (!error_text.empty() && name != "steady") m.std_errors[name] = number_of(error_text);
  }
  return m;
}

}  // namespace dem::report
