// Declarations of every contact effect; the table in src/effect_table.cpp lists them.
#pragma once

#include "effect.h"

namespace dem::effects {
extern const EffectSpec hertz_normal;
extern const EffectSpec linear_normal;
extern const EffectSpec restitution_damping;
extern const EffectSpec jkr_adhesion;
extern const EffectSpec sjkr_adhesion;
extern const EffectSpec mindlin_tangential;
extern const EffectSpec rolling_cdt;
extern const EffectSpec rolling_epsd;
extern const EffectSpec liquid_bridge;
}  // namespace dem::effects
