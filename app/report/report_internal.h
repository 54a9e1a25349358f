// What the files of the run report share (report.cpp, report_analysis.cpp, report_metrics.cpp); internal to app/.
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "statistics/diagnostics.h"

namespace dem::report {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// `text` as a metrics.csv key: every character but letters and digits becomes '_'.
std::string key(const std::string& text);

/// One value per row of the run's scalars.
template <typename F>
std::vector<double> column(const std::vector<Scalars>& rows, F f) {
  std::vector<double> out;
  out.reserve(rows.size());
  for (const Scalars& r : rows) out.push_back(f(r));
  return out;
}

/// v[k], or 0 beyond its end.
inline double at(const std::vector<double>& v, std::size_t k) { return k < v.size() ? v[k] : 0.0; }

}  // namespace dem::report
