// The small case the run report's tests share: a flat two-triangle steel liner, a gravel inlet of
// 2 kg/s and one outlet below; gravel given inline (solid density 2600 kg/m^3, no stated bulk
// density). Each test file gives it its own title.
#pragma once

#include <string>

namespace dem::test {

inline std::string chute_liner_case(const std::string& title) {
  return "title: " + title + R"(
simulation: {duration: 4.0}
materials:
  gravel: {density: 2600, youngs_modulus: 5e7, restitution: 0.4, friction: 0.5}
  steel: {density: 7800, youngs_modulus: 2e11, restitution: 0.4, friction: 0.4}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
meshes:
  - name: chute_liner
    material: steel
    vertices: [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    triangles: [[0, 1, 2], [0, 2, 3]]
inlets:
  - {name: feed, material: gravel, diameter: 0.01, mass_rate_kgs: 2.0, region: {min: [0, 0, 0.5], max: [0.5, 0.5, 0.8]}}
outlets:
  - {name: bin, region: {min: [-1, -1, -2], max: [2, 2, -0.5]}}
)";
}

}  // namespace dem::test
