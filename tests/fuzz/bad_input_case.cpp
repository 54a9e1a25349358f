#include <fmt/format.h>

#include "bad_input.h"
#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "equipment.h"

namespace dem::fuzz {

std::string read_case_text(const std::string& text, std::int64_t place_limit) {
  try {
    CaseSpec spec = parse_case_text(text, "fuzz.yaml");
    equipment::expand_equipment(spec);
    const Model model = compile(spec, [](const MeshWallSpec& m) -> TriangleSoup {
      throw CaseError(fmt::format("{}: mesh '{}': mesh files are not read here", m.location.str(), m.name));
    });
    std::int64_t particles = 0;
    for (const ParticleSource& source : model.sources) particles += source.spec.count;
    if (particles <= place_limit) initial_state(model);
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

}  // namespace dem::fuzz
