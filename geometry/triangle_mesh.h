// CAD meshes as walls, part 1: reading any mesh file a designer exports into one triangle soup
// in metres. Every format assimp reads (STL, OBJ, PLY, 3MF, glTF, FBX, Collada, ...) goes through
// import_mesh(); B-rep CAD (STEP, IGES) is refused with a message that says what to export
// instead. Checking and repairing the result is mesh_health.h.
#pragma once

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace dem::geometry {

/// A plain triangle soup with shared vertices, in metres.
struct TriangleMesh {
  std::vector<std::array<double, 3>> vertices;         // [m] (n_vertices x 3)
  std::vector<std::array<std::int32_t, 3>> triangles;  // (n_triangles x 3) indices into vertices,
                                                       // counter-clockwise seen from outside
  std::string source;                                  // file it came from
};

/// How file coordinates become metres: p = translate + Rz Ry Rx (scale * (unit_scale * p_file)).
struct ImportOptions {
  double unit_scale = 1.0;                    // [m per file unit] file units -> metres (0.001 for mm)
  std::array<double, 3> scale{1, 1, 1};       // [-] extra per-axis scale, after unit_scale; negative mirrors
  std::array<double, 3> rotate_deg{0, 0, 0};  // [deg] rotations about x, then y, then z, about the origin
  std::array<double, 3> translate{0, 0, 0};   // [m] applied last
};

/// Why a file could not be turned into a TriangleMesh. what() names the file and what would be valid.
class MeshError : public std::runtime_error {
 public:
  enum class Kind {
    missing,          // no such file, or not a regular file
    cad_format,       // STEP / IGES: B-rep CAD that must be exported as a mesh first
    unreadable,       // assimp rejected the file (unknown format, broken content)
    no_triangles,     // the file holds only points, lines, cameras, bones, ...
    invalid_options,  // ImportOptions not finite or a zero scale
  };
  MeshError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

/// Reads `path` with assimp: triangulates polygons, applies every node's transform down the node
/// hierarchy, merges all meshes of the file into one soup, joins vertices at identical positions,
/// then applies `options`. Points and lines are dropped. Throws MeshError.
TriangleMesh import_mesh(const std::string& path, const ImportOptions& options = {});

/// True when assimp has an importer for the file's extension (say ".stl" or ".glb"), and the
/// extension is not STEP / IGES. Says nothing about whether the content is valid.
bool has_importable_extension(const std::string& path);

}  // namespace dem::geometry
