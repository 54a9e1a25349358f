// The table of contact effects. To add an effect: write src/contact/effects/NAME.cpp defining
// `extern const EffectSpec NAME{...}` in namespace dem::effects, and add one row here. The row
// declares the spec and places it in the table; the build compiles every file of
// src/contact/effects/. Every effect enters the table by `admit`, these rows at first use and an
// effect defined outside the engine by register_effect (DEM_REGISTER_EFFECT): the same checks
// hold for both. Rejected: built-in effects registering themselves from their own files, as a
// plugin does: the engine is a static library, whose linker drops an object nothing references,
// and the table's order would follow the link order.
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

bool same_param(const ParamSpec& a, const ParamSpec& b) {
  return a.key == b.key && a.unit == b.unit && a.default_value == b.default_value && a.min_value == b.min_value &&
         a.max_value == b.max_value && a.mixing == b.mixing && a.tunable == b.tunable &&
         a.coarse_grain_exponent == b.coarse_grain_exponent && a.wall_candidate == b.wall_candidate &&
         a.plausible == b.plausible;
}

const EffectSpec* find_in(const std::vector<const EffectSpec*>& rows, Stage stage, std::string_view name) {
  for (const EffectSpec* e : rows)
    if (e->stage == stage && e->name == name) return e;
  return nullptr;
}

const ParamSpec* find_param_in(const std::vector<const EffectSpec*>& rows, std::string_view key) {
  for (const EffectSpec* e : rows)
    for (const ParamSpec& p : e->params)
      if (p.key == key) return &p;
  return nullptr;
}

/// The one way into the table, for the rows above and for register_effect alike: a normal law
/// gives its contact time, a stage has one effect of a name, a parameter key has one definition.
void admit(std::vector<const EffectSpec*>& rows, const EffectSpec* effect) {
  if (effect->stage == Stage::normal && !effect->contact_time)
    throw std::invalid_argument(fmt::format("effect '{}': a normal law must give its contact_time (the time step resolves it)", effect->name));
  if (find_in(rows, effect->stage, effect->name))
    throw std::invalid_argument(fmt::format("effect '{}': the {} stage already has an effect of that name", effect->name,
                                            stage_name(effect->stage)));
  for (const ParamSpec& p : effect->params)
    if (const ParamSpec* known = find_param_in(rows, p.key); known && !same_param(*known, p))
      throw std::invalid_argument(fmt::format("effect '{}': parameter '{}' is another effect's with a different definition; "
                                              "share that effect's ParamSpec or choose another key",
                                              effect->name, p.key));
  rows.push_back(effect);
}

std::vector<const EffectSpec*>& table() {
  static std::vector<const EffectSpec*> rows = [] {
#define DEM_EFFECT_ADDRESS(name) &effects::name,
    const EffectSpec* const built_in[] = {DEM_EFFECT_ROWS(DEM_EFFECT_ADDRESS)};
#undef DEM_EFFECT_ADDRESS
    std::vector<const EffectSpec*> admitted;
    for (const EffectSpec* e : built_in) admit(admitted, e);
    return admitted;
  }();
  return rows;
}

}  // namespace

std::span<const EffectSpec* const> effect_table() { return table(); }

const EffectSpec* find_effect(Stage stage, std::string_view name) { return find_in(table(), stage, name); }

const ParamSpec* find_param(std::string_view key) { return find_param_in(table(), key); }

void register_effect(const EffectSpec* effect) { admit(table(), effect); }

}  // namespace dem
