#include "pages/plot_contour.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "pages/plot.h"

namespace dem::plot {

namespace {

namespace fs = std::filesystem;

std::string number(double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v) : "NaN"; }

std::string terminal(int w, int h, const std::string& png) {
  return fmt::format(
      "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {{\n  set terminal pngcairo size {},{} noenhanced font 'DejaVu Sans,10'\n}} else {{\n"
      "  set terminal png size {},{} noenhanced\n}}\nset output {}\n",
      w, h, w, h, gnuplot_string(png));
}

/// Writes NAME.gp beside the PNG and runs gnuplot on it (plot.h).
bool run(const std::string& script, const std::string& png_path, std::string* message) {
  const fs::path gp = fs::path(png_path).replace_extension(".gp");
  {
    std::ofstream out(gp);
    if (!out) {
      if (message) *message = "cannot write " + gp.string();
      return false;
    }
    out << script;
  }
  return run_gnuplot_script(gp.string(), png_path, message);
}

void write_grid(const std::string& path, const std::vector<double>& x, const std::vector<double>& y, const std::vector<std::vector<double>>& z,
                bool log10) {
  std::ofstream out(path);
  for (size_t iy = 0; iy < y.size(); ++iy) {
    for (size_t ix = 0; ix < x.size(); ++ix) {
      const double v = log10 ? std::log10(std::max(z[iy][ix], 1e-3)) : z[iy][ix];
      out << number(x[ix]) << ' ' << number(y[iy]) << ' ' << number(v) << '\n';
    }
    out << '\n';
  }
}

}  // namespace

bool draw_errorbar_plot(const ErrorBarPlot& plot, const std::string& png_path, std::string* message) {
  try {
    fs::create_directories(fs::path(png_path).parent_path());
    const fs::path data = fs::path(png_path).replace_extension(".tsv");
    {
      std::ofstream out(data);
      for (const ErrorSeries& s : plot.series) {
        out << "# " << s.label << "\n";
        for (size_t k = 0; k < s.x.size(); ++k) out << number(s.x[k]) << '\t' << number(s.y[k]) << '\t' << number(k < s.error.size() ? s.error[k] : 0) << '\n';
        out << "\n\n";
      }
      // Each straight line as a block of its two end points, after the series' blocks.
      for (const StraightLine& l : plot.straight_lines)
        out << "# " << l.label << "\n" << number(l.x0) << '\t' << number(l.y0) << "\t0\n" << number(l.x1) << '\t' << number(l.y1) << "\t0\n\n\n";
    }
    std::string s = fmt::format("# demdesign plot: {}\n", plot.title) + terminal(plot.width, plot.height, fs::path(png_path).filename().string());
    s += fmt::format("set datafile separator tab\nset datafile missing 'NaN'\nset title {}\nset xlabel {}\nset ylabel {}\n", gnuplot_string(plot.title),
                     gnuplot_string(plot.x_label), gnuplot_string(plot.y_label));
    s += "set grid lc rgb '#dddddd'\nset key below noenhanced\nset border 3\nset tics nomirror\nset offsets 0.5, 0.5, 0, 0\n";
    if (!plot.x_tics.empty()) {
      s += "set xtics rotate by -40 (";
      for (size_t k = 0; k < plot.x_tics.size(); ++k) s += fmt::format("{}{} {}", k ? ", " : "", gnuplot_string(plot.x_tics[k]), k);
      s += ")\n";
    }
    std::vector<std::string> items;
    const std::string name = data.filename().string();
    for (size_t k = 0; k < plot.series.size(); ++k) {
      items.push_back(fmt::format("{} index {} using 1:2:3 with yerrorbars pt 7 ps 0.8 lw 1.5 lc {} title {}", gnuplot_string(name), k, k + 1,
                                  gnuplot_string(plot.series[k].label)));
      if (plot.series[k].lines) items.push_back(fmt::format("{} index {} using 1:2 with lines lw 1.2 lc {} notitle", gnuplot_string(name), k, k + 1));
    }
    for (size_t k = 0; k < plot.straight_lines.size(); ++k) {
      const StraightLine& l = plot.straight_lines[k];
      const std::string colour = l.series >= 0 ? std::to_string(l.series + 1) : "rgb '#888888'";
      items.push_back(fmt::format("{} index {} using 1:2 with lines lw 1.5 lc {} title {}", gnuplot_string(name), plot.series.size() + k, colour,
                                  gnuplot_string(l.label)));
    }
    for (double y : plot.zero_band) items.push_back(fmt::format("{} with lines dashtype 2 lc rgb '#888888' notitle", number(y)));
    s += "plot ";
    for (size_t k = 0; k < items.size(); ++k) s += (k ? ", \\\n     " : "") + items[k];
    s += "\n";
    return run(s, png_path, message);
  } catch (const std::exception& e) {
    if (message) *message = e.what();
    return false;
  }
}

bool draw_contour_plot(const ContourPlot& plot, const std::string& png_path, std::string* message) {
  try {
    fs::create_directories(fs::path(png_path).parent_path());
    const std::string stem = fs::path(png_path).stem().string();
    const fs::path dir = fs::path(png_path).parent_path();
    write_grid((dir / (stem + "_background.dat")).string(), plot.x, plot.y, plot.background, true);
    std::string s = fmt::format("# demdesign contour map: {}\n# Redraw: cd into this folder and run `gnuplot {}.gp`.\n", plot.title, stem);
    // Contour lines of each field at its levels, tabulated first, then drawn over the background.
    s += "set contour base\nunset surface\nset view map\n";
    for (size_t k = 0; k < plot.fields.size(); ++k) {
      const std::string field = fmt::format("{}_field{}.dat", stem, k);
      write_grid((dir / field).string(), plot.x, plot.y, plot.fields[k].value, false);
      std::string levels;
      for (double l : plot.fields[k].levels) {
        if (!levels.empty()) levels += ',';
        levels += number(l);
      }
      s += fmt::format("set cntrparam levels discrete {}\nset table {}\nsplot {} using 1:2:3 with lines\nunset table\n", levels,
                       gnuplot_string(fmt::format("{}_contour{}.dat", stem, k)), gnuplot_string(field));
    }
    s += "unset contour\nset surface\n";
    s += terminal(plot.width, plot.height, fs::path(png_path).filename().string());
    s += fmt::format("set title {}\nset xlabel {}\nset ylabel {}\nset cblabel {}\nset key tmargin center horizontal noenhanced\nset palette defined (0 '#f7fbff', 1 '#c6dbef', 2 '#6baed6', 3 '#2171b5')\n",
                     gnuplot_string(plot.title), gnuplot_string(plot.x_label), gnuplot_string(plot.y_label), gnuplot_string(plot.background_label));
    s += fmt::format("set xrange [{}:{}]\nset yrange [{}:{}]\n", number(plot.x.front()), number(plot.x.back()), number(plot.y.front()), number(plot.y.back()));
    s += fmt::format("plot {} using 1:2:3 with image notitle", gnuplot_string(stem + "_background.dat"));
    const char* colours[] = {"#b2182b", "#1b7837", "#762a83", "#e08214"};
    for (size_t k = 0; k < plot.fields.size(); ++k)
      s += fmt::format(", \\\n     {} using 1:2 with lines lw 2.5 lc rgb '{}' title {}", gnuplot_string(fmt::format("{}_contour{}.dat", stem, k)),
                       colours[k % 4], gnuplot_string(plot.fields[k].label));
    s += fmt::format(", \\\n     '-' using 1:2 with points pt 9 ps 2 lc rgb '#000000' title {}\n{} {}\ne\n", gnuplot_string(plot.marker_label),
                     number(plot.marker_x), number(plot.marker_y));
    return run(s, png_path, message);
  } catch (const std::exception& e) {
    if (message) *message = e.what();
    return false;
  }
}

}  // namespace dem::plot
