// The table of contact effects. To add an effect: write src/effects/NAME.cpp with its
// EffectSpec, declare it in src/effects/effects.h, and add one row here.
#include "effect.h"

#include "effects/effects.h"

namespace dem {

namespace {
const EffectSpec* const kTable[] = {
    // normal
    &effects::hertz_normal,
    &effects::linear_normal,
    // damping
    &effects::restitution_damping,
    // adhesion (any number)
    &effects::jkr_adhesion,
    &effects::sjkr_adhesion,
    // tangential
    &effects::mindlin_tangential,
    // rolling
    &effects::rolling_cdt,
    &effects::rolling_epsd,
    // extra (any number)
    &effects::liquid_bridge,
};
}  // namespace

std::span<const EffectSpec* const> effect_table() { return kTable; }

const EffectSpec* find_effect(Stage stage, std::string_view name) {
  for (const EffectSpec* e : kTable)
    if (e->stage == stage && e->name == name) return e;
  return nullptr;
}

}  // namespace dem
