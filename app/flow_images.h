// Images of a run's state for reports: particles coloured by a field, walls (planes clipped to
// the particles' neighbourhood, meshes at their current pose) cut away where they face the camera.
#pragma once

#include <string>

#include "model.h"
#include "state.h"
#include "workspace.h"

namespace dem::app {

struct ImageOptions {
  std::string camera = "iso";    // side, front, top, iso
  std::string colour = "speed";  // speed, radius, material
  int width = 1280, height = 720;
};

/// Renders the state to a PNG at `path` (headless, OSMesa).
void render_state(const Model& model, const State& state, const ImageOptions& options, const std::string& path);

}  // namespace dem::app
