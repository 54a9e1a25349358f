// Creating particles: diameters drawn from the case's size distributions and centres placed
// without overlap, reproducibly from the case's seed (same seed, same packing, any machine).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/model.h"
#include "core/state.h"

namespace dem {

/// splitmix64 (Steele, Lea & Flood 2014): tiny, fast, identical on every platform; the
/// standard library's distributions are not, so the draws below are written out.
struct Random {
  std::uint64_t state;
  explicit Random(std::uint64_t seed) : state(seed) {}
  std::uint64_t next();
  double uniform();  ///< in [0, 1), 53 random bits
  double normal();   ///< standard normal (Box-Muller)
};

/// One diameter drawn from a size distribution [m].
double draw_diameter(const SizeDistributionSpec& d, Random& random);

/// The state at t = 0: walls where the model puts them, every particle source placed (clumps
/// with random orientation). Throws CaseError when a region cannot hold its particles.
State initial_state(const Model& model);

/// Inserts what inlet `k` owes by its next insertion (mass rate x time since start), at random
/// places in its region that overlap nothing. Returns the number of particles (or clumps) inserted.
/// `others`: spheres (x, y, z, r) to keep clear of besides the state's (under domain
/// decomposition, every rank's near the region).
std::int64_t run_inlet(const Model& model, State& state, int k, const std::vector<std::array<double, 4>>* others = nullptr);
/// Whether inlet `k` inserts at the state's time (run_inlet does nothing otherwise).
bool inlet_due(const Model& model, const State& state, int k);
/// The box around inlet `k`'s region in which existing spheres matter to its overlap checks.
void inlet_reach(const Model& model, int k, double lo[3], double hi[3]);

/// Places the spheres of every body from its centre and orientation, with the body's velocity
/// (v + w x r) and angular velocity.
void place_body_spheres(const Model& model, State& state, const std::vector<std::int32_t>& body_begin,
                        const std::vector<std::int32_t>& body_members);

}  // namespace dem
