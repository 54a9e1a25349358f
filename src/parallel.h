// How the engine uses the cores and their vector units.
#pragma once

namespace dem {
/// OpenMP policy: loops over fewer items than this run on one thread. Opening a parallel region
/// costs microseconds and idle OpenMP threads spin; for a handful of particles that dominates.
inline constexpr long kParallelMin = 2048;
/// Particles per call of a vectorised pass (DEM_KERNEL) inside an OpenMP loop.
inline constexpr long kChunk = 1024;
}  // namespace dem

/// A loop the compiler vectorises (columns, no pointers into other memory, branches written as
/// selects): GCC builds the function three times, for AVX-512, AVX2 + FMA and the x86-64
/// baseline, and the loader picks the one this CPU runs (function multiversioning, an ifunc).
/// Floating-point contraction is off everywhere (CMakeLists.txt), so the three give the same
/// bits; only the speed differs.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(DEMDESIGN_NO_CLONES)
#define DEM_KERNEL [[gnu::target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")]]
#else
#define DEM_KERNEL
#endif
/// Put before such a loop: its iterations are independent, and what it writes overlaps nothing
/// it reads at another index. The compiler cannot prove that for columns reached through
/// pointers, and without it gives up on vectorising (too many run-time overlap checks).
#if defined(__clang__)
#define DEM_VECTOR_LOOP _Pragma("clang loop vectorize(assume_safety)")
#elif defined(__GNUC__)
#define DEM_VECTOR_LOOP _Pragma("GCC ivdep")
#else
#define DEM_VECTOR_LOOP
#endif
