// A contributor's effect, written as one file with its registration line and nothing else: a
// plain viscous dashpot in the normal direction, F = -c v_n while the bodies touch. With Hertz
// contact its dissipation depends on the impact speed (the contact lasts longer at low speed, so
// slow impacts lose more), which the restitution law (a constant e) cannot reproduce.
// tests/test_contributor_effect.cpp checks that it reaches every tool with no other edit.
#include "contact/effect.h"

namespace dem::test_effects {
namespace {

// Coarse graining: c x F^2 (exponent 2): at the real velocities the force c v_n keeps its stress.
constexpr ParamSpec kParams[] = {
    {"dashpot_coefficient", "N s/m", 0.0, 0.0, 1.0, Mixing::arithmetic, true, "normal dashpot coefficient c", 2},
};

DEM_KERNEL void dashpot_kernel(const EffectContext& ctx, ContactBatch& b) {
  DEM_VECTOR_LOOP
  for (int c = 0; c < b.count; ++c) {
    const bool touching = b.overlap[c] > 0.0;
    const double force = -ctx.param(b, c, 0) * b.vn[c];  // [N] repulsive while approaching
    b.fn[c] += touching ? force : 0.0;
    b.energy_dissipated[c] += touching ? force * -b.vn[c] * ctx.dt : 0.0;
  }
}

constexpr FittedParam kFitted[] = {{"dashpot_coefficient", 0.02, 0.0, 0.1}};
constexpr std::string_view kMoves[] = {"drop_rebound/restitution"};
constexpr CandidateSpec kCandidate{
    .title = "viscous normal dashpot",
    .signature = "rebounds that lose more at low impact speed than at high: a dissipation that grows with the contact time",
    .fitted = kFitted,
    .also_set = {},
    .moves = kMoves,
    .scale = nullptr,
};

}  // namespace

const EffectSpec viscous_dashpot{
    .stage = Stage::extra,
    .name = "viscous_dashpot",
    .summary = "normal dashpot F = -c v_n while touching (a contributor's example)",
    .citation = "-",
    .params = kParams,
    .options = {},
    .history = {},
    .kernel = dashpot_kernel,
    .range = nullptr,
    .requires_normal = "",
    .candidate = &kCandidate,
};

DEM_REGISTER_EFFECT(viscous_dashpot);

}  // namespace dem::test_effects
