// The run report's page: plots by gnuplot and one self-contained HTML file of the numbers that
// app/report/report_analysis.cpp finds (the sweep report is app/campaign/sweep_report.cpp; metrics.csv is
// app/report/report_metrics.cpp).
#include "report/report.h"

#include "pages/html.h"

#include <fmt/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

#include "case/liner_materials.h"
#include "output/run.h"
#include "pages/plot.h"
#include "report/liner_loads.h"
#include "report/choke.h"
#include "report/report_analysis.h"
#include "report/report_internal.h"
#include "report/report_wear.h"
#include "statistics/steady_state.h"

namespace dem::report {
namespace {

namespace fs = std::filesystem;

// ---- text (escaping, numbers, images, page head: app/pages/html.h) ------------------------------

using html::embed_image;
using html::esc;
using html::now_text;
using html::num;
std::string html_head(const std::string& title) { return html::head(title); }

std::string pm(double mean, double spread, int sig = 4) { return num(mean, sig) + " &plusmn; " + num(spread, 2); }

std::string table_row(std::initializer_list<std::string> cells, bool header = false) { return html::row(cells, header); }

/// Mean and standard error of the mean over the run's interval ("m &plusmn; e"), times `scale`
/// (1e-3: W to kW, N to kN, N m to kN m).
std::string pm_se(const IntervalStats& s, double scale) { return pm(scale * s.mean, scale * s.std_error); }

/// A series times `scale`, for a plot in kW or kN m.
std::vector<double> scaled(std::vector<double> y, double scale) {
  for (double& v : y) v *= scale;
  return y;
}

/// Where a series' own steady part begins, or why it has none.
std::string own_steady(const Quantity& q) { return q.own.found ? fmt::format("from {} s", num(q.own.t_start, 3)) : esc(q.own.why); }

/// "(x, y, z)" of a point [m] or a unit direction.
std::string vector_text(const Eigen::Vector3d& v) { return fmt::format("({}, {}, {})", num(v.x(), 4), num(v.y(), 4), num(v.z(), 4)); }

/// Draws a plot into dir/plots and returns the HTML figure (or the reason there is none).
std::string figure(const plot::Plot& p, const std::string& dir, const std::string& name, const std::string& caption) {
  const std::string png = (fs::path(dir) / "plots" / (name + ".png")).string();
  std::string message;
  const bool ok = plot::draw_plot(p, png, &message);
  std::string body = ok ? embed_image(png, p.title)
                        : fmt::format("<p class=\"missing\">Plot &ldquo;{}&rdquo; not drawn: {}. Its data are in plots/{}.tsv.</p>",
                                      esc(p.title), esc(message), esc(name));
  return fmt::format("<figure>{}<figcaption>{}</figcaption></figure>\n", body, caption);
}

// ---- the run report's page, section by section ----------------------------------------------

/// What the sections of the run report's page share: the input, its analysis, the model and
/// final state, and the report folder (plots go to its plots/).
struct Page {
  const RunReportInput& in;
  const RunAnalysis& run;
  const Model& model;
  const State& state;
  const std::string& dir;

  /// Shades, on a time plot, the interval the averages are taken over.
  void set_band(plot::Plot& p) const {
    p.band = std::pair<double, double>{run.run_t0, run.run_t1};
    p.band_label = run.steady ? "steady state" : "last third (not steady)";
  }
};

/// The page head, the title and the line of what was run.
std::string page_head(const Page& page) {
  const RunReportInput& in = page.in;
  const Model& model = page.model;
  const std::string title = model.title.empty() ? fs::path(in.case_path).stem().string() : model.title;
  std::string h = html_head(title + " - demdesign run report");
  h += fmt::format("<h1>{}</h1>\n<p class=\"meta\">Run report &middot; {} &middot; demdesign {} &middot; case <code>{}</code> &middot; "
                   "simulated {} s in {} s wall time</p>\n",
                   esc(title), esc(now_text()), esc(in.version), esc(in.case_path), num(page.run.t_end, 4), num(in.wall_seconds, 3));
  return h;
}

/// What to know before the numbers: a stopped run, no steady state, blockage, spillage, a scaled
/// model, or that all is well.
std::string banners(const Page& page) {
  const RunReportInput& in = page.in;
  const RunAnalysis& run = page.run;
  const Model& model = page.model;
  std::string h;
  if (!in.stopped.empty())
    h += fmt::format("<div class=\"banner bad\">The run stopped before its end, at t = {} s: {}. Everything below is what it computed up to "
                     "then.</div>\n",
                     num(run.t_end, 4), esc(in.stopped));
  if (!run.steady)
    h += fmt::format("<div class=\"banner bad\">No steady state reached ({}): {}. The values below are averages over the last third "
                     "of the run ({}) and are for information only.</div>\n",
                     esc(run.primary.name), esc(run.primary.own.why), run.interval_text);
  if (run.blockage.blocked) h += fmt::format("<div class=\"banner bad\">Blockage: {}.</div>\n", esc(run.blockage.text));
  if (run.spillage > 0)
    h += fmt::format("<div class=\"banner warn\">Spillage: {} kg ({} % of the inserted mass) left the domain or went to outlets that "
                     "are not intended.</div>\n",
                     num(run.spillage, 3), num(run.spillage_pct, 3));
  if (model.mass_scaling != 1 || model.stiffness_scaling != 1)
    h += fmt::format("<div class=\"banner warn\">Scaled model: particle density &times; {}, Young&#39;s modulus &times; {}. Forces, "
                     "power and wear scale with these factors.</div>\n",
                     num(model.mass_scaling, 3), num(model.stiffness_scaling, 3));
  if (model.coarse_grain != 1)
    h += fmt::format("<div class=\"banner warn\">Coarse-grained model: each particle is a parcel standing for {} real particles, "
                     "{} &times; their diameter, with the contact parameters scaled to keep the contact stresses (stress "
                     "similarity). Mass flow, power, pressure and wear are the real material&#39;s, not rescaled; what depends on "
                     "sizes finer than a parcel (segregation, fines) is not reproduced. Details under Reproducibility.</div>\n",
                     num(model.coarse_grain * model.coarse_grain * model.coarse_grain, 4), num(model.coarse_grain, 4));
  if (run.steady && !run.blockage.blocked && run.spillage <= 0)
    h += fmt::format("<div class=\"banner good\">Steady state from {} ({} samples); no blockage, no spillage.</div>\n", run.interval_text,
                     run.primary.own.samples);
  return h;
}

/// The key numbers in one table.
std::string summary(const Page& page) {
  const RunAnalysis& run = page.run;
  const Model& model = page.model;
  const Quantity& primary = run.primary;
  const std::vector<Hotspot>& spots = run.spots;
  std::string h = "<h2>Summary</h2>\n";
  h += fmt::format("<p><b>{}</b>.{} Values are means &plusmn; standard deviation of the signal over the {} interval <b>{}</b>, "
                   "except the drives&#39;, which are &plusmn; the standard error of the mean (batch means), as it is given for the "
                   "other means where it matters.</p>\n<table>\n",
                   esc(run.metrics.steady_text),
                   model.outlets.empty() ? std::string()
                                         : fmt::format(" Throughput {} t/h.", num(primary.at_run.mean, 4)),
                   run.steady ? "steady-state" : "last-third", run.interval_text);
  h += table_row({"quantity", "value", "unit", "note"}, true);
  if (!model.outlets.empty()) {
    h += table_row({"throughput (intended outlets)", pm(primary.at_run.mean, primary.at_run.std_dev), "t/h",
                    fmt::format("std error of the mean {} t/h", num(primary.own.std_error, 2))});
    if (!std::isnan(run.capacity))
      h += table_row({esc(run.capacity_label), num(run.capacity), "t/h",
                      esc(run.capacity_source) + (run.capacity > 0 ? fmt::format("; throughput = {} % of it", num(100 * primary.at_run.mean / run.capacity, 3)) : "")});
  }
  for (const Quantity& q : run.plane_sensors) h += table_row({esc(q.name) + " flow", pm(q.at_run.mean, q.at_run.std_dev), "t/h", ""});
  h += table_row({"spillage", num(run.spillage, 3), "kg", fmt::format("{} % of the inserted {} kg", num(run.spillage_pct, 3), num(run.last.inserted_mass, 4))});
  h += table_row({"hold-up at the end", num(run.holdup.empty() ? 0.0 : run.holdup.back()), "kg", "inserted &minus; removed &minus; lost"});
  h += table_row({"blockage", run.blockage.blocked ? "<b>yes</b>" : "no", "", esc(run.blockage.text)});
  for (const Drive& d : run.drives)
    h += table_row({"drive power of " + esc(d.name), pm_se(d.power.at_run, 1e-3), "kW",
                    fmt::format("{} {} {}", d.kind == DriveKind::rotating ? "shaft torque" : "pull",
                                pm_se(d.effort.at_run, 1e-3), d.kind == DriveKind::rotating ? "kN m about its own axis" : "kN")});
  for (const BoxResult& b : run.boxes)
    h += table_row({"centring offset on " + esc(b.name), pm(b.offset.at_run.mean, b.offset.at_run.std_dev, 3), "mm",
                    b.width > 0 ? fmt::format("{} % of the {} mm box width", num(100 * b.offset.at_run.mean / (1000 * b.width), 3), num(1000 * b.width, 4)) : ""});
  if (!spots.empty())
    h += table_row({"highest shear power per area (wear)", num(spots.front().shear_rate, 3), "W/m&sup2;",
                    fmt::format("{} triangle {}", esc(model.meshes[spots.front().mesh].name), spots.front().triangle)});
  h += "</table>\n";
  return h;
}

/// Mass flow at each outlet: the table and the plot.
std::string outlet_flow(const Page& page) {
  const RunAnalysis& run = page.run;
  const Model& model = page.model;
  const Quantity& primary = run.primary;
  const std::vector<Quantity>& outlets = run.outlets;
  std::string h = "<p>Mass flow at each outlet: the rate of its cumulative mass, by differences over a window of ten rows (centred). The green "
                  "band marks the interval the averages are taken over.</p>\n<table>\n";
  h += table_row({"outlet", "intended", "mean &plusmn; std dev [t/h]", "std error [t/h]", "own steady state", "total [kg]"}, true);
  for (std::size_t k = 0; k < outlets.size(); ++k)
    h += table_row({esc(model.outlets[k].name), run.intended[k] ? "yes" : "<b>no (spillage)</b>", pm(outlets[k].at_run.mean, outlets[k].at_run.std_dev),
                    num(outlets[k].own.std_error, 2),
                    outlets[k].own.found ? fmt::format("from {} s", num(outlets[k].own.t_start, 3)) : esc(outlets[k].own.why),
                    num(at(run.last.outlet_mass, k))});
  h += "</table>\n";
  plot::Plot p;
  p.title = "Mass flow at the outlets";
  p.x_label = "time [s]";
  p.y_label = "mass flow [t/h]";
  if (outlets.size() > 1) p.series.push_back({"throughput (intended outlets)", run.t, primary.y});
  for (const Quantity& q : outlets) p.series.push_back({q.name, run.t, q.y});
  page.set_band(p);
  p.lines.push_back({primary.at_run.mean, fmt::format("mean {:.4g} t/h", primary.at_run.mean)});
  if (!std::isnan(run.capacity)) p.lines.push_back({run.capacity, fmt::format("{} {:.4g} t/h", run.capacity_label, run.capacity)});
  h += figure(p, page.dir, "outlet_flow", fmt::format("Mass flow at the outlets; mean over {}: {} t/h.", run.interval_text,
                                                       pm(primary.at_run.mean, primary.at_run.std_dev)));
  return h;
}

/// Mass flow through the plane sensors and what crosses them: the tables and the plot.
std::string plane_sensor_flow(const Page& page) {
  const RunAnalysis& run = page.run;
  const std::vector<Quantity>& plane_sensors = run.plane_sensors;
  std::string h = "<h3>Plane sensors</h3>\n<table>\n";
  h += table_row({"sensor", "mean &plusmn; std dev [t/h]", "std error [t/h]", "own steady state"}, true);
  for (const Quantity& q : plane_sensors)
    h += table_row({esc(q.name), pm(q.at_run.mean, q.at_run.std_dev), num(q.own.std_error, 2),
                    q.own.found ? fmt::format("from {} s", num(q.own.t_start, 3)) : esc(q.own.why)});
  h += "</table>\n";
  h += fmt::format("<p>What crosses each plane, averaged over {} (&plusmn; the standard error of the mean, from batch means): "
                   "particles per second along the normal, and the mean velocity of the crossing material, each particle in the "
                   "sensor&#39;s slab weighted by the mass it carries across per second.</p>\n<table>\n", run.interval_text);
  h += table_row({"sensor", "particles through [1/s]", "v<sub>x</sub> [m/s]", "v<sub>y</sub> [m/s]", "v<sub>z</sub> [m/s]", "speed [m/s]"}, true);
  for (std::size_t j = 0; j < plane_sensors.size() && 4 * j + 3 < run.plane_detail.size(); ++j) {
    const auto se = [&](int c) { return pm(run.plane_detail[4 * j + c].at_run.mean, run.plane_detail[4 * j + c].at_run.std_error); };
    const double vx = run.plane_detail[4 * j + 1].at_run.mean, vy = run.plane_detail[4 * j + 2].at_run.mean, vz = run.plane_detail[4 * j + 3].at_run.mean;
    h += table_row({esc(plane_sensors[j].name), se(0), se(1), se(2), se(3), num(std::sqrt(vx * vx + vy * vy + vz * vz), 4)});
  }
  h += "</table>\n";
  plot::Plot p;
  p.title = "Mass flow through the plane sensors";
  p.x_label = "time [s]";
  p.y_label = "mass flow [t/h]";
  for (const Quantity& q : plane_sensors) p.series.push_back({q.name, run.t, q.y});
  page.set_band(p);
  if (!std::isnan(run.capacity)) p.lines.push_back({run.capacity, fmt::format("{} {:.4g} t/h", run.capacity_label, run.capacity)});
  h += figure(p, page.dir, "sensor_flow", "Mass flow through the plane sensors (along each sensor's normal).");
  return h;
}

/// Throughput: at the outlets, then through the plane sensors.
std::string throughput(const Page& page) {
  std::string h = "<h2>Throughput</h2>\n";
  if (page.model.outlets.empty() && page.run.plane_sensors.empty()) h += "<p>The case has no outlets and no plane sensors.</p>\n";
  if (!page.model.outlets.empty()) h += outlet_flow(page);
  if (!page.run.plane_sensors.empty()) h += plane_sensor_flow(page);
  return h;
}

/// Spillage and blockage, with the plot of the cumulative masses.
std::string mass_balance(const Page& page) {
  const RunAnalysis& run = page.run;
  const Model& model = page.model;
  const std::vector<double>& t = run.t;
  std::string intended_names;
  for (std::size_t k = 0; k < model.outlets.size(); ++k)
    if (run.intended[k]) intended_names += (intended_names.empty() ? "" : ", ") + esc(model.outlets[k].name);
  if (intended_names.empty()) intended_names = "none";
  std::string h = "<h2>Mass balance, spillage and blockage</h2>\n";
  h += fmt::format("<p>Spillage = mass that left the domain ({} kg) + mass into outlets that are not intended ({} kg) = <b>{} kg</b>, {} % "
                   "of the {} kg inserted. Intended outlets: {}.</p>\n",
                   num(run.last.lost_mass, 3), num(run.spill_outlets, 3), num(run.spillage, 3), num(run.spillage_pct, 3), num(run.last.inserted_mass, 4),
                   intended_names);
  h += fmt::format("<p>Blockage rule: {}. Result: {}.</p>\n", esc(kBlockageRule), esc(run.blockage.text));
  plot::Plot p;
  p.title = "Mass balance";
  p.x_label = "time [s]";
  p.y_label = "mass [kg]";
  p.series = {{"inserted", t, run.inserted}, {"removed by outlets", t, run.removed}, {"lost (left the domain)", t, run.lost}, {"hold-up", t, run.holdup}};
  h += figure(p, page.dir, "mass_balance", "Cumulative masses and the hold-up (inserted &minus; removed &minus; lost).");
  return h;
}

/// The particles' force on each mesh, by component, in kN.
std::string mesh_loads(const Page& page) {
  const RunAnalysis& run = page.run;
  const Model& model = page.model;
  std::string h = fmt::format("<h3>Loads on the meshes</h3>\n<p>The particles&#39; force on each mesh by component, averaged over {} &plusmn; "
                              "the standard error of the mean (batch means); |F&#772;| is the magnitude of the mean force, which noise does "
                              "not inflate as it does the mean of the magnitude. Static parts appear here only: they do no work. "
                              "mesh_loads.csv has these with the torque about each mesh&#39;s motion origin (the world origin for a mesh "
                              "that does not move).</p>\n<table>\n", run.interval_text);
  h += table_row({"mesh", "kind", "F<sub>x</sub> [kN]", "F<sub>y</sub> [kN]", "F<sub>z</sub> [kN]", "|F&#772;| [kN]"}, true);
  for (std::size_t m = 0; m < model.meshes.size() && 6 * m + 5 < run.mesh_load.size(); ++m) {
    const auto se = [&](int c) { return pm_se(run.mesh_load[6 * m + c].at_run, 1e-3); };
    const double fx = run.mesh_load[6 * m].at_run.mean, fy = run.mesh_load[6 * m + 1].at_run.mean, fz = run.mesh_load[6 * m + 2].at_run.mean;
    h += table_row({esc(model.meshes[m].name), drive_kind_name(run.mesh_kind[m]), se(0), se(1), se(2),
                    num(1e-3 * std::sqrt(fx * fx + fy * fy + fz * fz), 4)});
  }
  h += "</table>\n";
  return h;
}

/// What the drives table states: the window, the error, the sign conventions and the checks.
std::string drives_intro(const Page& page) {
  return fmt::format(
      "<p>What each drive supplies to the material, averaged over {} ({}) &plusmn; the standard error of the mean from "
      "non-overlapping batch means (10 to 30 batches over the window, so that correlated samples do not make it look smaller "
      "than it is). <b>Belt pull</b> F<sub>t</sub>: the particles&#39; force on the belt resolved along its direction of "
      "travel, positive when the material resists the belt (the drive must pull it). <b>Shaft torque</b> T: about the part&#39;s "
      "own axis (through its axis point, oriented so that the part turns anticlockwise about it), from the recorded force F and "
      "torque T<sub>o</sub> about the motion origin o: T = &minus;(T<sub>o</sub> &minus; (p &minus; o) &times; F) &middot; "
      "&acirc;, positive when the material resists the turning. <b>Power</b> P: the rate of work the part does on the material, "
      "&Sigma; F<sub>i</sub> &middot; v<sub>wall</sub> over its contacts. F<sub>t</sub> v and T &omega; check it: they equal P "
      "on a belt whose surface contains its direction of travel and on a part turning about a fixed axis. For parts carried on "
      "a path (buckets), F<sub>t</sub> is the force along the path at the carried frame&#39;s origin, and F<sub>t</sub> v leaves "
      "out the work of their turning round the pulleys. Only the material&#39;s share: idler, bearing and belt-bending losses "
      "are not modelled.</p>\n",
      page.run.interval_text, page.run.steady ? "the steady state" : "the last third of the run: no steady state");
}

/// The belts and the parts carried on a path: speed, pull, power and the check F_t v ("" without any).
std::string linear_drives(const Page& page) {
  std::string rows;
  for (const Drive& d : page.run.drives) {
    if (d.kind == DriveKind::rotating) continue;
    rows += table_row({esc(d.name) + (d.note.empty() ? std::string() : " (" + esc(d.note) + ")"), drive_kind_name(d.kind), num(d.speed, 4),
                       pm_se(d.effort.at_run, 1e-3), pm_se(d.power.at_run, 1e-3), pm_se(d.check.at_run, 1e-3), own_steady(d.power)});
  }
  if (rows.empty()) return "";
  return "<h3>Belts and parts carried on a path</h3>\n<table>\n" +
         table_row({"part", "kind", "speed v [m/s]", "pull F<sub>t</sub> [kN]", "power P [kW]", "check F<sub>t</sub> v [kW]",
                    "own steady state (P)"}, true) +
         rows + "</table>\n";
}

/// The rotating parts: axis, speed, shaft torque about the own axis, power and the check T omega
/// ("" without any).
std::string rotating_drives(const Page& page) {
  std::string rows;
  for (const Drive& d : page.run.drives) {
    if (d.kind != DriveKind::rotating) continue;
    rows += table_row({esc(d.name), vector_text(d.at_end.axis_point), vector_text(d.at_end.direction), num(d.speed * 30 / std::numbers::pi, 4),
                       pm_se(d.effort.at_run, 1e-3), pm_se(d.power.at_run, 1e-3), pm_se(d.check.at_run, 1e-3), own_steady(d.power)});
  }
  if (rows.empty()) return "";
  return "<h3>Rotating parts</h3>\n<table>\n" +
         table_row({"part", "axis point p [m]", "axis &acirc;", "speed [rpm]", "shaft torque T [kN m]", "power P [kW]",
                    "check T &omega; [kW]", "own steady state (P)"}, true) +
         rows + "</table>\n";
}

/// The drives' power over time, and the rotating parts' shaft torque about their own axes.
std::string drive_plots(const Page& page) {
  const RunAnalysis& run = page.run;
  plot::Plot p;
  p.title = "Drive power on the material";
  p.x_label = "time [s]";
  p.y_label = "power [kW]";
  for (const Drive& d : run.drives) p.series.push_back({d.name, run.t, scaled(d.power.y, 1e-3)});
  page.set_band(p);
  std::string h = figure(p, page.dir, "drive_power", "Power per drive (positive: the part does work on the material).");
  p.title = "Shaft torque about each rotating part's own axis";
  p.y_label = "torque [kN m]";
  p.series.clear();
  for (const Drive& d : run.drives)
    if (d.kind == DriveKind::rotating) p.series.push_back({d.name, run.t, scaled(d.effort.y, 1e-3)});
  if (!p.series.empty())
    h += figure(p, page.dir, "drive_torque", "Shaft torque about each rotating part's own axis (positive: the material resists the turning).");
  return h;
}

/// The drives of the moving parts (tables and plots), then the loads on every mesh.
std::string drives_and_loads(const Page& page) {
  std::string h = "<h2>Drives and loads</h2>\n";
  if (page.model.meshes.empty()) return h + "<p>The case has no mesh walls.</p>\n";
  if (page.run.drives.empty())
    h += "<p>No mesh moves or has a moving surface: there is no drive.</p>\n";
  else
    h += drives_intro(page) + linear_drives(page) + rotating_drives(page) + drive_plots(page);
  return h + mesh_loads(page);
}

/// When material first reached each outlet, sensor or the domain's bounds ("" without events).
std::string first_arrivals(const Page& page) {
  if (page.run.events.empty()) return "";
  std::string h = "<h2>First arrivals</h2>\n<p>When the first particle reached each outlet, crossed each plane sensor along its normal, or left "
                  "the domain: to the step (the run looks every few steps and traces the particle back along its velocity), not to the "
                  "spacing of the scalars&#39; rows. Also in events.csv of the run folder.</p>\n<table>\n";
  h += table_row({"event", "time [s]", "step", "particle"}, true);
  for (const RunEvent& e : page.run.events) h += table_row({esc(e.what), num(e.time, 6), std::to_string(e.step), std::to_string(e.particle)});
  h += "</table>\n";
  return h;
}

/// Wear per mesh over the recording interval, and whether a wear depth could be given.
std::string wear_per_mesh(const Page& page) {
  const Model& model = page.model;
  const std::vector<MeshWear>& mesh_wear = page.run.mesh_wear;
  std::string h = fmt::format(
      "<p>From the per-triangle records over the recording interval {} s to {} s ({} s): shear power per area q = friction work / "
      "(area &times; interval) [W/m&sup2;], the Archard wear input, and impact power per area q<sub>i</sub> = sum of &frac12; m* "
      "v<sub>n</sub>&sup2; at contact starts / (area &times; interval) [W/m&sup2;]. Where a mesh has a liner, its wear depth rate is "
      "h&#775; = k<sub>s</sub> q + K<sub>i</sub> q<sub>i</sub> [m/s] (sliding, Archard; impact, Bitter&#39;s deformation wear), "
      "shown in mm/year at {} h of operation a year.</p>\n<table>\n",
      num(page.in.records_from, 3), num(page.state.time, 4), num(page.run.record_time, 3), num(page.run.operating_hours, 4));
  h += table_row({"mesh", "area [m&sup2;]", "shear power [W]", "impact power [W]", "max shear power [W/m&sup2;]", "max impact power [W/m&sup2;]",
                  "k<sub>s</sub> [m&sup3;/J]", "max wear rate [mm/yr]"},
                 true);
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    const MeshWear& w = mesh_wear[m];
    h += table_row({esc(model.meshes[m].name), num(w.area), num(w.shear_power, 3), num(w.impact_power, 3), num(w.max_shear, 3), num(w.max_impact, 3),
                    std::isnan(w.k) ? std::string("not given") : num(w.k, 3), w.has_liner ? num(w.max_wear, 3) : std::string("&ndash;")});
  }
  h += "</table>\n";
  if (std::none_of(mesh_wear.begin(), mesh_wear.end(), [](const MeshWear& w) { return w.has_liner; })) {
    std::string words;
    for (const std::string& k : liner_material_keys()) words += (words.empty() ? "" : ", ") + k;
    h += fmt::format("<p class=\"note\">No wear depth: the case gives no liner. Add <code>wear: {{liners: {{default: {{material: ar400, "
                     "thickness_mm: 20}}}}}}</code> (or per mesh name; materials: {}) for the wear rate in mm/year and the liner life; "
                     "<code>wear_coefficients: {{default: K}}</code> still gives a sliding rate alone.</p>\n",
                     words);
  }
  return h;
}

/// What the liner life rests on: the operating hours, the laws, the throughput for mm/Mt.
std::string liner_life_basis(const Page& page) {
  const RunAnalysis& run = page.run;
  const std::string hours = run.operating_hours_given
                                ? fmt::format("{} h of operation a year (<code>wear.operating_hours_per_year</code>)", num(run.operating_hours, 4))
                                : fmt::format("<b>{} h of operation a year, assumed</b>: the case gives no <code>wear.operating_hours_per_year</code> "
                                              "(about two shifts a day, 250 days a year)",
                                              num(run.operating_hours, 4));
  const std::string tonnes = std::isnan(run.wear_throughput)
                                 ? std::string("no throughput is known (no outlet, plane sensor, design capacity or inlet rate): no mm/Mt")
                                 : fmt::format("{} t/h, {}", num(run.wear_throughput, 4), esc(run.wear_throughput_text));
  return fmt::format(
      "<p>Months until the liner&#39;s thickness is worn through, at {}: at the mesh&#39;s worst triangle (the highest depth rate) "
      "and at its mean (its wear volume spread over its area). Wear per million tonnes conveyed, the depth rate over the throughput, "
      "does not depend on the hours: {}. Belts and pulleys (meshes with a surface velocity) take no <code>default</code> liner, only "
      "one given by their name. The coefficients are order-of-magnitude values from the sources below, for rock on the liner; "
      "wear measured on the plant&#39;s own liners supersedes them (<code>sliding_coefficient</code>, "
      "<code>impact_coefficient</code> of a liner).</p>\n",
      hours, tonnes);
}

/// The liner life table: per mesh with a liner, its worst triangle and its mean.
std::string liner_life_table(const Page& page) {
  const RunAnalysis& run = page.run;
  const double hours = run.operating_hours;
  std::string h = "<table>\n" + table_row({"mesh", "liner material", "thickness [mm]", "k<sub>s</sub>, K<sub>i</sub> [m&sup3;/J]",
                                          "sliding [mm/yr]", "impact [mm/yr]", "worst-spot life [months]", "mean life [months]",
                                          "wear [mm/Mt]", "worst triangle (centroid [m])"},
                                         true);
  for (std::size_t m = 0; m < page.model.meshes.size(); ++m) {
    const MeshWear& w = run.mesh_wear[m];
    if (!w.has_liner) continue;
    const LinerMaterial* material = find_liner_material(w.liner.material);
    const std::string what = material ? esc(material->name) : "coefficient only (" + esc(w.liner.origin) + ")";
    h += table_row({esc(page.model.meshes[m].name), what, w.liner.thickness > 0 ? num(1e3 * w.liner.thickness, 3) : std::string("not given"),
                    num(w.liner.sliding_coefficient, 2) + ", " + num(w.liner.impact_coefficient, 2), num(mm_per_year(w.worst.sliding, hours), 3),
                    num(mm_per_year(w.worst.impact, hours), 3), num(w.worst.life_months, 3), num(w.mean.life_months, 3),
                    num(w.worst.mm_per_megatonne, 3), fmt::format("{} {}", w.worst.triangle, vector_text(w.worst.centroid))});
  }
  return h + "</table>\n<p class=\"note\">Sliding and impact at the worst triangle; wear per Mt at the worst triangle. Also in "
             "wear_life.csv (each mesh&#39;s worst triangle and mean).</p>\n";
}

/// The rows of the liner-material table the liners use, with their sources.
std::string liner_sources(const Page& page) {
  std::set<std::string> used;
  for (const MeshWear& w : page.run.mesh_wear)
    if (w.has_liner && !w.liner.material.empty()) used.insert(w.liner.material);
  if (used.empty()) return "";
  std::string h = "<table>\n" + table_row({"liner material", "k<sub>s</sub> [m&sup3;/J]", "K<sub>i</sub> [m&sup3;/J]", "sliding: source",
                                          "impact: source", "note"},
                                         true);
  for (const LinerMaterial& m : liner_materials())
    if (used.count(m.key))
      h += table_row({esc(m.name), num(m.sliding_coefficient, 2), num(m.impact_coefficient, 2), esc(m.sliding_source), esc(m.impact_source),
                      esc(m.note)});
  return h + "</table>\n<p class=\"note\">The table&#39;s values; a liner may override them in the case. The laws and the rejected "
             "alternatives are stated in src/case/liner_materials.cpp.</p>\n";
}

/// Liner life: its basis, the table per mesh, and the sources of the coefficients ("" without a liner).
std::string liner_life(const Page& page) {
  const std::vector<MeshWear>& mesh_wear = page.run.mesh_wear;
  if (std::none_of(mesh_wear.begin(), mesh_wear.end(), [](const MeshWear& w) { return w.has_liner; })) return "";
  return "<h3>Liner life</h3>\n" + liner_life_basis(page) + liner_life_table(page) + liner_sources(page);
}

/// The triangles with the highest shear power per area.
std::string wear_hotspots(const Page& page) {
  const std::vector<Hotspot>& spots = page.run.spots;
  std::string h = "<h3>Hot spots: the 10 triangles with the highest shear power per area</h3>\n<table>\n";
  h += table_row({"#", "mesh", "triangle", "centroid x, y, z [m] (pose at t = 0)", "shear power [W/m&sup2;]", "impact power [W/m&sup2;]",
                  "impacts [1/(s m&sup2;)]", "wear rate [mm/yr]"},
                 true);
  for (std::size_t r = 0; r < spots.size(); ++r) {
    const Hotspot& s = spots[r];
    h += table_row({std::to_string(r + 1), esc(page.model.meshes[s.mesh].name), std::to_string(s.triangle),
                    fmt::format("{}, {}, {}", num(s.centroid.x(), 4), num(s.centroid.y(), 4), num(s.centroid.z(), 4)), num(s.shear_rate, 3),
                    num(s.impact_rate, 3), num(s.impacts_rate, 3), num(s.wear_mm_per_year, 3)});
  }
  h += "</table>\n<p class=\"note\">Also in wear_hotspots.csv.</p>\n";
  return h;
}

/// Wear: per mesh and at the hot spots, or why there is none.
std::string wear(const Page& page) {
  std::string h = "<h2>Wear</h2>\n";
  if (page.model.meshes.empty()) {
    h += "<p>The case has no mesh walls.</p>\n";
  } else if (page.run.record_time <= 0) {
    h += fmt::format("<p>No wall records: recording starts at {} s, the run ended at {} s.</p>\n", num(page.in.records_from, 3), num(page.state.time, 4));
  } else {
    h += wear_per_mesh(page);
    h += liner_life(page);
    h += wear_hotspots(page);
  }
  return h;
}

/// Each liner's own pressure map side by side, with its name and peak pressure ("" without any).
std::string liner_map_gallery(const Page& page, const LinerLoads& loads) {
  if (page.in.liner_maps.empty()) return "";
  std::string h = "<h3>Pressure map of each liner</h3>\n<p>Each liner alone, seen face on (along its mean normal, weighted by area) "
                  "from the side the material pushes it, in the same window; its colour scale ends at its own 99th percentile, so "
                  "the peak may lie above it; grey: no records. Files pressure_map_MESH.png.</p>\n<div class=\"grid\">\n";
  for (const LinerMap& map : page.in.liner_maps) {
    // The peak from the table's numbers, found by the mesh's name.
    const auto load = std::find_if(loads.meshes.begin(), loads.meshes.end(), [&](const LinerLoad& l) { return l.name == map.mesh; });
    const double peak = load == loads.meshes.end() ? std::numeric_limits<double>::quiet_NaN() : 1e-3 * load->peak;  // [kPa]
    h += fmt::format("<figure>{}<figcaption><b>{}</b> &middot; peak {} kPa</figcaption></figure>\n", embed_image(map.path, map.mesh),
                     esc(map.mesh), num(peak));
  }
  return h + "</div>\n";
}

/// Liner pressure: per mesh its mean, 95th percentile and peak pressure and the material's mean
/// force over the records' window, each liner's own map, and the files a structural model reads
/// ("" without records).
std::string liner_pressure(const Page& page, const LinerLoads& loads) {
  if (page.model.meshes.empty() || !loads.recorded()) return "";
  std::string h = fmt::format(
      "<h2>Liner pressure</h2>\n<p>The material&#39;s pressure on each mesh over the wall records&#39; window t = {} s to {} s: per "
      "triangle the normal impulse / (area &times; window); its mean weighted by area, the 95th percentile by area (95 % of the "
      "area carries no more) and the peak, with the peak triangle&#39;s centroid; and the material&#39;s mean force on the mesh, "
      "friction included. Positions and forces are in each mesh&#39;s own frame (the case&#39;s coordinates for a mesh without "
      "motion). Also in liner_loads.csv; the map of all meshes is among the images (pressure_map.png){}.</p>\n<table>\n",
      num(loads.t0, 3), num(loads.t1, 4), page.in.liner_maps.empty() ? "" : "; each liner&#39;s own map follows the table");
  h += table_row({"mesh", "area [m&sup2;]", "mean [kPa]", "p95 [kPa]", "peak [kPa]", "peak at x, y, z [m]", "F<sub>x</sub> [kN]",
                  "F<sub>y</sub> [kN]", "F<sub>z</sub> [kN]", "for FEA"},
                 true);
  for (const LinerLoad& l : loads.meshes) {
    const std::string stem = esc(fea_name(l.name));
    h += table_row({esc(l.name), num(l.area), num(1e-3 * l.mean), num(1e-3 * l.p95), num(1e-3 * l.peak), vector_text(l.peak_centroid),
                    num(1e-3 * l.total_force.x()), num(1e-3 * l.total_force.y()), num(1e-3 * l.total_force.z()),
                    fmt::format("<code>fea/{}.inp</code>, <code>fea/{}.vtk</code>", stem, stem)});
  }
  h += "</table>\n" + liner_map_gallery(page, loads);
  return h + "<p>For a structural model, <code>fea/MESH.inp</code> is a CalculiX / Abaqus input fragment in the mesh&#39;s own "
             "frame, in N, m and Pa: the mesh&#39;s nodes (<code>*NODE</code>) and triangles as S3 shells (<code>*ELEMENT</code>), then "
             "two load blocks that are alternatives, use one: <code>*CLOAD</code>, each triangle&#39;s mean force (pressure and "
             "friction) split equally over its three nodes, or <code>*DLOAD</code>, each element&#39;s pressure (positive P acts "
             "against the element normal of its node order; friction left out). Give the elements a <code>*SHELL SECTION</code> with "
             "the liner&#39;s thickness and material and put the chosen block into a <code>*STEP</code> (CalculiX CrunchiX User&#39;s "
             "Manual, *CLOAD, *DLOAD). <code>fea/MESH.vtk</code> shows the same in ParaView (pressure_kPa, shear_stress_kPa, "
             "traction_Pa) in world coordinates at the pose of the run&#39;s end, as walls.h5.</p>\n";
}

/// What the capacity table states: the CEMA cross-section, the capacity, the throughput and the verdicts.
std::string belt_capacity_intro(const Page& page) {
  return fmt::format(
      "<p>The belt&#39;s capacity from the CEMA load cross-section of a belt on three equal-length troughing rolls (CEMA, <i>Belt "
      "Conveyors for Bulk Materials</i>, 7th ed., ch. 4): the standard edge distance c = 0.055 b + 0.9 in (0.0229 m) is left clear "
      "on each side, the belt on the centre roll is l = 0.371 b + 0.25 in, the load fills the trapezoid on the rolls troughed at "
      "&beta; up to its edges and above them a circular-arc segment meeting the edges at the surcharge angle &theta; (a flat belt: "
      "the segment alone). Capacity = A v &rho; &times; 3.6 (A v &rho; in kg/s; 1 kg/s = 3.6 t/h) at the belt speed v and the bulk "
      "density &rho;. Throughput: the run&#39;s flow onto the belt over {} ({}) &plusmn; the standard error of the mean, in tonnes "
      "of the real material (divided by the mass scaling). Loading = throughput / capacity: &le; 80 % fine (CEMA&#39;s usual "
      "design factor, room for surges and mistracking), 80&ndash;100 % near full, above 100 % overloaded: the load overtops the "
      "surcharge profile and spillage is expected. Values marked <i>assumed</i> are defaults the case does not state. Also in "
      "belt_capacity.csv.</p>\n",
      page.run.interval_text, page.run.steady ? "the steady state" : "the last third of the run: no steady state");
}

/// The receiving belts against their CEMA capacity: one row per belt, then where each input came
/// from ("" without a belt speed at any load box).
std::string belt_capacity_table(const Page& page) {
  const std::vector<BeltCapacity>& belts = page.run.belts;
  if (belts.empty()) return "";
  const auto assumed = [](const std::string& value, bool is_assumed) { return is_assumed ? value + " <i>(assumed)</i>" : value; };
  std::string rows, sources;
  for (const BeltCapacity& b : belts) {
    if (!b.missing.empty()) {
      sources += fmt::format("<li><b>{}</b> ({}): no capacity, {}.</li>\n", esc(b.belt), esc(b.sensor), esc(b.missing));
      continue;
    }
    rows += table_row({esc(b.belt) + " (" + esc(b.sensor) + ")", num(b.width, 3), num(b.troughing, 3), assumed(num(b.surcharge, 3), b.surcharge_assumed),
                       assumed(num(b.bulk_density, 4), b.bulk_density_assumed), num(b.speed, 3), num(b.section.area, 4), num(b.capacity, 4),
                       std::isnan(b.throughput) ? "&ndash;" : pm(b.throughput, b.throughput_error), std::isnan(b.loading) ? "&ndash;" : pm(b.loading, b.loading_error, 3),
                       loading_verdict_text(b.verdict)});
    sources += fmt::format("<li><b>{}</b>: width from the {}; troughing from the {}; surcharge angle {}; bulk density of {} {}; speed from the {}; "
                           "throughput: {}.</li>\n",
                           esc(b.belt), esc(b.width_source), esc(b.troughing_source), esc(b.surcharge_source), esc(b.material), esc(b.bulk_density_source),
                           esc(b.speed_source), esc(b.throughput_source.empty() ? "none (no plane sensor across the belt and no outlet)" : b.throughput_source));
  }
  std::string h = "<h3>Belt loading against capacity</h3>\n" + belt_capacity_intro(page);
  if (!rows.empty())
    h += "<table>\n" +
         table_row({"belt (load box)", "width b [m]", "troughing &beta; [&deg;]", "surcharge &theta; [&deg;]", "bulk density &rho; [kg/m&sup3;]",
                    "belt speed v [m/s]", "CEMA area A [m&sup2;]", "CEMA capacity [t/h]", "throughput [t/h]", "loading [%]", "verdict"},
                   true) +
         rows + "</table>\n";
  return h + "<ul>\n" + sources + "</ul>\n";
}

/// Belt loading at the box sensors: the table and the plot of the centring offset ("" without box sensors).
std::string belt_loading(const Page& page) {
  const std::vector<BoxResult>& boxes = page.run.boxes;
  if (boxes.empty()) return "";
  std::string h = "<h2>Belt loading (box sensors)</h2>\n";
  h += "<p>Centring offset: the centroid of the material in the box along the sensor&#39;s <code>across</code> axis, from the box centre "
       "(0 = centred). Velocities are mass-weighted means over the interval; &ldquo;along&rdquo; is the speed perpendicular to "
       "<code>across</code> and to the vertical, &ldquo;vertical&rdquo; is positive upwards (negative: the material moves down onto "
       "the belt, the impact speed).</p>\n<table>\n";
  h += table_row({"sensor", "offset [mm]", "offset [% of width]", "mass in box [kg]", "along [m/s]", "lateral [m/s]", "vertical [m/s]",
                  "belt speed [m/s]", "along / belt"},
                 true);
  for (const BoxResult& b : boxes)
    h += table_row({esc(b.name), pm(b.offset.at_run.mean, b.offset.at_run.std_dev, 3),
                    b.width > 0 ? num(100 * b.offset.at_run.mean / (1000 * b.width), 3) : "&ndash;", pm(b.mass.at_run.mean, b.mass.at_run.std_dev, 3),
                    num(b.along, 3), num(b.lateral, 3), num(b.vertical, 3),
                    std::isnan(b.belt_speed) ? "&ndash;" : num(b.belt_speed, 3) + " (" + esc(b.belt_name) + ")",
                    std::isnan(b.belt_speed) || b.belt_speed == 0 ? "&ndash;" : num(b.along / b.belt_speed, 3)});
  h += "</table>\n";
  h += belt_capacity_table(page);
  plot::Plot p;
  p.title = "Centring offset of the load";
  p.x_label = "time [s]";
  p.y_label = "offset along across [mm]";
  for (const BoxResult& b : boxes) p.series.push_back({b.name, page.run.t, b.offset.y});
  page.set_band(p);
  p.lines.push_back({0.0, "centred"});
  h += figure(p, page.dir, "centring_offset", "Offset of the load's centroid from the box centre along <code>across</code>.");
  return h;
}

/// The narrowest section's fill against the design rule, or why there is none ("" without a choke sensor).
std::string choke_table(const Page& page) {
  const ChokeResult& c = page.run.choke;
  if (c.sensor.empty()) return "";
  if (!c.missing.empty()) return fmt::format("<p>Narrowest section (box sensor <code>{}</code>): no fill, {}.</p>\n", esc(c.sensor), esc(c.missing));
  std::string h = fmt::format("<p>{} The mass m is the box sensor&#39;s mean over {} &plusmn; the standard error of the mean (batch means){}. "
                              "Also in choke.csv.</p>\n<table>\n",
                              esc(kChokeRule), page.run.interval_text, page.model.mass_scaling != 1 ? ", divided by the mass scaling" : "");
  h += table_row({"quantity", "value", "unit", "note"}, true);
  const std::string height = std::isnan(c.height) ? std::string() : ", at height " + num(c.height, 4) + " m";
  h += table_row({"free area of the section A", num(c.area, 4), "m&sup2;", "design value choke_section_area_m2" + height});
  h += table_row({"box length along the flow L", num(c.length, 3), "m", "design value choke_section_length_m"});
  h += table_row({"mass in the box m", pm(c.mass, c.mass_error), "kg", "box sensor " + esc(c.sensor)});
  h += table_row({"poured bulk density &rho;", num(c.material.bulk_density, 4) + (c.material.bulk_assumed ? " <i>(assumed)</i>" : ""), "kg/m&sup3;",
                  esc(c.material.name + ": " + c.material.bulk_source)});
  h += table_row({"fill m / (&rho; A L)", pm(c.fill.fill, c.fill.fill_error, 3), "&ndash;", fmt::format("{} % of the section", num(100 * c.fill.fill, 3))});
  h += table_row({"choke margin 1 &minus; fill", pm(c.fill.margin, c.fill.fill_error, 3), "&ndash;", ""});
  h += table_row({"verdict", "<b>" + esc(choke_verdict_text(c.fill.verdict)) + "</b>", "",
                  "ample below 1/3 (the design rule, assumed), adequate below 2/3, tight below 1, else choked"});
  return h + "</table>\n";
}

/// A stream profile's depth and velocity against the lateral position: two plots.
std::string stream_profile_figures(const Page& page, const StreamProfile& profile) {
  const ChokeResult& c = page.run.choke;
  plot::Plot depth;
  depth.title = "Stream depth across " + profile.sensor;
  depth.x_label = "lateral position along across [m]";
  depth.y_label = "depth [mm]";
  depth.series = {{"depth at the poured bulk density", profile.lateral, scaled(profile.depth, 1000.0)}};
  // Across the chute's narrowest section, the section's own depth (its area over the box's width).
  const double box_width = profile.width * static_cast<double>(profile.lateral.size());  // [m]
  if (profile.sensor == kChokeSensor && c.area > 0 && box_width > 0) depth.lines.push_back({1000 * c.area / box_width, "depth of the section"});
  std::string h = figure(depth, page.dir, "stream_depth_" + key(profile.sensor),
                         fmt::format("Depth of the stream in each of the {} bins of <code>{}</code> ({} mm wide, over {} mm along the flow).",
                                     profile.lateral.size(), esc(profile.sensor), num(1000 * profile.width, 3), num(1000 * profile.length, 3)));
  plot::Plot velocity;
  velocity.title = "Stream velocity across " + profile.sensor;
  velocity.x_label = depth.x_label;
  velocity.y_label = "velocity along the flow [m/s]";
  velocity.series = {{"mass-weighted mean", profile.lateral, profile.velocity}};
  h += figure(velocity, page.dir, "stream_velocity_" + key(profile.sensor),
              fmt::format("Velocity along the flow in each bin of <code>{}</code>, weighted by mass and time; empty bins are left out.", esc(profile.sensor)));
  return h;
}

/// The chute's narrowest section and the stream profiles ("" without either).
std::string choke_and_stream_profile(const Page& page) {
  const RunAnalysis& run = page.run;
  if (run.choke.sensor.empty() && run.profiles.empty()) return "";
  std::string h = "<h2>Choke and stream profile</h2>\n" + choke_table(page);
  if (run.profiles.empty()) return h;
  if (!(run.profiles.front().window > 0))
    return h + fmt::format("<p>No stream profiles: their records start at t = {} s, and the run ended at t = {} s.</p>\n",
                           num(page.in.records_from, 4), num(page.state.time, 4));
  const MaterialFacts& material = run.choke.material;
  h += fmt::format("<p>Stream profiles: each bin&#39;s time-mean mass and its velocity along the flow, weighted by mass and time, over the "
                   "records window of {} s from t = {} s (the run&#39;s stream_profiles.csv). Depth = mean mass / (&rho; &times; bin "
                   "width &times; the box&#39;s length along the flow), at the poured bulk density &rho; = {} kg/m&sup3; ({}): on a belt, "
                   "the bed&#39;s depth; across the chute, how much of the section&#39;s depth the stream takes.</p>\n",
                   num(run.profiles.front().window, 4), num(page.in.records_from, 4), num(material.bulk_density, 4), esc(material.bulk_source));
  for (const StreamProfile& profile : run.profiles) h += stream_profile_figures(page, profile);
  return h;
}

/// The caller's images ("" without any).
std::string images(const Page& page) {
  if (page.in.images.empty()) return "";
  std::string h = "<h2>Images</h2>\n";
  for (const ImageRef& img : page.in.images)
    h += fmt::format("<figure><h3>{}</h3>{}<figcaption>{}</figcaption></figure>\n", esc(img.title), embed_image(img.path, img.title), esc(img.caption));
  return h;
}

/// Plots of the run's own series: particles, kinetic energy, contacts, overlap.
std::string time_series(const Page& page) {
  const std::vector<Scalars>& rows = *page.run.rows;
  const std::vector<double>& t = page.run.t;
  std::string h = "<h2>Time series</h2>\n";
  plot::Plot p;
  p.x_label = "time [s]";
  p.title = "Particles in the domain";
  p.y_label = "particles [-]";
  p.series = {{"particles", t, page.run.particles.y}};
  h += figure(p, page.dir, "particles", "Number of particles.");
  p.title = "Kinetic energy";
  p.y_label = "kinetic energy [J]";
  p.series = {{"translation", t, column(rows, [](const Scalars& r) { return r.kinetic_translation; })},
              {"rotation", t, column(rows, [](const Scalars& r) { return r.kinetic_rotation; })}};
  page.set_band(p);
  h += figure(p, page.dir, "kinetic_energy", "Kinetic energy of the particles.");
  p.band.reset();
  p.title = "Contacts";
  p.y_label = "contacts [-]";
  p.series = {{"contacts", t, page.run.contacts.y}};
  h += figure(p, page.dir, "contacts", "Touching particle pairs and particle-wall contacts.");
  p.title = "Overlap";
  p.y_label = "overlap / smaller radius [-]";
  p.series = {{"max", t, column(rows, [](const Scalars& r) { return r.max_overlap_ratio; })},
              {"mean", t, column(rows, [](const Scalars& r) { return r.mean_overlap_ratio; })}};
  h += figure(p, page.dir, "overlap", "Largest and mean overlap relative to the smaller radius (a check of the stiffness and time step).");
  return h;
}

/// How each series' steady part is found, and what was found for each.
std::string steady_state_detection(const Page& page) {
  const std::vector<const Quantity*> all = page.run.all();
  std::string h = "<h2>Steady-state detection</h2>\n";
  h += "<p>Each series&#39; steady part is found from the data: MSER-5 (White 1997; batch means of 5 samples) chooses the warm-up "
       "truncation d minimising S&sup2;(d)/(n&minus;d)&sup2; over d &le; n/2; the rest must hold &ge; 10 samples and show no trend "
       "that is both significant (|t| &gt; 3 for the least-squares slope on 10&ndash;30 batch means) and relevant (change over the "
       "interval &gt; 2 % of max(|mean|, std dev)); if MSER&#39;s choice fails, the last half is tried. Standard error of the mean "
       "from the same batch means. The run&#39;s interval comes from the " +
       esc(page.run.primary.name) + ". Also in steady_state.csv.</p>\n<table>\n";
  h += table_row({"series", "unit", "steady", "from [s]", "to [s]", "mean", "std dev", "std error", "trend [unit/s]"}, true);
  for (const Quantity* q : all)
    h += table_row({esc(q->name), esc(q->unit), q->own.found ? "yes" : esc(q->own.why), q->own.found ? num(q->own.t_start, 4) : "&ndash;",
                    q->own.found ? num(q->own.t_end, 4) : "&ndash;", num(q->own.mean), num(q->own.std_dev, 3), num(q->own.std_error, 2),
                    num(q->own.trend_per_s, 3)});
  h += "</table>\n";
  return h;
}

/// The materials, the contact law's effects and every material pair's parameters.
std::string materials_and_contact_law(const Model& model) {
  std::string h = "<h3>Materials</h3>\n<table>\n";
  h += table_row({"material", "density [kg/m&sup3;]", "Young's modulus [Pa]", "Poisson ratio [-]"}, true);
  for (const Material& m : model.materials)
    h += table_row({esc(m.name), num(m.density), num(m.youngs_modulus), num(m.poisson_ratio, 3)});
  h += "</table>\n<h3>Contact law and pair parameters</h3>\n<ul>\n";
  for (const ActiveEffect& e : model.effects)
    h += fmt::format("<li>{}: <b>{}</b> &ndash; {} ({})</li>\n", esc(std::string(stage_name(e.spec->stage))),
                     esc(std::string(e.spec->name)), esc(std::string(e.spec->summary)), esc(std::string(e.spec->citation)));
  h += "</ul>\n<table>\n<tr><th>pair</th><th>E* [Pa]</th><th>G* [Pa]</th>";
  for (const ActiveEffect& e : model.effects)
    for (const ParamSpec& p : e.spec->params) h += fmt::format("<th>{} [{}]</th>", esc(std::string(p.key)), esc(std::string(p.unit)));
  h += "</tr>\n";
  for (int a = 0; a < model.n_materials(); ++a)
    for (int b = a; b < model.n_materials(); ++b) {
      const double* row = model.pair_row(model.pair_type(a, b));
      h += fmt::format("<tr><td>{} &ndash; {}</td><td class=\"n\">{}</td><td class=\"n\">{}</td>", esc(model.materials[a].name),
                       esc(model.materials[b].name), num(row[0]), num(row[1]));
      for (const ActiveEffect& e : model.effects)
        for (std::size_t k = 0; k < e.spec->params.size(); ++k) h += fmt::format("<td class=\"n\">{}</td>", num(row[e.param_offset + k]));
      h += "</tr>\n";
    }
  h += "</table>\n";
  return h;
}

/// What it takes to run it again: software, settings, materials, contact law, design values,
/// notes and the case file.
std::string reproducibility(const Page& page) {
  const RunReportInput& in = page.in;
  const Model& model = page.model;
  std::string h = "<h2>Reproducibility</h2>\n<table>\n";
  h += table_row({"item", "value"}, true);
  h += table_row({"software", "demdesign " + esc(in.version)});
  h += table_row({"case file", "<code>" + esc(in.case_path) + "</code>"});
  h += table_row({"model hash", fmt::format("<code>{:016x}</code>", model.hash)});
  h += table_row({"mass scaling (particle density factor)", num(model.mass_scaling)});
  h += table_row({"stiffness scaling (particle Young's modulus factor)", num(model.stiffness_scaling)});
  if (model.coarse_grain != 1) h += table_row({"coarse graining (parcel diameter / real diameter, F)", num(model.coarse_grain)});
  h += table_row({"time step [s]", num(model.dt, 4)});
  h += table_row({"Rayleigh time [s]", num(model.advice.rayleigh_time, 4)});
  h += table_row({"time step / Rayleigh time (Rayleigh fraction)",
                  model.advice.rayleigh_time > 0 ? num(model.dt / model.advice.rayleigh_time, 3) : "&ndash;"});
  h += table_row({"contact time [s]", num(model.advice.contact_time, 4)});
  h += table_row({"duration [s]", num(model.duration, 4)});
  h += table_row({"seed", std::to_string(model.seed)});
  h += table_row({"wall records from [s]", num(in.records_from, 4)});
  h += table_row({"run wall time [s]", num(in.wall_seconds, 4)});
  h += "</table>\n";
  if (!model.advice.report.empty()) h += "<h3>Time-step advice</h3>\n<pre>" + esc(model.advice.report) + "</pre>\n";
  if (!model.coarse_grain_report.empty()) {
    // F, the parcels of each set and inlet, the parameters scaled, what the results are, narrow openings.
    h += "<h3>Coarse graining</h3>\n<ul>\n";
    for (const std::string& line : model.coarse_grain_report) h += "<li>" + esc(line) + "</li>\n";
    h += "</ul>\n";
  }
  h += materials_and_contact_law(model);
  if (!in.design.empty()) {
    h += "<h3>Design values</h3>\n<table>\n" + table_row({"name (with unit)", "value"}, true);
    for (const auto& [name, value] : in.design) h += table_row({esc(name), num(value, 5)});
    h += "</table>\n";
  }
  if (!model.notes.empty()) {
    h += "<h3>Model notes</h3>\n<ul>\n";
    for (const std::string& note : model.notes) h += "<li>" + esc(note) + "</li>\n";
    h += "</ul>\n";
  }
  h += "<h3>Case file as run</h3>\n<pre>" + esc(in.case_text) + "</pre>\n";
  return h;
}

/// The list of the files beside the report, and the end of the page.
std::string page_foot() {
  return "<p class=\"note\">Files beside this report: metrics.csv, steady_state.csv, drives.csv (with moving parts), "
         "mesh_loads.csv (with meshes), wear_hotspots.csv, wear_life.csv, liner_loads.csv and fea/ (with meshes), belt_capacity.csv "
         "(with a belt&#39;s capacity), plots/*.png with their data "
         "(*.tsv) and gnuplot scripts (*.gp).</p>\n</body></html>\n";
}

}  // namespace

RunMetrics write_run_report(const RunReportInput& in, const std::string& report_dir) {
  RunAnalysis run = analyse_run(in);
  // The liners' pressure and loads (liner_loads.h): metrics.csv gets their metrics, fea/ their files.
  const LinerLoads loads = liner_loads(*in.model, *in.state, in.records_from);
  add_liner_pressure_metrics(loads, run.metrics);
  const Page page{in, run, *in.model, *in.state, report_dir};
  fs::create_directories(fs::path(report_dir) / "plots");
  write_run_tables(run, page.model, report_dir);
  write_liner_loads(loads, page.model, in.case_path, report_dir);
  // The 3D view gets the liners' life per triangle (report_wear.h).
  viewer3d::Options viewer = in.viewer;
  viewer.life_months = triangle_life_months(in);

  std::string h = page_head(page);
  h += banners(page);
  h += summary(page);
  h += throughput(page);
  h += mass_balance(page);
  h += drives_and_loads(page);
  h += first_arrivals(page);
  h += wear(page);
  h += liner_pressure(page, loads);
  h += belt_loading(page);
  h += choke_and_stream_profile(page);
  h += viewer3d::section(page.model, page.state, in.records_from, viewer);
  h += images(page);
  h += time_series(page);
  h += steady_state_detection(page);
  h += reproducibility(page);
  h += page_foot();
  write_file_atomically((fs::path(report_dir) / "report.html").string(), h);
  return run.metrics;
}

}  // namespace dem::report
