// Liner pressure and the loads a structural model reads (liner_loads.h): the statistics per mesh,
// the legacy VTK and CalculiX / Abaqus files, liner_loads.csv and the metrics.
#include "report/liner_loads.h"

#include <fmt/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <utility>

#include "output/run.h"
#include "report/report_internal.h"
#include "report/report_wear.h"

namespace dem::report {
namespace {

namespace fs = std::filesystem;

constexpr double kPascalsPerKilopascal = 1e3;
/// The share of a mesh's area whose pressure the 95th percentile bounds.
constexpr double kPercentileArea = 0.95;

/// [m] Centroid of triangle t, the mesh's own frame.
Eigen::Vector3d centroid(const TriangleSurface& surface, std::size_t t) {
  Eigen::Vector3d c(0, 0, 0);
  for (int k = 0; k < 3; ++k) {
    const auto& v = surface.vertices[surface.triangles[t][k]];
    c += Eigen::Vector3d(v[0], v[1], v[2]) / 3.0;
  }
  return c;
}

/// The area-weighted mean, the 95th percentile by area and the peak of a mesh's pressure.
void pressure_statistics(const TriangleSurface& surface, LinerLoad& load) {
  std::vector<std::pair<double, double>> by_pressure;  // (pressure [Pa], area [m^2])
  double carried = 0;                                  // [N] sum p A
  for (std::size_t t = 0; t < surface.size(); ++t) {
    if (!(surface.areas[t] > 0)) continue;
    by_pressure.emplace_back(load.pressure[t], surface.areas[t]);
    carried += load.pressure[t] * surface.areas[t];
    if (load.pressure[t] > load.peak) load.peak = load.pressure[t], load.peak_triangle = t;
  }
  if (surface.size() > 0) load.peak_centroid = centroid(surface, load.peak_triangle);
  if (!(load.area > 0)) return;
  load.mean = carried / load.area;
  // The lowest pressure such that the triangles at or below it cover 95 % of the area.
  std::sort(by_pressure.begin(), by_pressure.end());
  double covered = 0;  // [m^2]
  for (const auto& [pressure, area] : by_pressure) {
    covered += area;
    load.p95 = pressure;
    if (covered >= kPercentileArea * load.area) break;
  }
}

/// The loads of `mesh` from its records `rec` (none: zero) over `interval` [s].
LinerLoad mesh_load(const MeshWall& mesh, const TriangleRecords* rec, double interval) {
  const TriangleSurface& surface = *mesh.surface;
  const std::size_t n = surface.size();
  LinerLoad load;
  load.name = mesh.name;
  load.pressure.assign(n, 0.0), load.shear_stress.assign(n, 0.0), load.force.assign(n, Eigen::Vector3d(0, 0, 0));
  for (std::size_t t = 0; t < n; ++t) load.area += std::max(surface.areas[t], 0.0);
  if (rec && interval > 0) {
    // Per triangle: the mean force, and the mean stresses on its area.
    for (std::size_t t = 0; t < n; ++t) {
      load.force[t] = Eigen::Vector3d(at(rec->force_impulse_x, t), at(rec->force_impulse_y, t), at(rec->force_impulse_z, t)) / interval;
      load.total_force += load.force[t];
      if (!(surface.areas[t] > 0)) continue;
      load.pressure[t] = at(rec->normal_impulse, t) / (surface.areas[t] * interval);
      load.shear_stress[t] = at(rec->shear_impulse, t) / (surface.areas[t] * interval);
    }
  }
  pressure_statistics(surface, load);
  return load;
}

/// A VTK cell scalar: `scale` x each value.
std::string vtk_scalars(const char* name, const std::vector<double>& values, double scale) {
  std::string text = fmt::format("SCALARS {} double 1\nLOOKUP_TABLE default\n", name);
  for (const double v : values) text += fmt::format("{:.9g}\n", scale * v);
  return text;
}

/// The comment lines that open a .inp file: what it holds and how to use it.
std::string inp_header(const LinerLoads& loads, const LinerLoad& load, const std::string& case_name) {
  return fmt::format(
      "** demdesign liner loads of mesh {} (case {})\n"
      "** Units: N, m, Pa (forces, coordinates, pressures).\n"
      "** Window: means over t0 = {:.6g} s to t1 = {:.6g} s of the run (the wall records: output.records_from to the end).\n"
      "** Frame: the mesh's own, the one its vertices are given in (the case's coordinates for a mesh without motion;\n"
      "**   for a moving mesh the frame its pose carries). Coordinates and forces are both in it.\n"
      "** Ids: node k is the mesh's vertex k - 1, element k its triangle k - 1 (S3 shells, normal by the node order).\n"
      "** *CLOAD and *DLOAD below are ALTERNATIVES: use one of them, not both (each carries the liner's whole load).\n"
      "**   *CLOAD: each triangle's mean force (pressure and friction) split equally over its three nodes, summed per node [N].\n"
      "**   *DLOAD: each element's mean normal pressure [Pa], label P; positive P acts against the element normal\n"
      "**   (pushes into its face), negative P along it; the friction (shear) load is left out.\n"
      "** *NODE and *ELEMENT are model data; *CLOAD or *DLOAD goes inside a *STEP.\n"
      "** Keywords: CalculiX CrunchiX User's Manual, *NODE, *ELEMENT, *CLOAD, *DLOAD (the Abaqus syntax).\n",
      load.name, case_name, loads.t0, loads.t1);
}

/// *NODE and *ELEMENT: the mesh's vertices [m] and its triangles as S3 shells, ids from 1.
std::string inp_mesh(const LinerLoad& load, const TriangleSurface& surface) {
  std::string text = "*NODE\n";
  for (std::size_t v = 0; v < surface.vertices.size(); ++v)
    text += fmt::format("{}, {:.9g}, {:.9g}, {:.9g}\n", v + 1, surface.vertices[v][0], surface.vertices[v][1], surface.vertices[v][2]);
  text += fmt::format("*ELEMENT, TYPE=S3, ELSET={}\n", fea_name(load.name));
  for (std::size_t t = 0; t < surface.size(); ++t)
    text += fmt::format("{}, {}, {}, {}\n", t + 1, surface.triangles[t][0] + 1, surface.triangles[t][1] + 1, surface.triangles[t][2] + 1);
  return text;
}

/// *CLOAD: each triangle's mean force [N] split equally over its three nodes, summed per node;
/// lines `node, degree of freedom (1-3: x, y, z), force`, a component exactly zero left out.
std::string inp_cload(const LinerLoad& load, const TriangleSurface& surface) {
  std::vector<Eigen::Vector3d> nodal(surface.vertices.size(), Eigen::Vector3d(0, 0, 0));
  for (std::size_t t = 0; t < surface.size() && t < load.force.size(); ++t)
    for (int k = 0; k < 3; ++k) nodal[surface.triangles[t][k]] += load.force[t] / 3.0;
  std::string text = "** ---- Alternative 1: nodal forces [N] ----\n*CLOAD\n";
  for (std::size_t v = 0; v < nodal.size(); ++v)
    for (int dof = 0; dof < 3; ++dof)
      if (nodal[v][dof] != 0) text += fmt::format("{}, {}, {:.9g}\n", v + 1, dof + 1, nodal[v][dof]);
  return text;
}

/// *DLOAD: each element's mean pressure [Pa], signed as Abaqus and CalculiX read P on a shell
/// (positive acts against the normal of the node order): P = p where the particles' mean force
/// on the triangle points against its normal (F . n <= 0), -p where it points along it.
std::string inp_dload(const LinerLoad& load, const TriangleSurface& surface) {
  std::string text = "** ---- Alternative 2: element pressures [Pa] ----\n*DLOAD\n";
  for (std::size_t t = 0; t < surface.size() && t < load.pressure.size(); ++t) {
    if (load.pressure[t] == 0) continue;
    const Eigen::Vector3d normal(surface.normals[t][0], surface.normals[t][1], surface.normals[t][2]);
    const double sign = load.force[t].dot(normal) > 0 ? -1.0 : 1.0;
    text += fmt::format("{}, P, {:.9g}\n", t + 1, sign * load.pressure[t]);
  }
  return text;
}

/// One row of liner_loads.csv.
std::string csv_row(const LinerLoad& load) {
  const Eigen::Vector3d& c = load.peak_centroid;
  const Eigen::Vector3d& f = load.total_force;
  return fmt::format("\"{}\",{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n", load.name, load.area,
                     load.mean / kPascalsPerKilopascal, load.p95 / kPascalsPerKilopascal, load.peak / kPascalsPerKilopascal, c.x(), c.y(),
                     c.z(), f.x(), f.y(), f.z());
}

}  // namespace

LinerLoads liner_loads(const Model& model, const State& state, double records_from) {
  LinerLoads loads;
  loads.t0 = records_from, loads.t1 = state.time;
  for (std::size_t m = 0; m < model.meshes.size(); ++m)
    loads.meshes.push_back(mesh_load(model.meshes[m], m < state.records.size() ? &state.records[m] : nullptr, loads.t1 - loads.t0));
  return loads;
}

std::string liner_vtk(const LinerLoads& loads, const LinerLoad& load, const TriangleSurface& surface, const Pose& pose) {
  const std::size_t n = surface.size();
  // The header (its title one line of at most 256 characters), then the points in the world at `pose`.
  std::string text = fmt::format("# vtk DataFile Version 3.0\ndemdesign liner loads of {}, means over t = {:.6g} to {:.6g} s; world coordinates [m] at "
                                 "the pose of t = {:.6g} s\nASCII\nDATASET POLYDATA\nPOINTS {} double\n",
                                 fea_name(load.name).substr(0, 64), loads.t0, loads.t1, loads.t1, surface.vertices.size());
  for (const auto& v : surface.vertices) {
    const Eigen::Vector3d w = pose.rotation * Eigen::Vector3d(v[0], v[1], v[2]) + pose.translation;
    text += fmt::format("{:.9g} {:.9g} {:.9g}\n", w.x(), w.y(), w.z());
  }
  text += fmt::format("POLYGONS {} {}\n", n, 4 * n);
  for (const auto& t : surface.triangles) text += fmt::format("3 {} {} {}\n", t[0], t[1], t[2]);
  // Per triangle: the stresses in kPa, and the traction [Pa] turned into the world by `pose`.
  text += fmt::format("CELL_DATA {}\n", n);
  text += vtk_scalars("pressure_kPa", load.pressure, 1.0 / kPascalsPerKilopascal);
  text += vtk_scalars("shear_stress_kPa", load.shear_stress, 1.0 / kPascalsPerKilopascal);
  text += "VECTORS traction_Pa double\n";
  for (std::size_t t = 0; t < n; ++t) {
    const bool loaded = surface.areas[t] > 0 && t < load.force.size();
    const Eigen::Vector3d traction = loaded ? Eigen::Vector3d(pose.rotation * load.force[t] / surface.areas[t]) : Eigen::Vector3d(0, 0, 0);
    text += fmt::format("{:.9g} {:.9g} {:.9g}\n", traction.x(), traction.y(), traction.z());
  }
  return text;
}

std::string liner_inp(const LinerLoads& loads, const LinerLoad& load, const TriangleSurface& surface, const std::string& case_name) {
  return inp_header(loads, load, case_name) + inp_mesh(load, surface) + inp_cload(load, surface) + inp_dload(load, surface);
}

std::string fea_name(const std::string& mesh_name) {
  std::string name = key(mesh_name);
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) name = "MESH_" + name;
  return name;
}

void write_liner_loads(const LinerLoads& loads, const Model& model, const std::string& case_name, const std::string& report_dir) {
  if (model.meshes.empty() || !loads.recorded()) return;
  const fs::path fea = fs::path(report_dir) / "fea";
  std::string csv = "mesh,area_m2,mean_kPa,p95_kPa,peak_kPa,peak_x_m,peak_y_m,peak_z_m,force_x_N,force_y_N,force_z_N\n";
  // Per mesh its row, its VTK at the pose of the run's end and its input fragment in its own frame.
  for (std::size_t m = 0; m < model.meshes.size() && m < loads.meshes.size(); ++m) {
    const LinerLoad& load = loads.meshes[m];
    const TriangleSurface& surface = *model.meshes[m].surface;
    const std::string stem = fea_name(load.name);
    csv += csv_row(load);
    write_file_atomically((fea / (stem + ".vtk")).string(), liner_vtk(loads, load, surface, model.meshes[m].motion.pose(loads.t1)));
    write_file_atomically((fea / (stem + ".inp")).string(), liner_inp(loads, load, surface, case_name));
  }
  write_file_atomically((fs::path(report_dir) / "liner_loads.csv").string(), csv);
}

std::vector<std::size_t> liner_map_meshes(const LinerLoads& loads, const Model& model, const std::map<std::string, Liner>& liners) {
  std::vector<std::size_t> meshes;
  if (!loads.recorded()) return meshes;
  for (std::size_t m = 0; m < model.meshes.size() && m < loads.meshes.size(); ++m) {
    const bool named = liners.count(model.meshes[m].name) > 0;
    if (loads.meshes[m].mean > 0 && (named || !has_surface_velocity(model.meshes[m]))) meshes.push_back(m);
  }
  return meshes;
}

void add_liner_pressure_metrics(const LinerLoads& loads, RunMetrics& metrics) {
  if (!loads.recorded()) return;
  for (const LinerLoad& load : loads.meshes) {
    const std::string name = "liner_pressure_" + load.name;
    metrics.values.emplace_back(key(name + "_mean_kPa"), load.mean / kPascalsPerKilopascal);
    metrics.values.emplace_back(key(name + "_p95_kPa"), load.p95 / kPascalsPerKilopascal);
    metrics.values.emplace_back(key(name + "_peak_kPa"), load.peak / kPascalsPerKilopascal);
  }
}

}  // namespace dem::report
