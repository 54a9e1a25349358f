// Scalars of a state (energies, contacts, overlaps), a reproducibility hash, and the check for
// numerical trouble.
#pragma once

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem {

/// What a sensor (SensorSpec) saw at one instant. Plane sensors fill `flow`, `count_flow` and
/// the velocity; box sensors `mass`, the velocity and `offset`, and with bins their bins.
struct SensorReading {
  double flow = 0;        // [kg/s] plane: mass flow through it along its normal
  double count_flow = 0;  // [1/s] plane: particles through it along its normal (net)
  double mass = 0;        // [kg] box: mass of the particles inside
  /// [m/s] box: mass-weighted mean velocity of the particles inside. Plane: mean velocity of
  /// what crosses it, each particle in the slab weighted by the mass it carries across per
  /// second, m |v.n| (the velocity a flux-averaging probe would give; both directions count).
  double vx = 0, vy = 0, vz = 0;
  double offset = 0;      // [m] box: centroid offset along `across` from the box centre
  /// Box with bins (SensorSpec::bins): per lateral bin, the mass inside [kg] and its momentum
  /// along `along` [kg m/s]; empty otherwise. Not in scalars.csv: the run integrates them into
  /// State::stream_profiles (statistics/stream_profile.h) and keeps its rows without them.
  std::vector<double> bin_mass, bin_momentum;
};

struct Scalars {
  double time = 0;                 // [s]
  std::int64_t step = 0;
  std::size_t particles = 0;
  double kinetic_translation = 0;  // [J]
  double kinetic_rotation = 0;     // [J]
  std::size_t contacts = 0;        ///< touching particle pairs and particle-wall contacts
  double max_overlap_ratio = 0;    ///< largest overlap / smaller radius
  double mean_overlap_ratio = 0;   ///< over touching contacts
  double dt = 0;                   // [s]
  std::int64_t lost = 0;
  double inserted_mass = 0;        // [kg] by all inlets so far
  double removed_mass = 0;         // [kg] by all outlets so far
  std::vector<double> outlet_mass;       // [kg] per outlet, cumulative
  std::vector<double> wall_normal_force; // [N] per wall, pushing the wall along -normal
  std::vector<double> mesh_force;        // [N] per mesh, magnitude of the particles' force on it
  std::vector<double> mesh_torque;       // [N m] per mesh, about its rotation axis (|T| if it does not rotate)
  std::vector<double> mesh_power;        // [W] per mesh, rate of work it does on the particles
  /// Per mesh: the particles' force on it [N] (x, y, z) and its torque about the mesh's motion
  /// origin (the world origin when it does not move) [N m] (x, y, z), as components, so that a
  /// noisy force is averaged before its magnitude is taken.
  std::vector<std::array<double, 6>> mesh_load;
  double lost_mass = 0;                  // [kg] left the domain (outside every outlet): spillage
  std::vector<SensorReading> sensors;    ///< per sensor, in the model's order
};

Scalars measure(const Model& model, const State& state, const Workspace& work);

/// The additive parts of the scalars: sums over the particles a process owns, the contacts it
/// lists and its outlets and mesh loads, and the largest overlap. Under domain decomposition
/// (domain.h) each rank measures its parts (a pair across ranks is listed on one rank), the parts
/// of all ranks are summed, and the root finishes the row: no rank gathers the state for it.
struct ScalarParts {
  std::vector<double> sums;
  double max_overlap_ratio = 0;
};
ScalarParts measure_parts(const Model& model, const State& state, const Workspace& work);
/// Adds `more` to `total` (sums added, the larger overlap kept).
void add_parts(ScalarParts& total, const ScalarParts& more);
/// The row of the whole from the parts of every process: time, step, the inlets' counters and
/// the plane walls' loads come from `state` (the same on every rank), the rest from the parts.
/// measure() is finish_scalars(measure_parts()).
Scalars finish_scalars(const Model& model, const State& state, const ScalarParts& parts);

/// FNV-1a over position, velocity and angular velocity of every particle in id order, and the
/// history of every contact in id order: equal hashes mean bitwise equal states.
std::uint64_t state_hash(const State& state, int history_width);

/// Numerical trouble the run cannot continue through; the message says where and why.
class NumericalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws NumericalError when a particle has a non-finite position or velocity, or an overlap
/// beyond `max_overlap_ratio` of its radius, naming the particle and the likely cause.
void check_numerics(const Model& model, const State& state, const Workspace& work, double max_overlap_ratio = 0.5);

/// Kinetic (translation and rotation) plus gravitational potential energy of the free
/// particles and clumps [J] (glued particles move with their wall and are left out; under domain
/// decomposition, the rank's own: ghosts are left out).
double mechanical_energy(const Model& model, const State& state);

/// Why the energy check cannot be used for this model ("" when it can): the model has an energy
/// source (an inlet, a moving or servo wall, a moving mesh or belt surface, an attractive
/// contact effect that converts surface energy into motion).
std::string energy_source(const Model& model);

/// Energy rise without a source: watches mechanical_energy() of a source-free model. A
/// dissipative (or elastic, e = 1) system may not gain energy; the margin is `fraction` of the
/// energy scale: the initial kinetic energy plus every particle's weight times its diameter.
class EnergyWatch {
 public:
  EnergyWatch(const Model& model, const State& state, double fraction = 0.05);
  /// Throws NumericalError when the energy exceeds its value at the start by more than the
  /// margin, naming the fastest particle, where it is, and the likely cause.
  void check(const Model& model, const State& state);
  /// The same with the energy given (under domain decomposition: the sum of every rank's
  /// mechanical_energy); `state` names the fastest of its particles.
  void check(const Model& model, const State& state, double energy);
  bool active() const { return source_.empty(); }
  const std::string& source() const { return source_; }

 private:
  std::string source_;
  double fraction_ = 0.05;
  double lowest_ = 0, scale_ = 0;
};

}  // namespace dem
