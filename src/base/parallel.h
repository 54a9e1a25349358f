// How the engine uses the cores and their vector units.
#pragma once

#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "base/allocator.h"

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

namespace dem {
/// Builds a list in rows (CSR: row r's entries are out[begin[r]] .. out[begin[r + 1] - 1]) in
/// one pass over the rows: they are cut into pieces, 8 per thread, which the threads take in
/// turn as they become free (the entries per row vary: a sphere by a wall has many candidate
/// triangles, one in free flight none; with one piece per thread, the chute's threads waited for
/// each other: bench/results/design_measurements.csv). Each piece's rows are appended to a
/// buffer of its own (fill(r, buffer, m) appends row r's entries from index m on, growing the
/// buffer as needed, and returns the new end), then the buffers are copied into place. Rows come
/// out in order whatever the thread count. The buffers are kept between calls, so a rebuild
/// allocates nothing once they have grown.
template <typename T, typename Fill>
void fill_rows(long rows, bool parallel, std::vector<std::vector<T>>& buffers, std::vector<std::int32_t>& begin,
               std::vector<T>& out, Fill&& fill) {
  const int threads = parallel ? omp_get_max_threads() : 1;
  const long pieces = threads == 1 ? 1 : std::max(1L, std::min(rows, 8L * threads));
  if (buffers.size() < static_cast<size_t>(pieces)) buffers.resize(static_cast<size_t>(pieces));
  begin.assign(static_cast<size_t>(rows) + 1, 0);
  const auto first_row = [&](long piece) { return rows * piece / pieces; };
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(dynamic, 1)
    for (long piece = 0; piece < pieces; ++piece) {
      std::vector<T>& buffer = buffers[static_cast<size_t>(piece)];
      size_t m = 0;
      for (long r = first_row(piece); r < first_row(piece + 1); ++r) {
        const size_t before = m;
        m = fill(r, buffer, m);
        begin[static_cast<size_t>(r) + 1] = static_cast<std::int32_t>(m - before);
      }
    }
#pragma omp single
    {
      for (long r = 0; r < rows; ++r) begin[r + 1] += begin[r];
      resize_discarding(out, static_cast<size_t>(begin[rows]));
    }
#pragma omp for schedule(dynamic, 1)
    for (long piece = 0; piece < pieces; ++piece) {
      const long lo = first_row(piece), hi = first_row(piece + 1);
      std::copy_n(buffers[static_cast<size_t>(piece)].data(), begin[hi] - begin[lo], out.data() + begin[lo]);
    }
  }
}
}  // namespace dem
