// Liner pressure and the liner loads a structural (FEA) model reads (internal to app/): per mesh,
// from the wall records over their interval (output.records_from to the end of the run), the mean
// pressure per triangle [Pa] with its area-weighted mean, 95th percentile by area and peak, and the
// particles' mean force on each triangle [N]. Written into REPORT_DIR as liner_loads.csv (one row
// per mesh) and, per mesh, fea/MESH.vtk and fea/MESH.inp.
//
// Frames: the records keep the force in the mesh's own frame, the one its vertices are given in
// (for a mesh without motion that is where the case puts it; a moving mesh's pose carries it).
// liner_loads.csv and MESH.inp are in that frame: what a structural model of the part is built
// in. MESH.vtk is in world coordinates at the pose of the run's end, as walls.h5, so that
// ParaView shows it on the walls and particles (its traction vectors turned by that pose).
// For a mesh without motion both are the case's coordinates.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/state.h"
#include "report/report.h"

namespace dem::report {

/// One mesh's loads over the records' interval.
struct LinerLoad {
  std::string name;                    ///< the mesh's name
  std::vector<double> pressure;        ///< [Pa] per triangle: normal impulse / (area x interval); 0 on a triangle of no area
  std::vector<double> shear_stress;    ///< [Pa] per triangle: tangential impulse / (area x interval)
  std::vector<Eigen::Vector3d> force;  ///< [N] per triangle: the particles' mean force on it, the mesh's own frame
  double area = 0;                     ///< [m^2] of the mesh
  double mean = 0;                     ///< [Pa] area-weighted mean pressure: sum p A / sum A
  double p95 = 0;                      ///< [Pa] 95th percentile by area: 95 % of the area carries no more
  double peak = 0;                     ///< [Pa] the highest triangle's
  std::size_t peak_triangle = 0;
  Eigen::Vector3d peak_centroid{0, 0, 0};  ///< [m] its centroid, the mesh's own frame
  Eigen::Vector3d total_force{0, 0, 0};    ///< [N] sum of `force`, the mesh's own frame
};

/// The liner loads of a run: the records' window and one LinerLoad per mesh of the model.
struct LinerLoads {
  double t0 = 0, t1 = 0;  ///< [s] the window: output.records_from and the state's time
  std::vector<LinerLoad> meshes;
  bool recorded() const { return t1 > t0; }
};

/// The loads of every mesh of `model` from `state`'s wall records, accumulated since
/// records_from [s]. Records without force impulses (a fixture, a checkpoint before version 9)
/// give zero forces.
LinerLoads liner_loads(const Model& model, const State& state, double records_from);

/// Legacy VTK (POLYDATA, ASCII) of one mesh in world coordinates [m] at `pose` (the pose of the
/// run's end), with CELL_DATA pressure_kPa, shear_stress_kPa and the VECTORS traction_Pa (the
/// mean force per area, turned by `pose`).
std::string liner_vtk(const LinerLoads& loads, const LinerLoad& load, const TriangleSurface& surface, const Pose& pose);

/// A CalculiX / Abaqus input fragment of one mesh in its own frame: comment lines with the
/// units, window, case and frame; *NODE [m]; *ELEMENT, TYPE=S3 (ELSET named by fea_name);
/// *CLOAD, the nodal forces [N] (each triangle's mean force split equally over its three nodes,
/// summed per node); and as the alternative, *DLOAD, each element's pressure [Pa] with the
/// Abaqus sign (positive P acts against the element normal of its node order; CalculiX CrunchiX
/// User's Manual, *CLOAD and *DLOAD).
std::string liner_inp(const LinerLoads& loads, const LinerLoad& load, const TriangleSurface& surface, const std::string& case_name);

/// A mesh's name as a file stem and an Abaqus set name: letters, digits and '_', starting with a letter.
std::string fea_name(const std::string& mesh_name);

/// Writes REPORT_DIR/liner_loads.csv and, per mesh, REPORT_DIR/fea/MESH.vtk and MESH.inp, each
/// atomically; nothing without meshes or records. `case_name` is named in the .inp files.
void write_liner_loads(const LinerLoads& loads, const Model& model, const std::string& case_name, const std::string& report_dir);

/// The meshes that get a pressure map of their own (indices into model.meshes, in order): those
/// that carry load (a mean pressure above zero over the records' window) and are liners by the
/// rule of liners_for (report_wear.h): a belt or pulley (a mesh whose surface moves) only when
/// `liners` names it. The liner table lists every mesh; a map of what carries nothing shows nothing.
std::vector<std::size_t> liner_map_meshes(const LinerLoads& loads, const Model& model, const std::map<std::string, Liner>& liners);

/// Appends per mesh liner_pressure_MESH_mean_kPa, _p95_kPa and _peak_kPa (nothing without records).
void add_liner_pressure_metrics(const LinerLoads& loads, RunMetrics& metrics);

}  // namespace dem::report
