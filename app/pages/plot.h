// Line plots drawn by gnuplot (Debian package gnuplot-nox), a maintained plotting program: the
// data go to a TSV file and the commands to a gnuplot script next to the PNG, and gnuplot runs
// without a shell (posix_spawnp). The scripts are kept: `cd DIR && gnuplot NAME.gp` redraws a
// plot, and they document how it was made. The terminal is pngcairo, or png where gnuplot was
// built without cairo.
// Rejected alternative: drawing SVG by hand (axes, ticks and legends are a plotting program's job).
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace dem::plot {

/// One line of a plot; x and y have the same length (NaN leaves a gap). With `lo` and `hi` of the
/// same length too, the interval between them is shaded in the line's colour (a band, e.g. 5 % to
/// 95 % over samples) and named `band_label` in the key.
struct Series {
  std::string label;
  std::vector<double> x, y;
  std::vector<double> lo = {}, hi = {};
  std::string band_label = {};
};

/// A horizontal reference line (a mean, a design value), drawn dashed with its label in the key.
struct HorizontalLine {
  double y = 0;
  std::string label;
};

struct Plot {
  std::string title;
  std::string x_label;  ///< with units: "time [s]"
  std::string y_label;  ///< with units: "mass flow [t/h]"
  std::vector<Series> series;
  std::optional<std::pair<double, double>> band;  ///< shaded x interval, e.g. the steady state [s]
  std::string band_label = "steady state";
  std::vector<HorizontalLine> lines;
  int width = 960, height = 480;  // [px]
};

/// Writes NAME.tsv and NAME.gp next to png_path (NAME.png) and runs gnuplot on the script.
/// Returns false with a message (never throws for a missing or failing gnuplot): "gnuplot not
/// found: install gnuplot-nox for the plots", or gnuplot's own error output.
bool draw_plot(const Plot& plot, const std::string& png_path, std::string* message);

/// Runs gnuplot on the script `script_path` in the script's folder (no shell; gnuplot's errors go
/// to a .log beside the PNG, removed when empty) and checks that it drew `png_path`. Returns false
/// with a message as draw_plot does. For plot kinds that write their own script (plot_contour.h).
bool run_gnuplot_script(const std::string& script_path, const std::string& png_path, std::string* message);

/// `text` as a gnuplot single-quoted string literal (no escapes are interpreted inside; a quote
/// is doubled; line breaks become spaces). Labels are also set `noenhanced`, so underscores in
/// mesh names print as they are.
std::string gnuplot_string(const std::string& text);

}  // namespace dem::plot
