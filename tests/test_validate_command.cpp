// `demdesign validate`, the real binary: the validation page with its table, data and plots.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "binary_runs.h"

namespace {

namespace fs = std::filesystem;
using namespace dem::test;

TEST(ValidateCommand, WritesTheValidationPageWithEveryCurve) {
  const fs::path out = fs::temp_directory_path() / "demdesign_validate_test";
  fs::remove_all(out);
  ASSERT_EQ(run_binary({"validate", "--source", DEMDESIGN_SOURCE_DIR, "--out", out.string()}, out.string() + ".log"), 0)
      << read_text(out.string() + ".log");
  const std::string md = read_text(out / "validation.md");
  EXPECT_NE(md.find("98 points inside their tolerance, 0 outside, 3 known differences"), std::string::npos) << md.substr(0, 400);
  EXPECT_NE(md.find("## CO6 aluminium: beta"), std::string::npos);
  EXPECT_NE(md.find("![CO8 sphere on sphere: beta](plots/co8_sphere_on_sphere_beta.png)"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "plots" / "co6_nylon_beta.png"));
  // 101 points and a header.
  std::istringstream csv(read_text(out / "validation.csv"));
  int lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, 102);
  EXPECT_NE(read_text(out / "validation.html").find("data:image/png;base64"), std::string::npos);
}

}  // namespace
