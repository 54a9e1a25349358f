// Test helpers: load a shipped case (tests and cases share their set-ups), edit its spec,
// compile, and step it while recording what a test needs.
#pragma once

#include <cmath>
#include <string>

#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "core/state.h"
#include "core/step.h"
#include "core/workspace.h"
#include "statistics/diagnostics.h"

namespace dem::test {

inline std::string case_path(const std::string& name) { return std::string(DEMDESIGN_SOURCE_DIR) + "/cases/" + name; }
inline CaseSpec load_case(const std::string& name) { return parse_case_file(case_path(name)); }

/// A compiled case with its state, ready to step.
struct Sim {
  Model model;
  State state;
  Workspace work;
  explicit Sim(const CaseSpec& spec) : model(compile(spec)), state(initial_state(model)) { prepare(model, state, work); }
  void advance() { step(model, state, work); }
  /// Steps until `done(state)` or `max_time` [s] of simulated time.
  template <typename Done>
  void advance_until(Done done, double max_time) {
    while (state.time < max_time && !done(state)) advance();
  }
  /// Slot of the particle with this id.
  size_t slot(std::int64_t id) const {
    for (size_t p = 0; p < state.size(); ++p)
      if (state.id[p] == id) return p;
    return static_cast<size_t>(-1);
  }
};

inline double overlap_of(const State& s, size_t i, size_t j) {
  const double dx = s.x[i] - s.x[j], dy = s.y[i] - s.y[j], dz = s.z[i] - s.z[j];
  return s.radius[i] + s.radius[j] - std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace dem::test
