// Two more plot kinds drawn by gnuplot, in the manner of plot.h (data and script kept beside the
// PNG): points with error bars (measured against simulated), and the Fig. 5 map: a background
// field over two parameters with one contour line per observation at its measured value.
#pragma once

#include <string>
#include <vector>

namespace dem::plot {

struct ErrorSeries {
  std::string label;
  std::vector<double> x, y, error;  ///< error: one sigma (0: none)
  bool lines = false;               ///< join the points
};

/// A straight line between two points (a fitted line), drawn solid in the colour of one series.
struct StraightLine {
  std::string label;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int series = -1;  ///< index of the series whose colour it takes; -1: grey
};

struct ErrorBarPlot {
  std::string title, x_label, y_label;
  std::vector<ErrorSeries> series;
  std::vector<StraightLine> straight_lines;
  std::vector<std::string> x_tics;  ///< when given, x = 0, 1, ... are labelled with these (rotated)
  std::vector<double> zero_band;    ///< horizontal dashed lines (e.g. -2, 0, 2 sigma)
  int width = 960, height = 480;    // [px]
};

struct ContourField {
  std::string label;
  std::vector<std::vector<double>> value;  ///< [iy][ix]
  std::vector<double> levels;              ///< contour levels drawn (measured, and +- sigma)
};

struct ContourPlot {
  std::string title, x_label, y_label, background_label;
  std::vector<double> x, y;                       ///< axes
  std::vector<std::vector<double>> background;    ///< [iy][ix], drawn as log10 image
  std::vector<ContourField> fields;
  double marker_x = 0, marker_y = 0;              ///< the fit
  std::string marker_label = "fit";
  int width = 800, height = 640;
};

bool draw_errorbar_plot(const ErrorBarPlot& plot, const std::string& png_path, std::string* message);
bool draw_contour_plot(const ContourPlot& plot, const std::string& png_path, std::string* message);

}  // namespace dem::plot
