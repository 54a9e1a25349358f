// Bad input, one test per class of the README's "Bad input" table, and the inputs the fuzzers
// (tests/fuzz) found crashing, replayed through the same readers: each must give an error that
// names file, line and key (or mesh and triangle) and what is valid; none may crash or hang.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <iostream>
#include <limits>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bad_input.h"
#include "case/spec.h"
#include "triangle_mesh.h"

namespace {

namespace fs = std::filesystem;
using dem::fuzz::import_mesh_bytes;
using dem::fuzz::read_case_text;
using dem::fuzz::read_measurement_text;

/// A small valid case; each test breaks one thing in it.
std::string good_case(const std::string& particles = "{material: glass, diameter: 0.01, count: 10, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}",
                      const std::string& extra = "") {
  return "simulation: {duration: 0.01}\n"
         "materials:\n  glass: {density: 2500, youngs_modulus: 5.0e7, restitution: 0.9, friction: 0.3}\n"
         "walls:\n  - {name: floor, material: glass, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\n"
         "particles:\n  - " + particles + "\n" + extra;
}

#define EXPECT_ERROR(result, ...)                                              \
  do {                                                                          \
    const std::string message_ = (result);                                      \
    EXPECT_FALSE(message_.empty()) << "accepted, expected an error";            \
    for (const char* part : std::initializer_list<const char*>{__VA_ARGS__}) EXPECT_NE(message_.find(part), std::string::npos) << "'" << part << "' not in: " << message_; \
  } while (0)

TEST(BadInput, TheGoodCaseIsAccepted) { EXPECT_EQ(read_case_text(good_case()), ""); }

TEST(BadInput, BrokenYamlNamesLineAndColumn) {
  EXPECT_ERROR(read_case_text("simulation: {duration: 1\nmaterials: ["), "fuzz.yaml:", "not valid YAML");
  EXPECT_ERROR(read_case_text(""), "fuzz.yaml", "must be a map");
  EXPECT_ERROR(read_case_text("- just\n- a list\n"), "must be a map");
  // Deep nesting: refused, not a stack overflow.
  EXPECT_ERROR(read_case_text("simulation: " + std::string(20000, '[')), "fuzz.yaml");
}

TEST(BadInput, UnknownKeySuggestsTheNearest) {
  EXPECT_ERROR(read_case_text(good_case() + "simulaton: {}\n"), "fuzz.yaml:", "simulaton: unknown key", "simulation");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diametr: 0.01, count: 10, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "particles[0]", "diameter");
  // Each valid key once, although a material's properties are read and also listed as valid.
  std::string glassy = good_case();
  glassy.replace(glassy.find("friction: 0.3}"), 14, "friction: 0.3, frictoin: 0.2}");
  const std::string message = read_case_text(glassy);
  EXPECT_ERROR(message, "frictoin: unknown key", "friction");
  for (const char* key : {"density, density", "friction, friction", "youngs_modulus, youngs_modulus"})
    EXPECT_EQ(message.find(key), std::string::npos) << key << " in: " << message;
}

TEST(BadInput, WrongTypeSaysWhatIsValid) {
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: ten, count: 10, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "fuzz.yaml:7:", "particles[0].diameter", "'ten' is not a number");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, count: [1, 2], region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "particles[0].count", "must be a number");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, count: 10, region: {min: [0, 0], max: [0.1, 0.1, 0.1]}}")),
               "region.min", "three numbers");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, count: 2.5, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "particles[0].count", "whole number");
}

TEST(BadInput, OutOfRangeGivesTheRange) {
  EXPECT_ERROR(read_case_text("simulation: {duration: -1}\n" + good_case().substr(good_case().find("materials"))),
               "simulation.duration", "out of range; valid: [0, 1e+06] s");
  std::string c = good_case();
  c.replace(c.find("density: 2500"), 13, "density: -5");
  EXPECT_ERROR(read_case_text(c), "materials.glass.density", "out of range");
}

TEST(BadInput, MissingKeyOrFile) {
  EXPECT_ERROR(read_case_text("materials: {}\n"), "simulation", "missing");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "particles[0].count", "missing");
  try {
    dem::parse_case_file("/nonexistent/case.yaml");
    ADD_FAILURE() << "no error";
  } catch (const dem::CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/case.yaml: cannot open"), std::string::npos);
  }
  try {
    dem::geometry::import_mesh("/nonexistent/part.stl");
    ADD_FAILURE() << "no error";
  } catch (const dem::geometry::MeshError& e) {
    EXPECT_EQ(e.kind(), dem::geometry::MeshError::Kind::missing);
    EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos);
  }
  EXPECT_ERROR(read_case_text(good_case("{material: glas, diameter: 0.01, count: 10, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "unknown material 'glas'", "glass");
  EXPECT_ERROR(read_case_text("simulation: {duration: 1}\nmaterials:\n  g: {library: no_such_material}\nparticles: []\n"),
               "materials.g.library", "no material file 'no_such_material.yaml'");
}

TEST(BadInput, NanAndInfinityAreRefused) {
  EXPECT_ERROR(read_case_text("simulation: {duration: .nan}\n" + good_case().substr(good_case().find("materials"))),
               "simulation.duration", "is not a number");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, positions: [[0, 0, nan]]}")), "particles[0].positions",
               "not a number");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, positions: [[0, 0, .inf]]}")), "particles[0].positions",
               "finite");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: {distribution: discrete, values: [.inf], mass_fractions: [1]}, "
                                        "count: 1, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "diameter.values");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, count: 10, region: {min: [0, 0, 0], max: [0.1, .inf, 0.1]}}")),
               "region.max", "finite");
}

TEST(BadInput, NegativeOrZeroSizes) {
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: -0.01, count: 10, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "particles[0].diameter", "valid: (0, 10] m");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, count: 10, region: {min: [0, 0, 0], max: [0.1, -0.1, 0.1]}}")),
               "region.max", "must exceed min");
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, count: -3, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "particles[0].count", "out of range");
}

TEST(BadInput, HugeCountsAreRefusedBeforeAllocating) {
  // A count that would need tens of GB: refused by the limit, at once.
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.001, count: 90000000, region: {min: [0, 0, 0], max: [100, 100, 100]}}")),
               "particles[0].count", "exceeds the limit of 20000000");
  // A count that cannot fit its region: refused before any diameter is drawn.
  EXPECT_ERROR(read_case_text(good_case("{material: glass, diameter: 0.01, count: 1000000, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}")),
               "particles[0].count", "Enlarge `region` or lower `count`");
}

TEST(BadInput, OutputFolderStaysInsideTheWorkingDirectory) {
  EXPECT_ERROR(read_case_text(good_case() + "output: {directory: ../../etc}\n"), "output.directory", "no absolute path, no `..`");
  EXPECT_ERROR(read_case_text(good_case() + "output: {directory: /tmp/x}\n"), "output.directory");
  EXPECT_ERROR(read_case_text(good_case() + "output: {directory: out/../..}\n"), "output.directory");
  EXPECT_EQ(read_case_text(good_case() + "output: {directory: out/my_case}\n"), "");
}

TEST(BadInput, InlineMeshProblemsNameTheKey) {
  const std::string mesh = "meshes:\n  - {name: m, material: glass, vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles: [[0, 1, 3]]}\n";
  EXPECT_ERROR(read_case_text(good_case() + mesh), "meshes[0].triangles", "vertex index 3 is not one of the 3 vertices");
  const std::string nan_mesh = "meshes:\n  - {name: m, material: glass, vertices: [[0, 0, 0], [1, .nan, 0], [0, 1, 0]], triangles: [[0, 1, 2]]}\n";
  EXPECT_ERROR(read_case_text(good_case() + nan_mesh), "meshes[0].vertices");
  const std::string file_mesh = "meshes:\n  - {name: m, material: glass, file: part.stl}\n";
  EXPECT_ERROR(read_case_text(good_case() + file_mesh), "mesh 'm'");
}

std::string ascii_stl(const std::string& facets) { return "solid s\n" + facets + "endsolid s\n"; }
std::string facet(const std::string& a, const std::string& b, const std::string& c) {
  return " facet normal 0 0 1\n  outer loop\n   vertex " + a + "\n   vertex " + b + "\n   vertex " + c + "\n  endloop\n endfacet\n";
}

TEST(BadInput, MeshFilesAreRefusedWithTheReason) {
  // NaN vertices (binary STL: text STL readers parse "nan" as 0): fatal, with the triangles named.
  {
    std::string stl(80, ' ');
    const std::uint32_t count = 2;
    stl.append(reinterpret_cast<const char*>(&count), 4);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float tris[2][12] = {{0, 0, 1, 0, 0, 0, 1, 0, 0, 0, nan, 0}, {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1}};
    for (const auto& t : tris) {
      stl.append(reinterpret_cast<const char*>(t), sizeof t);
      stl.append(2, '\0');
    }
    EXPECT_ERROR(import_mesh_bytes(stl, ".stl"), "non-finite coordinates", "triangles 0 ");
  }
  // Empty mesh.
  EXPECT_ERROR(import_mesh_bytes(ascii_stl(""), ".stl"), "input.stl");
  EXPECT_ERROR(import_mesh_bytes("", ".obj"), "input.obj");
  // Non-triangle faces: polygons are triangulated (accepted), lines and points alone are refused.
  EXPECT_EQ(import_mesh_bytes("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", ".obj"), "");
  EXPECT_ERROR(import_mesh_bytes("v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2\nl 2 3\n", ".obj"), "no triangles");
  // A PLY header that declares more elements than the file has bytes (assimp would allocate them).
  EXPECT_ERROR(import_mesh_bytes("ply\nformat ascii 1.0\nelement vertex 99999999999\nproperty float x\nend_header\n", ".ply"),
               "declares 99999999999 elements");
  // Garbage.
  EXPECT_FALSE(import_mesh_bytes(std::string(300, '\x7f'), ".stl").empty());
  // Only degenerate triangles: nothing left to simulate.
  EXPECT_ERROR(import_mesh_bytes(ascii_stl(facet("0 0 0", "0 0 0", "0 0 0")), ".stl"));
  // A valid tetrahedron with a duplicated face is repaired, not refused.
  const std::string tetra = facet("0 0 0", "0 1 0", "1 0 0") + facet("0 0 0", "1 0 0", "0 0 1") + facet("0 0 0", "0 0 1", "0 1 0") +
                            facet("1 0 0", "0 1 0", "0 0 1");
  EXPECT_EQ(import_mesh_bytes(ascii_stl(tetra + facet("1 0 0", "0 1 0", "0 0 1")), ".stl"), "");
  // STEP: told what to export instead.
  EXPECT_ERROR(import_mesh_bytes("ISO-10303-21;\n", ".step"), "STEP/IGES");
}

TEST(BadInput, MeasurementFiles) {
  EXPECT_ERROR(read_measurement_text("experiments: ["), "fuzz_measurements.yaml:", "not valid YAML");
  EXPECT_ERROR(read_measurement_text("material: x\n"), "experiments", "missing");
  EXPECT_ERROR(read_measurement_text("experiments:\n  - {id: a, test: drop_rebond, setup: {}, observed: {}}\n"), "experiments[0].test",
               "drop_rebound");
  EXPECT_ERROR(read_measurement_text("experiments:\n  - {id: a, test: drop_rebound, setup: {height: .nan}, observed: {}}\n"),
               "experiments[0].setup.height", "finite");
  EXPECT_ERROR(read_measurement_text("walls: {steel: {youngs_modulus: -1}}\nexperiments: []\n"), "walls.steel.youngs_modulus",
               "out of range");
}

// ---- the table: one bad input a row, the reader it goes through, what the message must say ----

enum class Reader { case_text, measurements, stl, obj, ply, step };

struct BadInputRow {
  const char* what;
  Reader reader;
  std::string input;
  std::vector<std::string> says;
};

std::string measurement_file(const std::string& experiments, const std::string& head = "") {
  return head + "walls:\n  steel: {youngs_modulus: 2.0e11, poisson_ratio: 0.3, density: 7800}\nexperiments:\n" + experiments;
}

std::string binary_stl(std::uint32_t declared, std::uint32_t written) {
  std::string stl(80, ' ');
  stl.append(reinterpret_cast<const char*>(&declared), 4);
  const float tri[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  for (std::uint32_t k = 0; k < written; ++k) stl.append(reinterpret_cast<const char*>(tri), sizeof tri).append(2, '\0');
  return stl;
}

std::vector<BadInputRow> bad_inputs() {
  const std::string p = "{material: glass, diameter: 0.01, count: 10, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}";
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string c = good_case();
    c.replace(c.find(from), from.size(), to);
    return c;
  };
  const std::string drop = "  - {id: drop, test: drop_rebound, setup: {drop_height: 0.1, plate: steel}, observed: {restitution: {value: 0.5, sigma: 0.02}}}\n";
  const std::string silo = "  - {id: silo, test: hopper_discharge, setup: {silo_diameter: 0.12, orifice_diameter: 0.03, fill_height: 0.1, wall: steel}, "
                           "observed: {mass_flow_rate: {value: 0.2, sigma: 0.01}}}\n";
  const std::string drum = "  - {id: drum, test: rotating_drum, setup: {drum_diameter: 0.16, drum_depth: 0.03, fill_fraction: 0.35, rpm: 10, wall: steel}, "
                           "observed: {dynamic_angle_deg: {value: 35, sigma: 1}}}\n";
  const std::string tetra = facet("0 0 0", "0 1 0", "1 0 0") + facet("0 0 0", "1 0 0", "0 0 1") + facet("0 0 0", "0 0 1", "0 1 0") +
                            facet("1 0 0", "0 1 0", "0 0 1");
  const auto replaced = [](std::string text, const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  return {
      // Case files.
      {"broken YAML", Reader::case_text, "simulation: {duration: 1\nmaterials: [", {"fuzz.yaml:", "not valid YAML"}},
      {"an empty file", Reader::case_text, "", {"must be a map"}},
      {"a misspelt top-level key", Reader::case_text, good_case() + "simulaton: {}\n", {"simulaton: unknown key", "simulation"}},
      {"a misspelt particle key", Reader::case_text, good_case("{material: glass, diametr: 0.01, count: 10, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}"),
       {"particles[0]", "diameter"}},
      {"a word for a number", Reader::case_text, with("diameter: 0.01", "diameter: ten"), {"fuzz.yaml:7:", "'ten' is not a number"}},
      {"a fraction for a count", Reader::case_text, with("count: 10", "count: 2.5"), {"particles[0].count", "whole number"}},
      {"a negative duration", Reader::case_text, with("duration: 0.01", "duration: -1"), {"simulation.duration", "out of range; valid: [0, 1e+06] s"}},
      {"a negative density", Reader::case_text, with("density: 2500", "density: -5"), {"materials.glass.density", "out of range"}},
      {"a missing count", Reader::case_text, with("count: 10, ", ""), {"particles[0].count", "missing"}},
      {"an unknown material", Reader::case_text, with("material: glass, diameter", "material: glas, diameter"), {"unknown material 'glas'", "glass"}},
      {"a library material that does not exist", Reader::case_text,
       "simulation: {duration: 1}\nmaterials:\n  g: {library: no_such_material}\nparticles: []\n", {"materials.g.library", "no material file"}},
      {"NaN for a duration", Reader::case_text, with("duration: 0.01", "duration: .nan"), {"simulation.duration", "is not a number"}},
      {"an infinite position", Reader::case_text, good_case("{material: glass, diameter: 0.01, positions: [[0, 0, .inf]]}"), {"particles[0].positions", "finite"}},
      {"a region inside out", Reader::case_text, with("max: [0.1, 0.1, 0.1]", "max: [0.1, -0.1, 0.1]"), {"region.max", "must exceed min"}},
      {"a negative diameter", Reader::case_text, with("diameter: 0.01", "diameter: -0.01"), {"particles[0].diameter", "valid: (0, 10] m"}},
      {"ninety million particles", Reader::case_text,
       good_case("{material: glass, diameter: 0.001, count: 90000000, region: {min: [0, 0, 0], max: [100, 100, 100]}}"), {"exceeds the limit of 20000000"}},
      {"more particles than the region holds", Reader::case_text, with("count: 10", "count: 1000000"), {"Enlarge `region` or lower `count`"}},
      {"an output folder outside the working directory", Reader::case_text, good_case() + "output: {directory: ../../etc}\n", {"output.directory", "no `..`"}},
      {"an inline mesh with a vertex index past its vertices", Reader::case_text,
       good_case() + "meshes:\n  - {name: m, material: glass, vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles: [[0, 1, 3]]}\n",
       {"meshes[0].triangles", "vertex index 3"}},
      {"a key given twice", Reader::case_text, with("{duration: 0.01}", "{duration: 0.01, duration: 5}"),
       {"fuzz.yaml:1:", "simulation.duration: given twice in one map (first at line 1)"}},
      {"a section given twice", Reader::case_text, good_case() + "simulation: {duration: 5}\n", {"simulation: given twice", "first at line 1"}},
      {"a material name given twice", Reader::case_text,
       with("materials:\n", "materials:\n  glass: {density: 1000, youngs_modulus: 5.0e7, restitution: 0.9, friction: 0.3}\n"),
       {"materials.glass: given twice", "first at line 3"}},
      {"a wall name given twice", Reader::case_text,
       good_case() + "meshes:\n  - {name: floor, material: glass, vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles: [[0, 1, 2]]}\n",
       {"wall name 'floor' given twice (first at line 5)"}},
      {"an inlet name given twice", Reader::case_text,
       good_case() + "inlets:\n  - {name: feed, material: glass, diameter: 0.01, count: 5, region: {min: [0, 0, 0.2], max: [0.1, 0.1, 0.3]}}\n"
                     "  - {name: feed, material: glass, diameter: 0.01, count: 5, region: {min: [0, 0, 0.4], max: [0.1, 0.1, 0.5]}}\n",
       {"inlet name 'feed' given twice"}},
      {"an outlet name given twice", Reader::case_text,
       good_case() + "outlets:\n  - {name: bin, region: {min: [0, 0, -1], max: [1, 1, -0.5]}}\n  - {name: bin, region: {min: [2, 0, -1], max: [3, 1, -0.5]}}\n",
       {"outlet name 'bin' given twice"}},
      {"a feed port too small for its rate (a short, slow feed belt at 2000 t/h)", Reader::case_text,
       "simulation: {duration: 0.1}\nmaterials:\n  gravel: {density: 2650, youngs_modulus: 5.0e7, restitution: 0.5, friction: 0.5}\n"
       "  steel: {density: 7800, youngs_modulus: 2.0e11, restitution: 0.5, friction: 0.5}\n"
       "  rubber: {density: 1100, youngs_modulus: 1.0e7, restitution: 0.5, friction: 0.8}\n"
       "equipment:\n  transfer_chute:\n    feed_belt: {length: 1.0, speed: 0.5}\n"
       "inlets:\n  - {name: feed, port: feed_belt, material: gravel, mass_rate_tph: 2000, diameter: {distribution: uniform, min: 0.03, max: 0.05}}\n",
       {"inlets.feed: 2000 t/h needs its region (the port 'feed_belt'", "cannot deliver it", "feed length"}},
      {"a wall of an unknown material", Reader::case_text, replaced(good_case(), "{name: floor, material: glass", "{name: floor, material: stel"),
       {"stel"}},
      // Measurement files.
      {"a measurement file of broken YAML", Reader::measurements, "experiments: [", {"fuzz_measurements.yaml:", "not valid YAML"}},
      {"no experiments", Reader::measurements, "material: x\n", {"experiments", "missing"}},
      {"a misspelt test", Reader::measurements, measurement_file(replaced(drop, "drop_rebound", "drop_rebond")), {"experiments[0].test", "drop_rebound"}},
      {"a misspelt set-up key", Reader::measurements, measurement_file(replaced(drop, "plate: steel", "plate: steel, impact_angel_deg: 30")),
       {"experiment 'drop'", "impact_angel_deg", "did you mean 'impact_angle_deg'"}},
      {"NaN for a drop height", Reader::measurements, measurement_file(replaced(drop, "drop_height: 0.1", "drop_height: .nan")), {"drop_height"}},
      {"a negative Young's modulus of a wall", Reader::measurements, "walls: {steel: {youngs_modulus: -1}}\nexperiments: []\n",
       {"walls.steel.youngs_modulus", "out of range"}},
      {"an orifice wider than its silo", Reader::measurements, measurement_file(replaced(silo, "orifice_diameter: 0.03", "orifice_diameter: 0.2")),
       {"silo", "orifice_diameter"}},
      {"a drum turning backwards", Reader::measurements, measurement_file(replaced(drum, "rpm: 10", "rpm: -20")), {"drum", "rpm"}},
      {"an experiment id given twice", Reader::measurements, measurement_file(drop + drop), {"drop"}},
      {"a key given twice in a measurement file", Reader::measurements, measurement_file(drop, "material: a\nmaterial: b\n"),
       {"material: given twice", "first at line 1"}},
      {"an outcome written as an observable", Reader::measurements,
       measurement_file(replaced(silo, "observed: {mass_flow_rate: {value: 0.2, sigma: 0.01}}", "observed: {outcome: blocked}")), {"outcome"}},
      // Mesh files.
      {"an ASCII STL cut between facets", Reader::stl, "solid s\n" + tetra, {"input.stl", "ends without endsolid"}},
      {"an ASCII STL cut inside a facet", Reader::stl, "solid s\n" + tetra + " facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n",
       {"ends inside the facet of line 30"}},
      {"an ASCII STL facet of two vertices", Reader::stl, ascii_stl(replaced(tetra, "   vertex 1 0 0\n  endloop", "  endloop")), {"has 2 vertices, not 3"}},
      {"a binary STL cut after 3 of 12 facets", Reader::stl, binary_stl(12, 3), {"declares 12 facets", "cut after facet 3"}},
      {"a file shorter than a binary STL header", Reader::stl, "\x01\x02 not a mesh", {"shorter than a binary STL's 84-byte header"}},
      {"a binary STL with a NaN vertex", Reader::stl,
       [] {
         std::string stl = binary_stl(1, 1);
         const float nan = std::numeric_limits<float>::quiet_NaN();
         std::memcpy(stl.data() + 84 + 12, &nan, sizeof nan);
         return stl;
       }(),
       {"non-finite coordinates"}},
      {"an OBJ of lines only", Reader::obj, "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2\nl 2 3\n", {"no triangles"}},
      {"a PLY header declaring more vertices than bytes", Reader::ply,
       "ply\nformat ascii 1.0\nelement vertex 99999999999\nproperty float x\nend_header\n", {"declares 99999999999 elements"}},
      {"a STEP file", Reader::step, "ISO-10303-21;\n", {"STEP/IGES"}},
  };
}

TEST(BadInput, TableOfInputsEachWithItsMessage) {
  const std::vector<BadInputRow> rows = bad_inputs();
  EXPECT_GE(rows.size(), 40u);
  std::printf("| bad input | message (first 160 characters) |\n|---|---|\n");
  for (const BadInputRow& row : rows) {
    SCOPED_TRACE(row.what);
    std::string message;
    switch (row.reader) {
      case Reader::case_text: message = read_case_text(row.input); break;
      case Reader::measurements: message = read_measurement_text(row.input); break;
      case Reader::stl: message = import_mesh_bytes(row.input, ".stl"); break;
      case Reader::obj: message = import_mesh_bytes(row.input, ".obj"); break;
      case Reader::ply: message = import_mesh_bytes(row.input, ".ply"); break;
      case Reader::step: message = import_mesh_bytes(row.input, ".step"); break;
    }
    EXPECT_FALSE(message.empty()) << row.what << ": accepted";
    for (const std::string& part : row.says) EXPECT_NE(message.find(part), std::string::npos) << row.what << ": '" << part << "' not in: " << message;
    std::string shown = message.substr(0, 160);
    for (char& c : shown)
      if (c == '\n' || c == '|') c = ' ';
    std::printf("| %s | %s |\n", row.what, shown.c_str());
  }
}

/// Every saved fuzzer finding, through the reader that crashed on it: an answer, never a crash.
void replay(const std::string& kind, const std::function<std::string(const std::string&, const std::string&)>& read) {
  const fs::path dir = fs::path(DEMDESIGN_SOURCE_DIR) / "tests/fuzz/regressions" / kind;
  if (!fs::exists(dir)) return;
  int count = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file() || entry.path().filename() == "README.md") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    SCOPED_TRACE(entry.path().string());
    const std::string message = read(bytes.str(), entry.path().filename().string());
    // What the user gets is the error message (or a clean accept); print it for the record.
    std::cout << kind << "/" << entry.path().filename().string() << " -> "
              << (message.empty() ? "accepted" : message.substr(0, 200)) << "\n";
    ++count;
  }
  std::cout << count << " saved " << kind << " inputs replayed\n";
}

TEST(FuzzRegressions, CaseReader) {
  replay("case", [](const std::string& bytes, const std::string&) { return read_case_text(bytes); });
}
TEST(FuzzRegressions, MeasurementReader) {
  replay("measurements", [](const std::string& bytes, const std::string&) { return read_measurement_text(bytes); });
}
TEST(FuzzRegressions, MeshImport) {
  replay("mesh", [](const std::string& bytes, const std::string&) {
    if (bytes.empty()) return std::string();
    return import_mesh_bytes(bytes.substr(1), dem::fuzz::extension_of(static_cast<std::uint8_t>(bytes[0])));
  });
}

}  // namespace
