// Creating particles: diameters drawn from the case's size distributions and centres placed
// without overlap, reproducibly from the case's seed (same seed, same packing, any machine).
#pragma once

#include <cstdint>

#include "model.h"
#include "state.h"

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

/// The state at t = 0: every particle source of the model, placed. Throws CaseError when a
/// region cannot hold its particles.
State initial_state(const Model& model);

}  // namespace dem
