// `demdesign validate`: runs the published benchmarks (app/validation/validation.h) and writes
// OUT/validation.csv, OUT/validation.html, OUT/validation.md and OUT/plots/.
#pragma once

#include <ostream>
#include <string>

namespace dem::app {

/// Runs every benchmark from the cases in SOURCE_DIR/cases, writes the page into `out` and
/// prints a line per curve; 0 when every point is inside its tolerance (or a known difference).
int validate_command(const std::string& source_dir, const std::string& out, std::ostream& log);

}  // namespace dem::app
