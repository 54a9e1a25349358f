// Case reading: bad input gets an error naming file, line, key and what would be valid.
#include <gtest/gtest.h>

#include <string>

#include "model.h"
#include "spec.h"

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

}  // namespace
}  // namespace dem::test
