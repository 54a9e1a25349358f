// What the files of the run report share (report.cpp, report_metrics.cpp); internal to app/.
#pragma once

#include <limits>
#include <string>

namespace dem::report {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// `text` as a metrics.csv key: every character but letters and digits becomes '_'.
std::string key(const std::string& text);

}  // namespace dem::report
