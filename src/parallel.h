// OpenMP policy: loops over fewer items than this run on one thread. Opening a parallel region
// costs microseconds and idle OpenMP threads spin; for a handful of particles that dominates.
#pragma once

namespace dem {
inline constexpr long kParallelMin = 2048;
}  // namespace dem
