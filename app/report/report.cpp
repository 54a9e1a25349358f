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
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

#include "output/run.h"
#include "pages/plot.h"
#include "report/report_analysis.h"
#include "report/report_internal.h"
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
  h += fmt::format("<p><b>{}</b>.{} Values are means &plusmn; standard deviation of the signal over the {} interval <b>{}</b>; "
                   "the standard error of the mean (batch means) is given where it matters.</p>\n<table>\n",
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
  for (std::size_t m = 0; m < run.power.size(); ++m)
    h += table_row({"power of " + esc(model.meshes[m].name), pm(run.power[m].at_run.mean, run.power[m].at_run.std_dev), "W", ""});
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

/// The particles' force and torque on each mesh, by component.
std::string mesh_loads(const Page& page) {
  const RunAnalysis& run = page.run;
  const Model& model = page.model;
  std::string h = fmt::format("<h3>Loads on the meshes</h3>\n<p>The particles&#39; force on each mesh and its torque about the mesh&#39;s motion "
                              "origin (the world origin for a static mesh), by component, averaged over {} &plusmn; the standard error of the "
                              "mean (batch means); |F&#772;| is the magnitude of the mean force, which noise does not inflate as it does the mean "
                              "of the magnitude. Also in mesh_loads.csv.</p>\n<table>\n", run.interval_text);
  h += table_row({"mesh", "F<sub>x</sub> [N]", "F<sub>y</sub> [N]", "F<sub>z</sub> [N]", "|F&#772;| [N]", "T<sub>x</sub> [N m]",
                  "T<sub>y</sub> [N m]", "T<sub>z</sub> [N m]"}, true);
  for (std::size_t m = 0; m < model.meshes.size() && 6 * m + 5 < run.mesh_load.size(); ++m) {
    const auto se = [&](int c) { return pm(run.mesh_load[6 * m + c].at_run.mean, run.mesh_load[6 * m + c].at_run.std_error); };
    const double fx = run.mesh_load[6 * m].at_run.mean, fy = run.mesh_load[6 * m + 1].at_run.mean, fz = run.mesh_load[6 * m + 2].at_run.mean;
    h += table_row({esc(model.meshes[m].name), se(0), se(1), se(2), num(std::sqrt(fx * fx + fy * fy + fz * fz), 4), se(3), se(4), se(5)});
  }
  h += "</table>\n";
  return h;
}

/// Power and torque per mesh: the table, the two plots and the loads.
std::string power_and_torque(const Page& page) {
  const RunAnalysis& run = page.run;
  const Model& model = page.model;
  const std::vector<double>& t = run.t;
  const std::vector<Quantity>& power = run.power;
  const std::vector<Quantity>& torque = run.torque;
  std::string h = "<h2>Power and torque</h2>\n";
  if (power.empty()) {
    h += "<p>The case has no mesh walls.</p>\n";
    return h;
  }
  h += "<p>Sign convention: power is the rate of work a mesh does on the material; <b>positive = the mesh drives the material</b> "
       "(a rotating drum, a belt through its surface velocity), negative = the material does work on the mesh. Torque is about "
       "the mesh&#39;s rotation axis (its magnitude |T| about the motion origin when the mesh does not rotate). A static mesh "
       "without surface velocity does no work.</p>\n<table>\n";
  h += table_row({"mesh", "power [W]", "torque [N m]", "own steady state (power)"}, true);
  for (std::size_t m = 0; m < power.size(); ++m)
    h += table_row({esc(model.meshes[m].name), pm(power[m].at_run.mean, power[m].at_run.std_dev), pm(torque[m].at_run.mean, torque[m].at_run.std_dev),
                    power[m].own.found ? fmt::format("from {} s", num(power[m].own.t_start, 3)) : esc(power[m].own.why)});
  h += "</table>\n";
  plot::Plot p;
  p.title = "Power of the meshes on the material";
  p.x_label = "time [s]";
  p.y_label = "power [W]";
  for (std::size_t m = 0; m < power.size(); ++m) p.series.push_back({model.meshes[m].name, t, power[m].y});
  page.set_band(p);
  h += figure(p, page.dir, "mesh_power", "Power per mesh (positive: the mesh does work on the material).");
  p.title = "Torque on the meshes";
  p.y_label = "torque [N m]";
  p.series.clear();
  for (std::size_t m = 0; m < torque.size(); ++m) p.series.push_back({model.meshes[m].name, t, torque[m].y});
  h += figure(p, page.dir, "mesh_torque", "Torque per mesh about its rotation axis.");
  h += mesh_loads(page);
  return h;
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
      "(area &times; interval) [W/m&sup2;], the Archard wear input, and impact power per area = sum of &frac12; m* v<sub>n</sub>&sup2; "
      "at contact starts / (area &times; interval) [W/m&sup2;]. Where a specific wear rate k<sub>A</sub> = k/H [m&sup3;/J] is given "
      "for a mesh, the wear depth rate is h&#775; = k<sub>A</sub> q [m/s], shown in mm/year (8760 h of operation a year).</p>\n<table>\n",
      num(page.in.records_from, 3), num(page.state.time, 4), num(page.run.record_time, 3));
  h += table_row({"mesh", "area [m&sup2;]", "shear power [W]", "impact power [W]", "max shear power [W/m&sup2;]", "max impact power [W/m&sup2;]",
                  "k<sub>A</sub> [m&sup3;/J]", "max wear rate [mm/yr]"},
                 true);
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    const MeshWear& w = mesh_wear[m];
    h += table_row({esc(model.meshes[m].name), num(w.area), num(w.shear_power, 3), num(w.impact_power, 3), num(w.max_shear, 3), num(w.max_impact, 3),
                    std::isnan(w.k) ? std::string("not given") : num(w.k, 3), std::isnan(w.k) ? std::string("&ndash;") : num(w.max_wear, 3)});
  }
  h += "</table>\n";
  if (std::all_of(mesh_wear.begin(), mesh_wear.end(), [](const MeshWear& w) { return std::isnan(w.k); }))
    h += "<p class=\"note\">No wear depth: the case gives no specific wear rate. Add <code>wear_coefficients: {default: K}</code> "
         "(or per mesh name), K = k/H of the liner in m&sup3;/J, for the wear rate in mm/year.</p>\n";
  return h;
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
    h += wear_hotspots(page);
  }
  return h;
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
    h += fmt::format("<li>{}: <b>{}</b> &ndash; {} ({})</li>\n", esc(std::string(kStageKeys[static_cast<int>(e.spec->stage)])),
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
  return "<p class=\"note\">Files beside this report: metrics.csv, steady_state.csv, wear_hotspots.csv, plots/*.png with their data "
         "(*.tsv) and gnuplot scripts (*.gp).</p>\n</body></html>\n";
}

}  // namespace

RunMetrics write_run_report(const RunReportInput& in, const std::string& report_dir) {
  const RunAnalysis run = analyse_run(in);
  const Page page{in, run, *in.model, *in.state, report_dir};
  fs::create_directories(fs::path(report_dir) / "plots");
  write_run_tables(run, page.model, report_dir);

  std::string h = page_head(page);
  h += banners(page);
  h += summary(page);
  h += throughput(page);
  h += mass_balance(page);
  h += power_and_torque(page);
  h += first_arrivals(page);
  h += wear(page);
  h += belt_loading(page);
  h += viewer3d::section(page.model, page.state, in.records_from, in.viewer);
  h += images(page);
  h += time_series(page);
  h += steady_state_detection(page);
  h += reproducibility(page);
  h += page_foot();
  write_file_atomically((fs::path(report_dir) / "report.html").string(), h);
  return run.metrics;
}

}  // namespace dem::report
