// A contact effect is one physical mechanism at a contact (Hertz normal force, restitution
// damping, Coulomb friction, rolling resistance, a liquid bridge, ...). Each lives in one file
// under src/contact/effects/ (the build compiles every file there) and is registered in one row
// of src/contact/effect_table.cpp; nothing else names it.
//
// An effect declares
//   - the stage it runs in (stages run in the order of `Stage`),
//   - its parameter table (per material, mixed for unlike pairs), from which case parsing,
//     validation, the documentation (`demdesign effects`) and calibration ranges all derive,
//   - its options (model-wide choices such as the damping convention at the end of contact),
//   - the per-contact history it needs, by name,
//   - how far beyond touching it acts (liquid bridges, JKR necks),
//   - a kernel that runs over a batch of contacts stored as columns,
//   - whether a diagnosis may propose it, with the parameters a calibration then fits, their
//     ranges and start values, and the words that explain its signature (CandidateSpec).
//
// Rejected alternative: composing laws in the type system (LIGGGHTS/MercuryDPM templates).
// Combinations explode and errors are opaque; a batch loop through a short table of kernels
// costs one indirect call per effect per 64 contacts.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <utility>

#include "base/parallel.h"

namespace dem {

/// Order in which effects run at a contact. Later stages read what earlier ones wrote.
enum class Stage : std::uint8_t { normal, damping, adhesion, tangential, rolling, twisting, extra };

/// One stage: its key under `contact:` in YAML, and whether it takes any number of effects (a
/// YAML list, "additive") rather than exactly one or none.
struct StageRow {
  Stage stage;
  std::string_view key;
  bool additive;
};

/// Every stage in running order, a row at its enumerator's place. The case reader, compile, the
/// key reference and materials/ loop over it. A new stage is an enumerator above and a row here,
/// plus the one thing that cannot derive from them: its field in ContactSpec (src/case/spec.h,
/// returned by ContactSpec::single or ::additive; test Contact.EveryStageHasItsFieldInContactSpec).
inline constexpr std::array<StageRow, 7> kStageTable = {{
    {Stage::normal, "normal", false},
    {Stage::damping, "damping", false},
    {Stage::adhesion, "adhesion", true},
    {Stage::tangential, "tangential", false},
    {Stage::rolling, "rolling", false},
    {Stage::twisting, "twisting", false},
    {Stage::extra, "extra", true},
}};
static_assert(
    [] {
      for (std::size_t k = 0; k < kStageTable.size(); ++k)
        if (static_cast<std::size_t>(kStageTable[k].stage) != k) return false;
      return true;
    }(),
    "kStageTable: each stage's row sits at its enumerator's place, in running order");

/// The stages in running order, for `for (Stage stage : kStages)`.
inline constexpr std::array<Stage, kStageTable.size()> kStages = [] {
  std::array<Stage, kStageTable.size()> stages{};
  for (std::size_t k = 0; k < stages.size(); ++k) stages[k] = kStageTable[k].stage;
  return stages;
}();

/// The stage's key under `contact:`, e.g. "tangential".
inline constexpr std::string_view stage_name(Stage s) { return kStageTable[static_cast<std::size_t>(s)].key; }
/// Stages that take any number of effects (a YAML list); the others take exactly one or none.
inline constexpr bool stage_is_additive(Stage s) { return kStageTable[static_cast<std::size_t>(s)].additive; }

/// The single stages, then the additive ones, each in running order: the order a case's
/// `contact:` is read in (so which of two mistakes is reported first) and materials/ writes a
/// contact model in (calibrated material files, the keys of stored simulations).
inline constexpr std::array<Stage, kStages.size()> kStagesSingleFirst = [] {
  std::array<Stage, kStages.size()> stages{};
  std::size_t next = 0;
  for (const bool additive : {false, true})
    for (const Stage stage : kStages)
      if (stage_is_additive(stage) == additive) stages[next++] = stage;
  return stages;
}();

/// How a per-material parameter combines for a contact between two different materials.
/// Explicit `interactions:` entries in a case override any rule.
enum class Mixing : std::uint8_t { arithmetic, geometric, harmonic, minimum, maximum };

/// One row of an effect's parameter table.
struct ParamSpec {
  std::string_view key;   ///< key in a material's YAML map
  std::string_view unit;  ///< SI unit, "-" when dimensionless
  double default_value;
  double min_value;  ///< inclusive
  double max_value;  ///< inclusive
  Mixing mixing;
  bool tunable;  ///< calibration may vary it
  std::string_view doc;
  /// Coarse graining (src/core/coarse_grain.h): a pair of parcels F times the real diameter
  /// takes this parameter times F^exponent, so that the parcels' contact stresses are the real
  /// particles' (0: unchanged; 1: a linear stiffness [N/m], a surface energy [J/m^2], a surface
  /// tension [N/m]). Each row states it with its reason; none (std::nullopt): a case with
  /// coarse_grain != 1 and this effect is refused rather than scaled by a guess.
  std::optional<int> coarse_grain_exponent = std::nullopt;
  /// A parameter of each particle-wall pair (a wall liner's friction, restitution, ...) that a
  /// diagnosis offers as a candidate when the fit leaves it out: a test that misses on one wall
  /// only points at that wall's value, not at missing physics. Offered when its effect is active
  /// in the model. Rejected: a list of keys in the diagnosis, which a new effect's wall parameter
  /// would not reach and which would go on naming a parameter whose effect the model lacks.
  bool wall_candidate = false;
  /// Where a calibrated value of a dry bulk solid usually lies (none: not judged). A fit that
  /// lands outside, or runs to the edge of its tunable range, is named by the calibration as the
  /// fit absorbing physics the model lacks; a material file's `plausible:` overrides it.
  std::optional<std::pair<double, double>> plausible = std::nullopt;
};

/// A model-wide choice of an effect, given as `stage: {model: NAME, OPTION: VALUE}`.
struct OptionSpec {
  std::string_view key;
  std::span<const std::string_view> values;  ///< allowed values; values[0] is the default
  std::string_view doc;
};

/// Per-contact state an effect keeps from step to step, in doubles. A pair's history is seen
/// from body i; `odd` history (vectors of i relative to j: a tangential spring, a rolling
/// torque) changes sign when the two bodies swap roles, as they do when the slots are re-sorted.
struct HistorySpec {
  std::string_view name;
  int width;
  bool odd = false;
};

/// Contacts evaluated together. Columns, so kernels stream through them; 128 contacts (about 45
/// doubles a contact, 46 KiB: L1's size on Zen 5) rather than 64: measured faster on the dense
/// bed and the settle; 256 was no faster, 32 slower (bench/results/design_measurements.csv).
inline constexpr int kBatch = 128;
/// Most doubles of history one contact can carry (all effects of a case together; compile checks).
inline constexpr int kHistoryMax = 8;

// A contact kernel is a DEM_KERNEL (parallel.h): a DEM_VECTOR_LOOP over the batch's columns (the
// columns it writes never overlap the pair table it reads).

struct ContactBatch {
  int count = 0;
  // --- inputs, filled by the contact geometry ----------------------------------------------
  int pair_type[kBatch];              ///< row of the model's pair table
  double overlap[kBatch];             ///< [m] positive when the bodies overlap, negative: gap
  double nx[kBatch], ny[kBatch], nz[kBatch];  ///< unit normal, from body j towards body i
  double vn[kBatch];                  ///< [m/s] normal relative velocity (v_i - v_j)·n, < 0 approaching
  double vtx[kBatch], vty[kBatch], vtz[kBatch];  ///< [m/s] tangential relative velocity at the contact
  /// [rad/s] relative angular velocity w_i - w_j; with inertia_eff, set for particle pairs only
  /// when an effect reads them (EffectSpec::reads_spin)
  double wx[kBatch], wy[kBatch], wz[kBatch];
  double radius_i[kBatch];            ///< [m]
  double radius_j[kBatch];            ///< [m] 0 for a wall (flat, infinite radius)
  double r_eff[kBatch];               ///< [m] R* = R_i R_j/(R_i + R_j), R_i for a wall
  double m_eff[kBatch];               ///< [kg] m* = m_i m_j/(m_i + m_j), m_i for a wall
  double inertia_eff[kBatch];         ///< [kg m^2] reduced moment of inertia about the contact point
  double* history[kBatch];            ///< this contact's history row (all effects' slots)
  /// The history rows as columns: hist[q][c] = history[c][q]. evaluate_effects copies the rows in
  /// before the kernels and back after them, so kernels read and write columns only.
  double hist[kHistoryMax][kBatch];
  // --- written by effects, in stage order. The normal stage (always present, first) sets fn,
  // fn_elastic, kn, kt, damp_sn, damp_st and damp_shape; every other output starts at 0. -------
  double fn[kBatch];                  ///< [N] normal force on i along n (positive: repulsive)
  double fn_elastic[kBatch];          ///< [N] elastic part of fn (set by the normal stage)
  double load[kBatch];                ///< [N] normal load for friction limits, set after damping
  double kn[kBatch], kt[kBatch];      ///< [N/m] normal and tangential stiffness now
  double damp_sn[kBatch], damp_st[kBatch];  ///< [N/m] stiffness the damping law scales with
  double damp_shape[kBatch];          ///< [-] 1 for a linear law, sqrt(5/6) for Hertz (Tsuji form)
  double gamma_n[kBatch], gamma_t[kBatch];  ///< [N s/m] damping coefficients
  double ftx[kBatch], fty[kBatch], ftz[kBatch];  ///< [N] tangential force on i
  double mx[kBatch], my[kBatch], mz[kBatch];     ///< [N m] torque on i not from ft (rolling, ...)
  double energy_dissipated[kBatch];   ///< [J] this step, by friction and damping (diagnostic)
};

/// What a kernel needs besides the batch.
struct EffectContext {
  const double* pair_table;  ///< rows of mixed parameters, `pair_stride` doubles each
  int pair_stride;
  int param_offset;    ///< where this effect's parameters start in a row
  int history_offset;  ///< where this effect's history starts in a contact's row
  const std::uint8_t* options;  ///< this effect's option choices, index into OptionSpec::values
  double dt;           ///< [s] time step
  /// This effect's k-th parameter for contact c.
  double param(const ContactBatch& b, int c, int k) const {
    return pair_table[b.pair_type[c] * pair_stride + param_offset + k];
  }
  /// Column 0 and 1 of every pair row: effective Young's and shear modulus.
  double youngs_eff(const ContactBatch& b, int c) const { return pair_table[b.pair_type[c] * pair_stride]; }
  double shear_eff(const ContactBatch& b, int c) const { return pair_table[b.pair_type[c] * pair_stride + 1]; }
  /// Column q of this effect's history (q < its width): entry c is contact c's value.
  double* hist(ContactBatch& b, int q) const { return b.hist[history_offset + q]; }
};

using EffectKernel = void (*)(const EffectContext&, ContactBatch&);
/// Largest gap [m] at which the effect still acts for one pair row (0: only when touching).
/// `row` is the whole pair row (row[0] = E*, row[1] = G*), `params` this effect's part of it,
/// `radius_max` the largest particle radius of the case.
using EffectRange = double (*)(const double* row, const double* params, double radius_max);

/// One parameter a calibration fits when a diagnosis adds the effect.
struct FittedParam {
  std::string_view key;  ///< one of the effect's ParamSpec keys
  double start;          ///< value the effect is added with
  /// Range the fit searches (clipped to the ParamSpec's range). A `min` of 0 declares that the
  /// effect adds nothing at 0 (no force, no torque, no change of the time step): a diagnosis then
  /// takes the model's own simulations as the effect's at 0 (test EveryCandidateAddsNothingAtZero).
  double min, max;
};

/// A parameter given a value (not fitted) when the effect is added.
struct StartValue {
  std::string_view key;
  double value;
};

/// The particles' scale, for effects whose natural strength depends on it (a cohesion in units
/// of the particle weight).
struct ParticleScale {
  double density;        ///< [kg/m^3]
  double diameter;       ///< [m] typical (median) diameter
  double youngs_modulus; ///< [Pa]
  double poisson_ratio;  ///< [-]
};

/// What `diagnose` and `calibrate` need to propose an effect a material lacks: the effect's own
/// file declares it, and materials/ keeps no list of effects.
struct CandidateSpec {
  std::string_view title;      ///< in words, e.g. "rolling resistance"
  /// Why its signature fits a misfit: what the model without it gets wrong, and the physics.
  std::string_view signature;
  std::span<const FittedParam> fitted;
  std::span<const StartValue> also_set;
  /// Observables it is expected to move, as "test/observable" of the virtual tests.
  std::span<const std::string_view> moves;
  /// Multiplies `fitted`'s start, min and max for the material's scale; nullptr: 1.
  double (*scale)(const ParticleScale&) = nullptr;
};

struct EffectSpec {
  Stage stage;
  std::string_view name;      ///< the value that selects it in YAML, e.g. "hertz"
  std::string_view summary;   ///< one line
  std::string_view citation;  ///< source of the formulas
  std::span<const ParamSpec> params;
  std::span<const OptionSpec> options;
  std::span<const HistorySpec> history;
  EffectKernel kernel;
  EffectRange range;  ///< nullptr: acts only while touching
  /// Values computed once per pair row from the parameters (e.g. a damping ratio from the
  /// restitution coefficient), stored right after the parameters; `derive` fills them.
  int derived_count = 0;
  void (*derive)(double* row_params) = nullptr;
  /// Effects this one is written for (e.g. JKR adds to Hertz); empty: any.
  std::string_view requires_normal;
  /// Reads the batch's spin inputs (wx, wy, wz, inertia_eff), which the particle pairs' geometry
  /// computes only when an active effect reads them (forces.cpp).
  bool reads_spin = false;
  /// Set when a diagnosis may propose this effect for a material that lacks it.
  const CandidateSpec* candidate = nullptr;
  /// Normal laws (required of them): the duration [s] of an undamped binary impact of effective
  /// mass `m_eff` [kg] and radius `r_eff` [m] at `speed` [m/s], from the pair's row (`row[0]`, its
  /// effective Young's modulus [Pa]) and this effect's parameters (`params`): what the time step
  /// must resolve (core/timestep.cpp).
  double (*contact_time)(const double* row, const double* params, double m_eff, double r_eff, double speed) = nullptr;
  /// Normal laws whose stiffness comes from the elastic moduli (Hertz): the Rayleigh time limits
  /// the step. A spring of a given stiffness does not bind to it.
  bool rayleigh_binds = false;
};

/// Duration [s] of an undamped Hertz impact, 2.8683 (m*^2 / (R* E*^2 v))^(1/5) (Johnson 1985),
/// of effective mass [kg], radius [m] and Young's modulus [Pa] at impact speed [m/s].
double hertz_contact_time(double m_eff, double r_eff, double youngs_eff, double speed);

/// Every effect: the rows of src/contact/effect_table.cpp, then any registered by register_effect.
std::span<const EffectSpec* const> effect_table();
/// nullptr when no effect of that stage has that name.
const EffectSpec* find_effect(Stage stage, std::string_view name);
/// The parameter row of `key` (a parameter two variants of a stage share, such as
/// rolling_friction of cdt and epsd, is one ParamSpec both list); nullptr when no effect has it.
const ParamSpec* find_param(std::string_view key);

/// Adds an effect defined outside src/contact/effects/ (a plugin, or an effect of the test tree)
/// to the table; call before any case is read. Throws std::invalid_argument when its stage
/// already has an effect of that name, or when one of its parameter keys is another effect's with
/// a different definition.
void register_effect(const EffectSpec* effect);
/// Registration as one line beside the spec: `DEM_REGISTER_EFFECT(my_effect);` in a source file
/// linked into the program (not into a static library, whose unreferenced objects are dropped).
struct EffectRegistration {
  explicit EffectRegistration(const EffectSpec* effect) { register_effect(effect); }
};
#define DEM_REGISTER_EFFECT(spec) static const ::dem::EffectRegistration spec##_registration_{&(spec)}

}  // namespace dem
