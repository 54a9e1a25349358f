// Every shipped case reads, expands its equipment, compiles and runs (shortened to a few hundred
// steps; a sweep case runs its base values).
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include "equipment.h"
#include "output/run.h"
#include "sim.h"
#include "triangle_mesh.h"

namespace dem::test {
namespace {

std::vector<std::string> shipped_cases() {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(DEMDESIGN_SOURCE_DIR) + "/cases"))
    if (entry.path().extension() == ".yaml") names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

class ShippedCase : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedCase, RunsShortened) {
  CaseSpec spec = load_case(GetParam());
  equipment::expand_equipment(spec);
  // Mesh files through the geometry library, as the demdesign program reads them.
  const Model model = compile(spec, [](const MeshWallSpec& m) {
    geometry::ImportOptions options;
    options.unit_scale = m.unit_scale;
    for (int a = 0; a < 3; ++a) options.scale[a] = m.scale[a], options.rotate_deg[a] = m.rotate_deg[a], options.translate[a] = m.translate[a];
    geometry::TriangleMesh mesh = geometry::import_mesh(m.file, options);
    return TriangleSoup{std::move(mesh.vertices), std::move(mesh.triangles)};
  });
  State state = initial_state(model);
  Workspace work;
  RunOptions options;
  options.max_steps = 300;
  options.write_files = false;
  options.progress = false;
  std::ostringstream log;
  const RunSummary summary = run(model, state, work, options, log);
  EXPECT_GT(summary.steps, 0);
  EXPECT_GT(state.size(), 0u);
  EXPECT_TRUE(std::isfinite(summary.scalars.back().kinetic_translation)) << log.str();
}

INSTANTIATE_TEST_SUITE_P(Cases, ShippedCase, ::testing::ValuesIn(shipped_cases()),
                         [](const auto& param_info) {
                           std::string name = param_info.param.substr(0, param_info.param.size() - 5);
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

}  // namespace
}  // namespace dem::test
