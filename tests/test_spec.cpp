// Case reading: bad input gets an error naming file, line, key and what would be valid.
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "case/spec.h"
#include "contact/effect.h"
#include "core/model.h"

namespace dem::test {
namespace {

const char* kGood = R"(simulation: {duration: 0.1}
materials:
  glass: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}
particles:
  - {material: glass, diameter: 0.004, positions: [[0, 0, 0.01]]}
)";

/// The message of the CaseError that parsing and compiling `text` throws ("" when none).
std::string error_of(const std::string& text) {
  try {
    compile(parse_case_text(text, "case.yaml"));
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  return text.replace(text.find(from), from.size(), to);
}

TEST(CaseReading, GoodCaseCompiles) { EXPECT_EQ(error_of(kGood), ""); }

TEST(CaseReading, UnknownKeySuggestsTheNearestValidOne) {
  const std::string e = error_of(replace(kGood, "restitution", "restitutoin"));
  EXPECT_NE(e.find("case.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("materials.glass.restitutoin"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'restitution'"), std::string::npos) << e;
}

TEST(CaseReading, OutOfRangeValueNamesTheValidRange) {
  const std::string e = error_of(replace(kGood, "restitution: 0.5", "restitution: 1.5"));
  EXPECT_NE(e.find("case.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  EXPECT_NE(e.find("[0.0001, 1]"), std::string::npos) << e;
}

TEST(CaseReading, WrongTypeIsNamed) {
  const std::string e = error_of(replace(kGood, "duration: 0.1", "duration: long"));
  EXPECT_NE(e.find("case.yaml:1:"), std::string::npos) << e;
  EXPECT_NE(e.find("simulation.duration"), std::string::npos) << e;
  EXPECT_NE(e.find("not a number"), std::string::npos) << e;
}

TEST(CaseReading, UnknownModelListsTheModelsOfThatStage) {
  const std::string e = error_of(std::string(kGood) + "contact: {rolling: cdtt}\n");
  EXPECT_NE(e.find("contact.rolling"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'cdt'"), std::string::npos) << e;
  EXPECT_NE(e.find("epsd"), std::string::npos) << e;
}

TEST(CaseReading, UnknownMaterialIsNamed) {
  const std::string e = error_of(replace(kGood, "material: glass", "material: glas"));
  EXPECT_NE(e.find("unknown material 'glas'"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'glass'"), std::string::npos) << e;
}

TEST(CaseReading, MissingRequiredKeyIsNamed) {
  const std::string e = error_of(replace(kGood, "density: 2500, ", ""));
  EXPECT_NE(e.find("materials.glass.density: missing"), std::string::npos) << e;
}

TEST(CaseReading, BrokenYamlGivesLineAndColumn) {
  const std::string e = error_of("simulation: {duration: 0.1\nmaterials: [");
  EXPECT_NE(e.find("case.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("not valid YAML"), std::string::npos) << e;
}

TEST(CaseReading, BadOptionValueListsTheValidValues) {
  const std::string e = error_of(std::string(kGood) + "contact: {damping: {model: restitution, end_of_contact: never}}\n");
  EXPECT_NE(e.find("end_of_contact"), std::string::npos) << e;
  EXPECT_NE(e.find("tension, clip"), std::string::npos) << e;
}

TEST(CaseReading, AdhesionWrittenForHertzRefusesLinear) {
  const std::string e = error_of(std::string(kGood) + "contact: {normal: linear, adhesion: [jkr]}\n");
  EXPECT_NE(e.find("'jkr' is written for the 'hertz' normal law"), std::string::npos) << e;
}

TEST(CaseReading, ParameterOfASwitchedOffEffectIsNoted) {
  const Model model = compile(parse_case_text(replace(kGood, "restitution: 0.5", "rolling_friction: 0.1"), "case.yaml"));
  ASSERT_EQ(model.notes.size(), 1u);
  EXPECT_NE(model.notes[0].find("rolling_friction"), std::string::npos);
  EXPECT_NE(model.notes[0].find("contact.rolling"), std::string::npos);
}

TEST(CaseReading, MixingRulesAndInteractionOverrides) {
  const std::string text = std::string(kGood) +
                           "interactions:\n  - {materials: [glass, steel], friction: 0.9}\n";
  const std::string with_steel =
      replace(replace(text, "particles:", "  steel: {density: 7800, youngs_modulus: 2e11, restitution: 0.9, friction: 0.3}\nparticles:"),
              "glass: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}",
              "glass: {density: 2500, youngs_modulus: 5e7, restitution: 0.5, friction: 0.5}");
  const Model model = compile(parse_case_text(with_steel, "case.yaml"));
  const int glass = model.material_index("glass"), steel = model.material_index("steel");
  EXPECT_DOUBLE_EQ(model.pair_param(glass, steel, "restitution"), 0.7);  // arithmetic mean
  EXPECT_DOUBLE_EQ(model.pair_param(glass, steel, "friction"), 0.9);     // explicit interaction
  EXPECT_DOUBLE_EQ(model.pair_param(steel, glass, "friction"), 0.9);
  EXPECT_DOUBLE_EQ(model.pair_param(glass, glass, "friction"), 0.5);
}

// A material that does not state a parameter leaves the pair the other's value: the glass's
// rolling resistance and cohesion act on a steel wall that says nothing of them (mixed with the
// defaults, 0, they would be halved and, by the geometric mean, gone). Neither states it: the default.
TEST(CaseReading, AnUnstatedParameterLeavesThePairTheOthersValue) {
  const std::string text =
      replace(std::string(kGood) + "contact: {rolling: epsd, adhesion: [sjkr]}\n", "particles:",
              "  steel: {density: 7800, youngs_modulus: 2e11}\n  rubber: {density: 1100, youngs_modulus: 1e7, rolling_friction: 0.1}\nparticles:");
  const Model model = compile(parse_case_text(
      replace(text, "restitution: 0.5}", "restitution: 0.5, rolling_friction: 0.3, cohesion_energy_density: 1.5e5}"), "case.yaml"));
  const int glass = model.material_index("glass"), steel = model.material_index("steel"), rubber = model.material_index("rubber");
  EXPECT_DOUBLE_EQ(model.pair_param(glass, steel, "rolling_friction"), 0.3);
  EXPECT_DOUBLE_EQ(model.pair_param(steel, glass, "cohesion_energy_density"), 1.5e5);
  EXPECT_DOUBLE_EQ(model.pair_param(glass, rubber, "rolling_friction"), 0.2);  // both state it: arithmetic mean
  EXPECT_DOUBLE_EQ(model.pair_param(steel, rubber, "cohesion_energy_density"), 0.0);  // neither: the default
  EXPECT_DOUBLE_EQ(model.pair_param(steel, steel, "rolling_friction"), 0.0);
}

// The stages are declared once (kStageTable, contact/effect.h); ContactSpec maps each to its own
// field: a single stage to one choice, an additive stage to a list. A stage added to the table
// without its field fails here.
TEST(Contact, EveryStageHasItsFieldInContactSpec) {
  ContactSpec contact;
  std::set<const void*> fields;
  for (const Stage stage : kStages) {
    const bool additive = stage_is_additive(stage);
    EXPECT_EQ(contact.single(stage) != nullptr, !additive) << stage_name(stage);
    EXPECT_EQ(contact.additive(stage) != nullptr, additive) << stage_name(stage);
    fields.insert(additive ? static_cast<const void*>(contact.additive(stage)) : static_cast<const void*>(contact.single(stage)));
  }
  EXPECT_EQ(fields.size(), kStages.size()) << "two stages share a field of ContactSpec";
}

// compile switches the effects on by walking kStages: an adhesion list runs after damping and
// before the tangential law, whatever the order of the YAML keys.
TEST(Contact, EffectsSwitchOnInRunningOrder) {
  const Model model = compile(parse_case_text(std::string(kGood) + "contact: {rolling: epsd, adhesion: [sjkr]}\n", "case.yaml"));
  std::vector<std::string> order;
  for (const ActiveEffect& e : model.effects) order.push_back(std::string(stage_name(e.spec->stage)) + ": " + std::string(e.spec->name));
  EXPECT_EQ(order, (std::vector<std::string>{"normal: hertz", "damping: restitution", "adhesion: sjkr", "tangential: mindlin", "rolling: epsd"}));
}

}  // namespace
}  // namespace dem::test

namespace dem::test {
namespace {

TEST(MaterialLibrary, LibraryMaterialCarriesItsSourcesOverridesAndWallPairs) {
  const CaseSpec spec = parse_case_text(R"(simulation: {duration: 0.1}
materials:
  ore: {library: gravel, friction: 0.7}
  steel: {library: steel}
particles:
  - {material: ore, diameter: 0.02, positions: [[0, 0, 0.1]]}
)", DEMDESIGN_SOURCE_DIR "/cases/case.yaml");  // a case in cases/ finds the library in ../materials
  const MaterialSpec& ore = spec.materials[0];
  EXPECT_EQ(ore.name, "ore");
  EXPECT_DOUBLE_EQ(ore.density, 2650);
  EXPECT_DOUBLE_EQ(ore.params.at("friction"), 0.7) << "the case's override wins";
  EXPECT_EQ(ore.sources.at("friction"), "set in the case");
  EXPECT_NE(ore.sources.at("density").find("g/cm^3"), std::string::npos) << "library provenance is kept";
  EXPECT_NE(ore.library_file.find("gravel.yaml"), std::string::npos);
  EXPECT_EQ(ore.tunable.at("friction").first, 0.2);
  // The library's contact model and its pair parameters against steel.
  EXPECT_EQ(spec.contact.rolling.model, "epsd");
  ASSERT_EQ(spec.interactions.size(), 1u);
  EXPECT_EQ(spec.interactions[0].material_b, "steel");
  EXPECT_DOUBLE_EQ(spec.interactions[0].params.at("friction"), 0.45);
  const Model model = compile(spec);
  EXPECT_NEAR(model.pair_param(model.material_index("ore"), model.material_index("steel"), "friction"), 0.45, 1e-12);
}

TEST(MaterialLibrary, UnknownLibraryMaterialSaysWhereItLooked) {
  const std::string message = error_of(replace(kGood, "glass: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}", "glass: {library: unobtainium}"));
  EXPECT_NE(message.find("case.yaml:3"), std::string::npos) << message;
  EXPECT_NE(message.find("unobtainium.yaml"), std::string::npos) << message;
  EXPECT_NE(message.find("looked in"), std::string::npos) << message;
}

TEST(Sensors, PlaneAndBoxAreReadAndBadOnesNamed) {
  const std::string good = std::string(kGood) + R"(sensors:
  - {name: flow, plane: {point: [0, 0, 0], normal: [0, 0, 2]}, region: {min: [-1, -1, -1], max: [1, 1, 1]}}
  - {name: load, box: {min: [-1, -1, -1], max: [1, 1, 1], across: [0, 1, 0]}}
)";
  const Model model = compile(parse_case_text(good, "case.yaml"));
  ASSERT_EQ(model.sensors.size(), 2u);
  EXPECT_DOUBLE_EQ(model.sensors[0].normal.z(), 1.0) << "normal made unit";
  EXPECT_GT(model.sensors[0].thickness, 0) << "slab thickness defaults to a few particle sizes";
  const std::string both = replace(good, "box: {min", "plane: {point: [0, 0, 0]}, box: {min");
  EXPECT_NE(error_of(both).find("sensors[1]"), std::string::npos) << error_of(both);
  const std::string twice = replace(good, "name: load", "name: flow");
  EXPECT_NE(error_of(twice).find("sensor name 'flow' given twice"), std::string::npos) << error_of(twice);
}

TEST(Equipment, UnknownGeneratorSuggestsTheNearestAndPortsNeedEquipment) {
  const std::string typo = std::string(kGood) + "equipment:\n  transfer_chut: {}\n";
  const std::string message = error_of(typo);
  EXPECT_NE(message.find("did you mean 'transfer_chute'"), std::string::npos) << message;
  const std::string port = replace(kGood, "particles:\n  - {material: glass, diameter: 0.004, positions: [[0, 0, 0.01]]}",
                                   "inlets:\n  - {port: feed_belt, material: glass, diameter: 0.004, mass_rate_tph: 1}");
  EXPECT_NE(error_of(port).find("port"), std::string::npos) << error_of(port);
}

TEST(Output, ExplicitCameraIsReadAndCheckedPresetsListed) {
  const std::string good = std::string(kGood) + "output: {render: {camera: {eye: [1, -2, 1], target: [0, 0, 0], up: [0, 0, 1], fov_deg: 40}}}\n";
  const CaseSpec spec = parse_case_text(good, "case.yaml");
  EXPECT_TRUE(spec.output.has_camera_pose);
  EXPECT_DOUBLE_EQ(spec.output.camera_eye.y(), -2);
  EXPECT_DOUBLE_EQ(spec.output.camera_fov_deg, 40);
  const std::string bad = std::string(kGood) + "output: {render: {camera: sid}}\n";
  EXPECT_NE(error_of(bad).find("valid: side, front, top, iso"), std::string::npos) << error_of(bad);
  const std::string parallel = std::string(kGood) + "output: {render: {camera: {eye: [0, 0, 1], target: [0, 0, 0], up: [0, 0, 1]}}}\n";
  EXPECT_NE(error_of(parallel).find("parallel"), std::string::npos) << error_of(parallel);
}

TEST(Inlets, AFeedNeedsAMassRateOrACountAndACountIsRead) {
  const std::string fill = std::string(kGood) + "inlets:\n  - {material: glass, diameter: 0.004, count: 500, region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}\n";
  const CaseSpec spec = parse_case_text(fill, "case.yaml");
  ASSERT_EQ(spec.inlets.size(), 1u);
  EXPECT_EQ(spec.inlets[0].count, 500);
  EXPECT_EQ(spec.inlets[0].mass_rate, 0.0);
  const std::string neither = replace(fill, "count: 500, ", "");
  EXPECT_NE(error_of(neither).find("inlets[0].mass_rate_tph: missing"), std::string::npos) << error_of(neither);
  EXPECT_NE(error_of(neither).find("`count` alone"), std::string::npos) << error_of(neither);
  const std::string both = replace(fill, "count: 500", "mass_rate_tph: 1, mass_rate_kgs: 1");
  EXPECT_NE(error_of(both).find("not both"), std::string::npos) << error_of(both);
  const std::string mesh = std::string(kGood) +
                           "meshes:\n  - {material: glass, vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles: [[0, 1, 2]], active_from: -1}\n";
  EXPECT_NE(error_of(mesh).find("meshes[0].active_from"), std::string::npos) << error_of(mesh);
}

}  // namespace
}  // namespace dem::test
