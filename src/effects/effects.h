// Declarations of every contact effect; the table in src/effect_table.cpp lists them.
#pragma once

#include <cmath>

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

// Pieces shared by the kernels with a spring in the contact plane (Mindlin, EPSD), written as
// selects so the kernels' loops stay vectorised, and always inlined: a call left in a loop stops
// its vectorisation (GCC 12 left them out of line in Mindlin's loop with -march=native, and the
// kernel ran 3x slower: B1 20k 0.6x of the default build, with them inlined 0.9x).

/// Turns a spring (x, y, z) into the contact plane of unit normal n at constant length.
[[gnu::always_inline]] inline void keep_in_contact_plane(double& x, double& y, double& z, double nx, double ny, double nz) {
  const double old2 = x * x + y * y + z * z;
  const double along_n = x * nx + y * ny + z * nz;
  x -= along_n * nx, y -= along_n * ny, z -= along_n * nz;
  const double new2 = x * x + y * y + z * z;
  const double ratio = std::sqrt(old2 / new2);  // (not finite when new2 = 0: not used)
  const double keep = new2 > 0.0 ? ratio : 1.0;
  x *= keep, y *= keep, z *= keep;
}

/// Factor that brings a vector of squared length magnitude2 down to length `limit` when it is
/// longer (1 otherwise).
[[gnu::always_inline]] inline double cap_to_limit(double magnitude2, double limit) {
  const double to_limit = limit / std::sqrt(magnitude2);  // (not finite when magnitude2 = 0)
  return magnitude2 > limit * limit ? (magnitude2 > 0.0 ? to_limit : 0.0) : 1.0;
}
}  // namespace dem::effects
