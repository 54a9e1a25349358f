// Images of a run's state for reports: particles coloured by a field, walls (planes clipped to
// the particles' neighbourhood, meshes at their current pose) cut away where they face the camera.
#pragma once

#include <string>

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

/// The camera for a model when the case names none: the equipment's, else iso.
std::string default_camera(const Model& model);

}  // namespace dem::app
