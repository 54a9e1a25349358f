// Mesh reports as text, and the `demdesign check-mesh FILE...` command built on them.
// No CGAL or assimp here: this file compiles in a second.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <ostream>

#include "mesh_health.h"

namespace dem::geometry {
namespace {

const char* severity_name(MeshIssue::Severity severity) {
  switch (severity) {
    case MeshIssue::Severity::info:
      return "info";
    case MeshIssue::Severity::repaired:
      return "repaired";
    case MeshIssue::Severity::warning:
      return "warning";
    case MeshIssue::Severity::fatal:
      return "FATAL";
  }
  return "?";
}

}  // namespace

bool MeshReport::simulable() const {
  return std::none_of(issues.begin(), issues.end(),
                      [](const MeshIssue& issue) { return issue.severity == MeshIssue::Severity::fatal; });
}

std::string MeshReport::text() const {
  // Summary: verdict and counts, then the measures in SI units.
  std::string out = fmt::format("{}: {}, {} triangles ({} in), {} vertices, {}\n", source,
                                simulable() ? "simulable" : "NOT SIMULABLE", triangles_out, triangles_in, vertices_out,
                                closed ? "closed" : "open");
  if (triangles_out > 0) {
    out += fmt::format("  box [m]: ({:.4g}, {:.4g}, {:.4g}) to ({:.4g}, {:.4g}, {:.4g}); area {:.4g} m^2\n",
                       bbox_min[0], bbox_min[1], bbox_min[2], bbox_max[0], bbox_max[1], bbox_max[2], area);
    out += fmt::format("  edges [m]: min {:.4g}, median {:.4g}, max {:.4g}\n", edge_min, edge_median, edge_max);
  }
  // One line per issue, with example triangles (indices in the file's triangle order).
  for (const MeshIssue& issue : issues) {
    out += fmt::format("  {}: {}", severity_name(issue.severity), issue.what);
    if (!issue.triangles.empty()) out += fmt::format("; e.g. triangles {}", fmt::join(issue.triangles, ", "));
    out += '\n';
  }
  if (issues.empty()) out += "  no issues\n";
  return out;
}

int check_mesh_command(const std::vector<std::string>& files, const ImportOptions& options, double particle_diameter,
                       std::ostream& out) {
  // Each file on its own: one unreadable file does not stop the others from being checked.
  std::size_t simulable = 0;
  for (const std::string& file : files) {
    try {
      TriangleMesh mesh = import_mesh(file, options);
      const MeshReport report = check_and_repair(mesh, particle_diameter);
      out << report.text();
      simulable += report.simulable();
    } catch (const MeshError& error) {
      out << "error: " << error.what() << '\n';
    }
  }
  if (files.size() > 1) out << simulable << " of " << files.size() << " meshes simulable\n";
  return simulable == files.size() ? 0 : 1;
}

}  // namespace dem::geometry
