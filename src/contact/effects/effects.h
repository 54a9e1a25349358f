// What the effect files share: the spec types (effect.h), the parameters that two variants of a
// stage have in common, and the contact-plane helpers. The effects themselves are declared by
// their rows in src/contact/effect_table.cpp.
#pragma once

#include <cmath>

#include "contact/effect.h"

namespace dem::effects {

/// mu_r of both rolling variants (cdt, epsd): one row, so the two cannot disagree on its range
/// or default and a material's value means the same under either. Coarse graining
/// (core/coarse_grain.h): unchanged (exponent 0); the lever mu_r R* grows with the parcel's R*.
inline constexpr ParamSpec kRollingFrictionParam = {"rolling_friction", "-", 0.0, 0.0, 1.0, Mixing::arithmetic, true,
                                               "rolling friction coefficient mu_r; lever arm of the limiting torque is mu_r R*", 0,
                                               /*wall_candidate=*/true, /*plausible=*/std::pair{0.0, 0.4}};

// Pieces shared by the kernels with a spring in the contact plane (Mindlin, EPSD), written as
// selects so the kernels' loops stay vectorised, and always inlined: a call left in a loop stops
// its vectorisation (GCC 12 left them out of line in Mindlin's loop with -march=native, and the
// kernel, and with it the native build, ran far slower than with them inlined;
// bench/results/design_measurements.csv).

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
