// Test helpers: load a shipped case (tests and cases share their set-ups), edit its spec,
// compile, and step it while recording what a test needs.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "case/spec.h"
#include "core/model.h"
#include "core/forces.h"
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

/// Steps `sim` up to `steps` times, checking the numerics after each; the first NumericalError's
/// message, or "" when none came.
inline std::string numerical_trouble_within(Sim& sim, int steps) {
  try {
    for (int k = 0; k < steps; ++k) {
      sim.advance();
      check_numerics(sim.model, sim.state, sim.work);
    }
  } catch (const NumericalError& e) {
    return e.what();
  }
  return "";
}

inline double overlap_of(const State& s, size_t i, size_t j) {
  const double dx = s.x[i] - s.x[j], dy = s.y[i] - s.y[j], dz = s.z[i] - s.z[j];
  return s.radius[i] + s.radius[j] - std::sqrt(dx * dx + dy * dy + dz * dz);
}

/// A one-contact batch between two spheres of radius r (or a sphere and a wall), for evaluating
/// the model's effects directly at a chosen overlap.
struct OneContact {
  ContactBatch b{};
  std::vector<double> history;
  OneContact(const Model& model, double r_i, double r_j, double mass) : history(std::max(model.history_width, 1), 0.0) {
    b.count = 1;
    b.pair_type[0] = 0;
    b.nx[0] = 1, b.ny[0] = 0, b.nz[0] = 0;
    b.vn[0] = b.vtx[0] = b.vty[0] = b.vtz[0] = b.wx[0] = b.wy[0] = b.wz[0] = 0;
    b.radius_i[0] = r_i;
    b.radius_j[0] = r_j;
    b.r_eff[0] = r_j > 0 ? r_i * r_j / (r_i + r_j) : r_i;
    b.m_eff[0] = mass;
    b.inertia_eff[0] = 1.4 * mass * r_i * r_i;
    b.history[0] = history.data();
  }
  double force_at(const Model& model, double overlap) {
    b.overlap[0] = overlap;
    b.count = 1;
    evaluate_effects(model, b);
    return b.fn[0];
  }
};

}  // namespace dem::test
