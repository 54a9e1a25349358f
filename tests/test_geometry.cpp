// Mesh import (assimp), health check and repair (CGAL): small meshes written here in STL, OBJ and
// PLY whose every answer is known by hand, then every model in Debian's assimp-testmodels.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "mesh_health.h"
#include "triangle_mesh.h"

namespace {

namespace fs = std::filesystem;
using namespace dem::geometry;
using Severity = MeshIssue::Severity;

/// Axis-aligned cube [offset, offset + side]^3, 12 triangles counter-clockwise seen from outside.
/// Vertex k sits at (k & 1, k >> 1 & 1, k >> 2 & 1) * side; faces in the order -z, +z, -y, +y, -x, +x.
TriangleMesh cube(double side = 1, std::array<double, 3> offset = {0, 0, 0}) {
  TriangleMesh mesh;
  for (int k = 0; k < 8; ++k)
    mesh.vertices.push_back(
        {offset[0] + side * (k & 1), offset[1] + side * (k >> 1 & 1), offset[2] + side * (k >> 2 & 1)});
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  mesh.source = "cube";
  return mesh;
}

/// Two meshes as one soup (no vertices shared).
TriangleMesh join(TriangleMesh a, const TriangleMesh& b) {
  const auto offset = std::int32_t(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto [p, q, r] : b.triangles) a.triangles.push_back({p + offset, q + offset, r + offset});
  return a;
}

/// Open trough 3000 x 800 x 500 (file units, meant as mm): bottom and two sides, no ends.
TriangleMesh chute_in_millimetres() {
  const double profile[4][2] = {{-400, 500}, {-400, 0}, {400, 0}, {400, 500}};  // (y, z)
  TriangleMesh mesh;
  for (const auto& [y, z] : profile) {
    mesh.vertices.push_back({0, y, z});
    mesh.vertices.push_back({3000, y, z});
  }
  for (std::int32_t i = 0; i < 3; ++i) {
    const std::int32_t a = 2 * i, b = 2 * i + 1, c = 2 * i + 3, d = 2 * i + 2;
    mesh.triangles.push_back({a, b, c});
    mesh.triangles.push_back({a, c, d});
  }
  return mesh;
}

/// Signed enclosed volume [m^3]: positive when a closed mesh faces outward.
double signed_volume(const TriangleMesh& mesh) {
  double six_volume = 0;
  for (const auto& [a, b, c] : mesh.triangles) {
    const auto &p = mesh.vertices[a], &q = mesh.vertices[b], &r = mesh.vertices[c];
    six_volume +=
        p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) + p[2] * (q[0] * r[1] - q[1] * r[0]);
  }
  return six_volume / 6;
}

const MeshIssue* find_issue(const MeshReport& report, const std::string& words) {
  for (const MeshIssue& issue : report.issues)
    if (issue.what.find(words) != std::string::npos) return &issue;
  return nullptr;
}

void write_ascii_stl(const fs::path& path, const TriangleMesh& mesh, double scale = 1) {
  std::ofstream out(path);
  out.precision(17);
  out << "solid test\n";
  for (const auto& triangle : mesh.triangles) {
    out << " facet normal 0 0 0\n  outer loop\n";
    for (std::int32_t v : triangle)
      out << "   vertex " << scale * mesh.vertices[v][0] << ' ' << scale * mesh.vertices[v][1] << ' '
          << scale * mesh.vertices[v][2] << '\n';
    out << "  endloop\n endfacet\n";
  }
  out << "endsolid test\n";
}

/// Binary STL: 80-byte header (not starting with "solid"), count, 50 bytes per triangle.
void write_binary_stl(const fs::path& path, const TriangleMesh& mesh) {
  std::ofstream out(path, std::ios::binary);
  char header[80] = "binary STL written by demdesign test_geometry";
  out.write(header, sizeof header);
  const auto count = std::uint32_t(mesh.triangles.size());
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (const auto& triangle : mesh.triangles) {
    float record[12] = {};
    for (int corner = 0; corner < 3; ++corner)
      for (int axis = 0; axis < 3; ++axis) record[3 + 3 * corner + axis] = float(mesh.vertices[triangle[corner]][axis]);
    out.write(reinterpret_cast<const char*>(record), sizeof record);
    const std::uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), 2);
  }
}

/// OBJ; with `quads`, consecutive triangles (a, b, c), (a, c, d) are written as one face (a, b, c, d).
void write_obj(const fs::path& path, const TriangleMesh& mesh, bool quads = false) {
  std::ofstream out(path);
  out.precision(17);
  for (const auto& [x, y, z] : mesh.vertices) out << "v " << x << ' ' << y << ' ' << z << '\n';
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& [a, b, c] = mesh.triangles[t];
    if (quads && t + 1 < mesh.triangles.size() && mesh.triangles[t + 1][0] == a && mesh.triangles[t + 1][1] == c) {
      out << "f " << a + 1 << ' ' << b + 1 << ' ' << c + 1 << ' ' << mesh.triangles[++t][2] + 1 << '\n';
      continue;
    }
    out << "f " << a + 1 << ' ' << b + 1 << ' ' << c + 1 << '\n';
  }
}

/// A fresh directory per test, removed afterwards.
class MeshFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("demdesign_geometry_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

/// The unit cube's report: closed, 12 triangles, area 6 side^2, edges side and side*sqrt(2), no issues.
void expect_clean_cube(const TriangleMesh& mesh, const MeshReport& report, double side) {
  EXPECT_TRUE(report.issues.empty()) << report.text();
  EXPECT_TRUE(report.closed);
  EXPECT_TRUE(report.simulable());
  EXPECT_EQ(report.triangles_in, 12u);
  EXPECT_EQ(report.triangles_out, 12u);
  EXPECT_EQ(report.vertices_out, 8u);
  EXPECT_NEAR(report.area, 6 * side * side, 1e-9 * side * side);
  EXPECT_NEAR(report.edge_min, side, 1e-9 * side);
  EXPECT_NEAR(report.edge_median, side, 1e-9 * side);  // 12 sides of length `side`, 6 diagonals
  EXPECT_NEAR(report.edge_max, side * std::sqrt(2.0), 1e-9 * side);
  EXPECT_NEAR(signed_volume(mesh), side * side * side, 1e-9 * side * side * side);
}

TEST_F(MeshFiles, UnitCubeFromAsciiStlBinaryStlAndObj) {
  write_ascii_stl(path("cube.stl"), cube());
  write_binary_stl(path("cube_binary.stl"), cube());
  write_obj(path("cube.obj"), cube());
  write_obj(path("cube_quads.obj"), cube(), true);  // 6 quads: triangulated by assimp
  for (const char* name : {"cube.stl", "cube_binary.stl", "cube.obj", "cube_quads.obj"}) {
    SCOPED_TRACE(name);
    TriangleMesh mesh = import_mesh(path(name), {});
    EXPECT_EQ(mesh.source, path(name));
    EXPECT_EQ(mesh.vertices.size(), 8u);  // STL's 36 corners joined into 8
    EXPECT_EQ(mesh.triangles.size(), 12u);
    const MeshReport report = check_and_repair(mesh, 0);
    expect_clean_cube(mesh, report, 1);
    EXPECT_EQ(report.bbox_min, (std::array<double, 3>{0, 0, 0}));
    EXPECT_EQ(report.bbox_max, (std::array<double, 3>{1, 1, 1}));
  }
}

TEST_F(MeshFiles, UnitScaleTurnsMillimetresIntoMetres) {
  // A 1000 mm cube read with unit_scale 0.001 is the 1 m cube.
  write_ascii_stl(path("cube_mm.stl"), cube(), 1000);
  ImportOptions millimetres;
  millimetres.unit_scale = 0.001;
  TriangleMesh metre_cube = import_mesh(path("cube_mm.stl"), millimetres);
  expect_clean_cube(metre_cube, check_and_repair(metre_cube, 0), 1);
  // The unit cube read as millimetres is a 1 mm cube (1.7 mm across: still plausible).
  write_ascii_stl(path("cube.stl"), cube());
  TriangleMesh millimetre_cube = import_mesh(path("cube.stl"), millimetres);
  const MeshReport report = check_and_repair(millimetre_cube, 0);
  expect_clean_cube(millimetre_cube, report, 0.001);
  EXPECT_NEAR(report.bbox_max[2], 0.001, 1e-15);
}

TEST_F(MeshFiles, UnitsWarningsForMillimetreChuteAndTinyPart) {
  write_obj(path("chute.obj"), chute_in_millimetres());
  // Read as metres, the chute is 3 km long: warn that it is probably in millimetres.
  TriangleMesh as_metres = import_mesh(path("chute.obj"), {});
  const MeshReport wrong = check_and_repair(as_metres, 0);
  const MeshIssue* units = find_issue(wrong, "millimetres");
  ASSERT_NE(units, nullptr) << wrong.text();
  EXPECT_EQ(units->severity, Severity::warning);
  EXPECT_NE(units->what.find("unit_scale: 0.001"), std::string::npos);
  EXPECT_NE(units->what.find("3145 m across"), std::string::npos)
      << units->what;  // sqrt(3000^2 + 800^2 + 500^2) = 3145
  EXPECT_TRUE(wrong.simulable());
  // With unit_scale 0.001 only the open border remains: one loop of 8 edges, info, not fatal.
  ImportOptions millimetres;
  millimetres.unit_scale = 0.001;
  TriangleMesh chute = import_mesh(path("chute.obj"), millimetres);
  const MeshReport right = check_and_repair(chute, 0);
  ASSERT_EQ(right.issues.size(), 1u) << right.text();
  EXPECT_EQ(right.issues[0].severity, Severity::info);
  EXPECT_EQ(right.issues[0].count, 1);
  EXPECT_NE(right.issues[0].what.find("8 border edges"), std::string::npos) << right.issues[0].what;
  EXPECT_FALSE(right.closed);
  EXPECT_NEAR(right.area, 3.0 * (0.5 + 0.8 + 0.5), 1e-12);
  // A half-millimetre cube given in metres: probably scaled twice.
  TriangleMesh tiny = cube(0.0005);
  const MeshReport tiny_report = check_and_repair(tiny, 0);
  const MeshIssue* twice = find_issue(tiny_report, "metres already");
  ASSERT_NE(twice, nullptr) << tiny_report.text();
  EXPECT_EQ(twice->severity, Severity::warning);
}

TEST_F(MeshFiles, RotationsApplyAboutXThenYThenZAndMirrorsKeepOutwardFaces) {
  // Triangle (1,0,0), (0,1,0), (0,0,2): Rx(90) then Rz(90) gives (0,1,0), (0,0,1), (2,0,0).
  TriangleMesh triangle{{{1, 0, 0}, {0, 1, 0}, {0, 0, 2}}, {{0, 1, 2}}, ""};
  write_obj(path("triangle.obj"), triangle);
  ImportOptions rotated;
  rotated.rotate_deg = {90, 0, 90};
  rotated.translate = {10, 0, 0};
  const TriangleMesh moved = import_mesh(path("triangle.obj"), rotated);
  const std::array<std::array<double, 3>, 3> expected{{{10, 1, 0}, {10, 0, 1}, {12, 0, 0}}};
  ASSERT_EQ(moved.vertices.size(), 3u);
  for (int v = 0; v < 3; ++v)
    for (int axis = 0; axis < 3; ++axis) EXPECT_NEAR(moved.vertices[v][axis], expected[v][axis], 1e-12);
  // Mirrored in x (and stretched in y): winding reversed, so the cube still faces outward.
  write_ascii_stl(path("cube.stl"), cube());
  ImportOptions mirrored;
  mirrored.scale = {-1, 2, 1};
  TriangleMesh mirror_cube = import_mesh(path("cube.stl"), mirrored);
  const MeshReport report = check_and_repair(mirror_cube, 0);
  EXPECT_TRUE(report.issues.empty()) << report.text();
  EXPECT_NEAR(signed_volume(mirror_cube), 2.0, 1e-12);
  EXPECT_EQ(report.bbox_min, (std::array<double, 3>{-1, 0, 0}));
  // Invalid options are refused before the file is read.
  ImportOptions zero;
  zero.scale = {1, 0, 1};
  EXPECT_THROW(import_mesh(path("cube.stl"), zero), MeshError);
}

TEST_F(MeshFiles, NodeTransformsComposeDownTheHierarchyAndMirrorsKeepOutwardFaces) {
  // glTF: parent node translated by (10, 0, 0), child scaled by (-2, 1, 1) holding the unit cube
  // (positions and 16-bit indices in an embedded buffer, in cube()'s order).
  std::ofstream(path("cube.gltf")) << R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"translation": [10, 0, 0], "children": [1]}, {"scale": [-2, 1, 1], "mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": 168, "uri": "data:application/octet-stream;base64,)"
                                      "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAACAPwAAgD8AAAAAAAAAAAAAAAAAAIA/"
                                      "AACAPwAAAAAAAIA/AAAAAAAAgD8AAIA/AACAPwAAgD8AAIA/AAACAAMAAAADAAEABAAFAAcABAAHAAYA"
                                      "AAABAAUAAAAFAAQAAgAGAAcAAgAHAAMAAAAEAAYAAAAGAAIAAQADAAcAAQAHAAUA"
                                      R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96}, {"buffer": 0, "byteOffset": 96, "byteLength": 72}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]},
                {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]})";
  TriangleMesh mesh = import_mesh(path("cube.gltf"), {});
  const MeshReport report = check_and_repair(mesh, 0);
  EXPECT_TRUE(report.issues.empty()) << report.text();  // the mirror reversed the winding: no repair needed
  EXPECT_EQ(report.bbox_min, (std::array<double, 3>{8, 0, 0}));
  EXPECT_EQ(report.bbox_max, (std::array<double, 3>{10, 1, 1}));
  EXPECT_NEAR(signed_volume(mesh), 2.0, 1e-12);
  // The user's placement comes after the file's own: lifted 1 m in z.
  ImportOptions lifted;
  lifted.translate = {0, 0, 1};
  EXPECT_EQ(check_and_repair(mesh = import_mesh(path("cube.gltf"), lifted), 0).bbox_min,
            (std::array<double, 3>{8, 0, 1}));
}

TEST(MeshRepair, DegenerateAndDuplicateTrianglesAreRemovedAndCounted) {
  TriangleMesh mesh = cube();
  mesh.vertices.push_back({0.5, 0, 0});  // vertex 8, on the edge 0-1
  mesh.triangles.push_back({0, 0, 5});   // 12: repeated vertex
  mesh.triangles.push_back({0, 8, 1});   // 13: collinear, zero area
  mesh.triangles.push_back({3, 0, 2});   // 14: triangle 0 rotated
  mesh.triangles.push_back({7, 5, 4});   // 15: triangle 2 reversed
  const MeshReport report = check_and_repair(mesh, 0);
  ASSERT_EQ(report.issues.size(), 2u) << report.text();
  const MeshIssue* degenerate = find_issue(report, "degenerate");
  const MeshIssue* duplicate = find_issue(report, "duplicate");
  ASSERT_TRUE(degenerate && duplicate) << report.text();
  EXPECT_EQ(degenerate->severity, Severity::repaired);
  EXPECT_EQ(degenerate->count, 2);
  EXPECT_EQ(degenerate->triangles, (std::vector<std::int32_t>{12, 13}));
  EXPECT_EQ(duplicate->severity, Severity::repaired);
  EXPECT_EQ(duplicate->count, 2);
  EXPECT_EQ(duplicate->triangles, (std::vector<std::int32_t>{14, 15}));
  // What is left is the clean cube, vertex 8 dropped and indices still valid.
  EXPECT_EQ(report.triangles_in, 16u);
  EXPECT_EQ(mesh.triangles, cube().triangles);
  EXPECT_EQ(mesh.vertices, cube().vertices);
  EXPECT_TRUE(report.closed);
  EXPECT_NE(report.text().find("repaired: 2 degenerate triangles removed"), std::string::npos) << report.text();
}

TEST_F(MeshFiles, DegenerateAndDuplicateTrianglesThroughAnObjFile) {
  TriangleMesh mesh = cube();
  mesh.vertices.push_back({0.5, 0, 0});
  mesh.triangles.push_back({0, 8, 1});  // collinear
  mesh.triangles.push_back({3, 0, 2});  // duplicate
  write_obj(path("broken_cube.obj"), mesh);
  TriangleMesh imported = import_mesh(path("broken_cube.obj"), {});
  const MeshReport report = check_and_repair(imported, 0);
  EXPECT_EQ(report.triangles_in, 14u);
  EXPECT_EQ(report.triangles_out, 12u);
  ASSERT_NE(find_issue(report, "degenerate"), nullptr) << report.text();
  EXPECT_EQ(find_issue(report, "degenerate")->count, 1);
  ASSERT_NE(find_issue(report, "duplicate"), nullptr) << report.text();
  EXPECT_EQ(find_issue(report, "duplicate")->count, 1);
  EXPECT_TRUE(report.closed);
}

TEST(MeshRepair, DuplicateVertexPositionsAreJoined) {
  // Every triangle with its own three corners, as a plain STL soup: 36 vertices, 8 positions.
  const TriangleMesh welded = cube();
  TriangleMesh soup;
  for (const auto& triangle : welded.triangles) {
    for (std::int32_t v : triangle) soup.vertices.push_back(welded.vertices[v]);
    const auto n = std::int32_t(soup.vertices.size());
    soup.triangles.push_back({n - 3, n - 2, n - 1});
  }
  const MeshReport report = check_and_repair(soup, 0);
  ASSERT_NE(find_issue(report, "identical positions"), nullptr) << report.text();
  EXPECT_EQ(find_issue(report, "identical positions")->count, 28);
  EXPECT_EQ(report.vertices_out, 8u);
  EXPECT_TRUE(report.closed);
  EXPECT_NEAR(signed_volume(soup), 1.0, 1e-12);
}

TEST(MeshRepair, FlippedTrianglesAreTurnedBackOutward) {
  // Two triangles flipped: exactly those two are turned back.
  TriangleMesh mesh = cube();
  std::swap(mesh.triangles[3][1], mesh.triangles[3][2]);
  std::swap(mesh.triangles[7][1], mesh.triangles[7][2]);
  const MeshReport report = check_and_repair(mesh, 0);
  ASSERT_EQ(report.issues.size(), 1u) << report.text();
  EXPECT_EQ(report.issues[0].severity, Severity::repaired);
  EXPECT_EQ(report.issues[0].count, 2);
  EXPECT_EQ(report.issues[0].triangles, (std::vector<std::int32_t>{3, 7}));
  EXPECT_NEAR(signed_volume(mesh), 1.0, 1e-12);
  EXPECT_TRUE(report.closed);
  // An inside-out cube: consistent, but facing in; all 12 turned.
  TriangleMesh inside_out = cube();
  for (auto& triangle : inside_out.triangles) std::swap(triangle[1], triangle[2]);
  const MeshReport turned = check_and_repair(inside_out, 0);
  ASSERT_EQ(turned.issues.size(), 1u) << turned.text();
  EXPECT_EQ(turned.issues[0].count, 12);
  EXPECT_NEAR(signed_volume(inside_out), 1.0, 1e-12);
  // Two separate cubes, one inside out: each closed part faces outward on its own.
  TriangleMesh pair = join(cube(), inside_out);
  for (std::size_t v = 8; v < 16; ++v) pair.vertices[v][0] += 3;
  for (std::size_t t = 12; t < 24; ++t) std::swap(pair.triangles[t][1], pair.triangles[t][2]);
  const MeshReport pair_report = check_and_repair(pair, 0);
  ASSERT_EQ(pair_report.issues.size(), 1u) << pair_report.text();
  EXPECT_EQ(pair_report.issues[0].count, 12);
  EXPECT_EQ(pair_report.issues[0].triangles.front(), 12);
  EXPECT_NEAR(signed_volume(pair), 2.0, 1e-12);
}

TEST(MeshRepair, OpenBoxHasOneBorderLoopAndIsSimulable) {
  TriangleMesh box = cube();
  box.triangles.erase(box.triangles.begin() + 2, box.triangles.begin() + 4);  // no top (+z)
  const MeshReport report = check_and_repair(box, 0);
  ASSERT_EQ(report.issues.size(), 1u) << report.text();
  EXPECT_EQ(report.issues[0].severity, Severity::info);
  EXPECT_EQ(report.issues[0].count, 1);  // one loop
  EXPECT_NE(report.issues[0].what.find("1 open border loop (4 border edges)"), std::string::npos) << report.text();
  EXPECT_FALSE(report.closed);
  EXPECT_TRUE(report.simulable());
  EXPECT_NEAR(report.area, 5.0, 1e-12);
  // One flipped triangle in an open box: the majority's orientation wins, only that one turns.
  TriangleMesh flipped = cube();
  flipped.triangles.erase(flipped.triangles.begin() + 2, flipped.triangles.begin() + 4);
  std::swap(flipped.triangles[5][0], flipped.triangles[5][1]);
  const MeshReport repaired = check_and_repair(flipped, 0);
  const MeshIssue* orientation = find_issue(repaired, "flipped");
  ASSERT_NE(orientation, nullptr) << repaired.text();
  EXPECT_EQ(orientation->count, 1);
  EXPECT_EQ(orientation->triangles, (std::vector<std::int32_t>{5}));
  EXPECT_EQ(flipped.triangles[5], (std::array<std::int32_t, 3>{7, 3, 2}));  // (7, 2, 3) turned: (2, 7, 3) rotated
  flipped.triangles[5] = box.triangles[5];
  EXPECT_EQ(flipped.triangles, box.triangles);  // the others untouched, corner order too
  // A plate with a square hole: two loops.
  TriangleMesh plate;
  for (double r : {1.0, 2.0})
    for (auto [x, y] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) plate.vertices.push_back({r * x, r * y, 0});
  for (std::int32_t k = 0; k < 4; ++k) {
    const std::int32_t inner = k, next_inner = (k + 1) % 4;
    plate.triangles.push_back({inner, 4 + inner, 4 + next_inner});
    plate.triangles.push_back({inner, 4 + next_inner, next_inner});
  }
  const MeshReport plate_report = check_and_repair(plate, 0);
  ASSERT_EQ(plate_report.issues.size(), 1u) << plate_report.text();
  EXPECT_EQ(plate_report.issues[0].count, 2);
}

TEST_F(MeshFiles, TwoIntersectingCubesInOneFileWarnOfSelfIntersections) {
  write_ascii_stl(path("two_cubes.stl"), join(cube(), cube(1, {0.5, 0.5, 0.5})));
  TriangleMesh mesh = import_mesh(path("two_cubes.stl"), {});
  EXPECT_EQ(mesh.triangles.size(), 24u);
  const MeshReport report = check_and_repair(mesh, 0);
  const MeshIssue* crossing = find_issue(report, "intersect");
  ASSERT_NE(crossing, nullptr) << report.text();
  EXPECT_EQ(crossing->severity, Severity::warning);
  EXPECT_GT(crossing->count, 0);
  EXPECT_FALSE(crossing->triangles.empty());
  EXPECT_TRUE(report.simulable());
  // Apart, the two cubes are clean; face to face across a gap of 1 um, too.
  for (double gap : {1.0, 1e-6}) {
    TriangleMesh apart = join(cube(), cube(1, {1 + gap, 0, 0}));
    const MeshReport apart_report = check_and_repair(apart, 0);
    EXPECT_TRUE(apart_report.issues.empty()) << apart_report.text();
  }
  // Touching face to face (coplanar overlap without shared vertices) counts as intersecting.
  TriangleMesh touching = join(cube(), cube(1, {1, 0.5, 0}));
  EXPECT_NE(find_issue(check_and_repair(touching, 0), "intersect"), nullptr);
}

TEST(MeshRepair, NonManifoldEdgeIsAWarning) {
  // Three fins on the edge (0,0,0)-(1,0,0).
  TriangleMesh fins{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, -1}}, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}, ""};
  const MeshReport report = check_and_repair(fins, 0);
  const MeshIssue* non_manifold = find_issue(report, "non-manifold");
  ASSERT_NE(non_manifold, nullptr) << report.text();
  EXPECT_EQ(non_manifold->severity, Severity::warning);
  EXPECT_EQ(non_manifold->count, 1);
  EXPECT_EQ(non_manifold->triangles, (std::vector<std::int32_t>{0, 1, 2}));
  EXPECT_EQ(find_issue(report, "intersect"), nullptr) << report.text();
  EXPECT_FALSE(report.closed);
  EXPECT_TRUE(report.simulable());
}

TEST(MeshRepair, NonFiniteCoordinatesAndNothingLeftAreFatal) {
  TriangleMesh poisoned = cube();
  poisoned.vertices[7][1] = std::numeric_limits<double>::quiet_NaN();
  const MeshReport report = check_and_repair(poisoned, 0);
  EXPECT_FALSE(report.simulable());
  ASSERT_NE(find_issue(report, "non-finite"), nullptr) << report.text();
  EXPECT_EQ(find_issue(report, "non-finite")->count, 1);
  EXPECT_EQ(find_issue(report, "non-finite")->triangles.size(), 6u);  // vertex 7 is in 6 triangles
  EXPECT_NE(report.text().find("NOT SIMULABLE"), std::string::npos);
  // Only degenerate triangles: nothing left.
  TriangleMesh needles{{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 1, 2}, {0, 0, 1}}, "needles"};
  const MeshReport empty = check_and_repair(needles, 0);
  EXPECT_FALSE(empty.simulable());
  EXPECT_NE(find_issue(empty, "no triangles left"), nullptr) << empty.text();
  EXPECT_TRUE(needles.triangles.empty());
  EXPECT_TRUE(needles.vertices.empty());
}

TEST(MeshRepair, TriangleSizeAgainstParticleDiameter) {
  // Unit cube: longest edges 1 and 1.41 m.
  TriangleMesh mesh = cube();
  const MeshReport small_particles = check_and_repair(mesh, 0.01);  // 50 d = 0.5 m: all coarse
  ASSERT_NE(find_issue(small_particles, "coarse"), nullptr) << small_particles.text();
  EXPECT_EQ(find_issue(small_particles, "coarse")->count, 12);
  EXPECT_EQ(find_issue(small_particles, "coarse")->severity, Severity::info);
  const MeshReport big_particles = check_and_repair(mesh, 100);  // d/50 = 2 m: all fine
  ASSERT_NE(find_issue(big_particles, "smaller than"), nullptr) << big_particles.text();
  EXPECT_EQ(find_issue(big_particles, "smaller than")->count, 12);
  EXPECT_TRUE(check_and_repair(mesh, 0.05).issues.empty());  // 2.5 m and 1 mm: neither
}

TEST_F(MeshFiles, ErrorsNameTheFileAndWhatWouldWork) {
  const auto message = [](const std::string& file, MeshError::Kind kind) {
    try {
      import_mesh(file, {});
    } catch (const MeshError& error) {
      EXPECT_EQ(error.kind(), kind) << error.what();
      return std::string(error.what());
    }
    ADD_FAILURE() << file << " was imported";
    return std::string();
  };
  // STEP and IGES: refused by name, with the formats to export instead.
  std::ofstream(path("bracket.STEP")) << "ISO-10303-21;\nHEADER;\nENDSEC;\n";
  const std::string step = message(path("bracket.STEP"), MeshError::Kind::cad_format);
  EXPECT_NE(step.find(path("bracket.STEP")), std::string::npos) << step;
  EXPECT_NE(step.find("STL, OBJ, PLY, 3MF or glTF"), std::string::npos) << step;
  EXPECT_NE(message(path("liner.igs"), MeshError::Kind::cad_format).find("export"), std::string::npos);
  // A missing file.
  const std::string missing = message(path("no_such_chute.stl"), MeshError::Kind::missing);
  EXPECT_NE(missing.find(path("no_such_chute.stl")), std::string::npos) << missing;
  // Lines only (OBJ) and points only (PLY): no surface.
  std::ofstream(path("lines.obj")) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2 3\n";
  EXPECT_NE(message(path("lines.obj"), MeshError::Kind::no_triangles).find("no triangles"), std::string::npos);
  std::ofstream(path("points.ply")) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                       "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  message(path("points.ply"), MeshError::Kind::no_triangles);
  // Garbage with a mesh extension: refused, not crashed on.
  std::ofstream(path("junk.stl"), std::ios::binary) << std::string("\x01\x02 this is not a mesh \xff\xfe");
  const std::string junk = message(path("junk.stl"), MeshError::Kind::unreadable);
  EXPECT_NE(junk.find("junk.stl"), std::string::npos) << junk;
  // Headers that declare more elements than the file has bytes (assimp would try to allocate them all).
  std::ofstream(path("huge.off")) << "OFF\n353535235358 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_NE(message(path("huge.off"), MeshError::Kind::unreadable).find("declares 353535235358"), std::string::npos);
  std::ofstream(path("huge.ply")) << "ply\nformat ascii 1.0\nelement vertex 1347917086\nproperty float x\n"
                                     "property float y\nproperty float z\nend_header\n0 0 0\n";
  message(path("huge.ply"), MeshError::Kind::unreadable);
  std::ofstream(path("notes.txt")) << "not a mesh";
  message(path("notes.txt"), MeshError::Kind::unreadable);
}

TEST_F(MeshFiles, CheckMeshCommandPrintsReportsAndFailsOnErrors) {
  write_binary_stl(path("cube.stl"), cube());
  std::ostringstream good;
  EXPECT_EQ(check_mesh_command({path("cube.stl")}, {}, 0.01, good), 0);
  EXPECT_NE(good.str().find("simulable, 12 triangles (12 in), 8 vertices, closed"), std::string::npos) << good.str();
  EXPECT_NE(good.str().find("area 6 m^2"), std::string::npos) << good.str();
  EXPECT_NE(good.str().find("info: 12 triangles with an edge longer than 50"), std::string::npos) << good.str();
  std::ostringstream mixed;
  EXPECT_EQ(check_mesh_command({path("cube.stl"), path("gone.stl")}, {}, 0, mixed), 1);
  EXPECT_NE(mixed.str().find("error: " + path("gone.stl")), std::string::npos) << mixed.str();
  EXPECT_NE(mixed.str().find("1 of 2 meshes simulable"), std::string::npos) << mixed.str();
}

}  // namespace

/// With DEMDESIGN_SANITIZE: assimp 5.2 leaks some of what it allocated for files it rejects
/// (Assimp::BaseImporter::ReadFile); those leaks are assimp's, not ours. Unused otherwise.
extern "C" const char* __lsan_default_suppressions() {
  return "leak:libassimp.so\n";
}

namespace {

/// Debian's assimp-testmodels, or ASSIMP_TESTMODELS_DIR; empty when neither exists.
fs::path testmodels_directory() {
  if (const char* override_dir = std::getenv("ASSIMP_TESTMODELS_DIR")) return override_dir;
  for (const char* candidate : {"/usr/share/assimp/models", "/usr/share/assimp-testmodels"})
    if (fs::is_directory(candidate)) return candidate;
  return {};
}

TEST(AssimpTestModels, EveryModelWithTrianglesImportsAndGivesAReport) {
  const fs::path root = testmodels_directory();
  if (root.empty()) GTEST_SKIP() << "assimp-testmodels not installed (apt-get install assimp-testmodels)";
  constexpr std::uintmax_t kLargestFile = 20u << 20;  // [bytes] bigger files are skipped to keep the test short
  int imported = 0, rejected = 0, no_triangles = 0, too_large = 0, closed = 0, with_warnings = 0, not_simulable = 0;
  double slowest = 0;  // [s]
  std::string slowest_file;
  std::size_t triangles = 0;
  const auto start = std::chrono::steady_clock::now();
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    if (entry.is_regular_file() && has_importable_extension(entry.path().string())) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) {
    if (fs::file_size(file) > kLargestFile) {
      ++too_large;
      continue;
    }
    const auto file_start = std::chrono::steady_clock::now();
    try {
      TriangleMesh mesh = import_mesh(file.string(), {});
      const MeshReport report = check_and_repair(mesh, 0);
      EXPECT_GT(report.triangles_in, 0u) << file;
      EXPECT_FALSE(report.text().empty()) << file;
      // Whatever the file, the repaired mesh's indices are valid.
      for (const auto& triangle : mesh.triangles)
        for (std::int32_t v : triangle) ASSERT_TRUE(v >= 0 && std::size_t(v) < mesh.vertices.size()) << file;
      triangles += report.triangles_out;
      ++imported;
      closed += report.closed;
      not_simulable += !report.simulable();
      with_warnings += std::any_of(report.issues.begin(), report.issues.end(),
                                   [](const MeshIssue& issue) { return issue.severity == Severity::warning; });
    } catch (const MeshError& error) {
      (error.kind() == MeshError::Kind::no_triangles ? no_triangles : rejected) += 1;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - file_start).count();
    if (seconds > slowest) {
      slowest = seconds;
      slowest_file = file.string();
    }
  }
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "assimp-testmodels in %s: %zu files with importable extensions: %d imported (%zu triangles), "
      "%d rejected by assimp, %d without triangles, %d over 20 MB; of the imported: %d closed, %d with warnings, "
      "%d not simulable; %.1f s, slowest %.2f s (%s)\n",
      root.c_str(), files.size(), imported, triangles, rejected, no_triangles, too_large, closed, with_warnings,
      not_simulable, total, slowest, slowest_file.c_str());
  EXPECT_GE(imported, 50);
}

// The PLY header check that keeps assimp from hanging on damaged headers must still pass real
// exporters' files: Blender 2.4x's free-text line before the elements, binary and ASCII cubes.
TEST(AssimpTestModels, ValidPlyHeadersPassTheHeaderCheck) {
  const fs::path root = testmodels_directory();
  if (root.empty()) GTEST_SKIP() << "assimp-testmodels not installed (apt-get install assimp-testmodels)";
  for (const char* name : {"PLY/Wuson.ply", "PLY/cube.ply", "PLY/cube_binary.ply", "PLY/cube_uv.ply", "PLY/float-color.ply"}) {
    const fs::path file = root / name;
    if (!fs::exists(file)) continue;
    TriangleMesh mesh;
    EXPECT_NO_THROW(mesh = import_mesh(file.string(), {})) << file;
    EXPECT_GT(mesh.triangles.size(), 0u) << file;
  }
}

}  // namespace
