// Images of a run's state for reports: particles coloured by a field, walls (planes clipped to
// the particles' neighbourhood, meshes at their current pose) cut away where they face the camera.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem::app {

struct ImageOptions {
  std::string camera;            // side, front, top, iso; "": default_camera(model)
  std::string colour = "speed";  // speed, radius, material
  int width = 1280, height = 720;
};

/// Renders the state to a PNG at `path` (headless, OSMesa).
void render_state(const Model& model, const State& state, const ImageOptions& options, const std::string& path);

/// Renders the meshes coloured by a per-triangle field (one vector per mesh, NaN: not coloured)
/// with a colour bar titled `label` and no particles (they would hide the liners); the colour
/// scale ends at the field's 99th percentile so one hot triangle does not wash out the rest, and
/// walls that carry little of the field are drawn faint.
void render_wall_field(const Model& model, const State& state, const std::vector<std::vector<double>>& field,
                       const std::string& label, const ImageOptions& options, const std::string& path);

/// Renders mesh `mesh` alone (no other walls, no particles) coloured by its per-triangle `field`
/// (NaN: grey) with the conventions of render_wall_field (coolwarm from 0 to the field's 99th
/// percentile, a colour bar titled `label`), the mesh's name in the caption and a scale bar.
/// An orthographic camera looks along face_on_direction and frames the mesh's bounding sphere;
/// options.camera is not used. `load` is the particles' push on the mesh in the mesh's own frame
/// (as report/liner_loads.h gives forces, e.g. their mean force on it; zero: none): it is turned
/// by the mesh's pose at state.time and puts the camera on the particles' side.
void render_mesh_field(const Model& model, const State& state, std::size_t mesh, const std::vector<double>& field,
                       const Eigen::Vector3d& load, const std::string& label, const ImageOptions& options, const std::string& path);

/// The direction [unit] a camera looks along to see a mesh face on; `vertices` and `triangles`
/// as placed in the world, `load` the particles' push on it in the world (zero: none). Along the
/// mesh's area-weighted mean normal, turned so that the camera looks along `load` (from the
/// particles' side), else from the side the normals point to. A nearly closed or strongly
/// curved mesh, whose mean normal is shorter than a quarter, has no face: then along `load`
/// (the camera on the particles' side of it), else along the iso preset's (-1, 1, -1).
Eigen::Vector3d face_on_direction(std::span<const std::array<double, 3>> vertices,
                                  std::span<const std::array<std::int32_t, 3>> triangles, const Eigen::Vector3d& load);

/// The camera for a model when the case names none: the equipment's, else iso.
std::string default_camera(const Model& model);

}  // namespace dem::app
