// How the process's heap behaves under the engine's allocation pattern: once per list rebuild,
// buffers of tens of MiB (contact histories by id, new lists) are allocated and freed.
#pragma once

#include <cstddef>
#include <vector>

namespace dem {

/// Gives large blocks back to the system when they are freed. glibc's malloc serves a block
/// above a threshold from its own mapping, returned on free; but the threshold follows the
/// largest block freed so far (up to 32 MiB), after which a rebuild's buffers come from the heap
/// and the holes they leave stay resident. Fixing the threshold at 256 KiB (glibc's initial
/// value) lowered the peak memory of the settling bed with the same results, and its speed moved
/// within the noise (bench/results/design_measurements.csv).
/// Call once at the start of main(), before the engine allocates. Does nothing where the C
/// library is not glibc. Returns whether the setting took.
bool tune_allocator();

/// Resizes a buffer whose contents are about to be overwritten. std::vector, growing, holds the
/// old block and the new one at once and doubles; here the old block goes first, and the new
/// one is 1/8 larger than asked, so a list that grows a little at each rebuild (a settling bed)
/// does not move every time.
template <typename T>
void resize_discarding(std::vector<T>& v, std::size_t n) {
  if (n > v.capacity()) {
    std::vector<T>().swap(v);
    v.reserve(n + n / 8);
  }
  v.resize(n);
}

/// As resize_discarding, every element set to `value`.
template <typename T>
void assign_discarding(std::vector<T>& v, std::size_t n, const T& value) {
  if (n > v.capacity()) {
    std::vector<T>().swap(v);
    v.reserve(n + n / 8);
  }
  v.assign(n, value);
}

}  // namespace dem
