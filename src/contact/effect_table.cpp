// The table of contact effects. To add an effect: write src/contact/effects/NAME.cpp defining
// `extern const EffectSpec NAME{...}` in namespace dem::effects, and add one row here. The row
// declares the spec and places it in the table; the build compiles every file of
// src/contact/effects/.
// Rows of a stage in the order `demdesign effects` lists them; the order of the table does not
// change any result (a model's pair rows follow its active effects in stage order).
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "contact/effect.h"

#define DEM_EFFECT_ROWS(ROW)                     \
  /* normal */                                   \
  ROW(hertz_normal)                              \
  ROW(linear_normal)                             \
  /* damping */                                  \
  ROW(restitution_damping)                       \
  /* adhesion (any number) */                    \
  ROW(jkr_adhesion)                              \
  ROW(sjkr_adhesion)                             \
  /* tangential */                               \
  ROW(mindlin_tangential)                        \
  /* rolling */                                  \
  ROW(rolling_cdt)                               \
  ROW(rolling_epsd)                              \
  /* extra (any number) */                       \
  ROW(liquid_bridge)

namespace dem {

namespace effects {
#define DEM_DECLARE_EFFECT(name) extern const EffectSpec name;
DEM_EFFECT_ROWS(DEM_DECLARE_EFFECT)
#undef DEM_DECLARE_EFFECT
}  // namespace effects

namespace {

std::vector<const EffectSpec*>& table() {
#define DEM_EFFECT_ADDRESS(name) &effects::name,
  static std::vector<const EffectSpec*> rows = {DEM_EFFECT_ROWS(DEM_EFFECT_ADDRESS)};
#undef DEM_EFFECT_ADDRESS
  return rows;
}

bool same_param(const ParamSpec& a, const ParamSpec& b) {
  return a.key == b.key && a.unit == b.unit && a.default_value == b.default_value && a.min_value == b.min_value &&
         a.max_value == b.max_value && a.mixing == b.mixing && a.tunable == b.tunable;
}

}  // namespace

std::span<const EffectSpec* const> effect_table() { return table(); }

const EffectSpec* find_effect(Stage stage, std::string_view name) {
  for (const EffectSpec* e : table())
    if (e->stage == stage && e->name == name) return e;
  return nullptr;
}

const ParamSpec* find_param(std::string_view key) {
  for (const EffectSpec* e : table())
    for (const ParamSpec& p : e->params)
      if (p.key == key) return &p;
  return nullptr;
}

void register_effect(const EffectSpec* effect) {
  if (effect->stage == Stage::normal && !effect->contact_time)
    throw std::invalid_argument(fmt::format("effect '{}': a normal law must give its contact_time (the time step resolves it)", effect->name));
  if (find_effect(effect->stage, effect->name))
    throw std::invalid_argument(fmt::format("effect '{}': the {} stage already has an effect of that name", effect->name,
                                            stage_name(effect->stage)));
  for (const ParamSpec& p : effect->params)
    if (const ParamSpec* known = find_param(p.key); known && !same_param(*known, p))
      throw std::invalid_argument(fmt::format("effect '{}': parameter '{}' is another effect's with a different definition; "
                                              "share that effect's ParamSpec or choose another key",
                                              effect->name, p.key));
  table().push_back(effect);
}

}  // namespace dem
