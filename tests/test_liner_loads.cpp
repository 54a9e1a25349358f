// Liner pressure and the loads for a structural model (app/report/liner_loads.h): a bed of beads
// at rest on a meshed plate against its weight, the force kept in the frame of a mesh that was
// swung into place, the VTK and CalculiX / Abaqus files of two triangles against hand numbers,
// each liner's own pressure map seen face on (app/pages/flow_images.h, checked by pixel coverage
// bands, never byte for byte), the section, gallery, map field and metrics of the run report, and
// the force impulses through a checkpoint.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "output/checkpoint.h"
#include "pages/flow_images.h"
#include "pages/viewer3d.h"
#include "render/render.h"
#include "report/liner_loads.h"
#include "report/report.h"
#include "sim.h"

// For sanitizer builds (DEMDESIGN_SANITIZE): Mesa keeps a few hundred bytes until the process
// ends, which LeakSanitizer would report as ours (as in test_render.cpp).
extern "C" const char* __lsan_default_suppressions() { return "leak:libOSMesa.so\n"; }

namespace dem::test {
namespace {

namespace fs = std::filesystem;

constexpr double kG = 9.81;  // [m/s^2]

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// ---- reading the written files --------------------------------------------------------------

/// What a .inp fragment holds: its comment lines, nodes, elements and the two load blocks.
struct InpFile {
  std::string comments;
  std::map<int, std::array<double, 3>> nodes;           // [m]
  std::map<int, std::array<int, 3>> elements;           // node ids
  std::map<int, std::array<double, 3>> nodal_force;     // [N] *CLOAD per node and direction
  std::map<int, double> pressure;                       // [Pa] *DLOAD P per element
  std::string element_line;                             // the *ELEMENT keyword line
};

std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  std::string cell;
  while (std::getline(s, cell, ',')) out.push_back(cell);
  return out;
}

/// Reads a .inp fragment block by block (a keyword line starts a block, `**` is a comment).
InpFile parse_inp(const std::string& text) {
  InpFile inp;
  std::stringstream in(text);
  std::string line, block;
  while (std::getline(in, line)) {
    if (line.rfind("**", 0) == 0) {
      inp.comments += line + "\n";
      continue;
    }
    if (!line.empty() && line[0] == '*') {
      block = line.substr(0, line.find(','));
      if (block == "*ELEMENT") inp.element_line = line;
      continue;
    }
    const std::vector<std::string> c = cells(line);
    if (block == "*NODE" && c.size() == 4) inp.nodes[std::stoi(c[0])] = {std::stod(c[1]), std::stod(c[2]), std::stod(c[3])};
    else if (block == "*ELEMENT" && c.size() == 4) inp.elements[std::stoi(c[0])] = {std::stoi(c[1]), std::stoi(c[2]), std::stoi(c[3])};
    else if (block == "*CLOAD" && c.size() == 3) inp.nodal_force[std::stoi(c[0])][std::stoi(c[1]) - 1] += std::stod(c[2]);
    else if (block == "*DLOAD" && c.size() == 3 && c[1].find('P') != std::string::npos) inp.pressure[std::stoi(c[0])] = std::stod(c[2]);
    else ADD_FAILURE() << "unexpected line in block " << block << ": " << line;
  }
  return inp;
}

/// The `count` numbers after the line of `text` that starts with `header` (and its LOOKUP_TABLE line).
std::vector<double> numbers_after(const std::string& text, const std::string& header, std::size_t count) {
  std::size_t at = text.find("\n" + header);
  if (at == std::string::npos) {
    ADD_FAILURE() << "no line " << header;
    return std::vector<double>(count, std::nan(""));
  }
  at = text.find('\n', at + 1) + 1;
  if (text.compare(at, 12, "LOOKUP_TABLE") == 0) at = text.find('\n', at) + 1;
  std::stringstream in(text.substr(at));
  std::vector<double> out(count, std::nan(""));
  for (double& v : out) in >> v;
  return out;
}

// ---- a bed at rest on a meshed plate ---------------------------------------------------------

constexpr double kPlate = 0.04;        // [m] side of the square plate and box
constexpr double kRecordsFrom = 0.3;   // [s] the bed has settled
constexpr int kCells = 4;              // the plate: kCells x kCells squares of two triangles

/// 300 frictionless beads settling in a 40 mm square box whose floor is a mesh; recorded from
/// 0.3 s to 0.4 s. Without friction the box's walls carry none of the weight, so the floor
/// carries all of it. `swung`: the plate is given standing in its own frame (x-z plane, normal
/// +y) and swung flat about the x axis, (x, y, z) -> (x, -z, y), in the first 10 ms, before the
/// beads (from 5 mm up) reach it.
CaseSpec bed_case(bool swung) {
  std::string vertices, triangles;
  for (int j = 0; j <= kCells; ++j)
    for (int i = 0; i <= kCells; ++i) {
      const double x = kPlate * i / kCells, along = kPlate * j / kCells;
      vertices += fmt::format("{}[{}, {}, {}]", vertices.empty() ? "" : ", ", x, swung ? 0.0 : along, swung ? -along : 0.0);
    }
  for (int j = 0; j < kCells; ++j)
    for (int i = 0; i < kCells; ++i) {
      const int a = j * (kCells + 1) + i, b = a + 1, c = a + kCells + 2, d = a + kCells + 1;
      triangles += fmt::format("{}[{}, {}, {}], [{}, {}, {}]", triangles.empty() ? "" : ", ", a, b, c, a, c, d);
    }
  const std::string motion = swung ? fmt::format(", motion: {{rotation: {{axis: [1, 0, 0], rad_per_s: {:.17g}}}, stop: 0.01}}", std::numbers::pi / 2 / 0.01) : "";
  return parse_case_text(fmt::format(R"(
simulation: {{duration: 0.4, gravity: [0, 0, -9.81], seed: 7}}
materials:
  beads: {{density: 2500, youngs_modulus: 5.0e7, poisson_ratio: 0.25, restitution: 0.3, friction: 0.0}}
  steel: {{density: 7800, youngs_modulus: 2.0e11, poisson_ratio: 0.3, restitution: 0.3, friction: 0.0}}
contact: {{normal: hertz, damping: restitution, tangential: mindlin}}
walls:
  - {{name: x0, plane: {{point: [0, 0, 0], normal: [1, 0, 0]}}, material: steel}}
  - {{name: x1, plane: {{point: [{0}, 0, 0], normal: [-1, 0, 0]}}, material: steel}}
  - {{name: y0, plane: {{point: [0, 0, 0], normal: [0, 1, 0]}}, material: steel}}
  - {{name: y1, plane: {{point: [0, {0}, 0], normal: [0, -1, 0]}}, material: steel}}
meshes:
  - {{name: plate, material: steel, vertices: [{1}], triangles: [{2}]{3}}}
particles:
  - material: beads
    diameter: {{distribution: normal, mean: 0.004, std: 0.0003, min: 0.0035, max: 0.0045}}
    count: 300
    region: {{min: [0, 0, 0.005], max: [{0}, {0}, 0.05]}}
output: {{records_from: {4}}}
)",
                                     kPlate, vertices, triangles, motion, kRecordsFrom),
                         "bed_on_plate.yaml");
}

/// [kg m/s] The beads' vertical momentum.
double vertical_momentum(const State& s) {
  double p = 0;
  for (std::size_t k = 0; k < s.owned(); ++k) p += s.vz[k] / s.inv_mass[k];
  return p;
}

/// The bed of bed_case settled and recorded; its weight [N] and how far its vertical momentum
/// changed over the records' window, as a force [N] (a bed still moving would not rest on the plate).
struct SettledBed {
  explicit SettledBed(bool swung) : sim(bed_case(swung)) {
    while (sim.state.time < kRecordsFrom) sim.advance();
    const double before = vertical_momentum(sim.state);
    while (sim.state.time < sim.model.duration) sim.advance();
    interval = sim.state.time - kRecordsFrom;
    unsteady_force = (vertical_momentum(sim.state) - before) / interval;
    for (std::size_t k = 0; k < sim.state.owned(); ++k) weight += kG / sim.state.inv_mass[k];
  }
  Sim sim;
  double interval = 0, unsteady_force = 0, weight = 0;
};

/// [N] A column of a mesh's records summed over its triangles, over `interval` [s].
double mean_over(const std::vector<double>& column, double interval) {
  double sum = 0;
  for (const double v : column) sum += v;
  return sum / interval;
}

TEST(LinerLoads, BedAtRestOnAPlateLoadsItWithItsWeightInEveryOutput) {
  // Closed form: a bed at rest on the plate, frictionless, pushes it down with its weight m g.
  // Over the window, the particles' force impulse on the triangles / window = (0, 0, -m g); the
  // area-weighted mean pressure = m g / A (the bed covers the plate); the .inp's nodal forces
  // sum to (0, 0, -m g) and its pressures P times each element's area to +m g (positive P
  // pushes against the plate's normal +z). 2 % each.
  const SettledBed bed(false);
  const Model& model = bed.sim.model;
  const double weight = bed.weight, area = kPlate * kPlate;
  ASSERT_EQ(bed.sim.state.owned(), 300u);
  EXPECT_LT(std::abs(bed.unsteady_force), 0.005 * weight) << "the bed must rest over the window";
  const TriangleRecords& r = bed.sim.state.records[0];
  EXPECT_NEAR(mean_over(r.force_impulse_z, bed.interval), -weight, 0.02 * weight);
  EXPECT_NEAR(mean_over(r.force_impulse_x, bed.interval), 0.0, 0.02 * weight);
  EXPECT_NEAR(mean_over(r.force_impulse_y, bed.interval), 0.0, 0.02 * weight);
  const report::LinerLoads loads = report::liner_loads(model, bed.sim.state, kRecordsFrom);
  ASSERT_EQ(loads.meshes.size(), 1u);
  const report::LinerLoad& plate = loads.meshes[0];
  EXPECT_NEAR(plate.area, area, 1e-12);
  EXPECT_NEAR(plate.mean, weight / area, 0.02 * weight / area);
  EXPECT_NEAR(plate.total_force.z(), -weight, 0.02 * weight);
  EXPECT_GE(plate.peak, plate.p95);
  EXPECT_GT(plate.p95, 0.0);

  const fs::path dir = fs::temp_directory_path() / "demdesign_liner_loads_bed";
  fs::remove_all(dir);
  report::write_liner_loads(loads, model, "bed_on_plate.yaml", dir.string());
  const InpFile inp = parse_inp(read(dir / "fea" / "plate.inp"));
  ASSERT_EQ(inp.nodes.size(), model.meshes[0].surface->vertices.size());
  ASSERT_EQ(inp.elements.size(), model.meshes[0].surface->size());
  std::array<double, 3> nodal{0, 0, 0};  // [N]
  for (const auto& [node, force] : inp.nodal_force)
    for (int a = 0; a < 3; ++a) nodal[a] += force[a];
  EXPECT_NEAR(nodal[2], -weight, 0.02 * weight);
  EXPECT_NEAR(nodal[0], 0.0, 0.02 * weight);
  double pressure_force = 0;  // [N] sum of P x area
  for (const auto& [element, p] : inp.pressure) pressure_force += p * model.meshes[0].surface->areas[element - 1];
  EXPECT_NEAR(pressure_force, weight, 0.02 * weight);
  EXPECT_TRUE(fs::exists(dir / "fea" / "plate.vtk"));
  EXPECT_NE(read(dir / "liner_loads.csv").find("\"plate\","), std::string::npos);
  std::printf("bed %.5f N; floor %.5f N (records), mean pressure x area %.5f N, CLOAD %.5f N, DLOAD %.5f N; momentum change %.2e N\n",
              weight, -mean_over(r.force_impulse_z, bed.interval), plate.mean * area, -nodal[2], pressure_force, bed.unsteady_force);
  fs::remove_all(dir);
}

TEST(LinerLoads, ASwungPlateKeepsTheForceInItsOwnFrame) {
  // The plate is given standing (normal +y in its own frame) and swung flat before the beads
  // land: in the world the bed pushes it along -z, in the plate's own frame along -y, which is
  // what the records and the .inp (nodes in the plate's frame) must hold; the .vtk, in the world
  // at the end pose, holds the traction along -z.
  const SettledBed bed(true);
  const double weight = bed.weight;
  EXPECT_LT(std::abs(bed.unsteady_force), 0.005 * weight) << "the bed must rest over the window";
  const TriangleRecords& r = bed.sim.state.records[0];
  EXPECT_NEAR(mean_over(r.force_impulse_y, bed.interval), -weight, 0.02 * weight);
  EXPECT_NEAR(mean_over(r.force_impulse_z, bed.interval), 0.0, 0.02 * weight);
  const report::LinerLoads loads = report::liner_loads(bed.sim.model, bed.sim.state, kRecordsFrom);
  EXPECT_NEAR(loads.meshes[0].mean, weight / (kPlate * kPlate), 0.02 * weight / (kPlate * kPlate));
  const fs::path dir = fs::temp_directory_path() / "demdesign_liner_loads_swung";
  fs::remove_all(dir);
  report::write_liner_loads(loads, bed.sim.model, "bed_on_plate.yaml", dir.string());
  const InpFile inp = parse_inp(read(dir / "fea" / "plate.inp"));
  EXPECT_NEAR(inp.nodes.at(kCells + 2)[2], -kPlate / kCells, 1e-12) << "nodes in the plate's own frame";
  double pressure_force = 0;  // [N]
  for (const auto& [element, p] : inp.pressure) pressure_force += p * bed.sim.model.meshes[0].surface->areas[element - 1];
  EXPECT_NEAR(pressure_force, weight, 0.02 * weight) << "positive P: the bed pushes against the plate's normal";
  const std::string vtk = read(dir / "fea" / "plate.vtk");
  const std::size_t n = bed.sim.model.meshes[0].surface->size();
  const std::vector<double> traction = numbers_after(vtk, "VECTORS traction_Pa double", 3 * n);
  double world_z = 0;  // [N] sum of traction z x area
  for (std::size_t t = 0; t < n; ++t) world_z += traction[3 * t + 2] * bed.sim.model.meshes[0].surface->areas[t];
  EXPECT_NEAR(world_z, -weight, 0.02 * weight);
  fs::remove_all(dir);
}

// ---- two triangles with hand-set records -------------------------------------------------------

/// A unit square of two triangles (normal +z) named `plate`, and a bead so the case compiles.
const char* kTwoTriangles = R"(
simulation: {duration: 4.0}
materials:
  beads: {density: 2500, youngs_modulus: 5e7, restitution: 0.4, friction: 0.5}
  steel: {density: 7800, youngs_modulus: 2e11, restitution: 0.4, friction: 0.4}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
meshes:
  - name: plate
    material: steel
    vertices: [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    triangles: [[0, 1, 2], [0, 2, 3]]
particles:
  - {material: beads, diameter: 0.01, positions: [[0.5, 0.5, 0.5]]}
)";

/// The records from t = 1 s to 3 s: triangle 0 (area 0.5 m^2) pushed down with a mean force
/// (50, 0, -1000) N, pressure 2000 Pa, shear 100 Pa; triangle 1 pushed up from below with
/// (0, -25, 500) N, pressure 1000 Pa, shear 50 Pa.
State two_triangle_state(std::vector<double> shear_work = {0, 0}) {
  State state;
  state.time = 3.0;
  TriangleRecords r;
  r.normal_impulse = {2000, 1000};  // [N s] over 2 s
  r.shear_impulse = {100, 50};
  r.shear_work = std::move(shear_work);
  r.impacts = {0, 0};
  r.impact_energy = {0, 0};
  r.force_impulse_x = {100, 0};
  r.force_impulse_y = {0, -50};
  r.force_impulse_z = {-2000, 1000};
  state.records.push_back(r);
  return state;
}

TEST(LinerLoads, VtkAndInpOfTwoTrianglesHoldTheHandNumbers) {
  const Model model = compile(parse_case_text(kTwoTriangles, "two_triangles.yaml"));
  const State state = two_triangle_state();
  const report::LinerLoads loads = report::liner_loads(model, state, 1.0);
  const report::LinerLoad& plate = loads.meshes.at(0);
  // Statistics: mean (2000 x 0.5 + 1000 x 0.5) / 1 Pa; 95 % of the area carries no more than
  // 2000 Pa; the peak on triangle 0, centroid (2/3, 1/3, 0).
  EXPECT_DOUBLE_EQ(plate.area, 1.0);
  EXPECT_DOUBLE_EQ(plate.mean, 1500.0);
  EXPECT_DOUBLE_EQ(plate.p95, 2000.0);
  EXPECT_DOUBLE_EQ(plate.peak, 2000.0);
  EXPECT_EQ(plate.peak_triangle, 0u);
  EXPECT_NEAR((plate.peak_centroid - Eigen::Vector3d(2.0 / 3, 1.0 / 3, 0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((plate.total_force - Eigen::Vector3d(50, -25, -500)).norm(), 0.0, 1e-12);

  // VTK: points, polygons, pressure and shear in kPa, traction = force / area [Pa].
  const std::string vtk = report::liner_vtk(loads, plate, *model.meshes[0].surface, model.meshes[0].motion.pose(state.time));
  EXPECT_EQ(vtk.rfind("# vtk DataFile Version 3.0\n", 0), 0u);
  EXPECT_NE(vtk.find("\nASCII\nDATASET POLYDATA\nPOINTS 4 double\n"), std::string::npos);
  EXPECT_NE(vtk.find("\nPOLYGONS 2 8\n3 0 1 2\n3 0 2 3\nCELL_DATA 2\n"), std::string::npos);
  const std::vector<double> points = numbers_after(vtk, "POINTS 4 double", 12), expected_points = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  for (std::size_t k = 0; k < 12; ++k) EXPECT_DOUBLE_EQ(points[k], expected_points[k]) << k;
  const std::vector<double> pressure = numbers_after(vtk, "SCALARS pressure_kPa double 1", 2);
  EXPECT_DOUBLE_EQ(pressure[0], 2.0);
  EXPECT_DOUBLE_EQ(pressure[1], 1.0);
  const std::vector<double> shear = numbers_after(vtk, "SCALARS shear_stress_kPa double 1", 2);
  EXPECT_DOUBLE_EQ(shear[0], 0.1);
  EXPECT_DOUBLE_EQ(shear[1], 0.05);
  const std::vector<double> traction = numbers_after(vtk, "VECTORS traction_Pa double", 6), expected_traction = {100, 0, -2000, 0, -50, 1000};
  for (std::size_t k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(traction[k], expected_traction[k]) << k;

  // INP: nodes and S3 elements from 1; each triangle's force split over its nodes; P = +2000 Pa
  // on element 1 (pushed against its normal), -1000 Pa on element 2 (pushed along it).
  const InpFile inp = parse_inp(report::liner_inp(loads, plate, *model.meshes[0].surface, "two_triangles.yaml"));
  EXPECT_EQ(inp.element_line, "*ELEMENT, TYPE=S3, ELSET=plate");
  ASSERT_EQ(inp.nodes.size(), 4u);
  EXPECT_EQ(inp.nodes.at(3), (std::array<double, 3>{1, 1, 0}));
  EXPECT_EQ(inp.elements.at(1), (std::array<int, 3>{1, 2, 3}));
  EXPECT_EQ(inp.elements.at(2), (std::array<int, 3>{1, 3, 4}));
  const std::map<int, std::array<double, 3>> nodal = {{1, {50.0 / 3, -25.0 / 3, -500.0 / 3}}, {2, {50.0 / 3, 0, -1000.0 / 3}},
                                                      {3, {50.0 / 3, -25.0 / 3, -500.0 / 3}}, {4, {0, -25.0 / 3, 500.0 / 3}}};
  for (const auto& [node, force] : nodal)
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(inp.nodal_force.at(node)[a], force[a], 1e-6) << "node " << node << " direction " << a + 1;
  ASSERT_EQ(inp.pressure.size(), 2u);
  EXPECT_DOUBLE_EQ(inp.pressure.at(1), 2000.0);
  EXPECT_DOUBLE_EQ(inp.pressure.at(2), -1000.0);
  for (const char* says : {"Units: N, m, Pa", "t0 = 1 s to t1 = 3 s", "(case two_triangles.yaml)", "*CLOAD and *DLOAD below are ALTERNATIVES",
                           "Frame: the mesh's own", "CalculiX CrunchiX User's Manual"})
    EXPECT_NE(inp.comments.find(says), std::string::npos) << says << "\n" << inp.comments;

  // Metrics in kPa.
  report::RunMetrics metrics;
  report::add_liner_pressure_metrics(loads, metrics);
  EXPECT_DOUBLE_EQ(metrics.get("liner_pressure_plate_mean_kPa"), 1.5);
  EXPECT_DOUBLE_EQ(metrics.get("liner_pressure_plate_p95_kPa"), 2.0);
  EXPECT_DOUBLE_EQ(metrics.get("liner_pressure_plate_peak_kPa"), 2.0);
}

// ---- each liner's own pressure map ------------------------------------------------------------

TEST(LinerLoads, FaceOnDirectionLooksAtAPlateFromItsLoadedSideAndAlongTheLoadIntoABox) {
  // A unit square in the x-y plane, normal +z by its winding.
  const std::vector<std::array<double, 3>> square{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const std::vector<std::array<std::int32_t, 3>> halves{{0, 1, 2}, {0, 2, 3}};
  const Eigen::Vector3d up(0, 0, 1), down(0, 0, -1);
  // Face on: looking down at it when pushed down (the particles above), up at it when pushed up;
  // without a push, or with one in its plane, from the side its normal points to.
  EXPECT_NEAR((app::face_on_direction(square, halves, 3.0 * down) - down).norm(), 0.0, 1e-12);
  EXPECT_NEAR((app::face_on_direction(square, halves, Eigen::Vector3d(0.5, 0, 2)) - up).norm(), 0.0, 1e-12);
  EXPECT_NEAR((app::face_on_direction(square, halves, Eigen::Vector3d(0, 0, 0)) - down).norm(), 0.0, 1e-12);
  EXPECT_NEAR((app::face_on_direction(square, halves, Eigen::Vector3d(1, 0, 0)) - down).norm(), 0.0, 1e-12);
  // A closed unit box (its faces wound outward) has no face: the camera looks along the push,
  // else along the iso preset's (-1, 1, -1).
  std::vector<std::array<double, 3>> corners;
  for (int i = 0; i < 8; ++i) corners.push_back({i & 1 ? 1.0 : 0.0, i & 2 ? 1.0 : 0.0, i & 4 ? 1.0 : 0.0});
  std::vector<std::array<std::int32_t, 3>> box;
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) box.push_back({q[0], q[1], q[2]}), box.push_back({q[0], q[2], q[3]});
  const Eigen::Vector3d push(0.3, 0, -1);
  EXPECT_NEAR((app::face_on_direction(corners, box, push) - push.normalized()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((app::face_on_direction(corners, box, Eigen::Vector3d(0, 0, 0)) - Eigen::Vector3d(-1, 1, -1).normalized()).norm(), 0.0, 1e-12);
}

/// A known field [kPa] on bed_case's plate, by its columns of squares along x: none recorded on
/// the first (NaN: grey), 0 on the second (blue), 1.5 on the other two (red: the 99th percentile).
std::vector<double> column_field(std::size_t triangles) {
  std::vector<double> field(triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::size_t column = (t / 2) % static_cast<std::size_t>(kCells);  // two triangles a square, rows of kCells
    field[t] = column == 0 ? std::nan("") : column == 1 ? 0.0 : 1.5;
  }
  return field;
}

/// A map's pixels left of its colour bar (the right quarter is left out): those of a clearly
/// red or clearly blue hue (coolwarm's two ends, shaded), and their mean columns [px].
struct MapPixels {
  double red = 0, blue = 0;                // [px]
  double red_column = 0, blue_column = 0;  // [px]
};

MapPixels map_pixels(const render::Image& image) {
  MapPixels m;
  for (int row = 0; row < image.height; ++row)
    for (int column = 0; column < image.width * 3 / 4; ++column) {
      const std::uint8_t* p = image.pixel(column, row);
      if (p[0] > p[1] + 60 && p[0] > p[2] + 60) m.red += 1, m.red_column += column + 0.5;
      else if (p[2] > p[0] + 60 && p[2] > p[1] + 60) m.blue += 1, m.blue_column += column + 0.5;
    }
  if (m.red > 0) m.red_column /= m.red;
  if (m.blue > 0) m.blue_column /= m.blue;
  return m;
}

/// The map of column_field on bed_case's plate in 480 x 300 px, seen face on. Its bounding
/// sphere (radius 40 mm / sqrt 2) spans 85 % of the height: the plate is a square of
/// 0.85 x 300 / sqrt 2 = 180 px, 22.6 % of the image, three of its four columns coloured, 16.9 %.
/// Seen from the iso direction it would cover 0.58 of that (9.8 %), edge on next to nothing: a
/// band of 15 % to 19 % says face on and framed. Seen from above (x to the right) the red columns
/// lie right of the blue one, from below left of it; the unrecorded column is grey.
void expect_face_on(const render::Image& image, bool from_above, const std::string& what) {
  ASSERT_EQ(image.width, 480) << what;
  ASSERT_EQ(image.height, 300) << what;
  const MapPixels m = map_pixels(image);
  const double coloured = (m.red + m.blue) / (480.0 * 300.0);
  EXPECT_GT(coloured, 0.15) << what;
  EXPECT_LT(coloured, 0.19) << what;
  EXPECT_NEAR(m.red / std::max(m.blue, 1.0), 2.0, 0.2) << what << ": two red columns to one blue";
  EXPECT_EQ(m.red_column > m.blue_column, from_above) << what << ": red at " << m.red_column << " px, blue at " << m.blue_column << " px";
  // The middle of the unrecorded column (3/8 of the plate's side from its centre): grey.
  const double pixels_per_metre = 0.85 * 300 / (std::numbers::sqrt2 * kPlate);
  const int column = static_cast<int>(240 + (from_above ? -1 : 1) * 0.375 * kPlate * pixels_per_metre);
  const std::uint8_t* p = image.pixel(column, 150);
  EXPECT_LT(std::abs(p[0] - p[2]) + std::abs(p[1] - p[2]), 16) << what << ": grey at column " << column;
  EXPECT_GT(p[1], 90) << what;
  EXPECT_LT(p[1], 220) << what << ": drawn, not background";
}

TEST(LinerLoads, PressureMapOfOneLinerShowsItFaceOnFromTheParticlesSide) {
  const Model flat = compile(bed_case(false)), swung = compile(bed_case(true));
  const std::vector<double> field = column_field(flat.meshes[0].surface->size());
  const fs::path dir = fs::temp_directory_path() / "demdesign_liner_loads_map";
  fs::remove_all(dir);
  fs::create_directories(dir);
  app::ImageOptions options;
  options.width = 480, options.height = 300;
  const auto map_of = [&](const Model& model, double time, const Eigen::Vector3d& load, const std::string& name) {
    State state;
    state.time = time;
    const std::string png = (dir / name).string();
    app::render_mesh_field(model, state, 0, field, load, "mean pressure [kPa]", options, png);
    return render::read_png(png);
  };
  expect_face_on(map_of(flat, 0.0, Eigen::Vector3d(0, 0, -1), "above.png"), true, "pushed down: seen from above");
  expect_face_on(map_of(flat, 0.0, Eigen::Vector3d(0, 0, 2), "below.png"), false, "pushed up: seen from below");
  // The swung plate stands in its own frame (normal +y) and lies flat from 10 ms on: a push
  // along its own +y is, turned by its pose, one from below in the world (not turned, it would
  // lie in the plate and the camera would look from above).
  expect_face_on(map_of(swung, 0.4, Eigen::Vector3d(0, 1, 0), "swung.png"), false, "swung flat, pushed along its own +y: seen from below");
  fs::remove_all(dir);
}

TEST(LinerLoads, LinerMapsLeaveOutBeltsAndMeshesThatCarryNothing) {
  Model model = compile(parse_case_text(kTwoTriangles, "two_triangles.yaml"));
  const report::LinerLoads loads = report::liner_loads(model, two_triangle_state(), 1.0);
  EXPECT_EQ(report::liner_map_meshes(loads, model, {}), std::vector<std::size_t>{0});
  // The plate as a belt: a map only when the case gives it a liner by name (liners_for's rule).
  model.meshes[0].surface_velocity.kind = SurfaceVelocitySpec::Kind::linear;
  model.meshes[0].surface_velocity.velocity = Vec3(1, 0, 0);
  EXPECT_TRUE(report::liner_map_meshes(loads, model, {}).empty());
  EXPECT_EQ(report::liner_map_meshes(loads, model, {{"plate", report::Liner{}}}), std::vector<std::size_t>{0});
  // No records over the window: nothing carried, no map.
  State unrecorded;
  unrecorded.time = 3.0;
  EXPECT_TRUE(report::liner_map_meshes(report::liner_loads(model, unrecorded, 1.0), model, {{"plate", report::Liner{}}}).empty());
}

TEST(LinerLoads, RunReportHasTheSectionTheFilesTheMetricsAndTheViewFields) {
  // The two triangles' records in a run report, with a liner 20 mm thick wearing at
  // k_s = 1e-12 m^3/J: friction work 30 and 120 J on 0.5 m^2 over 2 s.
  const Model model = compile(parse_case_text(kTwoTriangles, "two_triangles.yaml"));
  const State state = two_triangle_state({30, 120});
  report::RunReportInput input;
  input.model = &model, input.state = &state, input.records_from = 1.0;
  input.case_path = "two_triangles.yaml", input.version = "test";
  for (int i = 0; i <= 300; ++i) {
    Scalars row;
    row.time = 0.01 * i, row.step = 100 * i, row.particles = 1;
    row.kinetic_translation = 1 + 0.1 * std::sin(i);
    row.mesh_force = {500};
    row.mesh_power = {0};
    row.mesh_torque = {0};
    input.scalars.push_back(row);
  }
  report::Liner liner;
  liner.origin = "test", liner.thickness = 0.02, liner.sliding_coefficient = 1e-12;
  input.liners["plate"] = liner;
  const fs::path dir = fs::temp_directory_path() / "demdesign_liner_loads_report";
  fs::remove_all(dir);
  fs::create_directories(dir);
  // The plate's own pressure map, made as the run makes it (app/cli/main.cpp, write_liner_maps).
  const report::LinerLoads loads = report::liner_loads(model, state, 1.0);
  ASSERT_EQ(report::liner_map_meshes(loads, model, input.liners), std::vector<std::size_t>{0});
  app::ImageOptions small;
  small.width = 320, small.height = 240;
  const std::string map = (dir / "pressure_map_plate.png").string();
  app::render_mesh_field(model, state, 0, {2.0, 1.0}, loads.meshes[0].total_force, "mean pressure [kPa]", small, map);
  input.liner_maps.push_back({"plate", map});
  const report::RunMetrics metrics = report::write_run_report(input, dir.string());
  EXPECT_DOUBLE_EQ(metrics.get("liner_pressure_plate_mean_kPa"), 1.5);
  EXPECT_DOUBLE_EQ(report::read_metrics((dir / "metrics.csv").string()).get("liner_pressure_plate_peak_kPa"), 2.0);
  const std::string html = read(dir / "report.html");
  EXPECT_NE(html.find("<h2>Liner pressure</h2>"), std::string::npos);
  EXPECT_NE(html.find("<code>fea/plate.inp</code>"), std::string::npos);
  EXPECT_LT(html.find("<h2>Wear</h2>"), html.find("<h2>Liner pressure</h2>")) << "after the wear and life section";
  // The gallery in the Liner pressure section, under its table: each liner's map, name and peak.
  const std::size_t section = html.find("<h2>Liner pressure</h2>"), gallery = html.find("<h3>Pressure map of each liner</h3>");
  ASSERT_NE(gallery, std::string::npos);
  EXPECT_LT(html.find("</table>", section), gallery);
  EXPECT_LT(gallery, html.find("<h2>", section + 1)) << "before the next section";
  EXPECT_NE(html.find("<div class=\"grid\">\n<figure><img alt=\"plate\" src=\"data:image/png;base64,", gallery), std::string::npos);
  EXPECT_NE(html.find("<figcaption><b>plate</b> &middot; peak 2.000 kPa</figcaption>", gallery), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "fea" / "plate.inp"));
  EXPECT_TRUE(fs::exists(dir / "fea" / "plate.vtk"));
  EXPECT_EQ(read(dir / "liner_loads.csv"), "mesh,area_m2,mean_kPa,p95_kPa,peak_kPa,peak_x_m,peak_y_m,peak_z_m,force_x_N,force_y_N,force_z_N\n"
                                           "\"plate\",1,1.5,2,2,0.666667,0.333333,0,50,-25,-500\n");
  if (fs::exists(viewer3d::kDefaultThreeJs)) {
    // Pressure scaled to the 99th percentile of 1 and 2 kPa (the lower); life reversed.
    EXPECT_NE(html.find("\"pressure\":{\"label\":\"mean pressure\",\"unit\":\"kPa\",\"max\":1,\"peak\":2}"), std::string::npos);
    EXPECT_NE(html.find("\"life\":{\"label\":\"liner life\",\"unit\":\"months\""), std::string::npos);
    EXPECT_NE(html.find(",\"reverse\":true}"), std::string::npos);
    EXPECT_NE(html.find("<option value=\"life\">liner life [months], short is yellow</option>"), std::string::npos);
  }
  fs::remove_all(dir);
}

// ---- checkpoints ------------------------------------------------------------------------------

TEST(LinerLoads, CheckpointCarriesTheForceImpulsesBitwise) {
  // Twenty beads thrown onto the plate of bed_case from just above it, recorded from the start:
  // a run stopped, checkpointed and resumed ends with the records of the run straight through,
  // bitwise.
  CaseSpec spec = bed_case(false);
  spec.particles[0].count = 20;
  spec.particles[0].region_max.z() = 0.012;
  spec.particles[0].velocity = Vec3(0.1, 0, -0.5);
  spec.output.records_from = 0;
  const int steps = 3000;
  Sim straight(spec);
  for (int k = 0; k < steps; ++k) straight.advance();
  Sim first(spec);
  for (int k = 0; k < steps / 2; ++k) first.advance();
  const fs::path dir = fs::temp_directory_path() / "demdesign_liner_loads_checkpoint";
  fs::remove_all(dir);
  save_checkpoint((dir / "checkpoint.bin").string(), first.model, first.state);
  Sim second(spec);
  second.state = load_checkpoint((dir / "checkpoint.bin").string(), second.model);
  EXPECT_EQ(second.state.records[0].force_impulse_z, first.state.records[0].force_impulse_z) << "read back as written";
  second.work = Workspace();
  prepare(second.model, second.state, second.work);
  for (int k = 0; k < steps / 2; ++k) second.advance();
  const TriangleRecords &a = straight.state.records[0], &b = second.state.records[0];
  double pushed = 0;  // [N s]
  for (const double v : a.force_impulse_z) pushed += v;
  EXPECT_LT(pushed, 0.0) << "the beads must have pushed the plate down";
  for (std::size_t c = 0; c < a.columns().size(); ++c) EXPECT_EQ(*a.columns()[c], *b.columns()[c]) << "column " << c;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dem::test
