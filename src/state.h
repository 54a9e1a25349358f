// Everything that changes during a run. Particle data are columns (struct of arrays) indexed by
// the particle's current slot; slots are re-sorted in space when the neighbour list is rebuilt,
// so anything that must follow a particle uses its `id`.
#pragma once

#include <cstdint>
#include <vector>

namespace dem {

/// Contacts that may interact: pairs closer than interaction range + skin at the last rebuild.
/// Particle pairs are owned by the lower slot i (sorted by i); wall pairs have j = wall index.
/// Per pair: 8 bytes of indices + history_width doubles.
struct ContactList {
  std::vector<std::int32_t> i, j;
  std::vector<double> history;  ///< (size() x history_width)
  std::size_t size() const { return i.size(); }
  void clear() { i.clear(), j.clear(), history.clear(); }
};

struct State {
  double time = 0.0;  // [s]
  std::int64_t step = 0;
  std::int64_t next_id = 0;
  std::int64_t lost = 0;  ///< particles removed because they left the domain

  // Particles (n): hot columns. 18 doubles + 12 bytes = 156 bytes a particle.
  std::vector<double> x, y, z;     // [m] centre
  std::vector<double> vx, vy, vz;  // [m/s]
  std::vector<double> wx, wy, wz;  // [rad/s]
  std::vector<double> fx, fy, fz;  // [N] total force at the last evaluation
  std::vector<double> tx, ty, tz;  // [N m] total torque at the last evaluation
  std::vector<double> radius;      // [m]
  std::vector<double> inv_mass;    // [1/kg]
  std::vector<double> inv_inertia; // [1/(kg m^2)]
  std::vector<std::int32_t> material;
  std::vector<std::int64_t> id;    ///< persistent, never reused

  ContactList pairs;       ///< particle-particle
  ContactList wall_pairs;  ///< particle-plane wall

  std::size_t size() const { return x.size(); }
  /// Appends a sphere at rest state; returns its slot.
  std::size_t add_sphere(double px, double py, double pz, double r, double density, int mat);
  /// Reorders particle slots: new slot k holds old slot order[k]. Contact lists are not touched.
  void permute(const std::vector<std::int32_t>& order);
  /// Keeps only slots with keep[k] != 0 (contact lists are not touched).
  void compact(const std::vector<std::uint8_t>& keep);
};

}  // namespace dem
