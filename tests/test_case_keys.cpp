// The case-key reference: MapReader reports what it is asked for to a KeyRecorder, and
// docs/case-keys.md is exactly what `demdesign keys --markdown` prints from the shipped files, so
// a key added to a reader without the reference regenerated fails here.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "case/spec.h"
#include "case/yaml_check.h"

namespace dem::test {
namespace {

namespace fs = std::filesystem;

class Collect : public KeyRecorder {
 public:
  void record(KeyRequest request) override { requests.push_back(std::move(request)); }
  const KeyRequest* find(const std::string& map_path, const std::string& key) const {
    for (const KeyRequest& r : requests)
      if (r.map_path == map_path && r.key == key) return &r;
    return nullptr;
  }
  std::vector<KeyRequest> requests;
};

const char* kCase = R"(simulation: {duration: 0.1, gravity: [0, 0, -9.81]}
materials:
  glass: {density: 2500, youngs_modulus: 5e7, restitution: 0.5}
particles:
  - {material: glass, diameter: 0.004, positions: [[0, 0, 0.01]]}
)";

TEST(CaseKeys, ARecorderSeesEveryKeyAskedForWithDefaultRangeUnitAndValue) {
  Collect collect;
  KeyRecorder* previous = set_key_recorder(&collect);
  parse_case_text(kCase, "case.yaml");
  set_key_recorder(previous);

  const KeyRequest* duration = collect.find("simulation", "duration");
  ASSERT_NE(duration, nullptr);
  EXPECT_TRUE(duration->required);
  EXPECT_EQ(duration->kind, "number");
  EXPECT_EQ(duration->unit, "s");
  EXPECT_EQ(duration->value, "0.1");
  const KeyRequest* skin = collect.find("simulation", "skin");  // absent: its default
  ASSERT_NE(skin, nullptr);
  EXPECT_EQ(skin->fallback, "0");
  EXPECT_EQ(skin->value, "");
  ASSERT_TRUE(skin->min && skin->max);
  EXPECT_EQ(*skin->max, 10.0);
  const KeyRequest* gravity = collect.find("simulation", "gravity");
  ASSERT_NE(gravity, nullptr);
  EXPECT_EQ(gravity->kind, "vector");
  EXPECT_EQ(gravity->value, "[0, 0, -9.81]");
  const KeyRequest* numerical = collect.find("simulation", "numerical_trouble");
  ASSERT_NE(numerical, nullptr);
  EXPECT_EQ(numerical->kind, "word");
  EXPECT_EQ(numerical->allowed, (std::vector<std::string>{"stop", "warn"}));
  EXPECT_NE(collect.find("particles[0]", "material"), nullptr);
  EXPECT_NE(collect.find("materials.glass", "density"), nullptr);

  // Without a recorder nothing is recorded.
  const size_t seen = collect.requests.size();
  parse_case_text(kCase, "case.yaml");
  EXPECT_EQ(collect.requests.size(), seen);
}

/// Runs the demdesign binary with `args`; its standard output, and the exit status in `status`.
std::string run(const std::vector<std::string>& args, int& status) {
  int out[2];
  if (::pipe(out) != 0) return "";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(out[1], STDOUT_FILENO);
    ::close(out[0]), ::close(out[1]);
    std::vector<char*> argv{const_cast<char*>(DEMDESIGN_BINARY)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(DEMDESIGN_BINARY, argv.data());
    ::_exit(127);
  }
  ::close(out[1]);
  std::string text;
  char buffer[65536];
  for (ssize_t n; (n = ::read(out[0], buffer, sizeof buffer)) > 0;) text.append(buffer, static_cast<size_t>(n));
  ::close(out[0]);
  int raw = 0;
  ::waitpid(pid, &raw, 0);
  status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  return text;
}

TEST(CaseKeys, TheReferenceInDocsIsWhatDemdesignKeysPrints) {
  int status = -1;
  const std::string generated = run({"keys", "--markdown", "--source", DEMDESIGN_SOURCE_DIR}, status);
  ASSERT_EQ(status, 0);
  const fs::path doc = fs::path(DEMDESIGN_SOURCE_DIR) / "docs" / "case-keys.md";
  std::ifstream in(doc, std::ios::binary);
  std::stringstream written;
  written << in.rdbuf();
  // The first line that differs, to say what changed.
  std::istringstream a(written.str()), b(generated);
  std::string line_a, line_b;
  int line = 0;
  while (true) {
    ++line;
    const bool more_a = static_cast<bool>(std::getline(a, line_a)), more_b = static_cast<bool>(std::getline(b, line_b));
    if (!more_a && !more_b) break;
    if (!more_a || !more_b || line_a != line_b) {
      line_a = more_a ? line_a : "(end of file)", line_b = more_b ? line_b : "(end of output)";
      break;
    }
  }
  EXPECT_TRUE(written.str() == generated)
      << doc.string() << " is not what `demdesign keys --markdown` prints (a key was added, removed or changed in a "
      << "reader, or a shipped file changed). Regenerate it from the source tree with\n"
      << "  ./build/app/demdesign keys --markdown > docs/case-keys.md\n"
      << "First difference, line " << line << ":\n  docs:      " << line_a << "\n  generated: " << line_b;
}

}  // namespace
}  // namespace dem::test
