// The interactive 3D view in the run report: the mesh walls in their final pose, coloured by a
// wall field (shear work rate, impact energy rate, mean pressure, liner life, or plain), and the
// particles of the final state as sphere sprites coloured by speed; orbit, zoom and pan with the
// mouse. three.js (Debian package libjs-three) is read from disk and inlined, with the data as
// base64 Float32 arrays, so the report stays one file that opens anywhere without a network.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/state.h"

namespace dem::viewer3d {

/// Where Debian's libjs-three puts the minified build.
inline constexpr const char* kDefaultThreeJs = "/usr/share/javascript/three/three.min.js";

struct Options {
  /// three.js to inline; empty: $DEMDESIGN_THREE_JS when set, else kDefaultThreeJs.
  std::string three_js;
  /// Particles above this many are subsampled (evenly over the slots), and the report says so.
  std::size_t max_particles = 20000;
  /// [months] Per mesh, per triangle: the life of the mesh's liner there (NaN where the mesh has
  /// no liner, infinite where it does not wear), computed by the caller (the run report:
  /// report/report_wear.h, triangle_life_months; pages include nothing of report/). Empty, or no
  /// value that is not NaN: the view offers no life field.
  std::vector<std::vector<double>> life_months;
};

/// The viewer's section of the report (heading, canvas, legends, scripts). Never throws: when
/// three.js is missing or anything else fails, the section is a note saying why. `records_from`
/// [s] is when the wall records started (the rates are averaged from then to state.time).
std::string section(const Model& model, const State& state, double records_from, const Options& options = {});

}  // namespace dem::viewer3d
