// CAD meshes as walls, part 2: is an imported mesh fit to be a DEM wall, and what can be repaired
// without changing its shape? check_and_repair() removes degenerate and duplicate triangles and
// orients triangles consistently (closed parts outward); it only reports what would need a
// designer's judgement (non-manifold edges, self-intersections, open borders, odd sizes or units).
// The checks use CGAL Polygon Mesh Processing (CGAL 5.5), all inside mesh_health.cpp.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "triangle_mesh.h"

namespace dem::geometry {

/// One finding of check_and_repair.
struct MeshIssue {
  enum class Severity {
    info,      // worth knowing, harmless for contact (open borders, coarse triangles)
    repaired,  // found and fixed in place (degenerate or duplicate triangles, orientation)
    warning,   // simulable, but the result may be wrong where it occurs (self-intersections)
    fatal,     // cannot be simulated (no triangles left, non-finite coordinates)
  } severity;
  std::string what;                     // one sentence, with its numbers
  std::int64_t count = 0;               // how many triangles, edges, loops, ... (the unit is in `what`)
  std::vector<std::int32_t> triangles;  // up to 10 examples, as indices into the mesh as it was passed in
};

/// What check_and_repair found, and the repaired mesh's measures.
struct MeshReport {
  std::string source;
  std::size_t triangles_in = 0, triangles_out = 0, vertices_out = 0;
  std::array<double, 3> bbox_min{}, bbox_max{};        // [m]
  double area = 0;                                     // [m^2]
  double edge_min = 0, edge_max = 0, edge_median = 0;  // [m] over distinct edges
  bool closed = false;                                 // watertight: every edge shared by exactly two triangles
  std::vector<MeshIssue> issues;

  /// False if any issue is fatal.
  bool simulable() const;
  /// Human-readable report: a summary, then one line per issue with its numbers.
  std::string text() const;
};

/// Checks `mesh` and repairs in place what can be repaired safely: degenerate and duplicate
/// triangles are removed, orientation is made consistent, and unused vertices are dropped
/// (indices stay valid). `particle_diameter` [m] (0 = unknown) enables the triangle size checks.
MeshReport check_and_repair(TriangleMesh& mesh, double particle_diameter);

/// Imports and checks each file, prints its report to `out`; returns 0 when all are simulable, 1 otherwise.
int check_mesh_command(const std::vector<std::string>& files, const ImportOptions& options, double particle_diameter,
                       std::ostream& out);

}  // namespace dem::geometry
