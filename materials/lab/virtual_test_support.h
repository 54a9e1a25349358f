// Internal to the virtual tests (lab_*.cpp): reading a set-up, building the case every test
// starts from (the material model's particle and wall materials, contact law, shape, scaling),
// small inline meshes (cylinders, discs), a runner that steps a compiled case and measures rest,
// and the least-squares line the extraction rules fit. Not part of the public API.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "case/spec.h"
#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"
#include "lab/virtual_tests.h"

namespace dem::materials::detail {

/// Reads the numbers and words of one experiment's set-up; errors name the experiment's
/// location, the key and what is valid.
class SetupReader {
 public:
  SetupReader(const MaterialModel& model, const TestSetup& setup) : model_(model), setup_(setup) {}
  /// A required number in [min, max].
  double number(const std::string& key, double min, double max, const std::string& unit) const;
  /// An optional number in [min, max], `fallback` when absent.
  double number(const std::string& key, double fallback, double min, double max, const std::string& unit) const;
  /// A word among `valid`, `fallback` when absent.
  std::string word(const std::string& key, const std::string& fallback, const std::vector<std::string>& valid) const;
  /// A wall material name that model.walls defines. Absent: `fallback_key`'s value when given,
  /// else the only wall material of the model; otherwise a CaseError listing the model's walls.
  std::string wall(const std::string& key, const std::string& fallback_key = "") const;
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;
  /// Refuses a set-up key the test did not ask for (a misspelt optional key would otherwise be
  /// ignored), with the nearest valid key. Called once every key is read.
  void finish() const;

 private:
  const MaterialModel& model_;
  const TestSetup& setup_;
  mutable std::vector<std::string> asked_;  ///< the keys read, in order
};

/// The particle material's name in the test cases: model.name, or "particle".
std::string particle_name(const MaterialModel& model);

/// Sizes of the particles the test simulates, from 4000 reproducible draws: d50 by mass and the
/// mean particle volume (pi/6 E[d^3]; a clump template is scaled to its volume-equivalent
/// diameter). With model.coarse_grain = F these are the parcels' (every diameter x F, volumes x
/// F^3): a test sizes its fill, lattice, bins and checks by what it simulates, in the real apparatus.
struct SizeFigures {
  double d50 = 0;              // [m] median by mass
  double mean_volume = 0;      // [m^3]
  double largest = 0;          // [m] largest diameter
  double bounding_factor = 1;  // [-] clump bounding diameter / equivalent diameter (1: spheres)
  double coarse_grain = 1;     // [-] the factor the figures include (model.coarse_grain)
  double mass_of(double count, double density) const { return count * mean_volume * density; }
};
SizeFigures size_figures(const MaterialModel& model);

/// The real particles `simulated` parcels of factor `coarse_grain` stand for, as a case counts
/// them (a set's or an inlet's `count`): round(simulated F^3), which compile's parcel_count turns
/// back into `simulated` (|rounding| <= 1/2 before the division by F^3 >= 1).
std::int64_t real_count(std::int64_t simulated, double coarse_grain);

/// The note every coarse-grained test adds: F, the parcels and the real particles they stand for.
std::string coarse_grain_note(double coarse_grain, std::int64_t parcels);

/// The case every test starts from: the particle material, the named wall materials, the
/// contact law, the particle-wall pairs of those walls (a pair side that is not a wall
/// material is read as the particle), the clump template, scaling and seed. No walls, no particles.
CaseSpec base_case(const MaterialModel& model, const TestOptions& options, const std::vector<std::string>& walls,
                   const std::string& title);

/// `count` particles of the model placed at random without overlap in the box [lo, hi]. `count`
/// is what the test simulates (parcels with model.coarse_grain = F); the set is stated as a case
/// states it, the real size distribution with `coarse_grain: F` and real_count(count, F), which
/// compile turns into `count` parcels F times the diameter, their contact parameters scaled.
/// Rejected: the parcel distribution stated as real particles, which would keep the parcels'
/// sizes but not scale the contact law (a linear spring's stiffness, a surface energy).
ParticleSetSpec particle_box(const MaterialModel& model, std::int64_t count, const Vec3& lo, const Vec3& hi);

/// Vertices and triangles of an inline mesh under construction.
struct Mesh {
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  /// Lateral surface of a cylinder about the z axis, radius r [m] from z0 to z1, `around`
  /// segments, rings at most `cell` [m] apart; triangle normals point inwards.
  void tube(double r, double z0, double z1, int around, double cell);
  /// Disc of radius r [m] at height z about the z axis, normal +z (`up`) or -z.
  void disc(double r, double z, int around, bool up);
  MeshWallSpec wall(const std::string& name, const std::string& material) const;
};

/// Segments around a circle of radius r [m] so that a facet is at most `edge` [m] long (48..256).
int segments_around(double r, double edge);

/// A compiled case with its state, stepped by the tests. `restart` recompiles a phase-2 spec
/// (same materials, walls and particles, a motion that starts now) and continues the state.
/// [kg] The mass of the particles whose spheres `counted(p)` accepts: a free sphere's own, and a
/// clump's shared equally among its spheres (each sphere of a clump carries the whole clump's
/// mass for the integrator, State::attach, so a sum over spheres would count a clump once per
/// sphere).
double mass_of_spheres(const State& state, const std::function<bool(std::size_t)>& counted);

struct Runner {
  Model model;
  State state;
  Workspace work;
  explicit Runner(const CaseSpec& spec);
  void restart(const CaseSpec& spec);
  void advance();
  /// Steps until `done()` (checked every `check_every` [s]) or until state.time reaches `until`;
  /// returns true when done() held.
  bool advance_until(const std::function<bool()>& done, double until, double check_every = 0.005);
  /// The impact speed [m/s] a phase starting from the present state can reach at most: a sphere's
  /// present speed and a free fall from its height down to `lowest` [m], sqrt(v^2 + 2 g h), the
  /// largest over the spheres. A phase that starts from a settled bed takes its time step from
  /// this (SimulationSpec::characteristic_velocity), not from the pour that made the bed.
  double phase_speed(double lowest) const;
  /// Mean speed [m/s] of the spheres whose slot passes `keep` (all when empty); 0 when none.
  double mean_speed(const std::function<bool(std::size_t)>& keep = {}) const;
  double particle_mass() const;  ///< [kg] total
};

/// Least-squares line y = a + b x; returns {a, b}. Needs two distinct x.
std::pair<double, double> fit_line(const std::vector<double>& x, const std::vector<double>& y);
/// Standard error of the slope b of that line, from its residuals: sqrt(S_rr / (n - 2) / S_xx).
/// Needs three points (two fit any line exactly: 0 is returned, the error unknown).
double slope_standard_error(const std::vector<double>& x, const std::vector<double>& y, std::pair<double, double> line);

/// Wall clock of a test, and what every test reports at its end.
struct Clock {
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); }
};
void finish(SimulatedOutcome& out, const Runner& run, const Clock& clock, std::int64_t particles, const TestOptions& options);

/// Progress line to stdout when options.progress.
void progress(const TestOptions& options, const std::string& line);

// One function per test, one file each (lab_<name>.cpp), declared and registered in the table of
// virtual_tests.cpp.

/// hopper_discharge's flat floor: a dead zone rising at slope tan(theta) from the orifice's edge
/// (radius r [m]) to the wall (radius R [m]) holds 2 pi tan(theta) (R^3/3 - r R^2/2 + r^3/6) of
/// volume; over the bed's volume pi R^2 H this is tan(theta) / H times the figure returned [m],
/// whatever the angle.
double retained_wedge_per_height(double R, double r);
/// The silo a size factor makes of one `silo_diameter` wide filled `fill_height` [m] over an
/// orifice of `orifice_diameter` [m], which is never shrunk (lab_hopper_discharge.cpp says why).
struct SiloSize {
  double diameter = 0, fill = 0;  // [m]
};
SiloSize shrunk_silo(double silo_diameter, double orifice_diameter, double fill_height, double scale);

}  // namespace dem::materials::detail
